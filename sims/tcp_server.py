"""TCP front end: the analyzer as ``TCPIP::127.0.0.1::<port>::SOCKET`` for pyvisa-py.

Binds to 127.0.0.1 unless told otherwise. One thread accepts, one thread serves
each client; all clients share the one instrument, as on a GPIB bus. Closing
the server shuts every client's socket down and joins every thread, waiting at
most ``CLOSE_WAIT_S`` in all: a thread still busy then (a client asked for a long
measurement, computed in its thread) is a daemon, logged and left to finish or to
end with the process, so a server told to stop stops promptly.
"""

from __future__ import annotations

import contextlib
import logging
import socket
import threading
import time
from collections.abc import Sequence

from sims.faults import parse_fault
from sims.instrument import Analyzer
from sims.session import Session

log = logging.getLogger(__name__)

#: How often blocked threads look up to see whether the server is closing, s.
POLL_S = 0.1
#: The longest close() waits for the server's threads, s, all of them together.
CLOSE_WAIT_S = 2.0


class TcpServer:
    """Serve ``analyzer`` on ``host:port`` (port 0: the system picks a free one)."""

    def __init__(
        self,
        analyzer: Analyzer,
        host: str = "127.0.0.1",
        port: int = 0,
        faults: Sequence[str] = (),
    ) -> None:
        self.analyzer = analyzer
        self.faults = tuple(faults)
        for spec in self.faults:  # a bad spec fails here, not on the first connection
            parse_fault(spec)
        self._listener = socket.create_server((host, port))
        self._listener.settimeout(POLL_S)
        self.host, self.port = self._listener.getsockname()[:2]
        self._stop = threading.Event()
        self._lock = threading.Lock()
        self._clients: dict[threading.Thread, socket.socket] = {}
        self._accepter = threading.Thread(target=self._accept_loop, name=f"sim-tcp-{self.port}", daemon=True)
        self.connections_served = 0

    @property
    def resource(self) -> str:
        return f"TCPIP::{self.host}::{self.port}::SOCKET"

    def start(self) -> TcpServer:
        self._accepter.start()
        return self

    def __enter__(self) -> TcpServer:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Stop accepting, end every connection and join the threads, in at most CLOSE_WAIT_S.

        A client thread blocked in recv or send wakes when its socket is shut down and
        polls the stop every POLL_S; one computing a reply under the instrument's lock
        (e.g. 9999 averages at time scale 0) looks up only when done. It is not waited
        for beyond the deadline: it is a daemon, and its socket is already shut down.
        """
        deadline = time.monotonic() + CLOSE_WAIT_S
        with self._lock:  # the accept loop registers a client under this lock, or none
            self._stop.set()
            clients = list(self._clients.items())
        for _, conn in clients:
            with contextlib.suppress(OSError):
                conn.shutdown(socket.SHUT_RDWR)
        if self._accepter.is_alive():
            self._accepter.join(max(0.0, deadline - time.monotonic()))
        self._listener.close()
        for thread, _ in clients:
            thread.join(max(0.0, deadline - time.monotonic()))
        busy = [thread.name for thread, _ in clients if thread.is_alive()]
        if busy:
            log.warning("closed with %s still busy after %g s; not waiting for them", busy, CLOSE_WAIT_S)

    @property
    def active_connections(self) -> int:
        with self._lock:
            return len(self._clients)

    def _accept_loop(self) -> None:
        while not self._stop.is_set():
            try:
                conn, peer = self._listener.accept()
            except TimeoutError:
                continue
            except OSError:
                return
            conn.settimeout(POLL_S)
            thread = threading.Thread(target=self._serve, args=(conn, peer), daemon=True)
            with self._lock:
                if self._stop.is_set():  # close() has taken its list of clients
                    conn.close()
                    return
                self._clients[thread] = conn
                self.connections_served += 1
                thread.name = f"sim-tcp-client-{self.connections_served}"
                thread.start()

    def _serve(self, conn: socket.socket, peer: object) -> None:
        session = Session(self.analyzer, self.faults)
        log.debug("client %s connected", peer)
        try:
            while not self._stop.is_set() and not session.closed:
                try:
                    data = conn.recv(65536)
                except TimeoutError:
                    continue
                if not data:
                    break
                for chunk in session.feed(data):
                    if chunk.delay_s and not self._hold(conn, chunk.delay_s):
                        return
                    if chunk.until is not None and not self._await(conn, chunk.until):
                        return
                    if chunk.data:
                        self._send(conn, chunk.data)
                    if chunk.close:
                        break
        except OSError as exc:  # the client vanished mid-transfer: its problem, not ours
            log.debug("client %s: %s", peer, exc)
        finally:
            try:
                conn.close()
            finally:
                with self._lock:
                    self._clients.pop(threading.current_thread(), None)
            log.debug("client %s closed", peer)

    def _hold(self, conn: socket.socket, delay_s: float) -> bool:
        """Wait out a slow reply; False if the server closes or the client leaves
        meanwhile (its thread and socket are not kept for a reply nobody reads)."""
        deadline = time.monotonic() + delay_s
        while (left := deadline - time.monotonic()) > 0:
            if self._stop.wait(min(POLL_S, left)):
                return False
            try:
                if conn.recv(1, socket.MSG_PEEK | socket.MSG_DONTWAIT) == b"":
                    return False
            except (BlockingIOError, TimeoutError):
                pass
        return True

    def _await(self, conn: socket.socket, until) -> bool:
        """Hold a reply until ``until()`` (SCPI's *OPC? waits for the measurement);
        False if the server closes or the client leaves meanwhile."""
        while not until():
            if self._stop.wait(0.005):
                return False
            try:
                if conn.recv(1, socket.MSG_PEEK | socket.MSG_DONTWAIT) == b"":
                    return False
            except (BlockingIOError, TimeoutError):
                pass
        return True

    def _send(self, conn: socket.socket, data: bytes) -> None:
        view = memoryview(data)
        deadline = time.monotonic() + 30.0  # a client that stops reading is gone
        while view:
            if self._stop.is_set() or time.monotonic() > deadline:
                raise OSError("client stopped reading")
            try:
                sent = conn.send(view)
            except TimeoutError:
                continue
            view = view[sent:]
