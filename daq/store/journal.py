"""The hit journal: every hit of a capture on disk, fsynced, the moment it is taken.

A capture writes ``<store>/.journal-<run_id>-<pid>.daqj`` (a hidden file, never
listed as a run) and holds an exclusive ``flock`` on it for as long as it lives.
The file is append-only:

- 8 bytes of magic, ``DAQJRNL1``;
- records, each ``<length u32 LE><crc32 u32 LE><payload>``, the payload being one
  type byte, a ``u32`` JSON length, the JSON text, and for a hit the force then the
  response record as raw little-endian float64 (complex128 in zoom).

Types: ``M`` the run's metadata (first, before any hit), ``H`` one hit as it arrived,
``D`` the verdict on a hit (accepted, or rejected and why). Every record is written
and fsynced before the capture goes on. A torn last record (a kill or a full disk
mid-write) fails its length or CRC and is ignored: only that record is lost.

Sealing the run removes the journal. A journal whose owner is gone (its flock is
free: the process ended, however it ended) is sealed as an INCOMPLETE run by
:func:`recover`, which every command that lists or writes the store calls. A hit
with no verdict in the journal is kept rejected, "interrupted before a decision".
The lock is the test of a live owner, not the pid, so this works across pid
namespaces (a container sharing the store folder).
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import json
import os
import re
import secrets
import signal
import struct
import threading
import zlib
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from daq.store.errors import StoreError

if TYPE_CHECKING:
    import numpy as np

# numpy is imported by the functions that need it: the store imports this module for
# recover(), which every listing calls, and a store without journals needs no numpy.

MAGIC = b"DAQJRNL1"
PREFIX = ".journal-"
SUFFIX = ".daqj"
JOURNAL_NAME = re.compile(r"\.journal-([0-9]{8}T[0-9]{6}\.[0-9]{3}Z-[0-9a-f]{8})-([0-9]+)\.daqj")
#: The reason kept for a hit the journal holds without a verdict.
UNDECIDED = "interrupted before a decision"
#: Room asked on top of the hits' bytes (metadata, HDF5 overhead, the analyzer's FRF).
OVERHEAD_BYTES = 256 * 1024
_RECORD = struct.Struct("<II")
_JSON_LEN = struct.Struct("<I")
_SIGNALS = {signal.SIGINT, signal.SIGTERM, signal.SIGHUP}

# Journals this process holds: closed in a forked child so that the child never keeps
# a dead parent's journal locked (flock locks follow the open file, not the process).
_OPEN: set[int] = set()


def _close_in_child() -> None:
    for fd in list(_OPEN):
        with contextlib.suppress(OSError):
            os.close(fd)
    _OPEN.clear()


os.register_at_fork(after_in_child=_close_in_child)


def is_journal_name(name: str) -> bool:
    return JOURNAL_NAME.fullmatch(name) is not None


def run_bytes_needed(hits: int, n_samples: int, complex_records: bool) -> int:
    """Bytes a run of ``hits`` hits needs while it is captured: the journal and the
    sealed run exist together until the journal is removed, so twice the raw records
    (2 channels x 8 bytes, 16 in zoom), plus OVERHEAD_BYTES."""
    per_sample = 16 if complex_records else 8
    return 2 * hits * n_samples * 2 * per_sample + OVERHEAD_BYTES


def check_room(store_dir: Path, need_bytes: int) -> None:
    """StoreError unless ``store_dir``'s filesystem has ``need_bytes`` free for this user."""
    try:
        st = os.statvfs(store_dir)
    except OSError:
        return  # no statvfs here: the journal still says where the hits are if it fills
    free = st.f_bavail * st.f_frsize
    if free < need_bytes:
        raise StoreError(
            f"store {store_dir} has {_size(free)} free, the run needs about {_size(need_bytes)}: "
            "free some space or give --store a folder on another disk"
        )


def _size(n: int) -> str:
    for unit in ("bytes", "KiB", "MiB", "GiB"):
        if n < 1024 or unit == "GiB":
            return f"{n} {unit}" if unit == "bytes" else f"{n:.1f} {unit}"
        n /= 1024
    return str(n)


@contextlib.contextmanager
def _signals_held():
    """SIGINT, SIGTERM and SIGHUP wait while a record is written: a handler raising in
    the middle would tear the record. (Only the main thread receives signals.)"""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old = signal.pthread_sigmask(signal.SIG_BLOCK, _SIGNALS)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


def _encode(kind: bytes, meta: dict[str, Any], *arrays: np.ndarray) -> bytes:
    import numpy as np

    text = json.dumps(meta, allow_nan=False, separators=(",", ":")).encode("utf-8")
    raw = [np.ascontiguousarray(a, dtype=a.dtype.newbyteorder("<")).tobytes() for a in arrays]
    body = b"".join([kind, _JSON_LEN.pack(len(text)), text, *raw])
    return _RECORD.pack(len(body), zlib.crc32(body)) + body


class Journal:
    """An open journal, locked by this process. Create with :meth:`create`."""

    def __init__(self, path: Path, fd: int) -> None:
        self.path = path
        self._fd: int | None = fd
        self.n_hits = 0

    @classmethod
    def create(cls, store_dir: Path | str, run_id: str, meta: dict[str, Any], need_bytes: int = 0) -> Journal:
        """A new journal for run ``run_id`` holding ``meta``, locked and fsynced before
        it appears under its name (so nobody sees an unlocked journal). StoreError when
        the store has not ``need_bytes`` free or the file cannot be written."""
        store_dir = Path(store_dir)
        try:
            store_dir.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise StoreError(f"cannot create store folder {store_dir}: {exc.strerror or exc}") from None
        if need_bytes:
            check_room(store_dir, need_bytes)
        final = store_dir / f"{PREFIX}{run_id}-{os.getpid()}{SUFFIX}"
        tmp = store_dir / f"{PREFIX}{run_id}.tmp-{os.getpid()}-{secrets.token_hex(4)}"
        fd = -1
        try:
            fd = os.open(tmp, os.O_RDWR | os.O_CREAT | os.O_EXCL | os.O_APPEND | os.O_CLOEXEC, 0o600)
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            _write_all(fd, MAGIC + _encode(b"M", meta))
            os.fsync(fd)
            os.rename(tmp, final)
            _fsync_dir(store_dir)
        except OSError as exc:
            if fd >= 0:
                os.close(fd)
            with contextlib.suppress(OSError):
                tmp.unlink()
            raise StoreError(f"cannot start the hit journal in {store_dir}: {_reason(exc)}") from None
        _OPEN.add(fd)
        return cls(final, fd)

    def add_hit(self, index: int, info: dict[str, Any], force: np.ndarray, response: np.ndarray) -> None:
        """Append hit ``index`` (its records and ``info``: overload, peak_force_n,
        timestamp_utc, checks, sample_rate_hz, start_s, center_hz) and fsync it."""
        import numpy as np

        force, response = np.asarray(force), np.asarray(response)
        meta = {**info, "index": index, "dtype": force.dtype.str.lstrip("<>="), "n_samples": int(force.size)}
        self._append(_encode(b"H", meta, force, response))
        self.n_hits += 1

    def add_verdict(self, index: int, accepted: bool, reason: str) -> None:
        self._append(_encode(b"D", {"index": index, "accepted": bool(accepted), "reason": reason}))

    def _append(self, record: bytes) -> None:
        if self._fd is None:
            raise StoreError(f"the hit journal {self.path} is closed")
        with _signals_held():
            size = os.fstat(self._fd).st_size
            try:
                _write_all(self._fd, record)
                os.fsync(self._fd)
            except OSError as exc:
                with contextlib.suppress(OSError):
                    os.ftruncate(self._fd, size)  # no torn record left behind
                    os.fsync(self._fd)
                kept = f"{self.n_hits} hit" + ("" if self.n_hits == 1 else "s")
                raise StoreError(
                    f"cannot write the hit journal: {_reason(exc)}; the {kept} taken so far are kept in "
                    f"{self.path}, sealed as an incomplete run by the next daq command on this store "
                    "(e.g. daq runs list) once it can write there"
                ) from None

    def release(self) -> None:
        """Close and unlock, keeping the file (it is recovered by the next command)."""
        if self._fd is not None:
            _OPEN.discard(self._fd)
            with contextlib.suppress(OSError):
                os.close(self._fd)
            self._fd = None

    def remove(self) -> None:
        """The run is sealed (or the hits were discarded on purpose): delete the journal."""
        if self._fd is None:
            return
        with contextlib.suppress(FileNotFoundError):
            self.path.unlink()
        _fsync_dir(self.path.parent)
        self.release()


def _write_all(fd: int, data: bytes) -> None:
    view = memoryview(data)
    while view:
        view = view[os.write(fd, view) :]


def _fsync_dir(path: Path) -> None:
    with contextlib.suppress(OSError):
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


def _reason(exc: OSError) -> str:
    return os.strerror(exc.errno) if exc.errno is not None else str(exc)


# ----------------------------------------------------------------------- reading


@dataclass
class JournalContents:
    meta: dict[str, Any]
    hits: list[dict[str, Any]]  # each: the H record's JSON plus "force", "response", "verdict"
    torn: bool  # the last record was cut short (ignored)


def read_journal(data: bytes) -> JournalContents:
    """Parse a journal's bytes; ValueError if it does not even hold its metadata."""
    import numpy as np

    if not data.startswith(MAGIC):
        raise ValueError("not a hit journal (wrong magic)")
    pos, meta, hits, verdicts, torn = len(MAGIC), None, [], {}, False
    while pos < len(data):
        if pos + _RECORD.size > len(data):
            torn = True
            break
        length, crc = _RECORD.unpack_from(data, pos)
        body = data[pos + _RECORD.size : pos + _RECORD.size + length]
        if len(body) != length or zlib.crc32(body) != crc or length < 5:
            torn = True
            break
        pos += _RECORD.size + length
        kind = body[:1]
        (n,) = _JSON_LEN.unpack_from(body, 1)
        info = json.loads(body[5 : 5 + n].decode("utf-8"))
        raw = body[5 + n :]
        if kind == b"M":
            meta = info
        elif kind == b"H":
            dtype = np.dtype("<" + info["dtype"])
            size = info["n_samples"] * dtype.itemsize
            arrays = np.frombuffer(raw, dtype=dtype)
            if arrays.size != 2 * info["n_samples"] or len(raw) != 2 * size:
                torn = True
                break
            native = arrays.astype(dtype.newbyteorder("="))
            n = info["n_samples"]
            hits.append({**info, "force": native[:n], "response": native[n:]})
        elif kind == b"D":
            verdicts[info["index"]] = (bool(info["accepted"]), str(info["reason"]))
    if meta is None:
        raise ValueError("the journal holds no run metadata")
    for hit in hits:
        hit["verdict"] = verdicts.get(hit["index"])
    return JournalContents(meta, hits, torn)


def journal_run(contents: JournalContents, file_name: str):
    """The incomplete Run a journal holds, or None when it holds no hit."""
    import numpy as np

    from daq.store.model import Hits, Instrument, Run, Sample

    meta = contents.meta
    hits = contents.hits
    if not hits:
        return None
    n = hits[0]["n_samples"]
    hits = [h for h in hits if h["n_samples"] == n and h["dtype"] == hits[0]["dtype"]]
    verdicts = [h["verdict"] or (False, UNDECIDED) for h in hits]
    last = hits[-1]
    records = Hits(
        force_n=np.stack([h["force"] for h in hits]),
        response_m_s2=np.stack([h["response"] for h in hits]),
        sample_rate_hz=last["sample_rate_hz"],
        start_s=last["start_s"],
        center_hz=last.get("center_hz", 0.0),
        accepted=np.array([v[0] for v in verdicts], dtype=bool),
        reject_reason=["" if v[0] else (v[1] or UNDECIDED) for v in verdicts],
        overload=np.array([h["overload"] for h in hits], dtype=bool),
        peak_force_n=np.array([h["peak_force_n"] for h in hits], dtype=float),
        timestamp_utc=[h["timestamp_utc"] for h in hits],
        checks=[h["checks"] for h in hits],
    )
    provenance = {**meta.get("provenance", {}), "recovered_from_journal": file_name}
    return Run(
        run_id=meta["run_id"],
        kind=meta["kind"],
        complete=False,
        start_time=meta["start_time"],
        end_time=last["timestamp_utc"],
        operator=meta.get("operator", ""),
        note=meta.get("note", ""),
        provenance=provenance,
        instrument=Instrument(**meta["instrument"]) if meta.get("instrument") else None,
        sample=Sample(**meta["sample"]) if meta.get("sample") else None,
        points=_points(meta.get("points")),
        hits=records,
    )


def _points(value: Any) -> Any:
    """The journaled run's points (RunPoints.to_dicts), so a recovered capture keeps its
    test: a daq.store.model.RunPoints, or None when the capture had none."""
    from daq.store.model import Point, RunPoints

    if not value:
        return None
    return RunPoints(
        value["article"],
        Point.from_dict(value["force_point"], "force point"),
        tuple(Point.from_dict(p, "response point") for p in value["response_points"]),
        value.get("test", ""),
    )


# ----------------------------------------------------------------------- recovery

# Failures already said by this process, by (name, size): a long-lived service that
# lists the store every second says each once.
_REPORTED: set[tuple[str, int]] = set()


def recover(store_dir: Path | str) -> list[str]:
    """Seal every journal in ``store_dir`` that has no live owner as an incomplete run
    and remove it; one line per journal handled, for stderr. Never raises for a bad
    journal: it is left in place and the line says why."""
    store_dir = Path(store_dir)
    try:
        names = sorted(e.name for e in os.scandir(store_dir) if is_journal_name(e.name))
    except OSError:
        return []
    if not names:
        return []  # the usual case, and a listing's: no need of the writer (h5py) then
    from daq.store.writer import run_path, seal

    lines = []
    for name in names:
        path = store_dir / name
        size = 0
        try:
            fd = os.open(path, os.O_RDONLY | os.O_CLOEXEC)
        except OSError:
            continue  # gone already (sealed, or recovered by another process)
        try:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError as exc:
                if exc.errno in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                    continue  # a live capture owns it
                raise
            try:
                if os.stat(path).st_ino != os.fstat(fd).st_ino:
                    continue  # removed (and maybe re-created) while we waited
            except FileNotFoundError:
                continue
            size = os.fstat(fd).st_size
            with open(fd, "rb", closefd=False) as f:
                data = f.read()
            line = _recover_one(store_dir, path, data, run_path, seal)
        except (OSError, ValueError, KeyError, TypeError) as exc:
            line = f"hit journal {path} could not be recovered: {exc}; it is kept"
            if (name, size) in _REPORTED:
                continue
            _REPORTED.add((name, size))
        finally:
            os.close(fd)
        if line:
            lines.append(line)
    return lines


def _recover_one(store_dir: Path, path: Path, data: bytes, run_path, seal) -> str:
    import numpy as np

    contents = read_journal(data)
    run_id = contents.meta["run_id"]
    if run_path(store_dir, run_id).exists():
        # Killed between sealing and removing the journal: the run is whole already.
        _unlink(path)
        return ""
    try:
        run = journal_run(contents, path.name)
    except (ValueError, KeyError, TypeError) as exc:
        raise ValueError(f"its hits do not make a run ({exc})") from None
    if run is None:
        _unlink(path)
        return f"removed hit journal {path.name} of an interrupted capture: no hits were taken"
    try:
        sealed = seal(run, store_dir)
    except StoreError as exc:
        raise ValueError(str(exc)) from None
    _unlink(path)
    accepted = int(np.count_nonzero(run.hits.accepted))
    torn = " (a last record cut short was dropped)" if contents.torn else ""
    return (
        f"recovered an interrupted capture from its hit journal: {run.hits.n_hits} hits "
        f"({accepted} accepted) sealed as incomplete run {run_id} in {sealed}{torn}"
    )


def _unlink(path: Path) -> None:
    with contextlib.suppress(FileNotFoundError):
        path.unlink()
    _fsync_dir(path.parent)
