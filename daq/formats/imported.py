"""What a reader returns, and the checks and file handling every reader and writer shares.

Readers refuse anything that is not a plain, non-empty file of bounded size BEFORE
opening it (a FIFO or a device would block or never end), and every error they raise
is a one-line :class:`~daq.formats.errors.FormatError` naming the file.
"""

from __future__ import annotations

import contextlib
import os
import stat
import tempfile
from collections.abc import Iterator
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import IO, Any

import numpy as np

from daq.formats.errors import FormatError
from daq.store.model import Hits, MeasuredFrf, Spectra

# 512 MiB: far above any real impact test (100 hits x 65536 samples as text is ~20 MiB),
# low enough that reading the whole file into memory cannot exhaust a lab PC.
MAX_IMPORT_BYTES = 512 * 2**20
#: Hits one import may hold: far above an impact test (tens of hits), low enough that the
#: per-hit objects of a run (verdicts, stamps, checks) stay small. A legal 30 MB CSV of
#: 10^6 two-sample hits once took 4.3 GB to import.
MAX_IMPORT_HITS = 10_000


@dataclass
class ImportedData:
    """Time records, FRFs and/or spectra read from a foreign file, in SI units.

    hits: the time records (all accepted, no overloads, peak_force_n = max |force| per
        hit, timestamp_utc = the file's modification time), or None.
    measured_frfs: FRFs in SI units of their form (receptance m/N, mobility (m/s)/N,
        accelerance (m/s^2)/N) with coherence when the file has it, or None.
    format: "csv", "frf-text", "uff" or "sdf".
    details: JSON-able notes for the run's provenance (columns, units, counts...).
    spectra: spectra that are not FRFs (power, linear, cross, coherence alone), in SI
        units where known, or None.
    """

    hits: Hits | None
    measured_frfs: MeasuredFrf | None
    format: str
    details: dict[str, Any] = field(default_factory=dict)
    spectra: Spectra | None = None


def show_path(path: Path | str) -> str:
    """The file name for a one-line message: repr() when it holds control characters."""
    text = str(path)
    # A newline in a file name would split the CLI's one-line error; repr escapes it.
    if any(not ch.isprintable() for ch in text):
        return repr(text)
    return text


def check_regular_file(path: Path, max_bytes: int = MAX_IMPORT_BYTES) -> os.stat_result:
    """stat() ``path`` and refuse a non-regular, empty or too large file (FormatError).

    Uses only os.stat, never open(), so a FIFO or a tape device is refused without blocking.
    """
    name = show_path(path)
    try:
        info = os.stat(path)
    except FileNotFoundError:
        raise FormatError(f"{name}: no such file") from None
    except OSError as exc:
        raise FormatError(f"{name}: cannot read: {exc.strerror or exc}") from None
    if not stat.S_ISREG(info.st_mode):
        kind = (
            "a directory"
            if stat.S_ISDIR(info.st_mode)
            else "a FIFO"
            if stat.S_ISFIFO(info.st_mode)
            else "a device or socket"
        )
        raise FormatError(f"{name} is {kind}, not a regular file")
    if info.st_size == 0:
        raise FormatError(f"{name} is empty")
    if info.st_size > max_bytes:
        raise FormatError(f"{name} is {info.st_size} bytes, more than the import limit of {max_bytes} bytes")
    return info


@contextlib.contextmanager
def open_checked(path: Path, max_bytes: int = MAX_IMPORT_BYTES) -> Iterator[tuple[IO[bytes], os.stat_result]]:
    """Open a checked regular file for binary reading; yields (file, stat result).

    O_NONBLOCK and a second fstat close the race where ``path`` is swapped for a FIFO
    between the stat and the open: such an open returns at once and is then refused.
    """
    info = check_regular_file(path, max_bytes)
    name = show_path(path)
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    except OSError as exc:
        raise FormatError(f"{name}: cannot open: {exc.strerror or exc}") from None
    try:
        now = os.fstat(fd)
        if not stat.S_ISREG(now.st_mode):
            raise FormatError(f"{name} is not a regular file")
        handle = os.fdopen(fd, "rb")
    except BaseException:
        os.close(fd)
        raise
    with handle:
        yield handle, info


def mtime_utc(info: os.stat_result) -> str:
    """The file's modification time as ISO 8601 UTC with milliseconds, e.g. "...T10:15:03.123Z"."""
    stamp = datetime.fromtimestamp(info.st_mtime, tz=UTC)
    return stamp.strftime("%Y-%m-%dT%H:%M:%S.") + f"{stamp.microsecond // 1000:03d}Z"


def make_hits(
    path: Path,
    force: np.ndarray,
    response: np.ndarray,
    sample_rate_hz: float,
    start_s: float,
    center_hz: float,
    timestamp_utc: str,
    rejected: dict[int, str] | None = None,
) -> Hits:
    """Hits for imported records (n_hits, n_samples), model errors -> FormatError.

    rejected : {hit index: reason} for hits the source file marks as rejected (our own
        exports do, so that export then import keeps every verdict); the others are accepted.
    """
    n_hits = force.shape[0]
    rejected = {
        k: (r.strip() or "rejected in the source file") for k, r in (rejected or {}).items() if k < n_hits
    }
    try:
        return Hits(
            force_n=force,
            response_m_s2=response,
            sample_rate_hz=sample_rate_hz,
            start_s=start_s,
            center_hz=center_hz,
            accepted=np.array([k not in rejected for k in range(n_hits)], dtype=bool),
            reject_reason=[rejected.get(k, "") for k in range(n_hits)],
            overload=np.zeros((n_hits, 2), dtype=bool),
            peak_force_n=np.max(np.abs(force), axis=1) if force.size else np.zeros(n_hits),
            timestamp_utc=[timestamp_utc] * n_hits,
            checks=[{} for _ in range(n_hits)],
        )
    except ValueError as exc:
        raise FormatError(f"{show_path(path)}: {one_line(str(exc))}") from None


def make_frfs(
    path: Path,
    frequency_hz: np.ndarray,
    frf: np.ndarray,
    coherence: np.ndarray | None,
    labels: list[str],
    form: str = "accelerance",
) -> MeasuredFrf:
    """MeasuredFrf from imported arrays; the model's ValueError becomes a FormatError naming the file."""
    try:
        return MeasuredFrf(frequency_hz=frequency_hz, frf=frf, coherence=coherence, labels=labels, form=form)
    except ValueError as exc:
        raise FormatError(f"{show_path(path)}: {one_line(str(exc))}") from None


def one_line(text: str) -> str:
    """``text`` with line breaks and other control characters replaced by spaces."""
    return "".join(ch if ch.isprintable() else " " for ch in text)


def atomic_temp(path: Path) -> Path:
    """A new empty temporary file next to ``path`` (same folder, so os.replace is atomic)."""
    try:
        fd, temp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    except OSError as exc:
        raise FormatError(f"cannot write {show_path(path)}: {exc.strerror or exc}") from None
    os.close(fd)
    # mkstemp makes the file 0600; an exported file is for colleagues and other
    # tools, so it gets the mode a plain open() would give it (0666 less the umask).
    umask = os.umask(0)
    os.umask(umask)
    with contextlib.suppress(OSError):
        os.chmod(temp, 0o666 & ~umask)
    return Path(temp)


def commit_temp(temp: Path, path: Path) -> None:
    """fsync ``temp``, rename it over ``path`` and fsync the folder: all or nothing at ``path``."""
    try:
        with open(temp, "rb+") as handle:
            os.fsync(handle.fileno())
        os.replace(temp, path)
        # The rename itself is only durable once the folder's entry is on disk.
        with contextlib.suppress(OSError):
            dir_fd = os.open(path.parent, os.O_RDONLY)
            try:
                os.fsync(dir_fd)
            finally:
                os.close(dir_fd)
    except OSError as exc:
        raise FormatError(f"cannot write {show_path(path)}: {exc.strerror or exc}") from None


def discard_temp(temp: Path) -> None:
    """Remove a temporary file after a failed write (ignore if already gone)."""
    with contextlib.suppress(OSError):
        temp.unlink()
