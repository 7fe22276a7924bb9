"""Sealing runs and results into a store folder, atomically and without overwriting.

Protocol (docs/run-format.md, "Sealing"):

1. build the whole HDF5 file in memory (h5py's core driver), then write those bytes
   with plain os.write under a hidden temporary name in the store folder,
   ``.<run_id>.h5.tmp-<pid>-<hex>``, which no reader lists. Building in memory
   keeps HDF5 away from a failing disk: HDF5 2.0 answers a write error during
   close with cascading errors and even a crash, os.write with one OSError;
2. fsync it and make it read-only (0o444);
3. publish it with ``os.link(tmp, final)``: link() fails if ``final`` exists, so an
   existing run is never replaced, even by a racing process on another machine
   sharing the folder; then unlink the temporary name;
4. fsync the folder so the new name survives a power cut.

Any failure (full disk, permissions, a name taken) removes the temporary file and
raises one StoreError; a process killed mid-way leaves only a hidden temporary,
which Store.clean_temporaries() removes later.
"""

from __future__ import annotations

import contextlib
import errno
import os
import secrets
from collections.abc import Callable
from pathlib import Path

import h5py

from daq.store import layout
from daq.store.encode import encode_run
from daq.store.errors import StoreError
from daq.store.ids import validate_run_id
from daq.store.model import Run
from daq.store.summary import write_summary

READ_ONLY_MODE = 0o444
# Filesystems without hard links (FAT, some network shares) answer link() with these.
_NO_HARD_LINKS = {errno.EPERM, errno.ENOTSUP, errno.EOPNOTSUPP, errno.ENOSYS, errno.EMLINK}


def run_path(store_dir: Path, run_id: str) -> Path:
    """Where the run ``run_id`` lives in ``store_dir`` (the id is validated)."""
    return Path(store_dir) / f"{validate_run_id(run_id)}{layout.RUN_SUFFIX}"


def seal(run: Run, store_dir: Path | str) -> Path:
    """Write ``run`` to ``<store_dir>/<run_id>.h5`` atomically; return that path.

    Creates ``store_dir`` if needed. Raises StoreError if a run with this id exists
    already or if anything goes wrong; nothing half-written is ever left visible.
    """
    if not isinstance(run, Run):
        raise StoreError(f"seal() needs a Run, got {type(run).__name__}")
    store_dir = Path(store_dir)
    final = run_path(store_dir, run.run_id)

    def fill(f: h5py.File) -> None:
        encode_run(f, run)
        write_summary(f, run)  # last: it records the size of the finished file

    image = build_image(fill, what=f"run {run.run_id}")
    return write_atomically(store_dir, final, image, what=f"run {run.run_id}")


def build_image(fill: Callable[[h5py.File], None], what: str) -> bytes:
    """The bytes of an HDF5 file made by ``fill(f)`` on an empty in-memory file."""
    try:
        # backing_store=False: the name is only a label, nothing touches the disk.
        with h5py.File(f"{what}.h5", "w", driver="core", backing_store=False, libver=layout.LIBVER) as f:
            fill(f)
            f.flush()
            return f.id.get_file_image()
    except StoreError:
        raise
    except Exception as exc:
        raise StoreError(f"cannot build {what}: {_reason(exc)}") from None


def write_atomically(store_dir: Path, final: Path, image: bytes, what: str, overwrite: bool = False) -> Path:
    """Create ``final`` holding ``image`` via a fresh temporary file, then publish it.

    overwrite: False (runs, and results by default) refuses an existing ``final``;
    True replaces it atomically with os.replace (a re-computed result).
    """
    try:
        store_dir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise StoreError(f"cannot create store folder {store_dir}: {_reason(exc)}") from None
    if not overwrite and os.path.lexists(final):
        raise StoreError(f"{what} already exists in {store_dir} ({final.name}); refusing to overwrite it")
    tmp = (
        store_dir / f"{layout.TMP_PREFIX}{final.name}{layout.TMP_MARKER}{os.getpid()}-{secrets.token_hex(4)}"
    )
    try:
        _write_new_file(tmp, image)
        _publish(tmp, final, overwrite)
        _fsync_dir(store_dir)
    except BaseException as exc:
        # BaseException too: Ctrl-C while writing must not leave a temporary behind.
        with contextlib.suppress(OSError):
            tmp.unlink()
        if isinstance(exc, StoreError):
            raise
        if not isinstance(exc, Exception):
            raise
        raise StoreError(f"cannot write {what} to {store_dir}: {_reason(exc)}") from None
    return final


def _publish(tmp: Path, final: Path, overwrite: bool) -> None:
    if overwrite:
        os.replace(tmp, final)
        return
    try:
        os.link(tmp, final)
    except FileExistsError:
        raise StoreError(f"{final.name} already exists in {final.parent}; refusing to overwrite it") from None
    except OSError as exc:
        if exc.errno not in _NO_HARD_LINKS:
            raise
        # No hard links here: check-then-rename. A racing writer of the SAME id could
        # slip in between; ids carry 32 random bits, so that needs a collision first.
        if os.path.lexists(final):
            raise StoreError(
                f"{final.name} already exists in {final.parent}; refusing to overwrite it"
            ) from None
        os.rename(tmp, final)
        return
    tmp.unlink()


def _write_new_file(path: Path, data: bytes) -> None:
    # O_EXCL: a temporary name is never shared, not even with a stale leftover.
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0), 0o600)
    try:
        view = memoryview(data)
        while view:
            view = view[os.write(fd, view) :]  # os.write may write less than asked
        os.fsync(fd)
        os.fchmod(fd, READ_ONLY_MODE)
    finally:
        os.close(fd)


def _fsync_dir(path: Path) -> None:
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
    except OSError:
        return  # some platforms cannot open folders; the rename itself is still atomic
    try:
        os.fsync(fd)
    except OSError:
        pass  # e.g. EINVAL on filesystems that do not sync folders
    finally:
        os.close(fd)


def _reason(exc: BaseException) -> str:
    if isinstance(exc, OSError) and exc.errno is not None:
        return f"{os.strerror(exc.errno)}" + (f" ({exc.filename})" if exc.filename else "")
    text = " ".join(str(exc).split()) or type(exc).__name__
    return text
