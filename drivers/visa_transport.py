"""VISA resources through pyvisa with the pyvisa-py backend.

``GPIB0::11::INSTR`` (pyvisa-py over linux-gpib or gpib-ctypes),
``TCPIP::host::port::SOCKET`` (the simulator, LAN-GPIB gateways) and
``ASRL/dev/ttyUSB0::INSTR``. Replies end with LF (CR LF from the analyzer); binary
blocks are read by count, never through the termination character (pyvisa #348).
"""

from __future__ import annotations

import contextlib
import os
import socket

from drivers.errors import ConnectionFailed, ConnectionLost, InstrumentTimeout
from drivers.transport import Transport

#: The longest reply line we accept; a line without its LF beyond this is garbage.
MAX_LINE_BYTES = 65536


class VisaTransport(Transport):
    def __init__(
        self, resource: str, timeout_s: float = 5.0, backend: str = "@py", lock_file: bool = True
    ) -> None:
        resource = _normalise(resource)
        # The lock key resolves a host name (DNS): only worth it when a lock is wanted.
        super().__init__(resource, timeout_s, lock_file, lock_key=_lock_key(resource) if lock_file else None)
        self.backend = backend
        self._inst = None

    @property
    def is_socket(self) -> bool:
        return self.resource.endswith("::SOCKET")

    def _open(self) -> None:
        import pyvisa

        try:
            # pyvisa hands out one ResourceManager per library: it is shared with every
            # other instrument in this process and is never closed here.
            rm = pyvisa.ResourceManager(self.backend)
            self._inst = rm.open_resource(self.resource, open_timeout=int(self.timeout_s * 1000))
        except Exception as exc:  # pyvisa raises assorted types for bad or absent resources
            self._release()
            raise ConnectionFailed(f"cannot open {self.resource}: {_reason(exc)}") from None
        self._inst.read_termination = "\n"
        self._inst.write_termination = "\n"
        self._apply_timeout()
        if self.is_socket and self.backend == "@py":
            self._check_connected()

    def _check_connected(self) -> None:
        """pyvisa-py's socket open reports success even when the connection was
        refused (its select sees the failed socket as ready); ask the socket."""
        try:
            sock = pyvisa_py_socket(self._inst)
        except RuntimeError:
            self._release()
            raise
        try:
            error = sock.getsockopt(socket.SOL_SOCKET, socket.SO_ERROR)
            if not error:
                sock.getpeername()
        except OSError as exc:
            error = exc.errno or -1
        if error:
            self._release()
            reason = os.strerror(error) if error > 0 else "not connected"
            raise ConnectionFailed(f"cannot open {self.resource}: {reason}")

    def _apply_timeout(self) -> None:
        if self._inst is not None:
            self._inst.timeout = int(self.timeout_s * 1000)

    def _release(self) -> None:
        if self._inst is not None:
            with contextlib.suppress(Exception):  # a broken session may not close cleanly
                self._inst.close()
        self._inst = None

    def _close(self) -> None:
        self._release()

    def _session(self):
        if self._inst is None:
            raise ConnectionLost(f"{self.resource} is not open")
        return self._inst

    def _call(self, what: str, action):
        import pyvisa

        try:
            return action(self._session())
        except pyvisa.errors.VisaIOError as exc:
            error = _translate(exc, self.resource, what)
            # pyvisa-py reads a socket the instrument closed as a timeout (recv() of
            # nothing until the deadline): say what it is, a closed connection.
            if isinstance(error, InstrumentTimeout) and self._peer_closed():
                error = ConnectionLost(f"{self.resource}: {what} failed (connection closed by the other end)")
            raise error from None
        except (pyvisa.errors.Error, OSError) as exc:  # an invalid session, a dead socket
            raise ConnectionLost(f"{self.resource}: {what} failed ({_reason(exc)})") from None

    def _peer_closed(self) -> bool:
        """True if this is a pyvisa-py socket whose other end closed the connection."""
        if not (self.is_socket and self.backend == "@py" and self._inst is not None):
            return False
        try:
            sock = pyvisa_py_socket(self._inst)
            return sock.recv(1, socket.MSG_PEEK | socket.MSG_DONTWAIT) == b""
        except BlockingIOError:
            return False  # open, just quiet
        except (RuntimeError, OSError):
            return True  # reset or unusable: closed as far as we are concerned

    def _write(self, message: bytes) -> None:
        self._call("write", lambda inst: inst.write_raw(message + b"\n"))

    def _read_line(self) -> bytes:
        return self._call("read", lambda inst: inst.read_raw(MAX_LINE_BYTES)).rstrip(b"\r\n")

    def _read_exact(self, count: int) -> bytes:
        return bytes(
            self._call(f"read of {count} bytes", lambda inst: inst.read_bytes(count, break_on_termchar=False))
        )

    def _clear(self) -> None:
        if self.is_socket:
            # A raw socket has no device clear. A fresh connection drops what the old
            # one still carried; what the instrument itself still holds (a LAN
            # gateway keeps it) is drained until the line stays quiet.
            self.reconnect()
            self._call("drain", lambda inst: inst.clear())
            return
        try:
            self._call("device clear", lambda inst: inst.clear())
        except NotSupported:
            self.reconnect()  # serial ports and some gateways have no device clear


def pyvisa_py_socket(inst) -> socket.socket:
    """The socket under a pyvisa-py TCPIP SOCKET resource.

    pyvisa has no public way to reach it: this reads pyvisa-py's internal session
    table (``visalib.sessions[session].interface``), the one place the driver does.
    Anything else than a socket there raises RuntimeError, so that a pyvisa-py
    release that changes the internal fails loudly (and its test with it) instead
    of silently skipping the check of a refused connection.
    """
    try:
        sock = inst.visalib.sessions[inst.session].interface
    except (AttributeError, KeyError, TypeError) as exc:
        raise RuntimeError(f"pyvisa-py's session table changed, cannot reach the socket: {exc!r}") from None
    if not isinstance(sock, socket.socket):
        raise RuntimeError(f"pyvisa-py's session interface is a {type(sock).__name__}, not a socket")
    return sock


def _normalise(resource: str) -> str:
    """Upper-case the resource class (pyvisa rejects ``::socket``), strip blanks."""
    parts = resource.strip().split("::")
    if parts and parts[-1].upper() in ("INSTR", "SOCKET", "INTFC", "BACKPLANE", "RAW"):
        parts[-1] = parts[-1].upper()
    return "::".join(parts)


def _lock_key(resource: str) -> str:
    """The physical link behind a VISA name, so that every spelling of one
    instrument shares one lock: ``TCPIP0::localhost::5025::SOCKET`` and
    ``TCPIP::127.0.0.1::5025::SOCKET`` are one socket; ``GPIB::11`` and
    ``GPIB0::11::INSTR`` one address; ``ASRL/dev/ttyUSB0::INSTR`` and a Prologix on
    /dev/ttyUSB0 one serial port."""
    from pyvisa import rname

    try:
        parsed = rname.parse_resource_name(resource)
    except Exception:  # not a VISA name we know; the open will say so
        return resource.upper()
    kind = type(parsed).__name__
    if kind == "TCPIPSocket":
        try:
            host = socket.gethostbyname(parsed.host_address)
        except OSError:
            host = parsed.host_address.lower()
        return f"TCPIP::{host}::{int(parsed.port)}::SOCKET"
    if kind == "GPIBInstr":
        secondary = f"::{parsed.secondary_address}" if parsed.secondary_address else ""
        return f"GPIB{parsed.board or 0}::{int(parsed.primary_address)}{secondary}"
    if kind == "ASRLInstr" and parsed.board.startswith("/"):
        return f"SERIAL::{os.path.realpath(parsed.board)}"
    return str(parsed).upper()


def _reason(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    return text or type(exc).__name__


def _translate(exc: Exception, resource: str, what: str) -> Exception:
    from pyvisa import constants

    code = getattr(exc, "error_code", None)
    if code == constants.StatusCode.error_timeout:
        return InstrumentTimeout(f"{resource}: {what} timed out")
    if code == constants.StatusCode.error_nonsupported_operation:
        return NotSupported(f"{resource}: {what} is not supported")
    return ConnectionLost(f"{resource}: {what} failed ({_reason(exc)})")


class NotSupported(ConnectionLost):
    """The link cannot do this (a device clear on a serial port)."""
