"""Time records as delimited text: import from CSV / whitespace tables, export a run's hits.

File layout (what :func:`write_csv` writes and :func:`read_csv` reads back exactly)::

    # run_id: 20261123T101503.123Z-3f9c1a2b
    # sample_rate_hz = 256.0
    # start_s = -0.125
    # center_hz = 0.0
    # units: time s, force N, response m/s^2
    hit,time,force,response
    0,-0.125,0.0,0.0
    ...

Numbers are written with repr(float), the shortest text that parses back to the same
float64, so an export/import round trip is bit for bit. Zoom (complex) records use the
columns force_re, force_im, response_re, response_im and need the ``center_hz`` comment.
"""

from __future__ import annotations

import math
import os
import re
from array import array
from pathlib import Path

import numpy as np

from daq.errors import UserError
from daq.formats.imported import (
    MAX_IMPORT_BYTES,
    ImportedData,
    atomic_temp,
    commit_temp,
    discard_temp,
    make_hits,
    mtime_utc,
    one_line,
    open_checked,
    show_path,
)
from daq.formats.units import parse_unit
from daq.store.model import Run

STEP_TOLERANCE = 1e-6  # relative to the mean step: uneven sampling within one hit
AXIS_TOLERANCE = 1e-9  # relative to the step: hits must share one time axis
COMPLEX_COLUMNS = ("force_re", "force_im", "response_re", "response_im")
_REJECTED = re.compile(r"rejected hit ([0-9]{1,6}):(.*)")


def read_csv(
    path: Path,
    columns: str | None = None,
    force_unit: str = "N",
    response_unit: str = "m/s^2",
    max_bytes: int = MAX_IMPORT_BYTES,
) -> ImportedData:
    """Read hits from a delimited text file; force in N and response in m/s^2 after conversion.

    columns: None (the first three columns other than ``hit``: time s, force, response) or
        three header names / 0-based indices, comma-separated, e.g. "t,F,a" or "0,2,1".
    force_unit, response_unit: units of those columns (see :mod:`daq.formats.units`).
    Returns ImportedData with hits of shape (n_hits, n_samples). Any problem: UserError.
    """
    path = Path(path)
    name = show_path(path)
    try:
        factors = (parse_unit(force_unit, "force"), parse_unit(response_unit, "response"))
    except UserError as exc:
        raise UserError(f"{name}: {exc}") from None
    with open_checked(path, max_bytes) as (handle, info):
        table = _Table(name)
        table.read(handle, max_bytes)
    return table.build(path, columns, factors, force_unit, response_unit, mtime_utc(info))


class _Table:
    """The numbers of a delimited file, kept flat (array of float64) with each row's line number."""

    def __init__(self, name: str) -> None:
        self.name = name
        self.comments: dict[str, str] = {}
        self.rejected: dict[int, str] = {}
        self.header: list[str] | None = None
        self.delimiter: str | None = None  # None: runs of whitespace
        self.n_cols = 0
        self.values = array("d")
        self.lines = array("q")

    def read(self, handle, max_bytes: int) -> None:
        total = 0
        for number, raw in enumerate(handle, start=1):
            total += len(raw)
            if total > max_bytes:  # the file grew after it was checked
                raise UserError(f"{self.name} is more than the import limit of {max_bytes} bytes")
            try:
                line = raw.decode("utf-8-sig" if number == 1 else "utf-8")
            except UnicodeDecodeError:
                raise UserError(f"{self.name} line {number}: not UTF-8 text") from None
            line = line.rstrip("\r\n")
            stripped = line.strip()
            if not stripped:
                continue
            if stripped.startswith("#"):
                self._comment(stripped[1:])
                continue
            self._row(line, number)
        if not self.lines:
            raise UserError(f"{self.name} holds no data rows")

    def _comment(self, text: str) -> None:
        # "# rejected hit <k>: <reason>" (write_csv), "# key = value" or "# key: value";
        # anything else is prose and ignored.
        verdict = _REJECTED.fullmatch(text.strip())
        if verdict:
            self.rejected[int(verdict.group(1))] = verdict.group(2)
            return
        for sep in ("=", ":"):
            key, found, value = text.partition(sep)
            if found and key.strip() and " " not in key.strip():
                self.comments.setdefault(key.strip().lower(), value.strip())
                return

    def _split(self, line: str) -> list[str]:
        if self.delimiter is None:
            return line.split()
        return [cell.strip() for cell in line.split(self.delimiter)]

    def _row(self, line: str, number: int) -> None:
        if self.n_cols == 0:
            # First data-ish row decides the delimiter: ";" before "," so that a
            # semicolon file with decimal commas fails on a cell, not silently.
            self.delimiter = next((d for d in (";", "\t", ",") if d in line), None)
            cells = self._split(line)
            self.n_cols = len(cells)
            if not all(_is_number(cell) for cell in cells):
                self.header = [cell.strip().strip('"').strip("'") for cell in cells]
                return
        cells = self._split(line)
        if len(cells) != self.n_cols:
            raise UserError(f"{self.name} line {number}: {len(cells)} columns, expected {self.n_cols}")
        for col, cell in enumerate(cells):
            try:
                value = float(cell)
            except ValueError:
                raise UserError(
                    f"{self.name} line {number} column {col + 1}: {_show(cell)} is not a number"
                ) from None
            if not math.isfinite(value):
                raise UserError(f"{self.name} line {number} column {col + 1}: {_show(cell)} is not finite")
            self.values.append(value)
        self.lines.append(number)

    def _pick(self, columns: str | None, complex_mode: bool) -> tuple[list[int], int | None]:
        """Indices of (time, force, response) or (time, force_re, force_im, ...), and of hit."""
        header = self.header or []
        hit = _find(header, "hit")
        if columns is None:
            if complex_mode:
                wanted = [_find(header, n) for n in COMPLEX_COLUMNS]
                rest = [i for i in range(self.n_cols) if i not in wanted and i != hit]
                time = _find(header, "time")
                if time is None and not rest:
                    raise UserError(f"{self.name} has complex columns but no time column")
                return [time if time is not None else rest[0], *wanted], hit  # type: ignore[list-item]
            rest = [i for i in range(self.n_cols) if i != hit]
            if len(rest) < 3:
                raise UserError(f"{self.name} has {len(rest)} data column(s); need time, force and response")
            named = [_find(header, n) for n in ("time", "force", "response")]
            return (named if None not in named else rest[:3]), hit  # type: ignore[return-value]
        items = [item.strip() for item in columns.split(",")]
        if len(items) != 3 or not all(items):
            raise UserError(
                f"{self.name}: columns {_show(columns)} must name three columns "
                "(time, force, response), e.g. t,F,a or 0,2,1"
            )
        picked = []
        for item in items:
            if item.isdigit():
                # Only ASCII digits count, and at most 6 of them (int() of a 5000-digit
                # string raises, and no file has a million columns).
                index = int(item) if item.isascii() and len(item) <= 6 else 10**6
                if index >= self.n_cols:
                    raise UserError(
                        f"{self.name}: column index {index if index < 10**6 else _show(item)} "
                        f"is out of range (the file has "
                        f"{self.n_cols} columns, 0..{self.n_cols - 1})"
                    )
            else:
                if self.header is None:
                    raise UserError(f"{self.name} has no header row, so column {_show(item)} cannot be found")
                index = _find(header, item)
                if index is None:
                    raise UserError(
                        f"{self.name}: no column {_show(item)} in the header ({', '.join(header)})"
                    )
            picked.append(index)
        if len(set(picked)) != 3:
            raise UserError(f"{self.name}: columns {_show(columns)} must be three different columns")
        if hit in picked:
            hit = None  # the user chose to read it as data
        return picked, hit

    def build(self, path, columns, factors, force_unit, response_unit, stamp) -> ImportedData:
        header = self.header or []
        complex_mode = columns is None and all(_find(header, n) is not None for n in COMPLEX_COLUMNS)
        picked, hit_col = self._pick(columns, complex_mode)
        data = np.frombuffer(self.values, dtype=np.float64).reshape(-1, self.n_cols)
        lines = np.frombuffer(self.lines, dtype=np.int64)
        groups = self._groups(data, lines, picked[0], hit_col)
        starts, steps = self._check_axes(data[:, picked[0]], lines, groups)
        n = groups[0].size
        sample_rate_hz, start_s, notes = 1.0 / steps[0], starts[0], {}
        # The exporter writes the exact rate and start; trust them only if the time column agrees.
        exact = _comment_float(self.comments, "sample_rate_hz")
        if exact is not None and exact > 0 and abs(1.0 / exact - steps[0]) <= STEP_TOLERANCE * steps[0]:
            sample_rate_hz = exact
        elif exact is not None:
            notes["ignored_sample_rate_hz"] = self.comments["sample_rate_hz"]
        exact = _comment_float(self.comments, "start_s")
        if exact is not None and abs(exact - starts[0]) <= STEP_TOLERANCE * steps[0]:
            start_s = exact
        elif exact is not None:
            notes["ignored_start_s"] = self.comments["start_s"]
        center = _comment_float(self.comments, "center_hz")
        if "center_hz" in self.comments and center is None:
            raise UserError(f"{self.name}: center_hz {_show(self.comments['center_hz'])} is not a number")
        order = np.concatenate(groups)
        if complex_mode:
            if center is None:
                raise UserError(f"{self.name} has complex (zoom) columns but no '# center_hz = ...' comment")
            cols = data[order][:, picked[1:]].reshape(len(groups), n, 4)
            force = _complex(cols[..., 0], cols[..., 1], factors[0])
            response = _complex(cols[..., 2], cols[..., 3], factors[1])
        else:
            if center not in (None, 0.0):
                raise UserError(
                    f"{self.name}: center_hz = {center} but the records are real; zoom records "
                    f"need columns {', '.join(COMPLEX_COLUMNS)}"
                )
            center = 0.0
            # Multiplying by exactly 1.0 keeps every bit; other units scale once here.
            force = data[order, picked[1]].reshape(len(groups), n) * factors[0]
            response = data[order, picked[2]].reshape(len(groups), n) * factors[1]
        hits = make_hits(path, force, response, sample_rate_hz, start_s, center, stamp, self.rejected)
        names = [header[i] if header else str(i) for i in picked]
        details = {
            "columns": names,
            "hit_column": header[hit_col] if hit_col is not None else None,
            "delimiter": self.delimiter or "whitespace",
            "header": self.header is not None,
            "force_unit": force_unit,
            "response_unit": response_unit,
            "n_records": len(groups),
            "n_samples": int(n),
            "zoom": bool(complex_mode),
            **notes,
        }
        return ImportedData(hits=hits, measured_frfs=None, format="csv", details=details)

    def _groups(self, data, lines, time_col, hit_col) -> list[np.ndarray]:
        """Row indices of each hit, in order of first appearance."""
        if hit_col is not None:
            ids = data[:, hit_col]
            bad = np.flatnonzero(ids != np.round(ids))
            if bad.size:
                raise UserError(
                    f"{self.name} line {lines[bad[0]]}: hit {float(ids[bad[0]])!r} is not a whole number"
                )
            _, first, inverse = np.unique(ids, return_index=True, return_inverse=True)
            rank = np.argsort(np.argsort(first))  # unique value -> order of first appearance
            keys = rank[inverse.ravel()]
            order = np.argsort(keys, kind="stable")
            bounds = np.flatnonzero(np.diff(keys[order])) + 1
            return np.split(order, bounds)
        drops = np.flatnonzero(np.diff(data[:, time_col]) < 0) + 1
        return np.split(np.arange(data.shape[0]), drops)

    def _check_axes(self, time, lines, groups):
        starts, steps = [], []
        for k, rows in enumerate(groups):
            t = time[rows]
            if t.size < 2:
                raise UserError(f"{self.name}: hit {k} (line {lines[rows[0]]}) has fewer than 2 samples")
            d = np.diff(t)
            bad = np.flatnonzero(d <= 0)
            if bad.size:
                raise UserError(f"{self.name} line {lines[rows[bad[0] + 1]]}: time does not increase")
            step = (t[-1] - t[0]) / (t.size - 1)
            bad = np.flatnonzero(np.abs(d - step) > STEP_TOLERANCE * step)
            if bad.size:
                # Point at the odd step: the first one far from the typical (median) step.
                odd = np.flatnonzero(np.abs(d - np.median(d)) > STEP_TOLERANCE * step)
                bad = odd if odd.size else bad
            if bad.size or not (math.isfinite(step) and step > 0):
                at = lines[rows[bad[0] + 1]] if bad.size else lines[rows[-1]]
                raise UserError(
                    f"{self.name} line {at}: uneven time step (more than {STEP_TOLERANCE:g} of the "
                    f"mean step {step:g} s from it)"
                )
            if k and t.size != groups[0].size:
                raise UserError(f"{self.name}: hit {k} has {t.size} samples, hit 0 has {groups[0].size}")
            if k and (
                abs(t[0] - starts[0]) > AXIS_TOLERANCE * steps[0]
                or abs(step - steps[0]) > AXIS_TOLERANCE * steps[0]
            ):
                raise UserError(
                    f"{self.name}: hit {k} (line {lines[rows[0]]}) has a different time axis from hit 0 "
                    f"(start {float(t[0])!r} s, step {float(step)!r} s vs "
                    f"{starts[0]!r} s, {float(steps[0])!r} s)"
                )
            starts.append(float(t[0]))
            steps.append(float(step))
        return starts, steps


def write_csv(run: Run, path: Path) -> None:
    """Write every hit (accepted and rejected) of ``run`` as text, atomically.

    Columns: hit (0-based), time (s), force (N), response (m/s^2); zoom runs have
    force_re, force_im, response_re, response_im instead. UserError if the run has no hits.
    """
    path = Path(path)
    hits = run.hits
    if hits is None:
        raise UserError(f"run {run.run_id} has no time records; export FRFs as UFF")
    if not (np.all(np.isfinite(hits.force_n)) and np.all(np.isfinite(hits.response_m_s2))):
        raise UserError(f"run {run.run_id} has non-finite samples; they cannot be exported as CSV")
    rejected = [i for i in range(hits.n_hits) if not hits.accepted[i]]
    head = [
        "# cantilever-daq time records",
        f"# run_id: {run.run_id}",
        f"# kind: {run.kind}",
        f"# sample_rate_hz = {float(hits.sample_rate_hz)!r}",
        f"# start_s = {float(hits.start_s)!r}",
        f"# center_hz = {float(hits.center_hz)!r}",
        "# units: time s, force N, response m/s^2",
    ]
    # One line per rejected hit with its reason: read back by read_csv, so that
    # export then import keeps every verdict.
    head += [f"# rejected hit {i}: {one_line(str(hits.reject_reason[i]))}" for i in rejected]
    head.append(
        "hit,time," + ("force_re,force_im,response_re,response_im" if hits.is_zoom else "force,response")
    )
    time = [repr(float(t)) for t in hits.time_s()]
    temp = atomic_temp(path)
    try:
        with open(temp, "w", encoding="utf-8", newline="\n") as out:
            out.write("\n".join(head) + "\n")
            for k in range(hits.n_hits):
                if hits.is_zoom:
                    parts = (hits.force_n[k].real, hits.force_n[k].imag)
                    parts += (hits.response_m_s2[k].real, hits.response_m_s2[k].imag)
                else:
                    parts = (hits.force_n[k], hits.response_m_s2[k])
                cells = [[repr(v) for v in p.tolist()] for p in parts]
                rows = (",".join((str(k), t, *row)) for t, *row in zip(time, *cells, strict=True))
                out.write("\n".join(rows) + "\n")
            out.flush()
            os.fsync(out.fileno())
        commit_temp(temp, path)
    except OSError as exc:
        discard_temp(temp)
        raise UserError(f"cannot write {show_path(path)}: {exc.strerror or exc}") from None
    except BaseException:
        discard_temp(temp)
        raise


def _complex(real: np.ndarray, imag: np.ndarray, factor: float) -> np.ndarray:
    # Fill the parts directly: re + 1j * im would turn some -0.0 into +0.0 (1j * x has a
    # real part 0 * x), which breaks the bit-exact round trip.
    out = np.empty(real.shape, dtype=np.complex128)
    out.real = real * factor
    out.imag = imag * factor
    return out


def _find(header: list[str], name: str) -> int | None:
    """Index of ``name`` in the header: exact match, else a unique case-insensitive one."""
    if name in header:
        return header.index(name)
    folded = [i for i, h in enumerate(header) if h.lower() == name.lower()]
    return folded[0] if len(folded) == 1 else None


def _is_number(cell: str) -> bool:
    try:
        float(cell)
    except ValueError:
        return False
    return True


def _comment_float(comments: dict[str, str], key: str) -> float | None:
    if key not in comments:
        return None
    try:
        value = float(comments[key])
    except ValueError:
        return None
    return value if math.isfinite(value) else None


def _show(text: str) -> str:
    return repr(one_line(text) if len(text) <= 40 else one_line(text[:40]) + "...")
