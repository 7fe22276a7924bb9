"""`daq serve` under clients that hold what they take: idle connections, a chunked body
that never ends, a flood of slow reads, and a SIGTERM while they are in flight.

Loopback only, real `daq serve` processes and sockets. The service's file-descriptor
limit is lowered (RLIMIT_NOFILE in the child) so that a few hundred idle sockets
would fill it; every wait is bounded.
"""

from __future__ import annotations

import concurrent.futures
import contextlib
import os
import resource
import signal
import socket
import subprocess
import threading
import time
from pathlib import Path
from urllib.parse import urlsplit

import httpx
import pytest

from daq.store import seal
from tests.cli.run_files import make_run
from tests.cli_helpers import DAQ
from tests.service.service_helpers import ADDRESS_LINE, Served, service_env, stop_service

pytestmark = pytest.mark.slow

SOUND = "20261123T101503.123Z-0000aaaa"


@contextlib.contextmanager
def serving_limited(tmp_path, nofile: int | None = None, *args: str):
    """`daq serve --sim` on a store with one run, its open files limited to ``nofile``."""
    store = tmp_path / "store"
    if not store.exists():
        seal(make_run(SOUND), store)
    env = service_env(tmp_path)

    def prepare() -> None:
        signal.signal(signal.SIGINT, signal.SIG_DFL)
        if nofile is not None:
            resource.setrlimit(resource.RLIMIT_NOFILE, (nofile, nofile))

    proc = subprocess.Popen(
        [str(DAQ), "serve", "--sim", "--workers", "1", "--port", "0", "--store", str(store), *args],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
        start_new_session=True,
        preexec_fn=prepare,
    )
    lines: list[str] = []
    drain = None
    try:
        url = token = None
        deadline = time.monotonic() + 60
        while url is None and time.monotonic() < deadline:
            line = proc.stderr.readline()
            if not line:
                raise AssertionError(f"daq serve exited: {''.join(lines)}")
            lines.append(line)
            if match := ADDRESS_LINE.search(line):
                url, token = match.group(1), match.group(2)
        assert url is not None, lines
        drain = threading.Thread(target=lambda: lines.extend(proc.stderr), daemon=True)
        drain.start()
        yield Served(url, token, proc, store, env, lines)
    finally:
        try:
            if proc.poll() is None:
                stop_service(Served("", "", proc, store, env))
        finally:
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGKILL)
            proc.wait(10)
            if drain is not None:
                drain.join(10)
            proc.stderr.close()


def _address(served: Served) -> tuple[str, int]:
    parts = urlsplit(served.url)
    return parts.hostname, parts.port


def test_idle_connections_do_not_lock_out_the_clients(tmp_path):
    """400 connections that send nothing, against a service allowed 256 open files:
    health, the listing and an authenticated POST still answer within seconds, and
    the idle connections are closed by the service."""
    n_idle = 400
    with serving_limited(tmp_path, nofile=256) as served:
        idle = []
        try:
            for _ in range(n_idle):
                sock = socket.create_connection(_address(served), timeout=5)
                idle.append(sock)
            time.sleep(0.5)  # let the service accept what it will
            with served.client(timeout=5) as client:
                # Answered at all, with the idle ones held: a locked-out client gets the
                # client's ReadTimeout instead.
                for _ in range(3):
                    assert client.get("/api/health").status_code == 200
                    assert client.get("/api/runs").status_code == 200
                    stop = client.post("/api/capture/stop", json={})
                    assert stop.status_code in (202, 409), stop.text
            # The idle ones are closed: by the cap at once, by the header timeout after it.
            deadline = time.monotonic() + 20
            open_ones = list(idle)
            while open_ones and time.monotonic() < deadline:
                still = []
                for sock in open_ones:
                    sock.settimeout(0.01)
                    try:
                        if sock.recv(1) == b"":
                            continue  # closed by the service
                    except (ConnectionResetError, BrokenPipeError):
                        continue
                    except TimeoutError:
                        pass
                    still.append(sock)
                open_ones = still
                time.sleep(0.2)
            assert not open_ones, f"{len(open_ones)} of {n_idle} idle connections still open after 20 s"
        finally:
            for sock in idle:
                sock.close()


def test_a_chunked_body_is_refused_before_it_is_read(tmp_path):
    """With the token, a small Content-Length and Transfer-Encoding: chunked: refused
    at once, and the connection closed long before 64 MiB went out."""
    with serving_limited(tmp_path) as served:
        head = (
            "POST /api/capture HTTP/1.1\r\nHost: 127.0.0.1\r\n"
            f"Authorization: Bearer {served.token}\r\nContent-Type: application/json\r\n"
            "Content-Length: 10\r\nTransfer-Encoding: chunked\r\n\r\n"
        ).encode()
        chunk = b"%x\r\n" % (1 << 20) + b" " * (1 << 20) + b"\r\n"
        sent = 0
        with socket.create_connection(_address(served), timeout=15) as sock:
            sock.sendall(head)
            try:
                for _ in range(64):
                    sock.sendall(chunk)
                    sent += len(chunk)
            except (BrokenPipeError, ConnectionResetError):
                pass
            with contextlib.suppress(OSError):
                sock.sendall(b"0\r\n\r\n")
            answer = b""
            with contextlib.suppress(ConnectionResetError, TimeoutError):
                while piece := sock.recv(65536):
                    answer += piece
        status = int(answer.split(b" ", 2)[1]) if answer.startswith(b"HTTP/1.1 ") else None
        assert status in (400, 411, 413), answer[:300]
        assert sent < 16 << 20, f"{sent >> 20} MiB sent before the service closed the connection"
        with served.client() as client:
            assert client.get("/api/capture").json()["state"] == "idle"


def _get(served: Served, path: str, timeout: float) -> int | str:
    try:
        with httpx.Client(base_url=served.url, timeout=timeout) as client:
            return client.get(path).status_code
    except httpx.HTTPError as exc:
        return type(exc).__name__


def _hard_link_bomb(store: Path) -> Path:
    """A sound run of the service's store turned into the issue's hard-link bomb."""
    from daq.store import seal
    from tests.store.store_helpers import add_hard_link_bomb, make_run

    return add_hard_link_bomb(seal(make_run(run_id="20261124T235958.000Z-0badf11e"), store))


@pytest.mark.parametrize("target", ["a FIFO named as a run", "a hard-link bomb"])
def test_a_flood_of_slow_reads_starves_nothing_and_sigterm_ends_the_service(tmp_path, target):
    """45 unauthenticated requests for a FIFO named as a run (whose open waits for
    ever), or for the issue's run file of groups holding 30 hard links to the next 7
    levels deep (whose link walk visited every path, for good): health and the other
    routes answer at once meanwhile, and SIGTERM then ends the process within seconds.
    (The bound on reads itself: test_service_hardening_reads.)"""
    with serving_limited(tmp_path) as served:
        pool = concurrent.futures.ThreadPoolExecutor(50)
        try:
            if target == "a hard-link bomb":
                fifo = _hard_link_bomb(served.store).stem
            else:
                fifo = "20261124T235959.000Z-deadbeef"
                os.mkfifo(served.store / f"{fifo}.h5")
            path = f"/api/runs/{fifo}"
            flood = [pool.submit(_get, served, path, 120) for _ in range(45)]
            time.sleep(1.0)
            # Answered at all, with the flood sent: a starved route gets the client's
            # ReadTimeout instead.
            with httpx.Client(base_url=served.url, timeout=10) as client:
                for path in ("/api/health", "/api/capture", "/api/instrument"):
                    assert client.get(path).status_code == 200, path
                stop = client.post(
                    "/api/capture/stop", json={}, headers={"Authorization": f"Bearer {served.token}"}
                )
                assert stop.status_code in (202, 409), stop.text
            answers = {f.result(30) for f in flood}
            assert len(answers) == 1, answers
            assert answers <= {404, 422}, answers  # refused, not read for ever
            served.proc.send_signal(signal.SIGTERM)
            try:
                served.proc.wait(15)
            except subprocess.TimeoutExpired:
                raise AssertionError("daq serve did not end within 15 s of SIGTERM") from None
        finally:
            pool.shutdown(wait=False, cancel_futures=True)
