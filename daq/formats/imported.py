"""What a reader returns, and the checks and file handling every reader and writer shares.

Readers refuse anything that is not a plain, non-empty file of bounded size BEFORE
opening it (a FIFO or a device would block or never end), and every error they raise
is a one-line :class:`~daq.formats.errors.FormatError` naming the file.
"""

from __future__ import annotations

import contextlib
import hashlib
import math
import os
import stat
import tempfile
from collections.abc import Iterator
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import IO, Any

import numpy as np

from analysis.hit_checks import file_checks
from daq.formats.errors import FormatError
from daq.store.model import Hits, MeasuredFrf, Spectra

# 512 MiB: far above any real impact test (100 hits x 65536 samples as text is ~20 MiB),
# low enough that reading the whole file into memory cannot exhaust a lab PC.
MAX_IMPORT_BYTES = 512 * 2**20
#: Hits one import may hold: far above an impact test (tens of hits), low enough that the
#: per-hit objects of a run (verdicts, stamps, checks) stay small. A legal 30 MB CSV of
#: 10^6 two-sample hits once took 4.3 GB to import.
MAX_IMPORT_HITS = 10_000
#: What to do about hits whose time axes differ (the CSV and UFF readers): a run's hits
#: share one axis, so that their spectra average line by line.
SAME_AXIS_REMEDY = (
    "the hits of one run must share one time axis (the same start and step): put every hit on one "
    "(e.g. each from the same pre-trigger) or import them separately"
)
#: Frequency lines above 0 Hz that any analysis needs: `daq analyze` refuses a band of
#: fewer (analysis/run_analysis.py, even with --max-order 2, whose LSCF needs 6): an
#: import holding fewer can never be analysed (short_of_lines says so).
MIN_ANALYSIS_LINES = 8
#: Sample rate per analysed band, analysis/spectra.py's ALIAS_FREE_FACTOR (the alias-free
#: lines reach fs/2.56); copied, not imported, because importing analysis.spectra loads
#: scipy.signal, most of a second on every import. tests/formats checks they agree.
ALIAS_FREE_FACTOR = 2.56


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
    """Hits for imported records (n_hits, n_samples), model errors -> FormatError. Each hit
    gets the checks a file allows (analysis/hit_checks.py file_checks: double impact,
    clipped); a failed check does not reject it: the analysis says so in a caution.

    rejected : {hit index: reason} for hits the source file marks as rejected (our own
        exports do, so that export then import keeps every verdict); the others are accepted.
    """
    n_hits = force.shape[0]
    rejected = {
        k: (r.strip() or "rejected in the source file") for k, r in (rejected or {}).items() if k < n_hits
    }
    # A force that is zero in every sample has no FRF: kept, as rejected, unless no hit
    # has a force at all, which is no file of hits (a wrong column, a dead channel).
    silent = [k for k in range(n_hits) if force[k].size and not np.any(force[k])]
    if silent and len(silent) == n_hits:
        raise FormatError(
            f"{show_path(path)}: the force is zero in every sample of every hit: no hammer hit to "
            "store (is the force column the right one?)"
        )
    for k in silent:
        rejected.setdefault(k, "the force is zero in every sample")
    _check_magnitudes(path, force, "force", "N")
    _check_magnitudes(path, response, "response", "m/s^2")
    # A response that is zero throughout has no FRF either (a dead or unplugged sensor):
    # its H1 is zero, and the analysis of it failed as a "Singular matrix".
    still = [k for k in range(n_hits) if k not in silent and response[k].size and not np.any(response[k])]
    if still and len(still) + len(silent) == n_hits:
        raise FormatError(
            f"{show_path(path)}: the response is zero in every sample of every hit with a force: nothing "
            "moved, or the sensor was dead or unplugged (is the response column the right one?)"
        )
    for k in still:
        rejected.setdefault(k, "the response is zero in every sample")
    # A hit that repeats an earlier one sample for sample is a copy (a block pasted twice),
    # not a second hit: averaged, it shrank the ± as if it were new data.
    seen: dict[bytes, int] = {}
    for k in range(n_hits):
        key = hashlib.sha256(
            np.ascontiguousarray(force[k]).tobytes() + np.ascontiguousarray(response[k]).tobytes()
        )
        first = seen.setdefault(key.digest(), k)
        if first != k:
            # Counted from 1 and said so: an exported '# rejected hit K' line counts from 0.
            rejected.setdefault(k, f"the same samples as hit {first + 1} (counted from 1): a copy")
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
            checks=[
                {c.name: c.as_dict() for c in file_checks(force[k], response[k], sample_rate_hz)}
                for k in range(n_hits)
            ],
        )
    except ValueError as exc:
        raise FormatError(f"{show_path(path)}: {one_line(str(exc))}") from None


#: Magnitudes (SI) beyond which a channel is no measurement: their squares overflow the
#: spectra (1e306 N gave ten numpy warnings and "Singular matrix"), and below which they
#: underflow (1e-300 N was called "no force"). A wrong unit or scaling, never data.
MAX_MAGNITUDE = 1e100
MIN_MAGNITUDE = 1e-100


def _check_magnitudes(
    path: Path, values: np.ndarray, what: str, unit: str, frequency_hz: np.ndarray | None = None
) -> None:
    """FormatError when the largest magnitude of ``values`` ((n_hits or n_frf, n) real or
    complex) lies beyond MAX_MAGNITUDE, or below MIN_MAGNITUDE while not zero, naming the
    hit and sample (counted from 1) or, for FRFs on ``frequency_hz`` (n,), the FRF and
    frequency."""
    magnitude = np.abs(values)
    if magnitude.size == 0 or not np.all(np.isfinite(magnitude)):
        return
    k, i = np.unravel_index(int(np.argmax(magnitude)), magnitude.shape)
    peak = float(magnitude[k, i])
    if frequency_hz is None:
        where = f"hit {k + 1}, sample {i + 1}" if magnitude.shape[0] > 1 else f"sample {i + 1}"
    else:
        at = f"at {float(frequency_hz[i]):.6g} Hz"
        where = f"FRF {k + 1} {at}" if magnitude.shape[0] > 1 else at
    if peak > MAX_MAGNITUDE:
        raise FormatError(
            f"{show_path(path)}: the {what} reaches {peak:.3g} {unit} ({where}), beyond any measurement: "
            "is its unit or scaling right?"
        )
    if 0 < peak < MIN_MAGNITUDE:
        raise FormatError(
            f"{show_path(path)}: the {what} is at most {peak:.3g} {unit} ({where}), below any measurement: "
            "is its unit or scaling right?"
        )


def make_frfs(
    path: Path,
    frequency_hz: np.ndarray,
    frf: np.ndarray,
    coherence: np.ndarray | None,
    labels: list[str],
    form: str = "accelerance",
) -> MeasuredFrf:
    """MeasuredFrf from imported arrays; the model's ValueError becomes a FormatError naming the file."""
    _check_magnitudes(path, np.atleast_2d(frf), "FRF", "in its form's SI unit", np.asarray(frequency_hz))
    try:
        return MeasuredFrf(frequency_hz=frequency_hz, frf=frf, coherence=coherence, labels=labels, form=form)
    except ValueError as exc:
        raise FormatError(f"{show_path(path)}: {one_line(str(exc))}") from None


def lines_above_zero(n_samples: int, center_hz: float = 0.0, sample_rate_hz: float = 1.0) -> int:
    """Frequency lines above 0 Hz the analysis gets from records of ``n_samples`` samples:
    the alias-free band of analysis/spectra.py (``linear_spectra``), lines 1..n/2.56 at
    baseband (``center_hz`` 0), centre +- n/2.56 lines in zoom (complex records, centre Hz,
    at ``sample_rate_hz`` Hz); only the lines above 0 Hz count."""
    # The same rounding as linear_spectra: fs/2.56 stays on its line.
    k_max = math.floor(n_samples / ALIAS_FREE_FACTOR * (1 + 1e-12) + 1e-9)
    if center_hz == 0:
        return max(0, min(k_max, n_samples // 2))
    offsets = np.arange(-k_max, min(k_max, (n_samples - 1) // 2) + 1)
    return int(np.count_nonzero(center_hz + offsets * (sample_rate_hz / n_samples) > 0))


def short_of_lines(hits: Hits | None, frfs: list[MeasuredFrf | None]) -> tuple[int, str] | None:
    """(lines, why) when the time records or an FRF set hold fewer than MIN_ANALYSIS_LINES
    frequency lines above 0 Hz, so that no analysis can use them; None when they hold
    enough. ``lines``: the lines above 0 Hz they give (records of n_samples give
    lines_above_zero(n_samples); FRFs, frequency_hz (n_lines,) Hz, their lines above 0 Hz);
    ``why``: one clause saying so, and what would be enough."""
    if hits is not None:
        n = hits.n_samples
        center, rate = float(hits.center_hz), float(hits.sample_rate_hz)
        lines = lines_above_zero(n, center, rate)
        if lines < MIN_ANALYSIS_LINES:
            longer = range(n + 1, 100 * MIN_ANALYSIS_LINES)
            need = next((m for m in longer if lines_above_zero(m, center, rate) >= MIN_ANALYSIS_LINES), None)
            rule = "a zoom record of n samples gives about 2n/2.56" if center else "n samples give n/2.56"
            # n >= 2: the readers refuse a record of fewer samples.
            return lines, (
                f"{n} samples per hit give {_lines(lines)} above 0 Hz ({rule}), "
                f"and an analysis needs {MIN_ANALYSIS_LINES}"
                + (f", so {need} samples per hit at least" if need else "")
            )
    for frf in frfs:
        if frf is not None:
            lines = int(np.count_nonzero(np.asarray(frf.frequency_hz) > 0))
            if lines < MIN_ANALYSIS_LINES:
                return lines, (
                    f"the FRFs hold {_lines(lines)} above 0 Hz, and an analysis needs {MIN_ANALYSIS_LINES} "
                    "at least"
                )
    return None


def _lines(n: int) -> str:
    return f"{n} frequency {'line' if n == 1 else 'lines'}"


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
