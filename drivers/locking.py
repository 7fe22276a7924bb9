"""A lock file per instrument, so that two processes never talk to one at once.

``flock`` on a file named after the resource: the kernel releases it when the
holding process dies, so a crash never leaves an instrument locked.
"""

from __future__ import annotations

import fcntl
import hashlib
import os
import re
import tempfile
from pathlib import Path

from drivers.errors import ResourceBusy


def lock_directory() -> Path:
    """$DAQ_LOCK_DIR, else $XDG_RUNTIME_DIR/daq-locks, else <tmp>/daq-locks-<uid>."""
    if os.environ.get("DAQ_LOCK_DIR"):
        return Path(os.environ["DAQ_LOCK_DIR"])
    runtime = os.environ.get("XDG_RUNTIME_DIR")
    if runtime and Path(runtime).is_dir():
        return Path(runtime) / "daq-locks"
    return Path(tempfile.gettempdir()) / f"daq-locks-{os.getuid()}"


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
        self.path.parent.mkdir(parents=True, exist_ok=True)
        fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.pread(fd, 64, 0).decode(errors="replace").strip() or "unknown"
            os.close(fd)
            shared = f" (it shares {self.key})" if self.key != self.label else ""
            raise ResourceBusy(f"{self.label} is in use by another process (pid {holder}){shared}") from None
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        self._fd = fd

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
