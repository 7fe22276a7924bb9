"""The same user's processes find the same locks whatever their environment (issue item 11).

A shell has XDG_RUNTIME_DIR and TMPDIR of its own; a service or cron job often has
neither. The instrument lock must still be one file for both, and the store's lock
lives in the store. Each test holds a lock in one subprocess and tries it from
another with a different environment: the second must be refused as busy.
"""

from __future__ import annotations

import os
import secrets
import subprocess
import sys
from pathlib import Path

import pytest

HOLD = """
import sys
from daq.store.lock import store_lock
from drivers.locking import ResourceLock
kind, name = sys.argv[1], sys.argv[2]
lock = store_lock(name, holder="holder") if kind == "store" else ResourceLock(name, holder="holder")
lock.acquire()
print(lock.path, flush=True)
sys.stdin.readline()  # held until the test closes our stdin
"""

TRY = """
import sys
from drivers.errors import ResourceBusy
from daq.store.lock import store_lock
from drivers.locking import ResourceLock
kind, name = sys.argv[1], sys.argv[2]
lock = store_lock(name) if kind == "store" else ResourceLock(name)
try:
    lock.acquire()
except ResourceBusy as exc:
    print("busy:", exc, lock.path)
else:
    print("acquired", lock.path)
"""


def _env(tmp_path: Path, xdg: bool) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in ("DAQ_LOCK_DIR", "XDG_RUNTIME_DIR", "TMPDIR")}
    if xdg:  # a login shell: a runtime dir and a tmp dir of its own
        for name, folder in (("XDG_RUNTIME_DIR", "run"), ("TMPDIR", "tmp")):
            (tmp_path / folder).mkdir(mode=0o700, exist_ok=True)
            env[name] = str(tmp_path / folder)
    return env


@pytest.mark.timeout(60)
@pytest.mark.parametrize("holder_has_xdg", [True, False], ids=["shell-holds", "service-holds"])
@pytest.mark.parametrize("kind", ["instrument", "store"])
def test_processes_with_and_without_xdg_runtime_dir_contend_for_one_lock(tmp_path, kind, holder_has_xdg):
    name = str(tmp_path / "store") if kind == "store" else f"TEST::lock-env-{secrets.token_hex(6)}"
    if kind == "store":
        (tmp_path / "store").mkdir()
    holder = subprocess.Popen(
        [sys.executable, "-c", HOLD, kind, name],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
        env=_env(tmp_path, holder_has_xdg),
    )
    try:
        held_at = holder.stdout.readline().strip()
        assert held_at, "the holder could not take the lock"
        other = subprocess.run(
            [sys.executable, "-c", TRY, kind, name],
            capture_output=True,
            text=True,
            timeout=30,
            env=_env(tmp_path, not holder_has_xdg),
        )
        assert other.returncode == 0, other.stderr
        assert other.stdout.startswith("busy:"), other.stdout
        assert "holder" in other.stdout
        assert other.stdout.split()[-1] == held_at  # one file for both
        if kind == "store":
            assert Path(held_at).parent == tmp_path / "store"  # the store's lock is in the store
        else:
            assert Path(held_at).parent == Path(f"/tmp/daq-locks-{os.getuid()}")
    finally:
        holder.stdin.close()
        holder.wait(timeout=10)
        holder.stdout.close()


# --------------------------------------------------- the instrument link (issue item 13)
# Kept here with the other instrument-link test of this issue; it belongs with
# tests/drivers/test_transports.py.
@pytest.mark.timeout(30)
def test_a_link_the_instrument_closed_is_reported_as_closed_not_as_a_timeout(tmp_path, monkeypatch):
    import socket
    import threading

    from drivers.errors import ConnectionLost
    from drivers.visa_transport import VisaTransport

    monkeypatch.setenv("DAQ_LOCK_DIR", str(tmp_path / "locks"))
    server = socket.create_server(("127.0.0.1", 0))
    port = server.getsockname()[1]

    def hang_up() -> None:
        peer, _ = server.accept()
        peer.recv(100)
        peer.close()

    threading.Thread(target=hang_up, daemon=True).start()
    link = VisaTransport(f"TCPIP::127.0.0.1::{port}::SOCKET", timeout_s=1.0)
    link.open()
    try:
        link.write(b"*IDN?")
        with pytest.raises(ConnectionLost, match="connection closed by the other end"):
            link.read_line()
    finally:
        link.close()
        server.close()
