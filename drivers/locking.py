"""A lock file per instrument, so that two processes never talk to one at once.

``flock`` on a file named after the resource: the kernel releases it when the
holding process dies, so a crash never leaves an instrument locked.
"""

from __future__ import annotations

import contextlib
import fcntl
import hashlib
import os
import re
import tempfile
from pathlib import Path

from drivers.errors import ConnectionFailed, ResourceBusy


def lock_directory() -> Path:
    """$DAQ_LOCK_DIR, else <tmp>/daq-locks: one directory for every user of the
    machine, so that two technicians cannot drive one instrument at once."""
    if os.environ.get("DAQ_LOCK_DIR"):
        return Path(os.environ["DAQ_LOCK_DIR"])
    return Path(tempfile.gettempdir()) / "daq-locks"


def lock_path(resource: str) -> Path:
    readable = re.sub(r"[^A-Za-z0-9]+", "_", resource).strip("_")[:60]
    digest = hashlib.sha1(resource.encode()).hexdigest()[:10]
    return lock_directory() / f"{readable}-{digest}.lock"


class ResourceLock:
    """Held from ``acquire()`` to ``release()``; ResourceBusy if another process holds it."""

    def __init__(self, key: str, label: str | None = None) -> None:
        """``key`` names the physical link (the file's name); ``label`` is what
        messages call it (default: the key)."""
        self.key = key
        self.label = label or key
        self.path = lock_path(key)
        self._fd: int | None = None

    def acquire(self) -> None:
        if self._fd is not None:
            return
        try:
            fd = self._open_file()
        except OSError as exc:
            raise ConnectionFailed(
                f"cannot create the lock file {self.path}: {exc.strerror or exc}"
            ) from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.pread(fd, 64, 0).decode(errors="replace").strip() or "unknown"
            os.close(fd)
            where = "this process" if holder == str(os.getpid()) else f"another process (pid {holder})"
            shared = f" (it shares {self.key})" if self.key != self.label else ""
            raise ResourceBusy(f"{self.label} is in use by {where}{shared}") from None
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        self._fd = fd

    def _open_file(self) -> int:
        directory = self.path.parent
        if not directory.is_dir():
            directory.mkdir(parents=True, exist_ok=True)
            # Sticky and writable by all, like /tmp: every user's locks live here.
            with contextlib.suppress(OSError):
                os.chmod(directory, 0o1777)
        fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o666)
        with contextlib.suppress(OSError):  # another user's file: keep its mode
            os.fchmod(fd, 0o666)
        return fd

    def release(self) -> None:
        if self._fd is None:
            return
        # The file stays: unlinking it would race with a process about to lock it.
        fcntl.flock(self._fd, fcntl.LOCK_UN)
        os.close(self._fd)
        self._fd = None

    @property
    def held(self) -> bool:
        return self._fd is not None
