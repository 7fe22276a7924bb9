"""A lock file per instrument, so that two processes never talk to one at once; and
one per store, so that two services never run on one store.

``flock`` on a file named after the resource: the kernel releases it when the
holding process dies, so a crash never leaves an instrument locked.

Every process of one user on one machine must find the same file, whatever its
environment: a shell with XDG_RUNTIME_DIR and a service or cron job without it
once got two directories, so `daq identify` talked to an instrument `daq serve`
held. So instrument locks live in ``/tmp/daq-locks-<uid>`` (``lock_directory``),
never in a directory chosen by XDG_RUNTIME_DIR or TMPDIR; only $DAQ_LOCK_DIR (for
tests, or a site that sets it for every process) overrides it. A directory shared
by every user, such as ``/tmp/daq-locks``, could be created by another user first,
who could then plant a symlink named like a lock file and have our open truncate
the file it points to. So the directory is created 0700, refused unless it is ours
and writable by nobody else, and lock files are opened without following symlinks
and without truncating. The store's lock (daq/store/lock.py) is a ResourceLock whose file lives in the
store itself, so every process using that folder finds it, from any environment and any user.

What these locks cannot see: another user's processes (two users still cannot
drive one GPIB bus at once: the bus itself, its device file, is theirs to share
through group permissions, not through these files), processes on another machine
(the store lock on a network filesystem is only as good as its flock), and a
process whose /tmp is private (systemd PrivateTmp=yes): give such a service and
its users one $DAQ_LOCK_DIR.
"""

from __future__ import annotations

import errno
import fcntl
import hashlib
import os
import re
import stat
from pathlib import Path

from drivers.errors import ConnectionFailed, ResourceBusy

#: Where instrument locks live unless $DAQ_LOCK_DIR says otherwise: the same for every
#: process of this user on this machine, whatever its environment (not tempfile's
#: choice, which follows $TMPDIR; not $XDG_RUNTIME_DIR, which services lack).
LOCK_ROOT = Path("/tmp")


def lock_directory() -> Path:
    """$DAQ_LOCK_DIR, else /tmp/daq-locks-<uid>: a directory of this user's, never one
    shared with other users, and the same whether or not XDG_RUNTIME_DIR or TMPDIR is set."""
    if os.environ.get("DAQ_LOCK_DIR"):
        return Path(os.environ["DAQ_LOCK_DIR"])
    return LOCK_ROOT / f"daq-locks-{os.getuid()}"


def lock_path(resource: str) -> Path:
    readable = re.sub(r"[^A-Za-z0-9]+", "_", resource).strip("_")[:60]
    digest = hashlib.sha1(resource.encode()).hexdigest()[:10]
    return lock_directory() / f"{readable}-{digest}.lock"


def check_lock_directory(directory: Path) -> None:
    """Create ``directory`` (0700) if absent; refuse one that is not a real
    directory of ours, or that others may write to (ConnectionFailed, saying why)."""
    try:
        directory.mkdir(mode=0o700, parents=True, exist_ok=True)
        info = os.lstat(directory)
    except OSError as exc:
        raise ConnectionFailed(
            f"cannot create the lock directory {directory}: {exc.strerror or exc}"
        ) from None
    if not stat.S_ISDIR(info.st_mode):
        raise ConnectionFailed(f"lock directory {directory} is not a directory (a symlink or a file)")
    if info.st_uid != os.getuid():
        raise ConnectionFailed(
            f"lock directory {directory} belongs to uid {info.st_uid}, not to us (uid {os.getuid()}): "
            "refused, another user could plant files in it; set DAQ_LOCK_DIR to a directory of yours"
        )
    if info.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
        raise ConnectionFailed(
            f"lock directory {directory} is writable by others (mode {stat.S_IMODE(info.st_mode):04o}): "
            f"refused; chmod 700 {directory}"
        )


class ResourceLock:
    """Held from ``acquire()`` to ``release()``; ResourceBusy if another process holds it."""

    def __init__(
        self, key: str, label: str | None = None, holder: str = "", path: Path | None = None
    ) -> None:
        """``key`` names the physical link (the file's name); ``label`` is what
        messages call it (default: the key); ``holder`` says who holds it, for the
        message another process gets (e.g. "daq serve at http://127.0.0.1:8000").
        ``path``: the lock file, when it is not the key's in lock_directory() (the
        store's lock, daq/store/lock.py); its folder is then not checked for ownership."""
        self.key = key
        self.label = label or key
        self.holder = " ".join(holder.split())[:200]
        self._own_directory = path is None
        self.path = lock_path(key) if path is None else Path(path)
        self._fd: int | None = None

    def acquire(self) -> None:
        if self._fd is not None:
            return
        if self._own_directory:
            check_lock_directory(self.path.parent)
        try:
            # No O_TRUNC: the holder's pid must survive a refused attempt. O_NOFOLLOW:
            # a symlink in the lock file's place is refused (ELOOP), never followed.
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_CLOEXEC, 0o600)
        except OSError as exc:
            reason = "it is a symlink" if exc.errno == errno.ELOOP else exc.strerror or exc
            raise ConnectionFailed(f"cannot create the lock file {self.path}: {reason}") from None
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode) or info.st_nlink != 1:
            os.close(fd)
            what = (
                "is not a regular file" if not stat.S_ISREG(info.st_mode) else "has other names (hard links)"
            )
            raise ConnectionFailed(f"lock file {self.path} {what}: refused")
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            pid, _, note = os.pread(fd, 512, 0).decode(errors="replace").strip().partition(" ")
            os.close(fd)
            pid = pid or "unknown"
            ours = pid == str(os.getpid())
            where = "this process" if ours else f"{note or 'another process'} (pid {pid})"
            shared = f" (it shares {self.key})" if self.key != self.label else ""
            raise ResourceBusy(f"{self.label} is in use by {where}{shared}") from None
        # Ours now: the pid replaces whatever a dead holder left.
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()} {self.holder}".strip().encode() + b"\n", 0)
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
