"""Issue 7's driver defects, pinned: lock files in a directory of the user's own,
never following a planted symlink; no DNS look-up unless a lock is wanted; the
one use of pyvisa-py's internals failing loudly; the package's NullHandler."""

from __future__ import annotations

import os
import socket
import stat
import subprocess
import sys
from pathlib import Path

import pytest

from drivers.errors import ConnectionFailed, ResourceBusy
from drivers.locking import ResourceLock, lock_directory
from drivers.visa_transport import VisaTransport, pyvisa_py_socket
from sims.instrument import Analyzer
from sims.sources import PhysicsSource
from sims.tcp_server import TcpServer

pytestmark = pytest.mark.timeout(30)
ROOT = Path(__file__).resolve().parents[2]
#: A uid that is not ours (the tests may run as root: chown then works).
STRANGER_UID = 54321


@pytest.fixture
def lock_dir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    path = tmp_path / "locks"
    monkeypatch.setenv("DAQ_LOCK_DIR", str(path))
    return path


# ------------------------------------------------------------------ lock directory
def test_the_default_directory_is_the_users_own(tmp_path: Path, monkeypatch: pytest.MonkeyPatch):
    # One directory per user whatever the environment says: with or without
    # XDG_RUNTIME_DIR or TMPDIR, every process of the user finds the same locks.
    monkeypatch.delenv("DAQ_LOCK_DIR", raising=False)
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path / "run"))
    with_xdg = lock_directory()
    monkeypatch.delenv("XDG_RUNTIME_DIR")
    monkeypatch.setattr("tempfile.tempdir", str(tmp_path))
    assert lock_directory() == with_xdg == Path(f"/tmp/daq-locks-{os.getuid()}")


def test_a_new_lock_directory_is_private(lock_dir: Path):
    lock = ResourceLock("GPIB0::11")
    lock.acquire()
    lock.release()
    assert stat.S_IMODE(lock_dir.stat().st_mode) == 0o700


def test_a_directory_writable_by_others_is_refused(lock_dir: Path):
    lock_dir.mkdir()
    lock_dir.chmod(0o777)
    with pytest.raises(ConnectionFailed, match=r"writable by others \(mode 0777\): refused"):
        ResourceLock("GPIB0::11").acquire()
    assert list(lock_dir.iterdir()) == []


def test_a_directory_of_another_user_is_refused(lock_dir: Path):
    if os.getuid() != 0:
        pytest.skip("giving a directory to another uid takes root")
    lock_dir.mkdir(mode=0o700)
    os.chown(lock_dir, STRANGER_UID, -1)
    with pytest.raises(ConnectionFailed, match=f"belongs to uid {STRANGER_UID}, not to us"):
        ResourceLock("GPIB0::11").acquire()
    assert list(lock_dir.iterdir()) == []


def test_a_symlink_in_place_of_the_directory_is_refused(tmp_path: Path, lock_dir: Path):
    real = tmp_path / "elsewhere"
    real.mkdir(mode=0o700)
    lock_dir.symlink_to(real)
    with pytest.raises(ConnectionFailed, match="not a directory"):
        ResourceLock("GPIB0::11").acquire()


# ------------------------------------------------------------------ lock files
def test_a_symlink_planted_as_the_lock_file_is_not_followed(tmp_path: Path, lock_dir: Path):
    victim = tmp_path / "thesis.tex"
    victim.write_text("three years of work\n")
    lock = ResourceLock("GPIB0::11")
    lock_dir.mkdir(mode=0o700)
    lock.path.symlink_to(victim)
    with pytest.raises(ConnectionFailed, match="is a symlink"):
        lock.acquire()
    assert not lock.held
    assert victim.read_text() == "three years of work\n"


def test_a_refused_attempt_leaves_the_holders_pid_in_the_file(lock_dir: Path):
    holder = ResourceLock("GPIB0::11")
    holder.acquire()
    try:
        with pytest.raises(ResourceBusy, match="in use by this process"):
            ResourceLock("GPIB0::11").acquire()
        assert holder.path.read_text() == f"{os.getpid()}\n"
    finally:
        holder.release()


# ------------------------------------------------------------------ DNS
def test_a_visa_transport_without_a_lock_resolves_no_host_name(monkeypatch: pytest.MonkeyPatch, lock_dir):
    asked: list[str] = []

    def resolve(host: str) -> str:
        asked.append(host)
        return "192.0.2.7"

    monkeypatch.setattr(socket, "gethostbyname", resolve)
    VisaTransport("TCPIP::analyzer.lab.example::5025::SOCKET", lock_file=False)
    assert asked == []
    locked = VisaTransport("TCPIP::analyzer.lab.example::5025::SOCKET", lock_file=True)
    assert asked == ["analyzer.lab.example"]
    assert locked.lock_key == "TCPIP::192.0.2.7::5025::SOCKET"


# ------------------------------------------------------------------ pyvisa-py internals
def test_the_socket_under_a_pyvisa_py_session_is_reached(lock_dir: Path):
    """The one read of pyvisa-py's session table: if a release changes it, this
    fails (the driver raises rather than skip its check of a refused connection)."""
    analyzer = Analyzer(PhysicsSource("seed", seed=0))
    with TcpServer(analyzer) as server, VisaTransport(server.resource, timeout_s=1.0) as transport:
        sock = pyvisa_py_socket(transport._inst)
        assert isinstance(sock, socket.socket)
        assert sock.getpeername() == ("127.0.0.1", server.port)


def test_something_else_than_a_pyvisa_py_session_fails_loudly():
    with pytest.raises(RuntimeError, match="session table changed"):
        pyvisa_py_socket(object())


# ------------------------------------------------------------------ logging
def test_driver_warnings_stay_off_stderr_without_a_logging_setup():
    """Python prints records no handler takes on stderr (its last resort); the
    package's NullHandler takes them, so a notebook sees no retry chatter."""
    code = "import logging, drivers.analyzer; logging.getLogger('drivers.analyzer').warning('retrying')"
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    assert done.stderr == ""
