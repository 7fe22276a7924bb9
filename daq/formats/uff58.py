"""UFF dataset 58 (function at nodal DOF) through pyuff: time records and FRFs, in and out.

Export is binary 58 ("58b"): pyuff writes ASCII 58 abscissa and data with %13.5e /
%20.11e, which loses float64 precision, while 58b stores every value as an IEEE double,
so values come back exactly (only the sign of a complex part that is zero may flip:
pyuff's reader forms complex values as re + 1j * im).
The header's abscissa minimum and increment are still %13.5e text, so the exact
sample rate, pre-trigger start and zoom centre go into the ID lines as well
(``sample_rate_hz=... start_s=...``, ``center_hz=...``); the reader uses them when they
agree with the header. FRF frequency axes are written with even spacing when pyuff's
%13.5e minimum and increment rebuild them exactly, else as uneven (x stored as doubles).

Records written (all func types as pyuff names them):
- func_type 1 (time response): per hit, force (node 1 +Z, ordinate type 13, N), then
  response (node 2 +Z, type 12, m/s^2); abscissa time, s.
- func_type 4 (FRF): analyzer then measured FRFs in their form (ordinate type 8 m, 11 m/s or
  12 m/s^2 over 13 N: receptance, mobility, accelerance), reference node 1 +Z, response node 2 +Z.
- func_type 6 (coherence): after all FRFs, in the same order, for FRF sets that have it.
"""

from __future__ import annotations

import gc
import math
import re
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pyuff

from daq.formats.axis import fit_regular, printed_half_units, whole_rate
from daq.formats.errors import FormatError
from daq.formats.imported import (
    MAX_IMPORT_BYTES,
    SAME_AXIS_REMEDY,
    ImportedData,
    check_regular_file,
    make_frfs,
    make_hits,
    mtime_utc,
    one_line,
    show_path,
)
from daq.formats.units import frf_unit, parse_unit, response_form

FUNC_TIME, FUNC_FRF, FUNC_COHERENCE = 1, 4, 6
FORCE_TYPES = (13, 9)  # excitation force, reaction force
RESPONSE_TYPES = (12,)  # acceleration
HEADER_TOLERANCE = 1e-5  # %13.5e keeps 6 significant digits: relative error <= 5e-6
AXIS_TOLERANCE = 1e-9  # relative to the step: all records of the hits share one time axis
# Ordinate specific data type of an FRF -> its form (what over force).
FRF_FORM_OF_TYPE = {8: "receptance", 11: "mobility", 12: "accelerance"}
FRF_TYPE_OF_FORM = {form: kind for kind, form in FRF_FORM_OF_TYPE.items()}
UNKNOWN_TYPES = (0, 1)  # "unknown", "general": the unit labels must say what the data are
FORCE_DENOMINATOR_TYPES = (0, 1, 9, 13)  # unknown, general, reaction force, excitation force
_KEY_VALUE = re.compile(r"([a-z_]+)=(\S+)")
_NO_UNIT = ("", "NONE")


@dataclass
class _Record:
    """One dataset 58 as read: data (n,) float64 or complex128, x (n,) abscissa."""

    index: int  # its number among the file's datasets 58, counted from 1 as people count
    func: int
    kind: int  # ordinate specific data type
    denominator_kind: int  # ordinate denominator specific data type
    data: np.ndarray
    x: np.ndarray
    even: bool
    x_min: float
    x_inc: float
    ids: list[str]
    keys: dict[str, str]
    unit: str
    denominator_unit: str
    nodes: tuple[Any, Any, Any, Any]


#: Names of UFF 58 function types and ordinate specific data types, to say what a file holds.
FUNC_NAMES = {1: "time record", 2: "auto spectrum", 3: "cross spectrum", 4: "FRF", 6: "coherence",
              9: "PSD", 12: "spectrum"}  # fmt: skip
KIND_NAMES = {0: "an unknown quantity", 1: "a general quantity", 2: "stress", 3: "strain",
              5: "temperature", 8: "displacement", 9: "force", 11: "velocity", 12: "acceleration",
              13: "force", 15: "pressure"}  # fmt: skip


def _contents(records: list[_Record]) -> str:
    """What the datasets 58 hold, counted: '2 × time record of pressure (Pa), 1 × PSD of acceleration'."""
    counts: dict[str, int] = {}
    for rec in records:
        what = FUNC_NAMES.get(rec.func, f"function type {rec.func}")
        of = KIND_NAMES.get(rec.kind, f"data type {rec.kind}")
        unit = rec.unit.strip()
        key = f"{what} of {of}" + (f" ({unit})" if unit and unit.upper() not in _NO_UNIT else "")
        counts[key] = counts.get(key, 0) + 1
    if not counts:
        return "no dataset 58"
    return ", ".join(f"{n} × {key}" for key, n in counts.items())


def read_uff(path: Path, max_bytes: int = MAX_IMPORT_BYTES) -> ImportedData:
    """Read dataset 58 records: time records as hits (N, m/s^2) and FRFs (SI units of their form).

    Any problem, including whatever pyuff raises on a damaged file: one-line FormatError.
    """
    path = Path(path)
    name = show_path(path)
    info = check_regular_file(path, max_bytes)
    _check_starts_as_uff(path, name)
    _check_ends_whole(path, name)
    records = [_record(d, k, name) for k, d in enumerate(read_uff_sets(path, name))]
    details: dict[str, Any] = {"n_datasets_58": len(records), "notes": []}
    by_func: dict[int, list[_Record]] = {}
    for rec in records:
        by_func.setdefault(rec.func, []).append(rec)
    skipped = sorted({r.func for r in records} - {FUNC_TIME, FUNC_FRF, FUNC_COHERENCE})
    if skipped:
        details["notes"].append(f"skipped records of func_type {', '.join(map(str, skipped))}")
    hits = _hits(path, name, by_func.get(FUNC_TIME, []), mtime_utc(info), details)
    frfs = _frfs(path, name, by_func.get(FUNC_FRF, []), by_func.get(FUNC_COHERENCE, []), details)
    if hits is None and frfs is None:
        raise FormatError(
            f"{name}: no force/acceleration time records and no FRFs among its datasets 58; "
            f"it holds {_contents(records)}"
        )
    return ImportedData(hits=hits, measured_frfs=frfs, format="uff", details=details)


def _check_starts_as_uff(path: Path, name: str) -> None:
    """Every UFF file starts with a "    -1" delimiter line (after blank lines, if any): a
    file that does not (a CSV given --format uff) is no UFF, not a truncated one."""
    try:
        with open(path, "rb") as handle:
            head = handle.read(512)
    except OSError as exc:
        raise FormatError(f"{name}: cannot read it ({exc.strerror or exc})") from None
    first = next((line for line in head.splitlines() if line.strip()), b"")
    if first.strip() != b"-1":
        # repr shows tabs and control characters as \t, \x00: the line stays one line
        # and a table's first line (tab-separated numbers) is named too.
        shown = first.strip()[:40].decode("utf-8", errors="replace")
        raise FormatError(
            f"{name}: does not look like a UFF file: its first line is not a UFF -1 delimiter line"
            + (f" but {shown!r}" if shown else "")
        )


def _check_ends_whole(path: Path, name: str) -> None:
    """Every UFF dataset ends with a "-1" delimiter line: a file cut short does not, and
    pyuff would read the records before the cut as if they were all there."""
    try:
        with open(path, "rb") as handle:
            handle.seek(max(0, handle.seek(0, 2) - 256))
            tail = handle.read()
    except OSError as exc:
        raise FormatError(f"{name}: cannot read it ({exc.strerror or exc})") from None
    # "    -1" in columns 1-6; after binary data (58b) it follows the last value directly.
    if not tail.rstrip(b" \t\r\n").endswith(b"    -1"):
        raise FormatError(f"{name}: truncated UFF file (it does not end with a -1 delimiter line)")


def read_uff_sets(path: Path, name: str) -> list[dict]:
    # pyuff raises bare Exception, IndexError, struct.error, ValueError... on damaged
    # input, and its numpy calls may warn: the one place a broad except is right, since
    # every failure inside pyuff means "this file cannot be read" and must become one line.
    failure = ""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            uff = pyuff.UFF(str(path))
            wanted = [i for i, t in enumerate(uff.get_set_types()) if int(t) == 58]
            sets = uff.read_sets(wanted) if wanted else []
        except Exception as exc:
            failure = one_line(str(exc))[:100] or type(exc).__name__
            del exc
        if failure:
            # pyuff leaves its open file in the frames of the traceback; collect it
            # here, where its ResourceWarning is silenced, not in some later test or call.
            gc.collect()
    if failure:
        raise FormatError(f"{name}: not a readable UFF file ({failure})")
    if not wanted:
        raise FormatError(f"no dataset 58 in {name}")
    return [sets] if isinstance(sets, dict) else list(sets)


def _record(d: Any, k: int, name: str) -> _Record:
    """Check one pyuff dict, the ``k``-th (0-based) dataset 58, and keep what the import
    needs; its messages number it k + 1, as a person counts the records of a file."""
    number = k + 1
    if not isinstance(d, dict):
        raise FormatError(f"{name}: dataset 58 #{number} could not be read")
    data = np.asarray(d.get("data"))
    x = np.asarray(d.get("x"))
    if data.ndim != 1 or data.dtype.kind not in "fc" or data.size == 0:
        raise FormatError(f"{name}: dataset 58 #{number} has no data values")
    if x.shape != data.shape or x.dtype.kind not in "fi":
        raise FormatError(
            f"{name}: dataset 58 #{number} has {x.size} abscissa values for {data.size} data values"
        )
    declared = _int(d.get("num_pts"), data.size)
    if declared != data.size:
        raise FormatError(
            f"{name}: dataset 58 #{number} declares {declared} values but holds {data.size}: "
            "truncated or damaged"
        )
    data = data.astype(np.complex128 if data.dtype.kind == "c" else np.float64)
    x = x.astype(np.float64)
    if not (np.all(np.isfinite(data)) and np.all(np.isfinite(x))):
        raise FormatError(f"{name}: dataset 58 #{number} holds NaN or infinite values")
    ids = [str(d.get(f"id{i}", "")).strip() for i in range(1, 6)]
    keys = dict(match for text in ids for match in _KEY_VALUE.findall(text))
    return _Record(
        index=number,
        func=_int(d.get("func_type"), -1),
        kind=_int(d.get("ordinate_spec_data_type"), 0),
        denominator_kind=_int(d.get("orddenom_spec_data_type"), 0),
        data=data,
        x=x,
        even=_int(d.get("abscissa_spacing"), 0) == 1,
        x_min=_float(d.get("abscissa_min")),
        x_inc=_float(d.get("abscissa_inc")),
        ids=ids,
        keys=keys,
        unit=str(d.get("ordinate_axis_units_lab", "")).strip(),
        denominator_unit=str(d.get("orddenom_axis_units_lab", "")).strip(),
        nodes=(d.get("ref_node"), d.get("ref_dir"), d.get("rsp_node"), d.get("rsp_dir")),
    )


def _hits(path: Path, name: str, records: list[_Record], stamp: str, details: dict):
    forces = [r for r in records if r.kind in FORCE_TYPES]
    responses = [r for r in records if r.kind in RESPONSE_TYPES]
    other = sorted({r.kind for r in records} - set(FORCE_TYPES) - set(RESPONSE_TYPES))
    if other:
        details["notes"].append(f"skipped time records of ordinate type {', '.join(map(str, other))}")
    if not forces and not responses:
        return None
    if len(forces) != len(responses):
        raise FormatError(
            f"{name}: {len(forces)} force and {len(responses)} acceleration time records; "
            "they must pair up (k-th force with k-th response)"
        )
    first = forces[0]
    n = first.data.size
    if n < 2:
        raise FormatError(f"{name}: time record #{first.index} has fewer than 2 samples")
    start, step = _time_axis(name, first)
    for rec in forces + responses:
        if rec.data.size != n:
            raise FormatError(
                f"{name}: time record #{rec.index} has {rec.data.size} samples, #{first.index} has {n}"
            )
        if rec.data.dtype != first.data.dtype:
            raise FormatError(
                f"{name}: time records #{first.index} and #{rec.index} mix real and complex data"
            )
        s0, d0 = _time_axis(name, rec)
        if abs(s0 - start) > AXIS_TOLERANCE * step or abs(d0 - step) > AXIS_TOLERANCE * step:
            if abs(s0 - start) > AXIS_TOLERANCE * step:
                how = f"it starts at {s0:.6g} s, #{first.index} at {start:.6g} s"
            else:
                how = f"its step is {d0:.6g} s, #{first.index}'s {step:.6g} s"
            raise FormatError(
                f"{name}: time record #{rec.index} has a different time axis from #{first.index} ({how}); "
                f"{SAME_AXIS_REMEDY}"
            )
    rate, start = _exact_axis(first, start, step, details)
    center = 0.0
    if first.data.dtype == np.complex128:
        text = first.keys.get("center_hz")
        center = _float(text)
        if text is None or not math.isfinite(center):
            raise FormatError(f"{name}: complex (zoom) time records need 'center_hz=...' in an ID line")
    units = {}
    force = np.stack([_to_si(r, "force", units) for r in forces])
    response = np.stack([_to_si(r, "response", units) for r in responses])
    details.update(n_records=len(forces), n_samples=n, time_units=units, zoom=force.dtype.kind == "c")
    rejected = {}
    for k, rec in enumerate(forces):
        _, found, reason = rec.ids[0].partition(" rejected:")
        if found:
            rejected[k] = reason
    return make_hits(path, force, response, rate, start, center, stamp, rejected)


def _time_axis(name: str, rec: _Record) -> tuple[float, float]:
    """(start s, step s) of a time record, from the header (even) or its x values (uneven)."""
    if rec.even:
        start, step = rec.x_min, rec.x_inc
    else:
        d = np.diff(rec.x)
        if np.any(d <= 0):
            raise FormatError(f"{name}: time record #{rec.index} has non-increasing time steps")
        # ASCII 58 prints x with %13.5e (6 significant digits): half a unit of the last is
        # at most 5e-6 of the value; binary 58 holds doubles (1 % of the step then decides).
        fit = fit_regular(rec.x, 5e-6 * np.abs(rec.x))
        if fit.bad is not None:
            raise FormatError(
                f"{name}: time record #{rec.index} has uneven time steps (from sample {fit.bad}: "
                "no straight line within the printed precision or 1 % of the step)"
            )
        start, step = fit.start, fit.step
    if not (math.isfinite(start) and math.isfinite(step) and step > 0):
        raise FormatError(f"{name}: time record #{rec.index} has no usable time axis (step {step!r} s)")
    return start, step


def _exact_axis(rec: _Record, start: float, step: float, details: dict) -> tuple[float, float]:
    """(sample rate Hz, start s): our exporter's exact ID-line values when they fit the header."""
    rate, exact_start = _float(rec.keys.get("sample_rate_hz")), _float(rec.keys.get("start_s"))
    if math.isfinite(rate) and rate > 0 and abs(1.0 / rate - step) <= HEADER_TOLERANCE * step:
        out_rate = rate
    else:
        out_rate = 1.0 / step
        if rec.even and (whole := _printed_increment_rate(rec.x_inc)):
            out_rate = whole[0]
            details["notes"].append(whole[1])
    if math.isfinite(exact_start) and abs(exact_start - start) <= HEADER_TOLERANCE * max(abs(start), step):
        start = exact_start
    details["exact_axis_from_id_lines"] = out_rate == rate and start == exact_start
    return out_rate, start


#: Significant digits of the abscissa increment in a dataset 58 header: the format prints
#: it as E13.5 (pyuff, and the writers that follow the format).
HEADER_DIGITS = 6


def _printed_increment_rate(increment: float) -> tuple[float, str] | None:
    """(a whole rate, Hz, and the note saying why) where the header's increment (s), printed
    to HEADER_DIGITS significant digits, allows exactly one whole number of hertz; else
    None. 4096 Hz prints as 2.44141e-04 s, which read back is 4095.99 Hz: the printed
    digits cannot say more, and a sampling rate is a whole number of hertz far more often
    than not (the CSV reader states such a rate in a note too, for coarse time columns)."""
    printed = f"{increment:.{HEADER_DIGITS - 1}e}"
    # More digits than the format's (a writer that prints them) hold the step closer.
    text = printed if float(printed) == increment else repr(increment)
    half = float(printed_half_units([text])[0])
    whole = whole_rate(increment, half)
    if whole is None:
        return None
    low, high = 1.0 / (increment + half), 1.0 / (increment - half)
    digits = max(0, 1 - math.floor(math.log10(high - low)))
    digits_said = len(text.split("e")[0].replace(".", "").replace("-", "").lstrip("0"))
    return float(whole), (
        f"sample rate {whole} Hz: the abscissa increment {text} s, printed to {digits_said} significant "
        f"digits, gives {1.0 / increment:.{digits}f} Hz, and any rate from {low:.{digits}f} to "
        f"{high:.{digits}f} Hz lies within half a unit of its last digit; {whole} Hz, the one whole "
        "number of hertz among them, is stored"
    )


def _to_si(rec: _Record, quantity: str, units: dict) -> np.ndarray:
    factor = 1.0
    if rec.unit in _NO_UNIT:
        units.setdefault(quantity, "none given, SI assumed")
    else:
        try:
            factor = parse_unit(rec.unit, quantity)
            units.setdefault(quantity, rec.unit)
        except FormatError:
            units.setdefault(quantity, f"unknown label {rec.unit!r}, values kept")
    return _scaled(rec.data, factor)


def _scaled(values: np.ndarray, factor: float) -> np.ndarray:
    # Skip the multiplication by 1.0: for complex values numpy multiplies by (1+0j),
    # which can flip the sign of a zero part.
    return values * factor if factor != 1.0 else values


def _dof_label(rec: _Record) -> str:
    return "ref{}{}->rsp{}{}".format(*rec.nodes)


def _frfs(path: Path, name: str, frf_recs: list[_Record], coh_recs: list[_Record], details: dict):
    if not frf_recs:
        if coh_recs:
            details["notes"].append("coherence records without FRFs ignored")
        return None
    freq = frf_recs[0].x
    for rec in frf_recs:
        if not np.array_equal(rec.x, freq):
            raise FormatError(
                f"{name}: FRF record #{rec.index} has a different frequency axis from #{frf_recs[0].index}"
            )
    units: list[str] = []
    forms = [_frf_form(name, rec) for rec in frf_recs]
    other = next((k for k, form in enumerate(forms) if form != forms[0]), None)
    if other is not None:
        raise FormatError(
            f"{name}: FRF records #{frf_recs[0].index} ({forms[0]}) and #{frf_recs[other].index} "
            f"({forms[other]}) are of different forms; one run holds FRFs of one form"
        )
    frf = np.stack([_scaled(rec.data.astype(np.complex128), _frf_factor(rec, units)) for rec in frf_recs])
    labels = [rec.ids[0] if rec.ids[0] not in _NO_UNIT else _dof_label(rec) for rec in frf_recs]
    coherence = None
    if coh_recs:
        if len(coh_recs) != len(frf_recs):
            details["notes"].append(
                f"{len(coh_recs)} coherence records for {len(frf_recs)} FRFs: coherence ignored"
            )
        elif not all(np.array_equal(rec.x, freq) for rec in coh_recs):
            details["notes"].append("coherence on a different frequency axis: ignored")
        elif any(rec.data.dtype.kind == "c" and np.any(rec.data.imag) for rec in coh_recs):
            details["notes"].append("complex coherence values: ignored")
        else:
            coherence = np.stack([rec.data.real for rec in coh_recs])
    details.update(
        n_frf=len(frf_recs), n_lines=int(freq.size), frf_units=sorted(set(units)), frf_forms=[forms[0]]
    )
    # The exponential window the FRFs went through, when the file says (daq export does).
    decay, pulse = _float(frf_recs[0].keys.get("exp_decay_s")), _float(frf_recs[0].keys.get("pulse_s"))
    if math.isfinite(decay) and decay > 0:
        details.update(exp_decay_s=decay, pulse_s=pulse if math.isfinite(pulse) else 0.0)
    return make_frfs(path, freq, frf, coherence, labels, forms[0])


def _unit_form(rec: _Record) -> str | None:
    """The form the record's unit labels say (m/N, g, (m/s)/N...), or None if they say none."""
    num = rec.unit
    try:
        return frf_unit(num)[0]  # the whole unit in the numerator label, e.g. "m/N"
    except FormatError:
        pass
    found = response_form(num) if num not in _NO_UNIT else None
    return found[0] if found else None


def _frf_form(name: str, rec: _Record) -> str:
    """receptance, mobility or accelerance: the ordinate's data type (8, 11, 12) and its
    unit labels decide; an unknown type, a non-force denominator or a disagreement: FormatError."""
    by_unit = _unit_form(rec)
    if rec.kind in FRF_FORM_OF_TYPE:
        form = FRF_FORM_OF_TYPE[rec.kind]
        if by_unit is not None and by_unit != form:
            raise FormatError(
                f"{name}: FRF record #{rec.index} has ordinate data type {rec.kind} ({form}) but unit "
                f"{rec.unit!r} ({by_unit}); which is it?"
            )
    elif rec.kind in UNKNOWN_TYPES and by_unit is not None:
        form = by_unit
    else:
        raise FormatError(
            f"{name}: FRF record #{rec.index} has ordinate data type {rec.kind} and unit "
            f"{rec.unit or 'none'!r}: only displacement (8), velocity (11) or acceleration (12) over "
            "force can be imported"
        )
    if rec.denominator_kind not in FORCE_DENOMINATOR_TYPES:
        raise FormatError(
            f"{name}: FRF record #{rec.index} has denominator data type {rec.denominator_kind}, "
            "not a force (13 or 9)"
        )
    return form


def _frf_factor(rec: _Record, units: list[str]) -> float:
    """SI factor of an FRF record from its numerator / denominator unit labels."""
    num, den = rec.unit, rec.denominator_unit
    if num in _NO_UNIT and den in _NO_UNIT:
        units.append("none given, SI assumed")
        return 1.0
    pairs = [(num, den)] if den not in _NO_UNIT else []
    # Some tools put the whole unit into the numerator label, e.g. "g/N" or "(m/s^2)/N".
    pairs += [(num[:i].strip(" ()"), num[i + 1 :].strip(" ()")) for i, ch in enumerate(num) if ch == "/"]
    for top, bottom in pairs:
        try:
            found = response_form(top)
            if found is None:
                raise FormatError(f"unknown unit {top!r}")
            factor = found[1] / parse_unit(bottom, "force")
        except FormatError:
            continue
        units.append(f"{top}/{bottom}")
        return factor
    units.append(f"unknown label {num!r}/{den!r}, values kept")
    return 1.0


def _int(value: Any, default: int) -> int:
    try:
        return int(value)
    except (TypeError, ValueError, OverflowError):
        return default


def _float(value: Any) -> float:
    try:
        return float(value)
    except (TypeError, ValueError, OverflowError):
        return math.nan
