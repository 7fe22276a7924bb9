"""LabVIEW Measurement files (.lvm): the channels of each segment as time records.

What LabVIEW's "Write To Measurement File" writes, as text::

    LabVIEW Measurement
    Writer_Version  2
    Separator       Tab            (or Comma)
    Decimal_Separator  .           (or ,)
    X_Columns       No             (One: one time column; Multi: one before each channel)
    ***End_of_Header***

    Channels        3
    Samples         8192    8192    8192
    Y_Unit_Label    N       m/s^2   m/s^2
    Delta_X         0.000977        0.000977        0.000977
    ***End_of_Header***
    X_Value F       m_1     m_2     Comment
    <samples, one row per time step>

then, for a file appended to, more segments, each with its own header. Each segment is
one hit. The samples go on to the time record reader of ``csv_text`` (its ``Table``) as
rows of hit, time and the channels named with their unit labels (``F (N)``), so force
and response are picked, units applied and every hit checked as in a CSV file, and every
refusal there names the line of the .lvm file it is about.

The sample rate: ``--sample-rate`` if given; else the time column's (X_Columns One or
Multi), fitted over the first segment within its printed precision
(``daq/formats/axis.py``); else 1 / Delta_X. LabVIEW prints Delta_X with 6 decimals by
default, 1/1024 s as 0.000977: where that text allows exactly one whole number of hertz
(1024 Hz here) that rate is taken and a note says so.
"""

from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from daq.formats.axis import common_rate, fit_regular, printed_half_units, step_fits, whole_rate
from daq.formats.cells import split_line
from daq.formats.csv_text import Table, decode_line, header_name_unit, is_number_text
from daq.formats.errors import FormatError
from daq.formats.imported import MAX_IMPORT_BYTES, ImportedData, mtime_utc, one_line, open_checked, show_path
from daq.formats.line_ends import text_lines

SIGNATURE = "LabVIEW Measurement"
END_OF_HEADER = "***End_of_Header***"
SEPARATORS = {"tab": "\t", "comma": ","}
X_COLUMNS = ("no", "one", "multi")
#: Delta_X printed so coarsely that 1 / Delta_X is off by more than this fraction gets a note.
COARSE_STEP_FRACTION = 1e-5


@dataclasses.dataclass
class Segment:
    """One segment's header as read: its first line, channel names and units, Delta_X text."""

    line: int  # 1-based line of its first header row
    names: list[str]
    units: list[str]
    delta_x: list[str]
    data_start: int = 0  # 1-based line of its first sample row
    rows: int = 0  # sample rows read
    declared: int = 0  # samples its header's Samples row declares (0: not said)
    n_file: int = 0  # channels in the file, the empty ones (Samples 0) too
    keep: list[int] = dataclasses.field(default_factory=list)  # the channels holding samples


@dataclasses.dataclass
class Layout:
    """The file header's settings and the segments found by the first pass."""

    separator: str = "\t"
    decimal: str = "."
    x_columns: str = ""  # "" until the file header or the first sample row says
    segments: list[Segment] = dataclasses.field(default_factory=list)
    x_texts: list[str] = dataclasses.field(default_factory=list)  # the first segment's times, as printed
    file_header: dict[str, str] = dataclasses.field(default_factory=dict)
    last_line: int = 0  # the file's last line, when it has no line end and too few values
    notes: list[str] = dataclasses.field(default_factory=list)


def looks_like_lvm(head: bytes) -> bool:
    """``head`` (a file's first bytes) starts with LabVIEW's signature line."""
    return head.lstrip(b"\xef\xbb\xbf").startswith(SIGNATURE.encode())


#: A channel name that says it holds a spectrum, not a time record.
_SPECTRUM_NAME = re.compile(r"(?i)\b(fft|spectrum|psd|power spectr|auto ?spectr|frequency response)\b")


def read_lvm(
    path: Path,
    columns: str | None = None,
    force_unit: str | None = None,
    response_unit: str | None = None,
    max_bytes: int = MAX_IMPORT_BYTES,
    sample_rate_hz: float | None = None,
) -> ImportedData:
    """Read the hits of a LabVIEW Measurement file; force in N, response in m/s^2.

    columns: None, or the force and response channels, comma-separated, by name (the
        column headings row, with or without the unit) or 0-based channel index, e.g.
        "F,m_2" or "0,2"; None picks them as csv_text.read_csv does (by names or units,
        else the first two channels).
    force_unit, response_unit: override the channels' Y_Unit_Label (daq.formats.units).
    sample_rate_hz: the rate (Hz) to use instead of the file's (see the module docstring).
    Returns ImportedData (format "lvm"), one hit per segment, hits of shape
    (n_segments, n_samples). Any problem: FormatError, one line.
    """
    path = Path(path)
    name = show_path(path)
    with open_checked(path, max_bytes) as (handle, info):
        layout = _scan(name, text_lines(handle))
        header = _column_names(layout.segments[0])
        spectra = [h for h in header if _SPECTRUM_NAME.search(h)]
        if spectra:
            # LabVIEW's FFT VIs log a spectrum with X_Dimension still 'Time' (a new user's
            # cantilever file: "Acceleration (FFT - (RMS))" in dB, every 0.128 Hz).
            raise FormatError(
                f"{name} holds a spectrum ({spectra[0]}), not time records: a run needs the force and "
                "response as recorded in time, before any FFT; log the raw channels"
            )
        if len(header) < 2:
            raise FormatError(
                f"{name} has {len(header)} channel ({header[0]}); a run needs two, a force and a response"
            )
        rate, rate_note, rate_u_rel = _rate(name, layout, sample_rate_hz)
        table = Table(name, columns=_table_columns(name, columns, header), keep_time_text=True)
        # The times handed on are k / rate exactly: the run stores that rate, not a fit.
        table.stated_rate = (rate, "the LabVIEW file")
        handle.seek(0)
        # The rows handed on are longer than the file's (hit and time added): the file's
        # own size was checked above, so the table's running limit only guards growth.
        try:
            table.read(_rows(name, layout, header, rate, text_lines(handle)), 4 * max_bytes + (1 << 20))
            data = table.build(path, table.columns, force_unit, response_unit, mtime_utc(info))
        except FormatError as exc:
            raise FormatError(_said_of_channels(str(exc), layout, header)) from None
    details = dict(data.details)
    notes = [_channel_note(n, details.get("columns", [])) for n in details.get("notes", [])]
    notes = [n for n in notes if not n.startswith("sample rate ")]
    details["notes"] = ([rate_note] if rate_note else []) + layout.notes + notes
    details.pop("sample_rate_u_rel", None)  # the table's times are exact: what it saw is no doubt
    if rate_u_rel:
        details["sample_rate_u_rel"] = rate_u_rel
    details["lvm"] = {
        "segments": len(layout.segments),
        "channels": header,
        "x_columns": layout.x_columns,
        "header": {one_line(k)[:60]: one_line(v)[:200] for k, v in list(layout.file_header.items())[:32]},
    }
    return dataclasses.replace(data, format="lvm", details=details)


_TABLE_COLUMNS = re.compile(r"--columns ([^,\s]+),([^,\s]+),([^,\s]+) \(time, force, response\)")
_TABLE_HEADER = re.compile(r"no column (.*) in the header \(hit, time \(s\), (.*)\)")
_TABLE_CELL = re.compile(r"line (\d+) column (\d+):")


def _said_of_channels(message: str, layout: Layout, header: list[str]) -> str:
    """A refusal of the table reader, said of the .lvm: its columns counted in the file's
    cells (the table's start with hit and time) and its --columns as channels."""

    def columns(match: re.Match) -> str:
        # The table's columns are hit, time, then the channels: its index 2 is channel 0.
        force, response = (str(int(c) - 2) if c.isdigit() else c for c in match.group(2, 3))
        return f"--columns {force},{response} (force, response channels)"

    message = _TABLE_COLUMNS.sub(columns, message)
    message = _TABLE_HEADER.sub(r"no channel \1 (the channels: \2)", message)

    def cell(match: re.Match) -> str:
        channel = int(match.group(2)) - 3  # the table's columns: hit, time, the channels
        if not 0 <= channel < len(header):
            return match.group(0)
        column = 2 * channel + 2 if layout.x_columns == "multi" else channel + 2
        return f"line {match.group(1)} column {column} (channel {header[channel]!r}):"

    return _TABLE_CELL.sub(cell, message)


def _channel_note(note: str, picked: list[str]) -> str:
    """A table note about an ignored column, said of the .lvm's channels: the table's
    column indices count the hit and time columns the file does not have."""
    match = _IGNORED.match(note)
    if match is None or len(picked) < 2:
        return note
    force = header_name_unit(picked[1])[0]
    channel = header_name_unit(match.group(1))[0]
    return (
        f"channel {match.group(1)!r} ignored: a run holds one force and one response; give --columns "
        f"with the two channels you mean (names or 0-based channel indices), e.g. --columns {force},{channel}"
    )


_IGNORED = re.compile(r"column \d+ '(.*)' ignored: ")


def _scan(name: str, lines) -> Layout:
    """First pass: the file header's settings and each segment's header (one line refusal
    of anything that is no LabVIEW Measurement file)."""
    layout = Layout()
    state = "signature"
    segment: Segment | None = None
    rows: dict[str, list[str]] = {}
    for number, raw in enumerate(lines, start=1):
        text = decode_line(raw, number == 1)
        if state == "signature":
            if not text.strip():
                continue
            if not text.strip().startswith(SIGNATURE):
                raise FormatError(
                    f"{name} line {number}: no '{SIGNATURE}' line: not a LabVIEW measurement file"
                )
            state = "file header"
            continue
        stripped = text.strip()
        if state == "file header":
            if stripped.startswith(END_OF_HEADER):
                state = "between"
                continue
            key, _, value = stripped.partition("\t")
            if not value and "," in key:
                key, _, value = stripped.partition(",")
            layout.file_header[key.strip()] = value.strip()
            _setting(name, number, layout, key.strip().lower(), value.strip())
            continue
        cells = split_line(text, layout.separator)
        if not any(c.strip() for c in cells):  # "" or, as LabVIEW writes it, "\t" or ","
            continue
        first = cells[0].strip()
        if (
            state in ("between", "data")
            and (first and not _is_number(first, layout.decimal))
            and (state == "between" or first != "X_Value")
        ) and (state == "data" or first == "Channels" or not layout.segments):
            segment, rows = Segment(number, [], [], []), {}
            state = "segment header"
        if state == "segment header":
            if first.startswith(END_OF_HEADER):
                segment = _segment(name, segment, rows, layout.x_columns)  # type: ignore[arg-type]
                layout.segments.append(segment)
                state = "names"
                continue
            rows[first] = [c.strip() for c in cells[1:]]
            continue
        if state == "names" and first == "X_Value":
            names = [c.strip() for c in cells]
            _names_row(layout, segment, names)  # type: ignore[arg-type]
            continue
        if state in ("names", "data", "between"):
            if segment is None:
                raise FormatError(f"{name} line {number}: samples before any segment header")
            if state != "data":
                segment.data_start = number
                state = "data"
            if not layout.x_columns:  # no X_Columns row: an empty first cell is no time
                layout.x_columns = "no" if not first else "one"
            segment.rows += 1
            short = len(_values(cells, layout, segment.n_file)) < segment.n_file
            if short and not raw.endswith((b"\n", b"\r")):
                layout.last_line = number  # cut short mid-row: no sample
                segment.rows -= 1
                layout.notes.append(
                    f"line {number}, the last, is cut short ({len(cells)} cells, no line end): left out; "
                    "the file may be incomplete"
                )
            elif len(layout.segments) == 1 and layout.x_columns != "no":
                layout.x_texts.append(cells[0].strip())
    if state in ("signature", "file header"):
        raise FormatError(f"{name}: the file header has no '{END_OF_HEADER}' line: nothing after it to read")
    _drop_incomplete_last(name, layout)
    empty = next((s for s in layout.segments if not s.data_start or not s.rows), None)
    if not layout.segments or empty is not None:
        where = f" (line {empty.line})" if empty is not None else ""
        raise FormatError(f"{name}: a segment{where} has a header but no samples")
    first = layout.segments[0]
    for segment in layout.segments:
        if segment.declared and segment.rows < segment.declared:
            layout.notes.append(
                f"the segment at line {segment.line} holds {segment.rows} samples where its header declares "
                f"{segment.declared}: the file may be cut short"
            )
    for other in layout.segments[1:]:
        if other.names == [f"channel {k}" for k in other.keep]:  # no headings row of its own
            other.names = list(first.names)
        if other.keep != first.keep or other.names != first.names or other.delta_x[:1] != first.delta_x[:1]:
            raise FormatError(
                f"{name} line {other.line}: this segment's channels or Delta_X differ from the first "
                f"segment's (line {first.line}): one run holds one set of channels at one rate; "
                "save the segments as separate files"
            )
    return layout


def _setting(name: str, number: int, layout: Layout, key: str, value: str) -> None:
    """Apply one row of the file header that decides how the samples are written."""
    low = value.lower()
    if key == "separator":
        if low not in SEPARATORS:
            raise FormatError(f"{name} line {number}: Separator {value!r}: LabVIEW writes Tab or Comma")
        layout.separator = SEPARATORS[low]
    elif key == "decimal_separator":
        if value not in (".", ","):
            raise FormatError(f"{name} line {number}: Decimal_Separator {value!r}: expected '.' or ','")
        layout.decimal = value
    elif key == "x_columns":
        if low not in X_COLUMNS:
            raise FormatError(f"{name} line {number}: X_Columns {value!r}: expected No, One or Multi")
        layout.x_columns = low
    if layout.decimal == "," and layout.separator == ",":
        raise FormatError(f"{name} line {number}: both the separator and the decimal separator are ','")


def _segment(name: str, segment: Segment, rows: dict[str, list[str]], x_columns: str) -> Segment:
    """The segment's channels from its header rows, checked. With X_Columns Multi each
    channel's value stands in every other cell (an empty one under each time column);
    channels whose Samples are 0 (LabVIEW's unused "Untitled" channels) are left out."""
    channels_text = (rows.get("Channels") or [""])[0]
    if not channels_text.isdigit() or not 1 <= int(channels_text) <= 64:
        raise FormatError(
            f"{name} line {segment.line}: the segment header has no Channels row with a count 1-64"
        )
    n = int(channels_text)

    def per_channel(key: str) -> list[str]:
        values = rows.get(key, [])
        values = values[0::2] if x_columns == "multi" else values
        return ([v.strip() for v in values] + [""] * n)[:n]

    samples = per_channel("Samples")
    segment.n_file = n
    segment.keep = [k for k in range(n) if samples[k] != "0"]
    if not segment.keep:
        raise FormatError(f"{name} line {segment.line}: every channel of the segment declares 0 samples")
    counts = [int(samples[k]) for k in segment.keep if samples[k].isdigit()]
    segment.declared = max(counts, default=0)
    delta = [d for k, d in enumerate(per_channel("Delta_X")) if k in segment.keep and d]
    if len(set(delta)) > 1:
        raise FormatError(
            f"{name} line {segment.line}: the channels have different Delta_X ({', '.join(delta)}): "
            "one run holds channels sampled at one rate"
        )
    units = per_channel("Y_Unit_Label")
    segment.units = [units[k] for k in segment.keep]
    segment.delta_x = delta
    segment.names = [f"channel {k}" for k in segment.keep]
    return segment


def _drop_incomplete_last(name: str, layout: Layout) -> None:
    """Leave out a last segment that stops short of the samples the others hold and of
    those its header declares: a file saved while LabVIEW still appended."""
    if len(layout.segments) < 2:
        return
    last, others = layout.segments[-1], layout.segments[:-1]
    full = min(s.rows for s in others)
    if last.rows < full and (not last.declared or last.rows < last.declared):
        layout.segments.pop()
        layout.notes.append(
            f"the last segment (line {last.line}) holds {last.rows} samples where the others hold {full}: "
            "left out, the file was saved while it was written"
        )


def _names_row(layout: Layout, segment: Segment, cells: list[str]) -> None:
    """Take the channels' names from the column headings row (X_Value, names, Comment)."""
    n = segment.n_file
    names = cells[1 : 2 * n : 2] if layout.x_columns == "multi" else cells[1 : 1 + n]
    for index, k in enumerate(segment.keep):
        text = names[k].strip() if k < len(names) else ""
        if text and text != "Comment":
            segment.names[index] = text


def _column_names(segment: Segment) -> list[str]:
    """The table's column names for the channels: 'name (unit)', made safe for a header."""
    out = []
    for text, unit in zip(segment.names, segment.units, strict=True):
        text = text.replace(",", " ").replace("(", " ").replace(")", " ").strip() or "channel"
        out.append(f"{text} ({unit})" if unit else text)
    return out


def _table_columns(name: str, columns: str | None, header: list[str]) -> str | None:
    """The --columns text for the table: time, then the force and response channels given
    by name or 0-based channel index."""
    if columns is None:
        return None
    items = [item.strip() for item in columns.split(",")]
    if len(items) != 2 or not all(items):
        raise FormatError(
            f"{name}: --columns {one_line(columns)[:60]!r}: give two channels, force then response, "
            f"by name or 0-based channel index, e.g. --columns 0,1 (the channels: {', '.join(header)})"
        )
    out = []
    for item in items:
        if item.isascii() and item.isdigit():
            index = int(item) if len(item) <= 6 else 10**6
            if index >= len(header):
                raise FormatError(
                    f"{name}: channel index {item[:8]} is out of range (the file has "
                    f"{len(header)} channels, 0..{len(header) - 1})"
                )
            out.append(header[index])
        else:
            out.append(item)
    return ",".join(["time", *out])


def _rate(name: str, layout: Layout, given: float | None) -> tuple[float, str, float]:
    """(sample rate Hz, the note saying where it came from, its relative standard
    uncertainty where the printed Delta_X leaves it in doubt, else 0)."""
    step_text = (layout.segments[0].delta_x or [""])[0]
    step = _number(step_text, layout.decimal)
    texts = layout.x_texts
    if len(texts) >= 2:
        first = layout.segments[0].data_start
        bad = next((k for k, t in enumerate(texts) if not _is_number(t, layout.decimal)), None)
        if bad is not None:
            raise FormatError(f"{name} line {first + bad}: time {texts[bad][:40]!r} is not a number")
        values = np.array([_number(t, layout.decimal) for t in texts])
        steps = np.diff(values)
        if not np.all(steps > 0):
            bad = int(np.argmin(steps > 0)) + 1
            raise FormatError(f"{name} line {first + bad}: the time column does not increase there")
        fit = fit_regular(values, printed_half_units([t.replace(",", ".") for t in texts]))
        if fit.bad is not None:
            raise FormatError(
                f"{name} line {first + fit.bad}: the time column steps unevenly there (a dropped sample or "
                f"a jump; the step is {float(np.median(steps)):.6g} s elsewhere): a run holds samples at one "
                "rate"
            )
        if given is None:
            return 1.0 / fit.step, f"sample rate {1.0 / fit.step:.8g} Hz fitted to the time column", 0.0
        half_units = printed_half_units([t.replace(",", ".") for t in texts])
        if not step_fits(values, half_units, 1.0 / given):
            raise FormatError(
                f"{name}: --sample-rate gives {given:g} Hz, but the time column steps at "
                f"{1.0 / fit.step:.6g} Hz, more than its printed precision allows; correct or remove one"
            )
        return float(given), f"sample rate {given:g} Hz from --sample-rate", 0.0
    if given is not None:
        if step_text and math.isfinite(step) and step > 0:
            half = float(printed_half_units([step_text.replace(",", ".")])[0])
            if abs(1.0 / given - step) > half * (1 + 1e-9):
                raise FormatError(
                    f"{name}: --sample-rate gives {given:g} Hz, but Delta_X {step_text} s allows only "
                    f"{1 / (step + half):.6g} to {1 / (step - half):.6g} Hz; correct or remove one"
                )
        said = f" (the file's Delta_X is {step_text})" if step_text else ""
        return float(given), f"sample rate {given:g} Hz from --sample-rate{said}", 0.0
    if not step_text:
        raise FormatError(
            f"{name}: the segment header (line {layout.segments[0].line}) has no Delta_X and the file "
            "no time column, so its sample rate is unknown; give --sample-rate HZ"
        )
    if not (math.isfinite(step) and step > 0):
        raise FormatError(f"{name}: Delta_X {step_text!r} is no time step above 0 s; give --sample-rate HZ")
    half = float(printed_half_units([step_text.replace(",", ".")])[0])
    exact = round(1.0 / step)
    if abs(1.0 / step - exact) <= 1e-9 / step:  # 3.906250E-5: 25600 Hz exactly
        return float(exact), f"sample rate {exact} Hz = 1 / Delta_X ({step_text} s)", 0.0
    whole = whole_rate(step, half)
    if whole is not None:
        return (
            float(whole),
            f"sample rate {whole} Hz: {_allows(step_text, step, half)}, the one whole rate among "
            f"them{_ANOTHER}",
            0.0,
        )
    common = common_rate(step, half)
    if common is not None:
        return (
            common,
            f"sample rate {common:g} Hz: {_allows(step_text, step, half)}, the one rate among them that "
            f"acquisition hardware runs at{_ANOTHER}",
            0.0,
        )
    if half / step > COARSE_STEP_FRACTION:
        return (
            1.0 / step,
            f"sample rate {1.0 / step:.8g} Hz = 1 / Delta_X ({step_text} s), known only to "
            f"+-{100 * half / step:.2g} % from its printed digits; give --sample-rate if you know it",
            half / step / math.sqrt(3.0),
        )
    return 1.0 / step, f"sample rate {1.0 / step:.8g} Hz = 1 / Delta_X ({step_text} s)", 0.0


_ANOTHER = "; give --sample-rate if the instrument ran at another"


def _allows(text: str, step: float, half: float) -> str:
    """What a printed Delta_X allows: "Delta_X 0.000977 s, printed to 3 digits, allows
    1023.02 to 1024.07 Hz"."""
    low, high = 1 / (step + half), 1 / (step - half)
    return f"Delta_X {text} s, printed to {_digits(text)} digits, allows {low:.6g} to {high:.6g} Hz"


def _rows(name: str, layout: Layout, header: list[str], rate: float, lines) -> Iterator[bytes]:
    """Second pass: each line of the file as the table reads it, its number kept: the
    header row (hit, time and the channels) where the first segment's samples begin,
    each sample row as hit (segments counted from 1), time, channel values; every other
    line blank. A last row without a line end keeps that, so the table notes it."""
    starts = {s.data_start: k for k, s in enumerate(layout.segments)}
    stop = layout.segments[-1].data_start + layout.segments[-1].rows  # a segment left out
    hit, k, segment = -1, 0, layout.segments[0]
    for number, raw in enumerate(lines, start=1):
        if number == layout.segments[0].data_start - 1:  # the headings row, or the header's end
            yield ("hit,time (s)," + ",".join(header) + "\n").encode()
            continue
        if number in starts:
            hit, k = starts[number], 0
            segment = layout.segments[hit]
        inside = hit >= 0 and number < stop and number != layout.last_line
        cells = split_line(decode_line(raw, number == 1), layout.separator) if inside else [""]
        if not any(cells) or not _is_sample_row(cells, layout):
            yield b"\n"
            continue
        values = _values(cells, layout, segment.n_file)
        if len(values) < segment.n_file:
            raise FormatError(f"{name} line {number}: {len(values)} of the {segment.n_file} channels' values")
        values = [values[c] for c in segment.keep]  # split_line strips each cell
        values = [v.replace(",", ".") for v in values] if layout.decimal == "," else values
        end = "\n" if raw.endswith((b"\n", b"\r")) else ""
        yield f"{hit + 1},{k / rate!r},{','.join(values)}{end}".encode()
        k += 1


def _values(cells: list[str], layout: Layout, n: int) -> list[str]:
    """The channels' cells of a sample row (at most n), without its time cells."""
    if layout.x_columns == "multi":
        return cells[1 : 2 * n : 2]
    if layout.x_columns == "no" and cells[0].strip() == "":  # LabVIEW's empty X_Value cell
        return cells[1 : 1 + n]
    if layout.x_columns == "no":
        return cells[:n]
    return cells[1 : 1 + n]


def _is_sample_row(cells: list[str], layout: Layout) -> bool:
    """A sample row (its first cell a number, or empty where X_Columns is No), not a
    segment's header row."""
    return (not cells[0] and layout.x_columns == "no") or _is_number(cells[0], layout.decimal)


def _is_number(text: str, decimal: str) -> bool:
    return is_number_text(text.replace(",", ".") if decimal == "," else text)


def _number(text: str, decimal: str) -> float:
    try:
        return float(text.replace(",", ".") if decimal == "," else text)
    except ValueError:
        return math.nan


def _digits(text: str) -> int:
    """Significant digits printed in a number's text ('0.000977' -> 3)."""
    mantissa = text.lower().split("e")[0].replace(",", ".").lstrip("+-").replace(".", "").lstrip("0")
    return max(len(mantissa), 1)
