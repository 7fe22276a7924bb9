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

What instruments and programs write is read too: ``;`` or tab separators with decimal
commas (``0,001;1,0;2,0``), comment lines (``#``, ``%``, ``//``), a header row or none,
units in the header (``Time (s)``, ``Force [N]``, ``acc (g)``), and a time column
printed with a few significant digits (daq/formats/axis.py decides whether it is regular).
"""

from __future__ import annotations

import math
import os
import re
from array import array
from pathlib import Path
from typing import IO

import numpy as np

from daq.formats.axis import fit_regular, printed_half_units, step_fits
from daq.formats.cells import outside_quotes, split_line
from daq.formats.errors import FormatError, count
from daq.formats.impacts import cut_note, find_cut
from daq.formats.imported import (
    MAX_IMPORT_BYTES,
    MAX_IMPORT_HITS,
    SAME_AXIS_REMEDY,
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
from daq.formats.line_ends import text_lines
from daq.formats.units import (
    TIME_UNITS,
    accepted_forms,
    clean_label,
    not_acceleration,
    parse_unit,
    spelled_as,
)
from daq.store.model import Run

AXIS_TOLERANCE = 1e-9  # kept for callers; hits now share one axis within the time rule
COMPLEX_COLUMNS = ("force_re", "force_im", "response_re", "response_im")
#: The time "column" of a file of force and response alone, read with a stated rate: its
#: times are k / rate, made here.
NO_TIME = -1
#: A time step this many times the median one is a gap (a sample dropped), not jitter.
GAP_STEPS = 1.5
COMMENT_MARKS = ("#", "%", "//")
# Header names (lower case, without their unit) that say which column is the force and
# which the response, whatever their order (a header unit in N or g says so too). Only
# acceleration units are read for a response, so velocity and displacement are not here.
KIND_NAMES = {
    "force": frozenset({"force", "f", "hammer", "excitation", "input", "load"}),
    "response": frozenset(
        {"response", "resp", "acc", "accel", "acceleration", "accelerometer", "a", "output"}
    ),
}
FREQUENCY_NAMES = ("freq", "frequency", "frequencies", "frequency_hz", "freq_hz", "hz")
DEFAULT_UNITS = {"force": "N", "response": "m/s^2"}
# A time column printed so that half a unit of its last digit is more than this fraction
# of the step leaves its fitted rate uncertain enough to say so (3 digits at 4 kHz: 20 %).
COARSE_FRACTION = 0.01
# ... and is said only where the rate the printed times allow spreads by more than this
# fraction of it (0.01 %: a mode's frequency off by as much, far below its damping's say).
COARSE_RATE_SPREAD = 1e-4
_REJECTED = re.compile(r"rejected hit ([0-9]{1,6}):(.*)")
# "Force [N]", "acc (g)", "Time (s)", "a / mV": a name and the unit in brackets.
_HEADER_UNIT = re.compile(r"(.*?)\s*(?:\[([^\]]*)\]|\(([^)]*)\))\s*")
_DECIMAL_COMMA = re.compile(r"[-+]?[0-9]*,[0-9]+(?:[eE][-+]?[0-9]+)?")
_THOUSANDS_POINT = re.compile(r"[-+]?[1-9][0-9]{0,2}(?:\.[0-9]{3})+")
_POINT_NUMBER = re.compile(r"[-+]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][-+]?[0-9]+)?")


def choose_delimiter(line: str) -> str | None:
    """The cell delimiter of a text table's line: ";" or tab where the line holds one,
    else "," unless the commas are decimal commas between runs of spaces ("0,001 1,0 2",
    "0 2,46e-07 0,025": every cell a number, one with a decimal comma; the table reader
    refuses points and commas mixed), else None (runs of whitespace). What is inside
    quotes is no delimiter ("Force; N" is one cell)."""
    line = outside_quotes(line)
    if ";" in line:
        return ";"
    if "\t" in line:
        return "\t"
    if "," in line:
        cells = line.split()
        if len(cells) >= 2 and all(_DECIMAL_COMMA.fullmatch(c) or _POINT_NUMBER.fullmatch(c) for c in cells):
            return None
        return ","
    return None


#: What a line's delimiter is called in a message (None: runs of whitespace).
_DELIMITER_NAMES = {",": "commas", ";": "semicolons", "\t": "tabs", None: "spaces"}

#: How far the preamble scan looks: lines, and bytes of one line.
HEAD_LINES = 200
HEAD_LINE_BYTES = 4096


def decode_line(raw: bytes, first: bool = False) -> str:
    """A line of a text export: UTF-8 (a BOM on the first line dropped), else Latin-1, which
    SignalCalc and other Windows programs write ("m/s²" with the byte 0xB2)."""
    try:
        text = raw.decode("utf-8-sig" if first else "utf-8")
    except UnicodeDecodeError:
        text = raw.decode("latin-1")
    return text.rstrip("\r\n")


def split_cells(line: str, delimiter: str | None = None) -> tuple[list[str], str | None]:
    """(cells, delimiter) of a line: ";", tab or "," (found in the line when not given),
    else runs of whitespace; cells stripped, quoted cells without their quotes
    (daq/formats/cells.py)."""
    if delimiter is None:
        delimiter = choose_delimiter(line)
    return split_line(line, delimiter), delimiter


def is_number_text(cell: str) -> bool:
    """A cell that any writer means as a number: quotes, a decimal comma, a Unicode minus
    or a Fortran D exponent allowed (the table reader may still refuse it as written)."""
    text = cell.strip().strip("\"'").replace("\u2212", "-")
    if text.count(",") == 1:
        text = text.replace(",", ".")
    text = re.sub(r"(?<=[0-9.])[dD](?=[-+]?[0-9])", "e", text)
    try:
        float(text)
    except ValueError:
        return False
    return True


def all_numbers(cells: list[str]) -> bool:
    """Every cell a number, but for empty cells after the last (a trailing delimiter)."""
    while cells and not cells[-1]:
        cells = cells[:-1]
    return bool(cells) and all(is_number_text(c) for c in cells)


def _metadata(line: str) -> tuple[str, str] | None:
    """(key, value) of a preamble line "key: value" or "key<TAB>value", else None. A line
    that is one quoted string (a title, or "key: value" in quotes, as PULSE writes its
    preamble) is read inside its quotes, a title as ("title", text)."""
    text = line.strip()
    if len(text) >= 2 and text[0] == text[-1] == '"' and '"' not in text[1:-1]:
        inner = text[1:-1].strip()
        return (_metadata(inner) or ("title", inner)) if inner else None
    if "\t" in line:
        cells = [c.strip() for c in line.split("\t")]
        if len([c for c in cells if c]) <= 2 and cells[0]:
            value = " ".join(c for c in cells[1:] if c)
            return cells[0].rstrip(":").strip(), value.removeprefix(":").strip()
        return None
    key, colon, value = line.partition(":")
    if colon and key.strip():
        return key.strip(), value.strip()
    return None


def _metadata_row(line: str, width: int) -> tuple[str, str] | None:
    """(key, value) of a preamble line: a ``key,value`` row of a delimited table (``,`` or
    ``;``, quoted or not, as oscilloscopes and acquisition programs write their settings
    above the data: ``"Sample rate","2048 Hz"``) of two filled cells, fewer than the
    ``width`` filled cells of a data row (or a sample rate: RATE_KEYS), its key no number
    and without a colon, neither cell with a unit; else _metadata's forms."""
    cells, delimiter = split_cells(line)
    filled = [c for c in cells if c]
    if delimiter in (",", ";") and len(filled) == 2 and cells[0] and ":" not in cells[0]:
        key, value = filled
        # As wide as the data, the row may be the header, unless it states the sample rate
        # (a file of force and response alone: "Sample rate,2048" above "Force,Acc"); a
        # name with a unit ("Force [kN]") is a column's, never a key.
        states_rate = _is_rate_key(key) and _RATE_VALUE.fullmatch(value) is not None
        named = any(header_name_unit(c)[1] is not None for c in filled)
        if (len(filled) < width or states_rate) and not is_number_text(key) and not named:
            return key, value
    return _metadata(line)


def _head_lines(handle: IO[bytes]) -> tuple[list[bytes], bool]:
    """The first HEAD_LINES raw lines (each complete), and whether the file ended among them."""
    head: list[bytes] = []
    for _ in range(HEAD_LINES):
        raw = handle.readline(HEAD_LINE_BYTES)
        if not raw:
            return head, True
        if not raw.endswith(b"\n"):
            raw += handle.readline()  # complete a long line: line numbers must stay right
            head.append(raw)
            return head, False
        head.append(raw)
    return head, False


_PLAIN_NAME = re.compile(r"[A-Za-z0-9_.+-]+")


def read_csv(
    path: Path,
    columns: str | None = None,
    force_unit: str | None = None,
    response_unit: str | None = None,
    max_bytes: int = MAX_IMPORT_BYTES,
    sample_rate_hz: float | None = None,
) -> ImportedData:
    """Read hits from a delimited text file; force in N and response in m/s^2 after conversion.

    columns: None or three header names / 0-based indices, comma-separated, e.g. "t,F,a"
        or "0,2,1". None: the force and response columns by their header names or units
        where these say which is which (KIND_NAMES; one of each, else nothing is guessed),
        the time column the one named "time" or the first; else the first three columns
        other than ``hit``: time, force, response. Taken out of position order, a note
        says so.
    force_unit, response_unit: units of those columns (see :mod:`daq.formats.units`); None
        takes the header's unit (``Force [N]``), else N and m/s^2. Given, they win over
        the header. details["units_from"] says which was used.
    sample_rate_hz: the rate (Hz) to store instead of the one fitted to the time column
        (--sample-rate); wins over a preamble's. FormatError if the printed times do not
        allow it (daq/formats/axis.py, step_fits).
    Returns ImportedData with hits of shape (n_hits, n_samples). Any problem: FormatError.
    """
    path = Path(path)
    name = show_path(path)
    try:
        for unit, quantity in ((force_unit, "force"), (response_unit, "response")):
            if unit is not None:
                parse_unit(unit, quantity)
    except FormatError as exc:
        raise FormatError(f"{name}: {exc}") from None
    with open_checked(path, max_bytes) as (handle, info):
        table = Table(name, columns=columns, keep_time_text=True)
        if sample_rate_hz is not None:
            # Before the rows: a file of force and response alone takes its times from it.
            table.stated_rate = (float(sample_rate_hz), "--sample-rate")
        # text_lines: a file whose lines end in CR alone (classic Mac OS) is read line by line too.
        table.read(_without_preamble(table, text_lines(handle)), max_bytes)
    return table.build(path, columns, force_unit, response_unit, mtime_utc(info))


#: Preamble keys (lower case, letters only) that state the sample rate.
RATE_KEYS = ("samplerate", "samplingrate", "samplingfrequency", "samplefrequency", "fs", "samplespersecond")
_RATE_VALUE = re.compile(r"([0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)\s*(hz|khz|s/s|sps)?", re.I)


def preamble_lines(texts: list[str]) -> list[tuple[int, tuple[str, str]]]:
    """(index, (key, value)) of each line of a preamble of metadata lines ("key: value",
    "key<TAB>value") among ``texts`` (a text file's first lines, decoded), before its
    header row or, with none, before its numbers (a row of 2 numbers or more); [] without
    one. Blank lines and comments may come between; indices count from 0."""
    rows: list[int] = []
    width = 0
    for index, text in enumerate(texts):
        stripped = text.strip()
        if not stripped or stripped.startswith(COMMENT_MARKS):
            continue
        cells, _ = split_cells(stripped)
        if all_numbers(cells):
            width = len([c for c in cells if c])
            break
        rows.append(index)
    # The row before the data is the header unless it is a metadata line too; a row that
    # is no metadata line before it (prose, a units row) leaves the table reader to decide.
    metas = [(i, _metadata_row(texts[i].strip(" \r\n"), width)) for i in rows]
    if metas and _names_row(texts[metas[-1][0]], width):
        # "Force [N]<TAB>Accel [g]" above two columns of numbers is their header, though it
        # reads as "key<TAB>value" too: skipped, its units were lost (g stored as m/s^2).
        metas[-1] = (metas[-1][0], None)
    # Metadata lines right before the numbers: no header at all.
    body = metas if metas and metas[-1][1] is not None else metas[:-1]
    if width >= 2 and body and len(body) <= 64 and all(meta is not None for _, meta in body):
        return body  # type: ignore[return-value]
    return []


def _names_row(line: str, width: int) -> bool:
    """A delimited row of ``width`` filled cells, none a number, one or more with a unit
    ("Force [N]<TAB>Accel [g]", "CH1: Force [N]<TAB>CH2: Accel [g]"), its first no sample-rate
    key: the names of the data's columns. "Operator<TAB>A. Smith", "Sample rate<TAB>2048 Hz"
    and "Input<TAB>Hammer" stay preamble lines."""
    cells, delimiter = split_cells(line.strip())
    filled = [c for c in cells if c]
    if delimiter is None or not 0 < len(filled) == width or _is_rate_key(filled[0].partition("[")[0]):
        return False
    with_unit = any(header_name_unit(c)[1] is not None for c in filled)
    return with_unit and not any(is_number_text(c) for c in filled)


def _is_rate_key(key: str) -> bool:
    """A preamble key stating the sample rate (RATE_KEYS, letters only, any case)."""
    return re.sub("[^a-z]", "", key.lower()) in RATE_KEYS


def _without_preamble(table: Table, handle):
    """The lines of ``handle`` for the table reader, with a preamble of metadata lines
    before the header row left blank (each line keeps its number); the preamble's
    sample rate, if it states one, goes to table.stated_rate. Without such a preamble
    the lines as they are: the table reader alone decides."""
    head, _ = _head_lines(handle)
    texts = [decode_line(raw, index == 0) for index, raw in enumerate(head)]
    preamble = preamble_lines(texts)
    skipped = {index for index, _ in preamble}
    table.preamble = [(index + 1, key, value) for index, (key, value) in preamble]
    for line, key, value in table.preamble:
        rate = _RATE_VALUE.fullmatch(value.strip())
        if _is_rate_key(key) and rate is not None:
            hz = float(rate.group(1)) * (1000.0 if (rate.group(2) or "").lower() == "khz" else 1.0)
            if math.isfinite(hz) and hz > 0 and table.stated_rate is None:  # --sample-rate wins
                table.stated_rate = (hz, f"line {line} ({one_line(key)[:40]}: {one_line(value)[:40]})")
                break
    for index, raw in enumerate(head):
        yield b"\n" if index in skipped else raw
    yield from handle


def join_units(cells: list[str]) -> list[str]:
    """The cells of a header split at whitespace, each unit in brackets joined to the name
    before it: ["Time", "(s)", "acc", "[m", "/", "s^2]"] -> ["Time (s)", "acc [m / s^2]"].
    Split at its spaces, the header of a whitespace table ("Time (s) Force (N)") would
    count a column per unit, and a one-column "Time (s)" two."""
    out: list[str] = []
    closing = ""
    for cell in cells:
        if closing or (out and cell.startswith(("(", "["))):  # "" is `in` every string
            closing = closing or (")" if cell[0] == "(" else "]")
            out[-1] += " " + cell
            if cell.endswith(closing):
                closing = ""
            continue
        out.append(cell)
    return out


def header_name_unit(cell: str) -> tuple[str, str | None]:
    """("Force", "N") for "Force [N]" or "Force (N)"; ("FRF Real", "(in/s^2)/lbf") for a
    unit with parentheses inside ("FRF Real ((in/s²)/lbf)", as Test.Lab writes it);
    (cell, None) without a unit."""
    match = _HEADER_UNIT.fullmatch(cell)
    if match is not None and match.group(1):
        unit = match.group(2) if match.group(2) is not None else match.group(3)
        return match.group(1).strip(), clean_label(unit) or None
    nested = _nested_unit(cell.rstrip())
    if nested is None:
        return cell, None
    name, unit = nested
    return name, clean_label(unit) or None


def _nested_unit(cell: str) -> tuple[str, str] | None:
    """(name, unit) of a cell ending in a parenthesised unit that holds parentheses itself,
    "FRF Real ((in/s²)/lbf)" -> ("FRF Real", "(in/s²)/lbf"); None otherwise."""
    if not cell.endswith(")"):
        return None
    depth = 0
    for index in range(len(cell) - 1, -1, -1):
        depth += {")": 1, "(": -1}.get(cell[index], 0)
        if depth == 0:
            name = cell[:index].strip()
            return (name, cell[index + 1 : -1]) if name else None
    return None


def is_frequency_name(name: str, unit: str | None) -> bool:
    """A header cell that names a frequency column: "freq", "Frequency (Hz)", "f [kHz]"...
    ("f" alone is no frequency here: in a time record's header it is the force)."""
    return name.strip().lower() in FREQUENCY_NAMES or (unit or "").lower() in ("hz", "khz")


class Table:
    """The numbers of a delimited file, kept flat (array of float64) with each row's line number.

    columns: the --columns text (for finding the time column early, so that its printed
        text is kept for the time rule); keep_time_text: keep it at all (time records).
    """

    def __init__(self, name: str, columns: str | None = None, keep_time_text: bool = False) -> None:
        self.name = name
        self.columns = columns
        self.keep_time_text = keep_time_text
        self.comments: dict[str, str] = {}
        self.rejected: dict[int, str] = {}
        self.header: list[str] | None = None  # the cells as written
        self.names: list[str] = []  # the cells without their units
        self.units: list[str | None] = []  # the units in the header, None where none
        self.units_row: int | None = None  # the line of a units row under the header
        self.from_units_row: set[int] = set()  # the columns whose unit it gave
        self.delimiter: str | None = None  # None: runs of whitespace
        self.decimal_comma = False
        # The first data line with a decimal comma, and the first cell that may hold a
        # thousands point (line, text), where the delimiter leaves both (_mixed_decimals).
        self.first_comma_line: int | None = None
        self.first_grouped: tuple[int, str] | None = None
        self.n_cols = 0
        # Columns empty on every line, header cell included (a delimiter at the end of every
        # line): no columns at all. Found at the first data row, holding 0.0 in ``values``.
        self.empty_cols: frozenset[int] = frozenset()
        self.first_data_line = 0
        self.values = array("d")
        self.lines = array("q")
        self.picked: list[int] | None = None
        # How the columns were taken when not by position (their header names or units).
        self.picked_note = ""
        self.hit_col: int | None = None
        self.complex_mode = False
        self.time_texts: list[str] = []
        self.unended: int | None = None  # the last line, a data row, when it has no line end
        self.preamble: list[tuple[int, str, str]] = []  # (line, key, value) left out before the header
        # A sample rate (Hz) stated outside the time column, and where: used when the
        # printed times allow it, else refused.
        self.stated_rate: tuple[float, str] | None = None

    def read(self, handle, max_bytes: int) -> None:
        total = 0
        number, raw = 0, b""
        for number, raw in enumerate(handle, start=1):
            total += len(raw)
            if total > max_bytes:  # the file grew after it was checked
                raise FormatError(f"{self.name} is more than the import limit of {max_bytes} bytes")
            # Not UTF-8: Latin-1, as Excel on Windows saves "Accel (m/s²)" (decode_line).
            line = decode_line(raw, number == 1)
            stripped = line.strip()
            if not stripped:
                continue
            mark = next((m for m in COMMENT_MARKS if stripped.startswith(m)), None)
            if mark is not None:
                self._comment(stripped[len(mark) :])
                continue
            try:
                self._row(line, number)
            except FormatError as exc:
                if raw.endswith((b"\n", b"\r")) or not self._cut_into_cells(line):
                    raise
                # Only the file's last line can lack a line end: a copy or download cut short.
                raise FormatError(
                    f"{exc}; it is the file's last line and has no line end: the file looks cut short "
                    "(compare its end with the source)"
                ) from None
        if not self.lines:
            raise FormatError(f"{self.name} holds no data rows")
        # A copy or download cut short ends mid-line, and its last number may be cut too
        # (0.06612 for -0.066120503): it reads as a number all the same. Many writers end
        # the last line without a line end, so it is told, not refused.
        if not raw.endswith((b"\n", b"\r")) and self.lines[-1] == number:
            self.unended = number

    def _cut_into_cells(self, line: str) -> bool:
        """Whether ``line`` reads as a row cut short: fewer cells than the rows above, or its
        last cell empty (a footer, an extra cell or a word in a cell is no cut)."""
        if self.n_cols == 0 or (self.delimiter is None and not line.strip()):
            return False
        cells = self._split(line)
        if len(cells) > self.n_cols:
            return False
        if len(cells) < self.n_cols:
            filled = [cell for cell in cells if cell.strip()]
            return all(self._is_number(cell) for cell in filled)
        return not cells[-1].strip()

    def unended_note(self) -> list[str]:
        """The note on a last data row with no line end, or none."""
        if self.unended is None:
            return []
        return [
            f"line {self.unended}, the last, has no line end: the file may be cut short and that row "
            "incomplete; compare its end with the source"
        ]

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
        # Quoted cells ("0","-0.06") lose their quotes: a spreadsheet's quotes are no part
        # of the number.
        return split_line(line, self.delimiter)

    def _number(self, cell: str) -> float:
        # With ";", tab or spaces between the cells, a comma can only be a decimal comma.
        if self.delimiter != "," and "," in cell:
            self.decimal_comma = True
            cell = cell.replace(",", ".", 1) if cell.count(",") == 1 else cell
        return float(cell)

    def _row(self, line: str, number: int) -> None:
        if self.n_cols == 0:
            self.delimiter = choose_delimiter(line)
            cells = self._split(line)
            self.n_cols = len(cells)
            _refuse_complex(self.name, number, cells)  # else a row of them reads as a header
            # Empty cells do not make a header: "0,1,2," is a row of numbers and a delimiter.
            filled = [cell for cell in cells if cell]
            if not filled or not all(self._is_number(cell) for cell in filled):
                if self.delimiter is None:  # "Time (s) Force [N]": a unit is no column of its own
                    cells = join_units(cells)
                    self.n_cols = len(cells)
                self.header = [cell.strip().strip('"').strip("'") for cell in cells]
                pairs = [header_name_unit(cell) for cell in self.header]
                self.names = [n for n, _ in pairs]
                self.units = [u for _, u in pairs]
                return
        cells = self._split(line)
        if len(cells) != self.n_cols:
            other = choose_delimiter(line)
            differs = (
                f" (its cells are separated by {_DELIMITER_NAMES.get(other, repr(other))}, the lines above "
                f"by {_DELIMITER_NAMES.get(self.delimiter, repr(self.delimiter))})"
                if other != self.delimiter and len(split_line(line, other)) == self.n_cols
                else ""
            )
            raise FormatError(
                f"{self.name} line {number}: {count(len(cells), 'column')}, expected {self.n_cols}{differs}"
            )
        if self.header is not None and not self.values and self.units_row is None:
            units = _units_row(cells)
            if units is not None:
                # A row of units under the names (LabVIEW, DEWESoft, Excel): each fills the
                # unit its column's name lacks; a unit in the name wins.
                self.from_units_row = {
                    c for c, (own, row) in enumerate(zip(self.units, units, strict=True)) if row and not own
                }
                self.units = [own or row for own, row in zip(self.units, units, strict=True)]
                self.units_row = number
                return
        if not self.lines:
            self._first_data_row(cells, number)
        if self.keep_time_text and self.picked is None:
            self.complex_mode = self.columns is None and all(
                self.find(n) is not None for n in COMPLEX_COLUMNS
            )
            self.picked, self.hit_col = self._pick(self.columns, self.complex_mode)
        if self.empty_cols:
            cells = self._fill_empty(cells)
        for col, cell in enumerate(cells):
            try:
                value = self._number(cell)
            except ValueError:
                _refuse_complex(self.name, number, [cell])
                if self.header is not None and not self.values and not any(map(self._is_number, cells)):
                    raise FormatError(
                        f"{self.name} line {number}: a row of words under the header is read as units "
                        f"only where each is a unit of time, force, acceleration or voltage, and "
                        f"{_show(next(c for c in cells if c.strip() and _units_row([c]) is None))} is none; "
                        "write the units in the header instead, e.g. Time (s),Force (N),Accel (g)"
                    ) from None
                raise FormatError(
                    f"{self.name} line {number} column {col + 1}: {_show(cell)} is not a number"
                ) from None
            if not math.isfinite(value):
                raise FormatError(f"{self.name} line {number} column {col + 1}: {_show(cell)} is not finite")
            self.values.append(value)
        if self.delimiter != ",":
            self._mixed_decimals(cells, number)
        if self.picked is not None and self.picked[0] != NO_TIME:
            self.time_texts.append(cells[self.picked[0]])
        self.lines.append(number)

    def _first_data_row(self, cells: list[str], number: int) -> None:
        """Note the columns that are no columns: empty in this, the first data row, with no
        name or unit in the header (or no header). Every later row must leave them empty."""
        self.first_data_line = number
        names = self.names or [""] * len(cells)
        units = self.units or [None] * len(cells)
        self.empty_cols = frozenset(
            c for c, cell in enumerate(cells) if not cell and not names[c].strip() and units[c] is None
        )

    def _fill_empty(self, cells: list[str]) -> list[str]:
        """``cells`` with a "0" for each empty column's cell (it holds 0.0 in ``values``);
        a cell there that is not empty makes the column one with empty cells, refused
        where it was first empty, as any empty cell is."""
        cells = list(cells)
        for col in self.empty_cols:
            if cells[col]:
                raise FormatError(
                    f"{self.name} line {self.first_data_line} column {col + 1}: '' is not a number"
                )
            cells[col] = "0"
        return cells

    def empty_note(self) -> list[str]:
        """The note on the columns read as none (empty on every line), or none."""
        if not self.empty_cols:
            return []
        cols = sorted(self.empty_cols)
        several = len(cols) > 1
        trailing = cols == list(range(self.n_cols - len(cols), self.n_cols))
        return [
            f"column{'s' if several else ''} {', '.join(str(c + 1) for c in cols)} "
            f"{'are' if several else 'is'} empty on every line"
            + (" (a delimiter at the end of every line)" if trailing else "")
            + f": read without {'them' if several else 'it'}"
        ]

    def drop_empty_columns(self) -> list[str]:
        """Take the empty columns (empty_cols) out of the table, so that its columns are
        counted without them; the note saying so, or none."""
        note = self.empty_note()
        if note:
            keep = [c for c in range(self.n_cols) if c not in self.empty_cols]
            self.values = array("d", self.data()[:, keep].ravel().tolist())
            if self.header is not None:
                self.header = [self.header[c] for c in keep]
                self.names = [self.names[c] for c in keep]
                self.units = [self.units[c] for c in keep]
            self.n_cols, self.empty_cols = len(keep), frozenset()
        return note

    def _mixed_decimals(self, cells: list[str], number: int) -> None:
        """Refuse a cell like "1.500" in a file that writes decimal commas: where commas
        are decimal, a point between groups of three digits is a thousands point (1500),
        and read as a decimal point it would silently be 1.5. Points that cannot be
        thousands points ("1.953125e-05", "0.5") are decimal points."""
        if self.first_comma_line is None and any("," in c for c in cells):
            self.first_comma_line = number
        if self.first_grouped is None:
            grouped = next((c for c in cells if _THOUSANDS_POINT.fullmatch(c)), None)
            if grouped is not None:
                self.first_grouped = (number, grouped)
        if self.first_comma_line is not None and self.first_grouped is not None:
            line, cell = self.first_grouped
            whole = cell.replace(".", "")
            decimal = cell.lstrip("+-").rstrip("0").rstrip(".") or "0"
            raise FormatError(
                f"{self.name} line {line}: {_show(cell)} could mean {whole} (a thousands point) or "
                f"{'-' if cell.startswith('-') else ''}{decimal}, and the file writes decimal commas "
                f"(line {self.first_comma_line}); write the numbers without thousands points"
            )

    def _is_number(self, cell: str) -> bool:
        try:
            self._number(cell)
        except ValueError:
            return False
        return True

    def find(self, name: str) -> int | None:
        """Index of column ``name``: the header cell as written, or its name without the unit;
        a unique exact match first, else a unique case-insensitive one; None where two
        columns share the name (``Time (s),force,force,response`` says no one force column,
        and the columns are taken in position)."""
        if self.header is None:
            return None
        for cells in (self.header, self.names):
            exact = [i for i, h in enumerate(cells) if h == name]
            if len(exact) > 1:
                return None
            if exact:
                return exact[0]
        for cells in (self.header, self.names):
            folded = [i for i, h in enumerate(cells) if h.lower() == name.lower()]
            if len(folded) == 1:
                return folded[0]
        return None

    def data(self) -> np.ndarray:
        return np.frombuffer(self.values, dtype=np.float64).reshape(-1, self.n_cols)

    def _pick(self, columns: str | None, complex_mode: bool) -> tuple[list[int], int | None]:
        """Indices of (time, force, response) or (time, force_re, force_im, ...), and of hit."""
        header = self.header or []
        hit = self.find("hit")
        picked, hit = self._pick_columns(columns, complex_mode, hit)
        if (
            self.header is not None
            and picked[0] != NO_TIME
            and is_frequency_name(self.names[picked[0]], self.units[picked[0]])
        ):
            raise FormatError(
                f"{self.name}: column {_show(header[picked[0]])} holds frequencies: this is a table of "
                "FRFs, not time records; import it with --format frf-text"
            )
        return picked, hit

    def _pick_columns(self, columns, complex_mode, hit) -> tuple[list[int], int | None]:
        header = self.header or []
        if columns is None:
            if complex_mode:
                wanted = [self.find(n) for n in COMPLEX_COLUMNS]
                rest = [
                    i for i in range(self.n_cols) if i not in wanted and i != hit and i not in self.empty_cols
                ]
                time = self.find("time")
                if time is None and not rest:
                    raise FormatError(f"{self.name} has complex columns but no time column")
                return [time if time is not None else rest[0], *wanted], hit  # type: ignore[list-item]
            rest = [i for i in range(self.n_cols) if i != hit and i not in self.empty_cols]
            if len(rest) == 2 and self.stated_rate is not None and self.find("time") is None:
                return self._pick_without_time(rest), hit
            if len(rest) == 2 and self.find("time") is not None:
                time = self.find("time")
                other = _show(header[rest[1] if rest[0] == time else rest[0]])
                raise FormatError(
                    f"{self.name} has 2 data columns, time {_show(header[time])} and {other}: an impact "
                    "record needs force and response (and time, or --sample-rate)"
                )
            if len(rest) < 3:
                raise FormatError(
                    f"{self.name} has {count(len(rest), 'data column')}; need time, force and response"
                    + (
                        " (a file of force and response alone needs its sample rate: give --sample-rate HZ)"
                        if len(rest) == 2
                        else ""
                    )
                )
            named = [self.find(n) for n in ("time", "force", "response")]
            said = "names"
            if None in named:
                named, said = self._by_kind(rest)  # type: ignore[assignment]
            if None in named:
                return rest[:3], hit
            if named != rest[:3]:
                shown = ", ".join(
                    f"{role} {self.header[i]!r}"  # type: ignore[index]
                    for role, i in zip(("time", "force", "response"), named, strict=True)
                )
                self.picked_note = f"columns taken by their {said}: {shown}"
            return named, hit  # type: ignore[return-value]
        items = [item.strip() for item in columns.split(",")]
        without_time = len(items) == 2 and self.stated_rate is not None
        if not (len(items) == 3 or without_time) or not all(items):
            raise FormatError(
                f"{self.name}: columns {_show(columns)} must name three columns "
                "(time, force, response), e.g. t,F,a or 0,2,1; or two (force, response) with "
                "--sample-rate for a file without a time column"
            )
        picked = []
        for item in items:
            if item.isdigit():
                # Only ASCII digits count, and at most 6 of them (int() of a 5000-digit
                # string raises, and no file has a million columns).
                index = int(item) if item.isascii() and len(item) <= 6 else 10**6
                if index >= self.n_cols:
                    raise FormatError(
                        f"{self.name}: column index {index if index < 10**6 else _show(item)} "
                        f"is out of range (the file has "
                        f"{self.n_cols} columns, 0..{self.n_cols - 1})"
                    )
            else:
                if self.header is None:
                    raise FormatError(
                        f"{self.name} has no header row, so column {_show(item)} cannot be found"
                    )
                index = self.find(item)
                if index is None:
                    raise FormatError(
                        f"{self.name}: no column {_show(item)} in the header ({', '.join(header)})"
                    )
            if index in self.empty_cols:
                raise FormatError(
                    f"{self.name}: column index {index} is empty on every line; it holds no data"
                )
            picked.append(index)
        if len(set(picked)) != len(picked):
            raise FormatError(f"{self.name}: columns {_show(columns)} must be different columns")
        if hit in picked:
            hit = None  # the user chose to read it as data
        return ([NO_TIME, *picked] if without_time else picked), hit

    def _pick_without_time(self, rest: list[int]) -> list[int]:
        """[NO_TIME, force, response] of a file with two data columns and a stated rate:
        by the header's names or units where they say which is which, else in position
        (force first), said in a note."""
        by_name = [self.find("force"), self.find("response")]
        if None not in by_name:
            force, response = by_name
        else:
            kinds = {col: self._kind(col)[0] for col in rest} if self.header is not None else {}
            forces = [c for c in rest if kinds.get(c) == "force"]
            responses = [c for c in rest if kinds.get(c) == "response"]
            if len(forces) == 1 and len(responses) == 1:
                force, response = forces[0], responses[0]
            elif len(forces) == 2 or len(responses) == 2:
                said = "forces" if len(forces) == 2 else "responses"
                names = ", ".join(_show(self.header[c]) for c in rest)  # type: ignore[index]
                raise FormatError(
                    f"{self.name}: both columns ({names}) are {said} by their names or units; a file of "
                    "force and response alone needs one of each"
                )
            else:
                force, response = rest
        if (force, response) != tuple(rest):
            shown = f"force {self.header[force]!r}, response {self.header[response]!r}"  # type: ignore[index]
            how = "names" if None not in by_name else "names or units"
            self.picked_note = f"no time column: columns taken by their {how}: {shown}"
        elif None in by_name:
            self.picked_note = "no time column: columns taken in position, force then response"
        return [NO_TIME, force, response]

    def _kind(self, col: int) -> tuple[str | None, str]:
        """What a header column holds, by its name and its unit: ("force", how),
        ("response", how), (None, "") when neither says, ("conflict", "") when they disagree
        (a force-like name in an acceleration unit). how: "names" where the name says so (its
        unit, if any, agreeing), else "units"."""
        name = self.names[col].strip().strip("\"'").strip().lower()
        by_name = next((q for q, names in KIND_NAMES.items() if name in names), None)
        by_unit = None
        unit = self.units[col]
        if unit is not None:
            fits = []
            for quantity in ("force", "response"):
                try:
                    parse_unit(unit, quantity)
                except FormatError:
                    continue
                fits.append(quantity)
            by_unit = fits[0] if len(fits) == 1 else None
        if by_name and by_unit and by_name != by_unit:
            return "conflict", ""
        if by_name:
            return by_name, "names"
        return by_unit, "units" if by_unit else ""

    def _by_kind(self, rest: list[int]) -> tuple[list[int | None], str]:
        """([time, force, response], how) where the header's names or units say which
        column is the force and which the response: exactly one force-like and one
        response-like column among those after the time column (which stays the first
        column other than hit) and none whose name and unit disagree; else a list holding
        None (the columns are then taken by position). how: what said so, for the note."""
        if self.header is None or len(rest) < 3:
            return [None], ""
        found: dict[str, list[int]] = {"force": [], "response": []}
        hows: set[str] = set()
        for col in rest[1:]:
            kind, how = self._kind(col)
            if kind == "conflict":
                return [None], ""
            if kind is not None:
                found[kind].append(col)
                hows.add(how)
        if len(found["force"]) != 1 or len(found["response"]) != 1:
            return [None], ""
        said = next(iter(hows)) if len(hows) == 1 else "names and units"
        return [rest[0], found["force"][0], found["response"][0]], said

    def _unit(self, col: int, option: str | None, quantity: str) -> tuple[str, float, str]:
        """(unit, SI factor, where from: "option", "header" or "default") of a data column."""
        header_unit = self.units[col] if self.header is not None else None
        if option is not None:
            said = f"option; the header says {header_unit}" if header_unit else "option"
            return option, parse_unit(option, quantity), said
        if header_unit is None:
            return DEFAULT_UNITS[quantity], 1.0, "default"
        flag = "--force-unit" if quantity == "force" else "--response-unit"
        volts = {"Volts": "V"}.get(header_unit, header_unit)  # LabVIEW spells it out
        if volts in ("V", "mV"):
            example = "mV@2.25mV/N" if quantity == "force" else "mV@10.2mV/g"
            raise FormatError(
                f"{self.name}: column {_show(self.header[col])} is in {header_unit}: give the sensor's "  # type: ignore[index]
                f"sensitivity, e.g. {flag} {volts}{example[example.index('@') :]}"
            )
        try:
            where = "units row" if col in self.from_units_row else "header"
            if same := spelled_as(header_unit, quantity):  # "G": say how it was read
                where += f", read as {same}"
            return header_unit, parse_unit(header_unit, quantity), where
        except FormatError:
            other_quantity = "response" if quantity == "force" else "force"
            if (order := self._order_by_units()) is not None or (
                _parses(header_unit, other_quantity) and (order := self._order_by_units(first=True))
            ):
                # Several columns in a force (or response) unit: the first of each is an
                # example, and the message says so; nothing is guessed.
                several = self._order_by_units() is None
                example = "--columns with the force and response you mean, e.g. " if several else ""
                other = "an acceleration" if quantity == "force" else "a force"
                raise FormatError(
                    f"{self.name}: column {_show(self.header[col])} is read as the {quantity}, but "  # type: ignore[index]
                    f"{_show(header_unit)} is {other} unit: the columns are in another order; give "
                    f"{example}--columns {order} (time, force, response)"
                ) from None
            if why := not_acceleration(header_unit):
                # A velocity or displacement column: no --response-unit makes it one.
                raise FormatError(f"{self.name}: column {_show(self.header[col])}: {why}") from None  # type: ignore[index]
            raise FormatError(
                f"{self.name}: column {_show(self.header[col])}: unknown {quantity} unit "  # type: ignore[index]
                f"{_show(header_unit)} in the header; use {accepted_forms(quantity)}, or give {flag}"
            ) from None

    def _order_by_units(self, first: bool = False) -> str | None:
        """The --columns value (time, force, response) that the header's units say, when
        exactly one other column is in a force unit and one in a response unit (first:
        the first of each where there are several); else None. Header names where
        --columns finds them, else 0-based indices."""
        time = self.picked[0] if self.picked else 0
        found: dict[str, list[int]] = {"force": [], "response": []}
        for i, unit in enumerate(self.units):
            if i in (time, self.hit_col) or unit is None:
                continue
            for quantity, cols in found.items():
                try:
                    parse_unit(unit, quantity)
                except FormatError:
                    continue
                cols.append(i)
        counts = (len(found["force"]), len(found["response"]))
        if counts != (1, 1) and not (first and min(counts) >= 1):
            return None
        order = [time, found["force"][0], found["response"][0]]
        names = [self.names[i] for i in order]
        if all(_PLAIN_NAME.fullmatch(n) and self.find(n) == i for n, i in zip(names, order, strict=True)):
            return ",".join(names)
        return ",".join(str(i) for i in order)

    def _time_unit(self, col: int) -> tuple[str, float]:
        unit = self.units[col] if self.header is not None else None
        if unit is None:
            return "s", 1.0
        if unit not in TIME_UNITS:
            raise FormatError(
                f"{self.name}: column {_show(self.header[col])}: unknown time unit {_show(unit)}; "  # type: ignore[index]
                f"use {', '.join(TIME_UNITS)}"
            )
        return unit, TIME_UNITS[unit]

    def build(self, path, columns, force_unit, response_unit, stamp) -> ImportedData:
        header = self.header or []
        picked, hit_col, complex_mode = self.picked, self.hit_col, self.complex_mode
        assert picked is not None  # set with the first data row
        force = self._unit(picked[1], force_unit, "force")
        response = self._unit(picked[3 if complex_mode else 2], response_unit, "response")
        factors = (force[1], response[1])
        data = self.data()
        lines = np.frombuffer(self.lines, dtype=np.int64)
        if picked[0] == NO_TIME:
            self._refuse_time_axis(data, picked[1:])
            time_unit = None
            time, half, groups = self._made_time(data, lines, hit_col)
        else:
            time_unit, time_factor = self._time_unit(picked[0])
            time = data[:, picked[0]] * time_factor if time_factor != 1.0 else data[:, picked[0]]
            groups = self._groups(data, lines, time, hit_col)
            half = printed_half_units(self.time_texts) * time_factor
        ids = None if hit_col is None else data[:, hit_col]
        starts, steps, tolerance = self._check_axes(time, half, lines, groups, ids)
        n = groups[0].size
        sample_rate_hz, start_s, notes = 1.0 / steps[0], starts[0], {}
        # The exporter writes the exact rate and start; trust them only if the time column agrees.
        exact = _comment_float(self.comments, "sample_rate_hz")
        if exact is not None and exact > 0 and abs(1.0 / exact - steps[0]) * max(n - 1, 1) <= tolerance:
            sample_rate_hz = exact
        elif exact is not None:
            notes["ignored_sample_rate_hz"] = self.comments["sample_rate_hz"]
        exact = _comment_float(self.comments, "start_s")
        if exact is not None and abs(exact - starts[0]) <= tolerance:
            start_s = exact
        elif exact is not None:
            notes["ignored_start_s"] = self.comments["start_s"]
        if self.stated_rate is not None:
            rate, said = self.stated_rate
            if not step_fits(time[groups[0]], half[groups[0]], 1.0 / rate):
                raise FormatError(
                    f"{self.name}: {said} gives a sample rate of {rate:g} Hz, but the time column steps at "
                    f"{1.0 / steps[0]:.6g} Hz, more than its printed precision allows; correct or remove one"
                )
            sample_rate_hz = rate
            notes.setdefault("notes", []).append(
                f"no time column: sample k of each hit taken at k / {rate:g} Hz, the rate {said} gives"
                if picked[0] == NO_TIME
                else f"sample rate {rate:g} Hz as {said} gives it; the time column allows it"
            )
        elif sample_rate_hz == 1.0 / steps[0] and (
            coarse := self._coarse_note(time[groups[0]], half[groups[0]], steps[0])
        ):
            notes.setdefault("notes", []).append(coarse)
            spread = self._rate_spread(time[groups[0]], half[groups[0]], steps[0])
            notes["sample_rate_u_rel"] = spread * steps[0] / math.sqrt(3.0)
        if self.preamble:
            lines_said = ", ".join(str(line) for line, _, _ in self.preamble[:8])
            notes.setdefault("notes", []).append(
                f"preamble line{'s' if len(self.preamble) > 1 else ''} {lines_said} skipped (kept in the "
                "provenance)"
            )
            notes["preamble"] = {one_line(k)[:60]: one_line(v)[:200] for _, k, v in self.preamble[:64]}
        center = _comment_float(self.comments, "center_hz")
        if "center_hz" in self.comments and center is None:
            raise FormatError(f"{self.name}: center_hz {_show(self.comments['center_hz'])} is not a number")
        order = np.concatenate(groups)
        if complex_mode:
            if center is None:
                raise FormatError(
                    f"{self.name} has complex (zoom) columns but no '# center_hz = ...' comment"
                )
            cols = data[order][:, picked[1:]].reshape(len(groups), n, 4)
            force_n = _complex(cols[..., 0], cols[..., 1], factors[0])
            response_m_s2 = _complex(cols[..., 2], cols[..., 3], factors[1])
        else:
            if center not in (None, 0.0):
                raise FormatError(
                    f"{self.name}: center_hz = {center} but the records are real; zoom records "
                    f"need columns {', '.join(COMPLEX_COLUMNS)}"
                )
            center = 0.0
            # Multiplying by exactly 1.0 keeps every bit; other units scale once here.
            force_n = data[order, picked[1]].reshape(len(groups), n) * factors[0]
            response_m_s2 = data[order, picked[2]].reshape(len(groups), n) * factors[1]
            if len(groups) == 1 and (cut := find_cut(force_n[0], response_m_s2[0], sample_rate_hz)):
                take = cut.starts[:, None] + np.arange(cut.length)
                force_n, response_m_s2 = force_n[0][take], response_m_s2[0][take]
                start_s = -cut.pretrigger / sample_rate_hz
                n = cut.length
                groups = [g for g in take]
                notes.setdefault("notes", []).append(cut_note(cut, sample_rate_hz))
        hits = make_hits(path, force_n, response_m_s2, sample_rate_hz, start_s, center, stamp, self.rejected)
        if self.picked_note and columns is None:
            notes.setdefault("notes", []).insert(0, self.picked_note)
        names = [None if i == NO_TIME else header[i] if header else str(i) for i in picked]
        ignored = [
            i for i in range(self.n_cols) if i not in picked and i != hit_col and i not in self.empty_cols
        ]
        if ignored:
            notes.setdefault("notes", []).append(self._ignored_note(ignored, picked, complex_mode))
        if said := self.empty_note():
            notes.setdefault("notes", []).extend(said)
        if said := self.unended_note():
            notes.setdefault("notes", []).extend(said)
        if said := self._marker_notes(len(groups), None if ids is None else [int(ids[g[0]]) for g in groups]):
            notes.setdefault("notes", []).extend(said)
        details = {
            "columns": names,
            "hit_column": header[hit_col] if hit_col is not None else None,
            "delimiter": self.delimiter or "whitespace",
            "decimal_comma": self.decimal_comma,
            "header": self.header is not None,
            "time_unit": time_unit,
            "force_unit": force[0],
            "response_unit": response[0],
            "units_from": {"force": force[2], "response": response[2]},
            "time_tolerance_s": tolerance,
            "n_records": len(groups),
            "n_samples": int(n),
            "zoom": bool(complex_mode),
            **notes,
        }
        return ImportedData(hits=hits, measured_frfs=None, format="csv", details=details)

    @staticmethod
    def _coarse_note(t: np.ndarray, half: np.ndarray, step: float) -> str:
        """The note on a fitted rate that a coarsely printed time column (half a unit of a
        last digit more than COARSE_FRACTION of the step) knows only roughly, or "".
        t, half: one hit's times and their printed half units (s); step: the fitted step (s)."""
        coarsest = float(half.max())
        spread = Table._rate_spread(t, half, step)
        if not spread:
            return ""
        return (
            f"the time column is printed coarsely (half a unit of its last digit is {coarsest:.3g} s, "
            f"{100 * coarsest / step:.0f} % of the step): the printed times allow any rate within "
            f"{spread:.2g} Hz of the fitted {1 / step:.6g} Hz; if you know the exact rate, give it with "
            "--sample-rate HZ"
        )

    @staticmethod
    def _rate_spread(t: np.ndarray, half: np.ndarray, step: float) -> float:
        """How far (Hz) the true rate may lie from the fitted 1/step that a coarsely printed
        time column allows, or 0 where that is too little to tell (see _coarse_note)."""
        if float(half.max()) <= COARSE_FRACTION * step or t.size < 2:
            return 0.0
        # The fitted line and the true one both pass within the first and the last values'
        # tolerances, so their steps differ by at most twice those over the record.
        ends = max(float(half[0]), 0.01 * step) + max(float(half[-1]), 0.01 * step)
        spread = 2.0 * ends / (t.size - 1) / step**2
        # Coarse, but over enough samples (4000 Hz +- 0.08 Hz) needs no word.
        return spread if spread > COARSE_RATE_SPREAD / step else 0.0

    def _ignored_note(self, ignored: list[int], picked: list[int], complex_mode: bool) -> str:
        """One line naming the columns the run leaves out (counted from 1, as in the other
        messages, with their header names) and how --columns picks others."""
        header = self.header or []
        shown = ", ".join(f"{i + 1} {header[i]!r}" if header else str(i + 1) for i in ignored)
        plural = "s" if len(ignored) > 1 else ""
        text = f"column{plural} {shown} ignored: a run holds one time, force and response"
        if complex_mode:
            return text
        if picked[0] == NO_TIME:
            # Without a time column (--sample-rate; an example of NO_TIME's -1 was refused as
            # "no column '-1'"): a time column left out is meant so, another column is
            # offered as the response.
            left = ignored[0]
            unit = self.units[left] if self.header is not None else None
            if self.find("time") == left or (unit is not None and unit in TIME_UNITS):
                return f"{text} (the times come from --sample-rate)"
            cols: tuple[int, ...] = (picked[1], left)
        else:
            cols = (picked[0], picked[1], ignored[0])
        example = [header[i] if header else str(i) for i in cols]
        if not all(_PLAIN_NAME.fullmatch(c) for c in example):  # no quoting for the shell
            example = [str(i) for i in cols]
        return (
            f"{text}; give --columns to choose (header names or 0-based indices), e.g. --columns "
            + ",".join(example)
        )

    def _marker_notes(self, n_hits: int, labels: list[int] | None) -> list[str]:
        """One line per '# rejected hit K' whose meaning a reader could mistake: K counts
        the file's hits from 0 in file order (as our exports write it, where the hit
        column counts so too), never by the file's own hit column. labels: that column's
        value for each of the n_hits hits in file order, or None without one. Told when K
        names no hit (it rejects nothing) and when the hit it rejects is labelled otherwise
        than K (a hit column counting from 1: '# rejected hit 3' leaves out the hit labelled 4)."""
        out = []
        for k in sorted(self.rejected):
            if k < n_hits and (labels is None or labels[k] == k):
                continue
            marker = f"'# rejected hit {k}'"
            other = labels.index(k) if labels is not None and k in labels else None
            if labels is not None and k < n_hits:
                text = (
                    f"{marker} rejected the file's {_ordinal(k + 1)} hit, labelled {labels[k]} in its hit "
                    "column: the marker counts hits from 0 in file order, not by the hit column"
                )
                if other is not None and other not in self.rejected:
                    text += f"; the hit labelled {k} is kept (its marker would be '# rejected hit {other}')"
            else:
                text = (
                    f"{marker} names no hit and rejects nothing: the marker counts the file's "
                    f"{count(n_hits, 'hit')} from 0 in file order (0-{n_hits - 1})"
                )
                if other is not None:
                    text += f"; the hit labelled {k} in the hit column is '# rejected hit {other}'"
            out.append(text)
        return out

    def _time_said(self) -> str:
        """What the time column is called in a message: "time" under a header; without one,
        the first column may as well be a frequency (an FRF table whose axis is broken, so
        that it was not detected as one), and the message must not insist on time."""
        col = self.picked[0] if self.picked else 0
        if self.header is not None:
            return "time"
        return "the first column (time or frequency)" if col == 0 else f"column {col + 1} (time)"

    def _refuse_time_axis(self, data: np.ndarray, signals: list[int]) -> None:
        """FormatError where a column taken for force or response (``signals``, without a
        time column) rises over every row, as a time axis does and no signal does: a file
        of time and one signal stored its time ramp as the force."""
        for role, col in zip(("force", "response"), signals, strict=True):
            x = data[:, col]
            if x.size >= 8 and x[-1] > x[0] and np.all(np.diff(x) >= 0):
                shown = _show(self.header[col]) if self.header else str(col + 1)
                raise FormatError(
                    f"{self.name}: column {shown}, taken for the {role}, rises over every row as a time "
                    "axis does: the file holds time and one signal; an impact record needs force and "
                    "response (and time, or --sample-rate)"
                )

    def _made_time(self, data, lines, hit_col) -> tuple[np.ndarray, np.ndarray, list[np.ndarray]]:
        """(time s, its half unit, the hits' rows) of a file without a time column: one hit,
        or one per value of the hit column; sample k of each at k / the stated rate."""
        assert self.stated_rate is not None
        rows = data.shape[0]
        groups = self._groups(data, lines, np.zeros(rows), hit_col)
        time = np.empty(rows)
        for g in groups:
            time[g] = np.arange(g.size) / self.stated_rate[0]
        return time, np.zeros(rows), groups

    def _groups(self, data, lines, time, hit_col) -> list[np.ndarray]:
        """Row indices of each hit, in order of first appearance; at most MAX_IMPORT_HITS
        hits, counted with numpy before any per-hit object is made."""
        if hit_col is not None:
            ids = data[:, hit_col]
            bad = np.flatnonzero(ids != np.round(ids))
            if bad.size:
                raise FormatError(
                    f"{self.name} line {lines[bad[0]]}: hit {float(ids[bad[0]])!r} is not a whole number"
                )
            _, first, inverse = np.unique(ids, return_index=True, return_inverse=True)
            self._check_hit_count(first.size)
            rank = np.argsort(np.argsort(first))  # unique value -> order of first appearance
            keys = rank[inverse.ravel()]
            order = np.argsort(keys, kind="stable")
            bounds = np.flatnonzero(np.diff(keys[order])) + 1
            return np.split(order, bounds)
        drops = np.flatnonzero(np.diff(time) < 0) + 1
        self._check_hit_count(drops.size + 1)
        return np.split(np.arange(data.shape[0]), drops)

    def _check_hit_count(self, n_hits: int) -> None:
        if n_hits > MAX_IMPORT_HITS:
            raise FormatError(
                f"{self.name} holds {n_hits} hits, more than the {MAX_IMPORT_HITS} one import may hold; "
                "split the file"
            )

    def _check_axes(self, time, half, lines, groups, ids=None):
        """(starts, steps, tolerance) of the hits' time axes, which must all be regular
        (daq/formats/axis.py) and one and the same axis within the tolerance. ids: the
        hit column (n_rows,), whose values (the file's own numbers) name the hits in a
        refusal; without one the hits (split where the time starts over) count from 1."""

        def hit(k: int) -> str:
            if ids is None:
                return f"hit {k + 1}"
            return f"hit {float(ids[groups[k][0]]):g}"

        starts, steps, tolerance = [], [], 0.0
        first_t = None
        for k, rows in enumerate(groups):
            t = time[rows]
            said = self._time_said()
            if t.size < 2 and self.hit_col is None and k + 1 < len(groups):
                # Split here by a step back: say so, not only "fewer than 2 samples".
                after = groups[k + 1][0]
                raise FormatError(
                    f"{self.name} line {lines[after]}: {said} goes down (from {time[rows[0]]:g} to "
                    f"{time[after]:g}); read as time, a step back starts a new hit, which leaves line "
                    f"{lines[rows[0]]} a hit of 1 sample"
                )
            if t.size < 2:
                raise FormatError(f"{self.name}: {hit(k)} (line {lines[rows[0]]}) has fewer than 2 samples")
            d = np.diff(t)
            bad = np.flatnonzero(d <= 0)
            if bad.size:
                raise FormatError(f"{self.name} line {lines[rows[bad[0] + 1]]}: {said} does not increase")
            if k and t.size != groups[0].size:
                raise FormatError(
                    f"{self.name}: {hit(k)} (line {lines[rows[0]]}) has {t.size} samples, {hit(0)} has "
                    f"{groups[0].size}"
                )
            if k and np.array_equal(t, first_t):  # the same printed axis again (our exports)
                starts.append(starts[0])
                steps.append(steps[0])
                continue
            fit = fit_regular(t, half[rows])
            if fit.bad is not None:
                if self.header is not None:
                    what, unit = "uneven time step (the time column is", " s"
                else:
                    what, unit = f"{said} steps unevenly (it is", ""
                picked = self.picked or []
                # Jittered time stamps of samples taken at a steady rate (a logger's clock)
                # are refused as a dropped sample is: the way round is the user's to take,
                # and is not offered where a step spans a gap (a sample dropped).
                around = (
                    f"; if the samples were taken at a steady rate and only their times are uneven, leave "
                    f"the time column out: --columns {picked[-2]},{picked[-1]} --sample-rate HZ"
                    if len(picked) == 3 and not self.complex_mode and np.max(d) < GAP_STEPS * np.median(d)
                    else ""
                )
                raise FormatError(
                    f"{self.name} line {lines[rows[fit.bad]]}: {what} not a straight line within its printed "
                    f"precision or 1 % of the step {float(np.median(d)):g}{unit}, whichever is larger)"
                    + around
                )
            tolerance = max(tolerance, fit.tolerance)
            if k:
                drift = abs(fit.step - steps[0]) * (t.size - 1)
                if abs(fit.start - starts[0]) > tolerance or drift > tolerance:
                    if abs(fit.start - starts[0]) > tolerance:
                        how = f"it starts at {fit.start:.6g} s, {hit(0)} at {starts[0]:.6g} s"
                    else:
                        how = f"its step is {fit.step:.6g} s, {hit(0)}'s {steps[0]:.6g} s"
                    raise FormatError(
                        f"{self.name}: {hit(k)} (line {lines[rows[0]]}) has a different time axis "
                        f"from {hit(0)} ({how}); {SAME_AXIS_REMEDY}"
                    )
            else:
                first_t = t
            starts.append(fit.start)
            steps.append(fit.step)
        return starts, steps, tolerance


def write_csv(run: Run, path: Path) -> None:
    """Write every hit (accepted and rejected) of ``run`` as text, atomically.

    Columns: hit (0-based), time (s), force (N), response (m/s^2); zoom runs have
    force_re, force_im, response_re, response_im instead. FormatError if the run has no hits.
    """
    path = Path(path)
    hits = run.hits
    if hits is None:
        raise FormatError(f"run {run.run_id} has no time records; export FRFs as UFF")
    if not (np.all(np.isfinite(hits.force_n)) and np.all(np.isfinite(hits.response_m_s2))):
        raise FormatError(f"run {run.run_id} has non-finite samples; they cannot be exported as CSV")
    rejected = [i for i in range(hits.n_hits) if not hits.accepted[i]]
    head = [
        "# cantilever-daq time records",
        f"# run_id: {run.run_id}",
        f"# kind: {run.kind}",
        f"# sample_rate_hz = {float(hits.sample_rate_hz)!r}",
        f"# start_s = {float(hits.start_s)!r}",
        f"# center_hz = {float(hits.center_hz)!r}",
        "# units: time s, force N, response m/s^2",
        # People count hits from 1 (daq runs show, the page, the report); this file keeps
        # the run's 0-based index, and says so.
        "# hit numbering: the hit column and the rejected hit lines count from 0 "
        "(hit 0 is hit 1 in daq runs show)",
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
        raise FormatError(f"cannot write {show_path(path)}: {exc.strerror or exc}") from None
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


def _comment_float(comments: dict[str, str], key: str) -> float | None:
    if key not in comments:
        return None
    try:
        value = float(comments[key])
    except ValueError:
        return None
    return value if math.isfinite(value) else None


def looks_complex(cell: str) -> bool:
    """A cell written as a complex number, ``(a+bj)`` as Python prints it, ``a+bi`` as
    MATLAB does; not a plain real number."""
    text = cell.strip().strip("\"'").replace(" ", "")
    try:
        float(text)
        return False
    except ValueError:
        pass
    if text.startswith("(") and text.endswith(")"):
        text = text[1:-1]
    if text.endswith(("i", "I")):
        text = text[:-1] + "j"
    if not text.endswith(("j", "J")):
        return False
    try:
        complex(text)
    except ValueError:
        return False
    return True


def _refuse_complex(name: str, number: int, cells: list[str]) -> None:
    """FormatError when a cell of line ``number`` is a complex number (see looks_complex):
    no reader here takes them, and read as a header or text they give a puzzling message."""
    cell = next((c for c in cells if looks_complex(c)), None)
    if cell is not None:
        raise FormatError(
            f"{name} line {number}: cells look like complex numbers (a+bj), e.g. {_show(cell)}; "
            "write the real and imaginary parts as two columns"
        )


def _ordinal(n: int) -> str:
    """1st, 2nd, 3rd, 4th, 11th, 12th, 13th, 21st, ..."""
    suffix = "th" if 10 <= n % 100 <= 20 else {1: "st", 2: "nd", 3: "rd"}.get(n % 10, "th")
    return f"{n}{suffix}"


def _show(text: str) -> str:
    return repr(one_line(text) if len(text) <= 40 else one_line(text[:40]) + "...")


def _parses(unit: str, quantity: str) -> bool:
    """Whether ``unit`` is one of ``quantity``'s units ("force" or "response")."""
    try:
        parse_unit(unit, quantity)
    except FormatError:
        return False
    return True


def _units_row(cells: list[str]) -> list[str | None] | None:
    """The units of a row of units (``s, N, g``, ``[s], [N], [m/s^2]``; a cell may be
    empty), or None where the row is not one: a cell that is a number or no unit of
    time, force, acceleration or voltage. None for a row of empty cells."""
    units: list[str | None] = []
    for cell in cells:
        text = cell.strip().strip("\"'").strip()
        if not text:
            units.append(None)
            continue
        bare = text[1:-1].strip() if text[:1] + text[-1:] in ("[]", "()") else text
        _, unit = header_name_unit(f"x ({bare})")
        # A velocity or displacement unit is a unit too: its column is then refused as
        # no acceleration, not the row as no units.
        known = unit is not None and (
            unit in TIME_UNITS
            or unit in ("V", "mV")
            or _parses(unit, "force")
            or _parses(unit, "response")
            or bool(not_acceleration(unit))
        )
        if not known:
            return None
        units.append(unit)
    return units if any(u is not None for u in units) else None
