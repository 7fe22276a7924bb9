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
from daq.formats.units import FORM_OF_QUANTITY, PHYSICAL_UNITS, SHOWN_UNITS

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
GZIP_MAGIC = b"\x1f\x8b"


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
    x_kind: int = 18  # abscissa specific data type: 17 time, 18 frequency
    x_unit: str = ""  # abscissa units label


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
    """Read dataset 58 records: time records as hits (N, m/s^2) and FRFs (SI units of their form,
    on a frequency axis in Hz).

    Any problem, including whatever pyuff raises on a damaged file: one-line FormatError.
    What is left out (other datasets, other function types, unpaired time records beside
    FRFs, coherence that matches no FRF) and what is converted is said in ``details["notes"]``.
    """
    path = Path(path)
    name = show_path(path)
    info = check_regular_file(path, max_bytes)
    _check_starts_as_uff(path, name)
    _check_ends_whole(path, name)
    sets, other_types = _read_sets58(path, name)
    records = [_record(d, k, name) for k, d in enumerate(sets)]
    details: dict[str, Any] = {"n_datasets_58": len(records), "notes": []}
    if other_types:
        details["notes"].append(skipped_datasets_note(other_types, "a run holds only datasets 58"))
    by_func: dict[int, list[_Record]] = {}
    for rec in records:
        by_func.setdefault(rec.func, []).append(rec)
    skipped = [r for r in records if r.func not in (FUNC_TIME, FUNC_FRF, FUNC_COHERENCE)]
    if skipped:
        details["notes"].append(
            f"skipped {_records_text(skipped)}: a run holds time records (function type 1), "
            "FRFs (4) and their coherence (6)"
        )
    frf_recs = by_func.get(FUNC_FRF, [])
    hits = _hits(path, name, by_func.get(FUNC_TIME, []), mtime_utc(info), details, bool(frf_recs))
    frfs = _frfs(path, name, frf_recs, by_func.get(FUNC_COHERENCE, []), details)
    if hits is None and frfs is None:
        raise FormatError(
            f"{name}: no force/acceleration time records and no FRFs among its datasets 58; "
            f"it holds {_contents(records)}"
        )
    return ImportedData(hits=hits, measured_frfs=frfs, format="uff", details=details)


#: What the datasets other than 58 are, to name them when they are skipped.
DATASET_NAMES = {15: "nodes", 18: "coordinate systems", 55: "data at nodes", 82: "trace lines",
                 151: "header", 164: "units", 1858: "qualifiers", 2400: "model header",
                 2411: "nodes", 2412: "elements", 2414: "analysis data",
                 2420: "coordinate systems"}  # fmt: skip


def skipped_datasets_note(types: list[int], why: str) -> str:
    """'skipped datasets 151 (header), 15 (nodes): WHY', each type once, in file order."""
    named = [f"{t} ({DATASET_NAMES[t]})" if t in DATASET_NAMES else str(t) for t in dict.fromkeys(types)]
    return f"skipped datasets {', '.join(named)}: {why}"


def _records_text(records: list[_Record]) -> str:
    """'dataset 58 #3 (auto spectrum), #6 (cross spectrum)': records named for a note."""
    parts = [
        f"#{r.index} ({FUNC_NAMES.get(r.func, f'function type {r.func}')}"
        + (f" of {KIND_NAMES[r.kind]}" if r.func == FUNC_TIME and r.kind in KIND_NAMES else "")
        + ")"
        for r in records
    ]
    return ("datasets 58 " if len(parts) > 1 else "dataset 58 ") + ", ".join(parts)


def _check_starts_as_uff(path: Path, name: str) -> None:
    """Every UFF file starts with a "    -1" delimiter line (after blank lines, if any): a
    file that does not (a CSV given --format uff) is no UFF, not a truncated one."""
    try:
        with open(path, "rb") as handle:
            head = handle.read(512)
    except OSError as exc:
        raise FormatError(f"{name}: cannot read it ({exc.strerror or exc})") from None
    if head.startswith(GZIP_MAGIC):
        # gzip's magic bytes: a .uff.gz renamed, or a tool that compresses its export.
        raise FormatError(f"{name}: gzip-compressed: unpack it first (gunzip) and import the UFF inside")
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


def _which_dataset_fails(path: Path, uff) -> str:
    """ ", at dataset #k (from line L)": the first dataset pyuff cannot read alone, or "".
    pyuff says only "Error when reading data-set(s)" of a file of hundreds; its block
    index (byte offsets, a private attribute) gives the line where the dataset starts."""
    try:
        count = len(uff.get_set_types())
    except Exception:
        return ""
    for k in range(count):
        try:
            uff.read_sets(k)
        except Exception:
            block = getattr(uff, "_block_ind", None)
            try:
                with open(path, "rb") as handle:
                    text = handle.read(int(block[k][1]))
                first = text[: int(block[k][0])].count(b"\n") + 1
                bad = _first_bad_line(text[int(block[k][0]) :].decode("latin-1").splitlines())
            except Exception:
                return f", at dataset #{k + 1}"
            if bad is None:
                return f", at dataset #{k + 1} (from line {first})"
            offset, token = bad
            return f", at dataset #{k + 1}: line {first + offset} holds {token!r}, which is no number"
    return ""


#: A number as an ASCII dataset 58 prints it (Fortran E or D format).
_FORTRAN_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[EeDd][-+]?\d+)?")


def _first_bad_line(lines: list[str]) -> tuple[int, str] | None:
    """(index in ``lines``, token) of the first field of an ASCII dataset 58 (its lines from
    the -1 that opens it) that should be a number and is not: record 6's function type,
    record 7 whole, the four data-type fields of records 8-11, and every data line; None
    if none (or binary)."""
    if len(lines) < 2 or lines[1].strip() != "58":
        return None  # 58b: binary values, no lines to blame
    for index, line in enumerate(lines[2:], start=2):
        if line.strip() == "-1":
            return None
        if index < 7:
            continue  # records 1-5: free text
        tokens = line.split()
        if index == 7:
            tokens = tokens[:1]  # record 6: its function type; its entity names are text
        elif 9 <= index <= 12:
            tokens = tokens[:4]  # records 8-11: data types and exponents, then labels
        for token in tokens:
            if not _FORTRAN_NUMBER.fullmatch(token):
                return index, token[:20]
    return None


def read_uff_sets(path: Path, name: str) -> list[dict]:
    """The datasets 58 of ``path`` as pyuff reads them (their text fields decoded as
    :func:`decode_texts` does); FormatError (one line) if there are none or pyuff fails."""
    return _read_sets58(path, name)[0]


def _read_sets58(path: Path, name: str) -> tuple[list[dict], list[int]]:
    """(the datasets 58, the types of the other datasets in file order)."""
    # pyuff raises bare Exception, IndexError, struct.error, ValueError... on damaged
    # input, and its numpy calls may warn: the one place a broad except is right, since
    # every failure inside pyuff means "this file cannot be read" and must become one line.
    failure = ""
    other: list[int] = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        uff = None
        try:
            uff = pyuff.UFF(str(path))
            types = [int(t) for t in uff.get_set_types()]
            wanted = [i for i, t in enumerate(types) if t == 58]
            other = [t for t in types if t != 58]
            sets = uff.read_sets(wanted) if wanted else []
            sets = [sets] if isinstance(sets, dict) else list(sets)
            decode_texts(path, uff, wanted, sets)
        except Exception as exc:
            failure = one_line(str(exc))[:100] or type(exc).__name__
            del exc
            if uff is not None:
                failure = failure.rstrip(".") + _which_dataset_fails(path, uff)
        if failure:
            # pyuff leaves its open file in the frames of the traceback; collect it
            # here, where its ResourceWarning is silenced, not in some later test or call.
            gc.collect()
    if failure:
        raise FormatError(f"{name}: not a readable UFF file ({failure})")
    if not wanted:
        raise FormatError(f"no dataset 58 in {name}")
    return sets, other


# Header lines of a dataset 58 (0 is its -1 delimiter) with text fields: ID lines 1 to 5,
# and the abscissa, ordinate, denominator and z-axis lines (axis label in columns 26-46,
# units label in 47-67, as pyuff splits them).
_ID_LINES = {2: "id1", 3: "id2", 4: "id3", 5: "id4", 6: "id5"}
_AXIS_LINES = {9: "abscissa", 10: "ordinate", 11: "orddenom", 12: "z_axis"}


def decode_texts(path: Path, uff: Any, indices: list[int], sets: list[Any]) -> None:
    """Decode the ID lines and axis labels of datasets 58 that are not UTF-8 as Latin-1, in place.

    pyuff decodes each header as UTF-8 and replaces what is not, so a Latin-1 '²' (as
    Windows tools write "m/s²") reaches us as U+FFFD and messages showed 'm/s\ufffd'.
    Only fields holding U+FFFD are read again, from the bytes at pyuff's own block offsets;
    without those offsets (another pyuff) the fields stay as pyuff gave them.
    """
    blocks = getattr(uff, "_block_ind", None)
    if blocks is None or len(indices) != len(sets):
        return
    with open(path, "rb") as handle:
        for i, dset in zip(indices, sets, strict=True):
            if not isinstance(dset, dict) or not any(
                isinstance(v, str) and "\ufffd" in v for v in dset.values()
            ):
                continue
            start, end = int(blocks[i][0]), int(blocks[i][1])
            handle.seek(start)
            lines = handle.read(end - start + 1).splitlines()[:13]
            for j, raw in enumerate(lines):
                try:
                    text = raw.decode("utf-8")
                except UnicodeDecodeError:
                    text = raw.decode("latin-1")
                text = text.ljust(80)
                fields = {}
                if j in _ID_LINES:
                    fields[_ID_LINES[j]] = text[:80].strip()
                elif j in _AXIS_LINES:
                    axis = _AXIS_LINES[j]
                    fields[f"{axis}_axis_lab"] = text[25:46].strip()
                    fields[f"{axis}_axis_units_lab"] = text[46:67].strip()
                for key, value in fields.items():
                    if "\ufffd" in str(dset.get(key, "")):
                        dset[key] = value


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
        x_kind=_int(d.get("abscissa_spec_data_type"), 0),
        x_unit=str(d.get("abscissa_axis_units_lab", "")).strip(),
    )


def _hits(path: Path, name: str, records: list[_Record], stamp: str, details: dict, has_frfs: bool = False):
    """Hits (N, m/s^2) from the time records, or None. Beside FRFs (``has_frfs``), time
    records that do not pair up are left out with a note: the FRFs are the file's data."""
    forces = [r for r in records if r.kind in FORCE_TYPES]
    responses = [r for r in records if r.kind in RESPONSE_TYPES]
    other = [r for r in records if r.kind not in FORCE_TYPES + RESPONSE_TYPES]
    if other:
        details["notes"].append(
            f"skipped {_records_text(other)}: a hit is an excitation force (data type 13 or 9) "
            "and an acceleration (12)"
        )
    if not forces and not responses:
        return None
    if len(forces) != len(responses) and has_frfs:
        details["notes"].append(
            f"skipped {_records_text(forces + responses)}: {len(forces)} force and {len(responses)} "
            "acceleration time records do not pair up into hits; the FRFs are imported"
        )
        return None
    if responses and not forces:
        # Output-only data (operational modal analysis): no hit to divide by. Beside
        # records of other types, one of them may be the force, written under another type.
        also = (
            f"; the file's other time records ({_records_text(other)}) are no force by their data type"
            if other
            else " (output-only data cannot give FRFs here)"
        )
        raise FormatError(
            f"{name}: {len(responses)} acceleration time record{'s' if len(responses) > 1 else ''} and no "
            f"force record: an impact test needs the hammer's force beside each response{also}"
        )
    if len(forces) != len(responses):
        points = sorted({(_int(r.nodes[2], -1), _int(r.nodes[3], 0)) for r in responses})
        several = (
            f", at {len(points)} response points ({', '.join(f'node {n} dir {d}' for n, d in points)}); "
            "a run holds one response per hit: write one file per response point, each with its "
            "force records, or export time, force and one response as CSV"
            if len(points) > 1
            else ""
        )
        raise FormatError(
            f"{name}: {len(forces)} force and {len(responses)} acceleration time records; "
            f"they must pair up (k-th force with k-th response){several}"
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
    force = np.stack([_to_si(r, "force", units, name) for r in forces])
    response = np.stack([_to_si(r, "response", units, name) for r in responses])
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


def _printed_step_u_rel(rec: _Record) -> float:
    """The relative standard uncertainty of an even abscissa's step printed to HEADER_DIGITS
    significant digits (half a unit of its last digit over sqrt 3, over the step), or 0:
    uneven axes (their own values, doubles in binary 58), and a step whose printed digits
    end in zeros (1.00000E+00, 2.50000E-01: a step that short is taken as exact). The
    header is text in binary 58 too, so an even axis there has the same doubt. A new
    user's 1/3 Hz lines, printed 3.33333E-01, put a 4000 Hz mode 0.0033 Hz low with a ±
    of 0.0010 Hz."""
    step = rec.x_inc
    if not (rec.even and math.isfinite(step) and step > 0):
        return 0.0
    printed = f"{step:.{HEADER_DIGITS - 1}e}"
    mantissa = printed.split("e")[0]
    if float(printed) != step or mantissa.endswith("0"):
        return 0.0
    half = 0.5 * 10.0 ** (int(printed.split("e")[1]) - (HEADER_DIGITS - 1))
    return half / step / math.sqrt(3.0)


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


def _to_si(rec: _Record, quantity: str, units: dict, name: str = "") -> np.ndarray:
    """A time record's values in SI (N for "force", m/s^2 for "response") by its unit label.

    No label: SI assumed (said in ``units``). Volts: FormatError, as a UFF file carries no
    sensor sensitivity. A label of another quantity (m/s on an acceleration): FormatError.
    A label no table knows: FormatError, as for an FRF (kept, it was stored as SI with
    one import warning and nothing said after: a force in 'furlong' read as newtons).
    """
    factor = 1.0
    if rec.unit.upper() in _NO_UNIT:
        units.setdefault(quantity, "none given, SI assumed")
        return rec.data
    wanted = "force" if quantity == "force" else "acceleration"
    found = uff_unit(rec.unit)
    what = f"{name}: time record #{rec.index} ({KIND_NAMES.get(rec.kind, 'data type ' + str(rec.kind))})"
    if found is not None and found[0] == "voltage":
        raise FormatError(f"{what} is in {rec.unit!r}: {NO_SENSITIVITY}")
    if found is not None and found[0] != wanted:
        raise FormatError(
            f"{what} has unit label {rec.unit!r}, {_A[found[0]]} unit: understood are {_understood(wanted)}"
        )
    if found is None:
        raise FormatError(
            f"{what} has unit label {rec.unit!r}, which is not known: understood are {_understood(wanted)}"
        )
    factor = found[1]
    units.setdefault(quantity, rec.unit)
    return _scaled(rec.data, factor)


def _scaled(values: np.ndarray, factor: float) -> np.ndarray:
    # Skip the multiplication by 1.0: for complex values numpy multiplies by (1+0j),
    # which can flip the sign of a zero part.
    return values * factor if factor != 1.0 else values


def _dof_label(rec: _Record) -> str:
    return "ref{}{}->rsp{}{}".format(*rec.nodes)


def _frfs(path: Path, name: str, frf_recs: list[_Record], coh_recs: list[_Record], details: dict):
    notes = details["notes"]
    if not frf_recs:
        if coh_recs:
            notes.append(f"skipped {_records_text(coh_recs)}: coherence without FRFs")
        return None
    for rec in frf_recs:
        check_complex(name, rec)
    freq = frequency_axis(name, frf_recs, notes, tuple(coh_recs))
    if (u_rel := _printed_step_u_rel(frf_recs[0])) > 0:
        # Every frequency is f0 + k x step: the step's printed precision scales them all.
        details["frequency_axis_u_rel"] = u_rel
        notes.append(
            f"the frequency step {frf_recs[0].x_inc:.5e} is printed to {HEADER_DIGITS} significant digits: "
            f"every frequency is known to ±{100 * u_rel * math.sqrt(3):.2g} %, which daq analyze adds to "
            "each ±"
        )
    for rec in frf_recs:
        if not np.array_equal(rec.x, frf_recs[0].x):
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
    factors = [_frf_factor(rec, units, name) for rec in frf_recs]
    frf = np.stack(
        [_scaled(rec.data.astype(np.complex128), f) for rec, f in zip(frf_recs, factors, strict=True)]
    )
    notes.extend(conversion_notes(frf_recs, factors, forms[0]))
    labels = [rec.ids[0] if rec.ids[0] not in _NO_UNIT else _dof_label(rec) for rec in frf_recs]
    coherence = _coherence_by_dof(frf_recs, coh_recs, notes)
    if freq.order is not None:  # frequencies given falling: every array in rising order
        frf = frf[:, freq.order]
        coherence = coherence[:, freq.order] if coherence is not None else None
    details.update(
        n_frf=len(frf_recs), n_lines=int(freq.hz.size), frf_units=sorted(set(units)), frf_forms=[forms[0]]
    )
    # The exponential window the FRFs went through, when the file says (daq export does).
    decay, pulse = _float(frf_recs[0].keys.get("exp_decay_s")), _float(frf_recs[0].keys.get("pulse_s"))
    if math.isfinite(decay) and decay > 0:
        details.update(exp_decay_s=decay, pulse_s=pulse if math.isfinite(pulse) else 0.0)
    return make_frfs(path, freq.hz, frf, coherence, labels, forms[0])


def dof_key(rec: _Record) -> tuple:
    """(reference node, direction, response node, direction) of a record, as the file gives them."""
    return tuple(_int(v, -1) for v in rec.nodes)


def _coherence_by_dof(
    frf_recs: list[_Record], coh_recs: list[_Record], notes: list[str]
) -> np.ndarray | None:
    """Coherence (n_frf, n_lines) matched to the FRFs by reference and response node and
    direction, or None (with a note). Among records of one DOF pair (daq's own export
    writes every FRF at the tip's one node), the k-th coherence goes with the k-th FRF.
    A coherence record that matches no FRF is left out with a note."""
    if not coh_recs:
        return None
    waiting: dict[tuple, list[_Record]] = {}
    for rec in coh_recs:
        waiting.setdefault(dof_key(rec), []).append(rec)
    found: list[_Record | None] = []
    for rec in frf_recs:
        same = waiting.get(dof_key(rec))
        found.append(same.pop(0) if same else None)
    unmatched = [rec for recs in waiting.values() for rec in recs]
    if unmatched:
        notes.append(
            f"skipped {_records_text(unmatched)}: coherence of no FRF's reference and response "
            "(node and direction)"
        )
    lacking = [frf.index for frf, coh in zip(frf_recs, found, strict=True) if coh is None]
    if lacking:
        notes.append(
            f"no coherence record for FRF record{'s' if len(lacking) > 1 else ''} "
            f"{', '.join(f'#{i}' for i in lacking)}: coherence ignored (a run holds it for every FRF or none)"
        )
        return None
    return coherence_values([rec for rec in found if rec is not None], frf_recs[0].x, notes)


def coherence_values(matched: list[_Record], axis: np.ndarray, notes: list[str]) -> np.ndarray | None:
    """The coherence records matched to the FRFs, one each, as (n_frf, n_lines), or None
    with a note where one lies on another axis than ``axis`` (Hz) or holds complex values."""
    if not all(np.array_equal(rec.x, axis) for rec in matched):
        notes.append("coherence on a different frequency axis: ignored")
        return None
    if any(rec.data.dtype.kind == "c" and np.any(rec.data.imag) for rec in matched):
        notes.append("complex coherence values: ignored")
        return None
    return np.stack([rec.data.real.astype(np.float64) for rec in matched])


# --- the frequency axis ------------------------------------------------------------------------

#: Abscissa units labels of a frequency axis (lower case) and their factor to Hz. "rpm" is
#: left out: on a UFF abscissa it is a shaft speed (order tracking), not a frequency.
FREQUENCY_LABELS_HZ = {"hz": 1.0, "1/s": 1.0, "khz": 1e3, "rad/s": 1 / (2 * math.pi),
                       "rad/sec": 1 / (2 * math.pi), "cpm": 1 / 60, "c/min": 1 / 60,
                       "cycles/min": 1 / 60}  # fmt: skip
_HOW = {"khz": "multiplied by 1000", "rad/s": "divided by 2π", "rad/sec": "divided by 2π",
        "cpm": "divided by 60", "c/min": "divided by 60", "cycles/min": "divided by 60"}  # fmt: skip
_TIME_LABELS = ("s", "sec", "ms", "us", "µs", "μs", "min")
ABSCISSA_FREQUENCY, ABSCISSA_TIME = 18, 17
_ABSCISSA_OTHER = {19: "shaft speed (rpm)", 20: "order"}


@dataclass
class FrequencyAxis:
    """hz (n,) rising; order: indices that put the file's values in that order, or None."""

    hz: np.ndarray
    order: np.ndarray | None = None


def frequency_axis(
    name: str, records: list[_Record], notes: list[str], coherence: tuple[_Record, ...] = ()
) -> FrequencyAxis:
    """Every record's x (the FRFs' and their ``coherence``'s) converted to Hz in place; the
    first FRF's axis, rising.

    The abscissa's data type (18 frequency, 0/1 unknown/general) and units label (Hz, kHz,
    rad/s, cpm, or none: Hz) decide. A time (17), rpm or order abscissa, or a label that
    is no frequency unit: FormatError naming the record and the label. An axis given
    falling is turned round (``order``) when every FRF shares it, with a note; any
    other axis that does not rise is refused.
    """
    converted: dict[str, list[_Record]] = {}
    for rec in (*records, *coherence):
        label = rec.x_unit.strip()
        key = label.lower().replace(" ", "")
        shown = f"{name}: {FUNC_NAMES.get(rec.func, 'function')} record #{rec.index}"
        if rec.x_kind == ABSCISSA_TIME or (key in _TIME_LABELS and rec.x_kind != ABSCISSA_FREQUENCY):
            raise FormatError(
                f"{shown}: its abscissa is time (data type {rec.x_kind}, unit {label or 'none'!r}), "
                "not frequency: an FRF needs a frequency axis (Hz)"
            )
        if rec.x_kind in _ABSCISSA_OTHER or key == "rpm":
            said = _ABSCISSA_OTHER.get(rec.x_kind, "shaft speed (rpm)")
            raise FormatError(
                f"{shown}: its abscissa is a {said} (data type {rec.x_kind}, unit {label or 'none'!r}), "
                "not frequency: export the FRF over frequency in Hz"
            )
        if rec.x_kind not in (ABSCISSA_FREQUENCY, 0, 1):
            raise FormatError(
                f"{shown}: its abscissa is of data type {rec.x_kind} (unit {label or 'none'!r}), not "
                "frequency (18): an FRF needs a frequency axis (Hz)"
            )
        if label.upper() in _NO_UNIT:
            continue  # frequency by its data type, or unknown: Hz, as the format's default
        if key in _TIME_LABELS:
            raise FormatError(
                f"{shown}: its abscissa is of data type 18 (frequency) but unit {label!r} (time); "
                "which is it? An FRF needs a frequency axis (Hz)"
            )
        if key not in FREQUENCY_LABELS_HZ:
            raise FormatError(
                f"{shown}: unknown frequency unit {label!r} on its abscissa; use Hz, kHz, rad/s or cpm"
            )
        if key in _HOW:
            rec.x = rec.x * FREQUENCY_LABELS_HZ[key]
            converted.setdefault(label, []).append(rec)
    for label, recs in converted.items():
        said = f"{FUNC_NAMES.get(recs[0].func, 'function')} record" if len(recs) == 1 else "datasets 58"
        notes.append(
            f"{said} {', '.join(f'#{r.index}' for r in recs)}: "
            f"abscissa in {label}, converted to Hz ({_HOW[label.lower().replace(' ', '')]})"
        )
    first = records[0]
    x = first.x
    step = np.diff(x)
    if np.all(step > 0):
        return FrequencyAxis(x)
    if x.size > 1 and np.all(step < 0) and all(np.array_equal(r.x, x) for r in records):
        notes.append(
            f"the frequencies fall from {x[0]:g} to {x[-1]:g} Hz in every FRF record: read in rising order"
        )
        order = np.arange(x.size)[::-1]
        return FrequencyAxis(x[order], order)
    bad = int(np.flatnonzero(step <= 0)[0]) if x.size > 1 else 0
    raise FormatError(
        f"{name}: FRF record #{first.index}: frequencies must increase, and value {bad + 2} "
        f"({x[min(bad + 1, x.size - 1)]:g} Hz) follows {x[bad]:g} Hz"
    )


def check_complex(name: str, rec: _Record) -> None:
    """An FRF record must hold complex values: refuse a magnitude (or a level in dB) alone."""
    if rec.data.dtype.kind == "c":
        return
    level = " in dB" if uff_unit(rec.unit) == ("level", 1.0) else ""
    raise FormatError(
        f"{name}: FRF record #{rec.index} holds real values{level} (ordinate data type real, not "
        "complex): a magnitude without its phase; modes are identified from the complex FRF, so "
        "export it as complex (re, im)"
    )


# --- unit labels ---------------------------------------------------------------------------------

#: Unit labels modal software writes into datasets 58: the one table of daq/formats/units.py.
UFF_UNITS = PHYSICAL_UNITS
#: Labels of values a UFF file cannot turn into engineering units: it carries no sensitivity.
VOLTAGE_LABELS = ("V", "mV", "Volt", "Volts", "EU")
NO_SENSITIVITY = (
    "a UFF file carries no sensor sensitivity, so volts (or 'EU') cannot be turned into N or m/s^2; "
    "export the data in engineering units (N, m/s^2, g ...)"
)
FORM_QUANTITY = {form: quantity for quantity, form in FORM_OF_QUANTITY.items()}
_A = {"force": "a force", "acceleration": "an acceleration", "velocity": "a velocity",
      "displacement": "a displacement"}  # fmt: skip


_SHOWN = SHOWN_UNITS


def _understood(quantity: str) -> str:
    return _SHOWN[quantity]


def _understood_frf(quantity: str) -> str:
    return (
        f"{_SHOWN[quantity]} over {_SHOWN['force']} (or the whole unit in the ordinate label, e.g. (m/s^2)/N)"
    )


def clean_uff_label(label: str) -> str:
    """A units label in the spelling of UFF_UNITS: spaces, surrounding brackets and quotes
    taken off, '²' and '**' as '^', micro signs as 'u', 'sec' as 's' ("in/sec" -> "in/s")."""
    text = label.strip().strip("\"'").replace(" ", "")
    while len(text) > 1 and (text[0], text[-1]) in (("[", "]"), ("(", ")")) and _balanced(text[1:-1]):
        text = text[1:-1]
    text = text.replace("²", "^2").replace("**", "^").replace("µ", "u").replace("μ", "u")
    return re.sub(r"sec\b", "s", text)


def _balanced(text: str) -> bool:
    depth = 0
    for ch in text:
        depth += {"(": 1, ")": -1}.get(ch, 0)
        if depth < 0:
            return False
    return depth == 0


def uff_unit(label: str) -> tuple[str, float] | None:
    """(quantity, SI factor) of one unit label: quantity "force", "acceleration", "velocity",
    "displacement", "voltage" (factor 1: unknown without a sensitivity) or "level" (dB);
    None for a label no table knows."""
    text = clean_uff_label(label)
    for quantity, table in UFF_UNITS.items():
        if text in table:
            return quantity, table[text]
    if text in VOLTAGE_LABELS or text.upper() == "EU":
        return "voltage", 1.0
    if text.lower() == "db":
        return "level", 1.0
    return None


# An FRF unit written whole in the numerator label: "X/F", "(X)/F", SignalCalc's "(X)(F)",
# "(1/F)*(X)" and "X*(1/F)" (as some tools spell "general" data), "X*F^-1".
_ONE_OVER_FIRST = re.compile(r"\(?1/([^()*]+?)\)?\*\(?(.+?)\)?")
_ONE_OVER_LAST = re.compile(r"\(?(.+?)\)?\*\(?1/([^()*]+?)\)?")
_POWER_MINUS_ONE = re.compile(r"\(?(.+?)\)?\*\(?([^()*]+?)\)?\^-1")
_PAIR = re.compile(r"\(([^()]+)\)\(([^()]+)\)")


def frf_label_parts(label: str) -> tuple[str, str] | None:
    """(numerator, denominator) of an FRF unit written whole in one label, in clean_uff_label's
    spelling, e.g. ("m/s^2", "N") for "(1/N)*(m/s^2)", "m/s²/N" or "(m/s^2)/N"; None when the
    label has no force or voltage denominator."""
    text = clean_uff_label(label)
    candidates: list[tuple[str, str]] = []
    if match := _ONE_OVER_FIRST.fullmatch(text):
        candidates.append((match.group(2), match.group(1)))
    for pattern in (_ONE_OVER_LAST, _POWER_MINUS_ONE, _PAIR):
        if match := pattern.fullmatch(text):
            candidates.append((match.group(1), match.group(2)))
    top, slash, bottom = text.rpartition("/")
    if slash:
        candidates.append((top, bottom))
    for top, bottom in candidates:
        found = uff_unit(bottom)
        if found is not None and found[0] in ("force", "voltage") and top:
            return clean_uff_label(top), clean_uff_label(bottom)
    return None


def _frf_units(rec: _Record) -> tuple[str, str] | None:
    """(numerator, denominator) of an FRF record's labels: both labels, or the whole unit
    in the numerator label; denominator "" when only a numerator is given; None when
    neither reading finds a known numerator (over a force or a voltage)."""
    num, den = rec.unit, rec.denominator_unit
    if den.upper() not in _NO_UNIT and uff_unit(num) is not None:
        return num, den
    parts = frf_label_parts(num)
    if parts is not None and uff_unit(parts[0]) is not None:
        return parts[0], parts[1]
    if den.upper() in _NO_UNIT and uff_unit(num) is not None:
        return num, ""
    return None


def _unit_form(rec: _Record) -> str | None:
    """The form the record's unit labels say, or None if they say none."""
    found = _frf_units(rec)
    if found is None:
        return None
    quantity = uff_unit(found[0])
    return FORM_OF_QUANTITY.get(quantity[0]) if quantity else None


def _frf_form(name: str, rec: _Record) -> str:
    """receptance, mobility or accelerance: the ordinate's data type (8, 11, 12) and its
    unit labels decide; an unknown type, a non-force denominator or a disagreement: FormatError.
    Volts refused first: whatever the type, no sensitivity turns them into a form."""
    _check_volts(name, rec)
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


def _frf_factor(rec: _Record, units: list[str], name: str = "") -> float:
    """SI factor of an FRF record from its numerator / denominator unit labels.

    No labels (or no numerator label): SI assumed, said in ``units``. Volts or 'EU'
    anywhere, a label no table knows, or a label of another quantity than the
    record's form: FormatError naming the record, the label and the labels understood.
    """
    num, den = rec.unit, rec.denominator_unit
    where = f"{name}: FRF record #{rec.index}"
    if num.upper() in _NO_UNIT and den.upper() in _NO_UNIT:
        units.append("none given, SI assumed")
        return 1.0
    _check_volts(name, rec)
    if num.upper() in _NO_UNIT:
        found = uff_unit(den)
        if found is not None and found[0] == "force":
            # The numerator unsaid, its data type gives the form: SI assumed, as before.
            units.append(f"unknown label {num!r}/{den!r}, values kept")
            return 1.0 / found[1]
        raise FormatError(
            f"{where} has denominator unit {den!r}, which daq does not know: understood are "
            f"{_understood_frf(FORM_QUANTITY[FRF_FORM_OF_TYPE.get(rec.kind, 'accelerance')])}"
        )
    found = _frf_units(rec)
    form = FRF_FORM_OF_TYPE.get(rec.kind) or _unit_form(rec) or "accelerance"
    quantity = FORM_QUANTITY[form]
    if found is None:
        level = uff_unit(num) == ("level", 1.0)
        said = f"{num!r} over {den!r}" if den.upper() not in _NO_UNIT else repr(num)
        raise FormatError(
            f"{where} has unit {said}, "
            + ("a level in dB, which daq cannot convert" if level else "which daq does not know")
            + f": understood are {_understood_frf(quantity)}"
        )
    top, bottom = found
    top_unit = uff_unit(top)
    if top_unit is None or top_unit[0] != quantity:
        # e.g. N over N on an acceleration record: no form of FRF at all.
        raise FormatError(
            f"{where} has numerator unit {top!r}, not {_A[quantity]} ({form}): understood are "
            f"{_understood_frf(quantity)}"
        )
    if bottom:
        bottom_unit = uff_unit(bottom)
        if bottom_unit is None or bottom_unit[0] != "force":
            raise FormatError(
                f"{where} has denominator unit {bottom!r}, which daq does not know: understood are "
                f"{_understood_frf(quantity)}"
            )
        factor = top_unit[1] / bottom_unit[1]
        units.append(f"{top}/{bottom}")
    else:
        factor = top_unit[1]
        units.append(f"{top}/N (no force label: N assumed)")
    return factor


def _check_volts(name: str, rec: _Record) -> None:
    """Refuse an FRF record in volts or 'EU' (numerator, denominator or the whole unit)."""
    num, den = rec.unit, rec.denominator_unit
    labels = (num, den, *(frf_label_parts(num) or ()), *clean_uff_label(num).split("/"))
    if any(uff_unit(label) == ("voltage", 1.0) for label in labels):
        raise FormatError(f"{name}: FRF record #{rec.index} is in {num!r} over {den!r}: {NO_SENSITIVITY}")


def conversion_notes(records: list[_Record], factors: list[float], form: str) -> list[str]:
    """'FRF units: ft/s^2 over N converted to (m/s^2)/N (x 0.3048) in record #2' for labels
    that are not SI; nothing for SI labels or when nothing was converted."""
    si = {"receptance": "m/N", "mobility": "(m/s)/N", "accelerance": "(m/s^2)/N"}[form]
    said: dict[tuple[str, float], list[int]] = {}
    for rec, factor in zip(records, factors, strict=True):
        if factor != 1.0:
            label = (
                rec.unit
                if rec.denominator_unit.upper() in _NO_UNIT
                else f"{rec.unit} over {rec.denominator_unit}"
            )
            said.setdefault((label, factor), []).append(rec.index)
    return [
        f"FRF unit {label} converted to {si} (x {factor:.6g}) in record{'s' if len(numbers) > 1 else ''} "
        f"{', '.join(f'#{i}' for i in numbers)}"
        for (label, factor), numbers in said.items()
    ]


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
