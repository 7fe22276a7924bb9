"""Measured FRFs as delimited text: a frequency column, then per FRF Re and Im, or
magnitude and phase, optionally followed by its coherence.

    Frequency (Hz);H11 Re [m/s^2/N];H11 Im [m/s^2/N];H21 Re;H21 Im
    0,0;1,0;0,0;...

    freq [Hz], mag [dB], phase [deg], coherence

The header names each column (``re``/``real``, ``im``/``imag``, ``mag``/``magnitude``/
``amp``/``abs``, ``phase``/``angle``/``arg``, ``coh``/``coherence``; the rest of the name
is the FRF's label). Without a header the columns are frequency, then Re, Im pairs.
Units in the header decide the form and the SI factor: ``m/N``, ``mm/N`` (receptance),
``(m/s)/N`` (mobility), ``(m/s^2)/N``, ``g/N`` (accelerance); magnitude in ``dB`` (20 log10
of the linear value in that unit) or linear; phase in ``deg`` (the default) or ``rad``.
``frf_form`` (``--frf-form``) wins over the header; without either, accelerance in SI
units is assumed, and the details say so.

Exports of analyzer software put a preamble before the table and the units in a row of
their own (DataPhysics SignalCalc ASCII, CRLF, tabs, Latin-1)::

    Units: Ratio
    Ref Chan:Resp Chan<TAB>0-Z:0-Z
    Channel Name<TAB> :

    Frequency<TAB> Real<TAB> Imaginary

    Units:
    Hz<TAB>(m/s²)(N)<TAB>
    0.0000000000000e+000<TAB>      -0.1504349<TAB>               0

:func:`scan_layout` finds the preamble (``key: value`` and ``key<TAB>value`` lines, blank
lines, comments), the column-name row and an optional units row (after an optional
``Units:`` line). The units row fills the units the column names lack; a unit in it that is
no FRF unit ("Ratio") leaves the default, accelerance, and the details say so.
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

import numpy as np

from daq.formats.csv_text import (
    COMMENT_MARKS,
    Table,
    _head_lines,
    _metadata,
    all_numbers,
    decode_line,
    header_name_unit,
    is_frequency_name,
    split_cells,
)
from daq.formats.errors import FormatError, count
from daq.formats.imported import MAX_IMPORT_BYTES, ImportedData, make_frfs, one_line, open_checked, show_path
from daq.formats.line_ends import text_lines
from daq.formats.units import FREQUENCY_UNITS, clean_label, frf_unit, frf_unit_text, looks_like_frf_unit
from daq.store.model import FRF_FORMS

_KINDS = {
    "re": "re",
    "real": "re",
    "im": "im",
    "imag": "im",
    "imaginary": "im",
    "mag": "mag",
    "magnitude": "mag",
    "amp": "mag",
    "amplitude": "mag",
    "abs": "mag",
    "db": "mag",
    "phase": "phase",
    "ph": "phase",
    "angle": "phase",
    "arg": "phase",
    "coh": "coh",
    "coherence": "coh",
}
_PHASE_UNITS = {
    "deg": 1.0,
    "degree": 1.0,
    "degrees": 1.0,
    "°": 1.0,
    "rad": 180.0 / np.pi,
    "radian": 180.0 / np.pi,
}
_TOKEN = re.compile(r"[A-Za-z0-9]+")
#: Preamble lines at most, and what of them the provenance keeps.
MAX_PREAMBLE_LINES = 64
MAX_PREAMBLE_KEY = 60
MAX_PREAMBLE_VALUE = 200


@dataclass
class Layout:
    """Where the parts of a text table are, by 0-based line index (see scan_layout)."""

    preamble: list[int] = field(default_factory=list)  # metadata lines before the column names
    metadata: list[tuple[str, str]] = field(default_factory=list)  # their (key, value)
    header: int | None = None  # the column-name row
    header_cells: list[str] = field(default_factory=list)
    marker: int | None = None  # a "Units:" line before the units row
    units: int | None = None  # the units row
    unit_cells: list[str] = field(default_factory=list)
    first_data: int | None = None  # the first all-number row seen
    data_cells: list[str] = field(default_factory=list)

    @property
    def skipped(self) -> set[int]:
        """Lines the table reader must not see (they are read here)."""
        return {*self.preamble, *(i for i in (self.marker, self.units) if i is not None)}


def _is_units_marker(line: str) -> bool:
    return line.strip().rstrip(":").strip().lower() in ("units", "unit") and line.strip().endswith(":")


#: A quoted preamble line holds at most this many cells ("X axis","Frequency","Hz").
QUOTED_PREAMBLE_CELLS = 4
_QUOTED_CELLS = re.compile(r'\s*"[^"]*"(?:\s*[,;\t]\s*"[^"]*")+\s*')


def _quoted_metadata(line: str) -> tuple[str, str] | None:
    """(key, value) of a preamble line written in quotes, as PULSE and Test.Lab exports
    write them, else None: one quoted string ("Averages:<TAB>5", or a title with neither,
    kept as the title), or a few quoted cells ("Name","FRF Point1:+Z/Point1:+Z"). Only
    before a frequency column's header (scan_layout): a time record's quoted header row
    would read the same."""
    if len(line) >= 2 and line[0] == line[-1] == '"' and '"' not in line[1:-1]:
        inner = line[1:-1].strip()
        return (_metadata(inner) or ("title", inner)) if inner else None
    if not _QUOTED_CELLS.fullmatch(line):
        return None
    cells = [c.strip() for c in re.findall(r'"([^"]*)"', line)]
    if not 2 <= len(cells) <= QUOTED_PREAMBLE_CELLS or not cells[0]:
        return None
    return cells[0].rstrip(":").strip(), " ".join(c for c in cells[1:] if c)


def scan_layout(lines: list[str]) -> Layout:
    """Where the preamble, column names, units row and data begin in a table's first lines.

    Before the column-name row only blank lines, comments and metadata lines
    ("key: value", "key<TAB>value") may come. The column-name row's first cell names a
    frequency; with a preamble before it, it needs three cells at least (frequency and a
    pair). After it, blank lines, an optional "Units:" line and one units row, then data.
    A row of numbers (quotes, decimal commas, a trailing delimiter allowed) is always data:
    when one comes first, there is no header. When a line fits none of these before the
    column names (a time-record header, prose), the layout is empty: the table reader
    alone decides.
    """
    layout = Layout()
    candidates: list[tuple[int, tuple[str, str]]] = []
    start = len(lines)
    for index, line in enumerate(lines):
        stripped = line.strip()
        if not stripped or stripped.startswith(COMMENT_MARKS):
            continue
        cells, _ = split_cells(stripped)
        if all_numbers(cells):
            layout.first_data, layout.data_cells = index, cells
            break
        first = header_name_unit(cells[0].strip("\"'"))
        named = is_frequency_name(*first) or (first[0].strip().lower() == "khz" and first[1] is None)
        if (named or f_then_frf_columns(cells)) and (len(cells) >= 3 or not candidates):
            layout.header, layout.header_cells = index, cells
            start = index + 1
            break
        # A quoted line first: "Key:<TAB>value" split at the tab would keep the quote in its key.
        meta = _quoted_metadata(stripped) or _metadata(line.strip(" \r\n"))  # "key<TAB>" keeps its tab
        if meta is None or len(candidates) >= MAX_PREAMBLE_LINES:
            return Layout()
        candidates.append((index, meta))
    if layout.header is None:
        if layout.first_data is not None and candidates:
            # A preamble, then numbers without column names: a table without a header.
            layout.preamble = [i for i, _ in candidates]
            layout.metadata = [m for _, m in candidates]
        return layout
    layout.preamble = [i for i, _ in candidates]
    layout.metadata = [m for _, m in candidates]
    _, delimiter = split_cells(lines[layout.header].strip())
    for index in range(start, len(lines)):
        stripped = lines[index].strip()
        if not stripped or stripped.startswith(COMMENT_MARKS):
            continue
        cells, _ = split_cells(lines[index].strip(" "), delimiter)
        if all_numbers(cells):
            layout.first_data, layout.data_cells = index, cells
            break
        if _is_units_marker(stripped) and layout.marker is None and layout.units is None:
            layout.marker = index
            continue
        if layout.units is None:
            layout.units, layout.unit_cells = index, cells
            continue
        break  # a second non-number row: the table reader says what is wrong with it
    return layout


def _fed_lines(head: list[bytes], texts: list[str], layout: Layout, handle: IO[bytes]) -> Iterator[bytes]:
    """The lines the table reader sees: the head as UTF-8, with the preamble and units rows
    blank (so that every line keeps its number), then the rest of the file as it is."""
    skipped = layout.skipped
    for index, text in enumerate(texts):
        # The last line keeps its lack of a line end: the reader notes a file cut short.
        end = b"\n" if head[index].endswith((b"\n", b"\r")) else b""
        yield b"\n" if index in skipped else text.encode("utf-8") + end
    yield from handle


def read_frf_text(path: Path, frf_form: str | None = None, max_bytes: int = MAX_IMPORT_BYTES) -> ImportedData:
    """FRFs from a delimited text table (frequency, then Re/Im or magnitude/phase per FRF).

    frf_form: "receptance", "mobility" or "accelerance" to say what the values are (wins
        over the header's units); None: the header's unit decides, else accelerance.
    Returns ImportedData with measured_frfs in SI units of their form. Any problem: FormatError.
    """
    path = Path(path)
    name = show_path(path)
    if frf_form is not None and frf_form not in FRF_FORMS:
        raise FormatError(f"FRF form {frf_form!r} is not one of {', '.join(FRF_FORMS)}")
    with open_checked(path, max_bytes) as (raw_handle, _):
        handle = text_lines(raw_handle)  # lines ending in CR alone are lines too
        head, _ = _head_lines(handle)
        texts = [decode_line(raw, index == 0) for index, raw in enumerate(head)]
        layout = scan_layout(texts)
        _check_first_data(name, layout)
        table = Table(name)
        table.read(_fed_lines(head, texts, layout, handle), max_bytes)
    # A delimiter at the end of every line makes a column empty on every line: none at all.
    empty_note = table.drop_empty_columns()
    data = table.data()
    lines = np.frombuffer(table.lines, dtype=np.int64)
    if table.header is None:
        kinds = ["freq"] + ["re", "im"] * ((table.n_cols - 1) // 2)
        if table.n_cols < 3 or (table.n_cols - 1) % 2:
            raise FormatError(
                f"{name}: {count(table.n_cols, 'column')} without a header; an FRF table needs frequency, "
                "then Re, Im for each FRF (or a header naming the columns)"
            )
        labels_of = [""] * table.n_cols
        units = [None] * table.n_cols
    else:
        kinds, labels_of = [], []
        for i, (cell_name, unit) in enumerate(zip(table.names, table.units, strict=True)):
            kind, label = _kind(cell_name, unit, i == 0)
            if kind is None:
                raise FormatError(
                    f"{name}: column {table.header[i]!r} is not frequency, re, im, mag, phase or coherence"
                )
            kinds.append(kind)
            labels_of.append(label)
        # A bracketed part that named the column's kind ("(Real)") is no unit.
        units = [None if _kind_as_unit(u) is not None else u for u in table.units]
        for i, cell_name in enumerate(table.names):
            if kinds[i] == "phase" and units[i] is None and _bare_phase_unit(cell_name):
                units[i] = _bare_phase_unit(cell_name)  # a column named "°" or "rad" only
            if kinds[i] == "mag" and units[i] is None and _bare_frf_unit(cell_name):
                units[i] = _bare_frf_unit(cell_name)  # a column named "(m/s²)/N" only
        if kinds and kinds[0] == "freq" and units[0] is None and table.names[0].strip().lower() == "khz":
            units[0] = "kHz"  # a frequency column named "kHz" only
    from_row: set[int] = set()
    if layout.units is not None:
        if len(layout.unit_cells) > table.n_cols and any(layout.unit_cells[table.n_cols :]):
            raise FormatError(
                f"{name} line {layout.units + 1}: {count(len(layout.unit_cells), 'unit')} "
                f"for {count(table.n_cols, 'column')}"
            )
        for col, cell in enumerate(layout.unit_cells[: table.n_cols]):
            if units[col] is None and cell.strip("[]()\"' "):
                units[col] = cell if "/" in cell or ")(" in cell else clean_label(cell)
                from_row.add(col)
    if kinds.count("freq") != 1 or kinds[0] != "freq":
        raise FormatError(f"{name}: an FRF table needs exactly one frequency column, the first")
    # Units the preamble states ("X axis","Frequency","kHz"; "Y-Axis Unit: g/N") stand for
    # those the header and units row leave out: ignored, they put a 120 Hz mode at 0.12 Hz
    # and a g/N FRF at (m/s^2)/N (a new user's Test.Lab- and PULSE-like exports).
    preamble_x, preamble_y = _preamble_units(layout.metadata)
    unit_notes: list[str] = []
    if units[0] is None and preamble_x is not None:
        units[0] = preamble_x[0]
        if FREQUENCY_UNITS[preamble_x[0]] != 1.0:
            unit_notes.append(f"frequency in {preamble_x[0]}, as the preamble's {preamble_x[1]!r} says")
    from_preamble: set[str] = set()
    if preamble_y is not None:
        for col in range(1, table.n_cols):
            if kinds[col] in ("re", "im", "mag") and units[col] is None:
                units[col] = preamble_y[0]
                from_preamble.add(preamble_y[0])
    freq_unit = units[0] or "Hz"
    if freq_unit not in FREQUENCY_UNITS:
        raise FormatError(f"{name}: unknown frequency unit {freq_unit!r}; use Hz or kHz")
    freq = data[:, 0] * FREQUENCY_UNITS[freq_unit]
    bad = np.flatnonzero(np.diff(freq) <= 0)
    if bad.size:
        raise FormatError(f"{name} line {lines[bad[0] + 1]}: frequency does not increase")
    frfs, labels, coherence, frf_units, layouts = [], [], [], [], set()
    phase_notes: list[str] = []
    col = 1
    while col < table.n_cols:
        pair = tuple(kinds[col : col + 2])
        if pair[0] == "mag" and pair != ("mag", "phase"):
            raise FormatError(
                f"{name}: column {col + 1} ({_label(table, col)}) is a magnitude without its phase "
                "in the next column: modes are identified from the complex FRF, so each FRF needs "
                "its phase (or re, im) beside it"
            )
        if pair not in (("re", "im"), ("mag", "phase")):
            raise FormatError(
                f"{name}: column {col + 1} ({_label(table, col)}) starts no FRF: each FRF is a "
                "re, im or a mag, phase pair (optionally followed by its coherence)"
            )
        layouts.add("re-im" if pair == ("re", "im") else "mag-phase")
        first, second = data[:, col], data[:, col + 1]
        if pair == ("re", "im"):
            values = first + 1j * second
            unit_text = units[col] or units[col + 1]
        else:
            # A column named by its unit alone, "dB re 1 (m/s²)/N" (PULSE), says its unit.
            named = table.names[col] if re.match(r"(?i)\s*db\s+re\s", table.names[col]) else ""
            mag_unit = units[col] or named
            db = "db" in mag_unit.lower() or "db" in table.names[col].lower()
            magnitude = 10.0 ** (first / 20.0) if db else first
            if not db and np.any(first < 0):
                row = int(np.flatnonzero(first < 0)[0])
                raise FormatError(
                    f"{name} line {lines[row]}: negative magnitude {first[row]:g} (dB? say [dB])"
                )
            if units[col + 1] is None and (said := _radians_note(table, col + 1, second)):
                phase_notes.append(said)
            phase_unit = (units[col + 1] or "deg").lower()
            if phase_unit not in _PHASE_UNITS:
                raise FormatError(f"{name}: unknown phase unit {phase_unit!r}; use deg or rad")
            values = magnitude * np.exp(1j * np.deg2rad(second * _PHASE_UNITS[phase_unit]))
            unit_text = re.sub(r"(?i)db|re\s*1", "", mag_unit).strip() or None
            frf_units.append(f"phase {'deg' if _PHASE_UNITS[phase_unit] == 1.0 else 'rad'}")
            if db:
                frf_units.append("magnitude dB")
        frfs.append(values)
        frf_units.append(unit_text or "")
        labels.append(labels_of[col] or labels_of[col + 1] or f"FRF {len(frfs)}")
        col += 2
        if col < table.n_cols and kinds[col] == "coh":
            coherence.append(data[:, col])
            col += 1
        elif col < table.n_cols and kinds[col] not in ("re", "mag"):
            raise FormatError(f"{name}: column {col + 1} ({_label(table, col)}) follows no FRF")
    row_units = {units[c] for c in from_row}
    form, factor, said = _form(
        name,
        [u for u in frf_units if u and ("/" in u or ")(" in u or u in row_units)],
        frf_form,
        row_units,
        from_preamble and preamble_y[1],  # type: ignore[index]
    )
    frf = np.stack(frfs) * factor if factor != 1.0 else np.stack(frfs)
    coh = np.stack(coherence) if coherence and len(coherence) == len(frfs) else None
    details: dict[str, Any] = {
        "layout": sorted(layouts),
        "delimiter": table.delimiter or "whitespace",
        "decimal_comma": table.decimal_comma,
        "header": table.header is not None,
        "n_frf": len(frfs),
        "n_lines": int(freq.size),
        "frequency_unit": freq_unit,
        "frf_units": sorted({u for u in frf_units if u}),
        "form": form,
        "form_from": said,
    }
    if layout.units is not None:
        details["units_row"] = [one_line(c)[:40] for c in layout.unit_cells[:32]]
    if layout.metadata:
        details["preamble"] = _kept_preamble(layout.metadata)
    if coherence and coh is None:
        details["notes"] = [f"{len(coherence)} coherence columns for {len(frfs)} FRFs: coherence ignored"]
    if empty_note:
        details.setdefault("notes", []).extend(empty_note)
    if unit_notes:
        details.setdefault("notes", []).extend(unit_notes)
    if phase_notes:
        details.setdefault("notes", []).extend(phase_notes)
        details["phase_looks_like_radians"] = len(phase_notes)
    if said := table.unended_note():
        details.setdefault("notes", []).extend(said)
    measured = make_frfs(path, freq, frf, coh, labels, form)
    return ImportedData(hits=None, measured_frfs=measured, format="frf-text", details=details)


def f_then_frf_columns(cells: list[str]) -> bool:
    """A header "f, Re, Im, ...": "f" alone is frequency only beside FRF columns (in a
    time record's header "F" is the force)."""
    names = [header_name_unit(c.strip("\"'")) for c in cells]
    return (
        len(names) >= 3
        and names[0][0].strip().lower() == "f"
        and (names[0][1] or "hz").lower() in ("hz", "khz")
        and all(_kind(n, u, False)[0] is not None for n, u in names[1:])
    )


def _kind_as_unit(unit: str | None) -> str | None:
    """The kind a header cell's bracketed part names where a unit would stand ("Real",
    "Imag.", "Magnitude", "Phase": an export that brackets the part, e.g. "Signal 2
    (Real)"), or None."""
    if unit is None:
        return None
    word = unit.strip().rstrip(".").lower()
    return _KINDS.get(word) if word not in ("db",) else None


def _kind(cell: str, unit: str | None, first: bool) -> tuple[str | None, str]:
    """(kind, label) of a header cell: kind "freq", "re", "im", "mag", "phase", "coh"
    ("f" as the first cell is frequency here: the table is read as FRFs, f_then_frf_columns)."""
    if first and (is_frequency_name(cell, unit) or (cell.strip().lower() in ("f", "khz") and unit is None)):
        return "freq", ""
    tokens = _TOKEN.findall(cell)
    kind = next((_KINDS[t.lower()] for t in tokens if t.lower() in _KINDS), None)
    if kind is None and _kind_as_unit(unit) is not None:
        return _kind_as_unit(unit), " ".join(tokens)  # "Signal 2 (Real)", "Signal 2 (Imag.)"
    if kind is None and unit is not None and clean_label(unit).lower() in ("db",):
        kind = "mag"
    if kind is None and unit is not None and clean_label(unit).lower() in _PHASE_UNITS:
        kind = "phase"
    if kind is None and unit is None and _bare_phase_unit(cell):
        kind = "phase"  # PULSE names its columns by their units: "Hz", "dB re 1 g/N", "°"
    if kind is None and unit is None and _bare_frf_unit(cell):
        return "mag", ""  # ... and a linear magnitude by the FRF's unit: "(m/s²)/N"
    label = " ".join(t for t in tokens if t.lower() not in _KINDS)
    if re.match(r"(?i)\s*db\s+re\s", cell):
        label = ""  # a column named by its unit, "dB re 1 (m/s²)/N": no label in it
    return kind, label


#: Preamble keys (lower case, letters only) that state the frequency axis's unit, and the
#: FRF's (Test.Lab's "X axis","Frequency","Hz"; PULSE's "X-Axis Unit:<TAB>Hz").
_X_UNIT_KEYS = {"xaxis", "xaxisunit", "xaxisunits", "xunit", "xunits", "abscissaunit"}
_Y_UNIT_KEYS = {"yaxis", "yaxisunit", "yaxisunits", "yunit", "yunits", "ordinateunit"}


def _preamble_units(metadata: list[tuple[str, str]]) -> tuple[tuple[str, str] | None, tuple[str, str] | None]:
    """((frequency unit, key), (FRF unit, key)) the preamble states, each None if not:
    the last word of an x-axis line if it is Hz or kHz; the last word of a y-axis line if
    it is an FRF unit (the whole value where it is a level in dB, "dB re 1 g/N")."""
    x = y = None
    for key, value in metadata:
        folded = re.sub("[^a-z]", "", key.lower())
        words = value.split()
        if not words:
            continue
        if folded in _X_UNIT_KEYS and x is None and words[-1] in FREQUENCY_UNITS:
            x = (words[-1], key)
        if folded in _Y_UNIT_KEYS and y is None:
            unit = value.strip() if "db" in value.lower() else words[-1]
            try:
                frf_unit(clean_label(re.sub(r"(?i)db|re\s*1", "", unit)))
            except FormatError:
                continue
            y = (unit if "db" in value.lower() else clean_label(unit), key)
    return x, y


def _bare_frf_unit(cell: str) -> str | None:
    """The FRF unit a header cell is made of alone ("(m/s²)/N", "g/N"), else None."""
    text = cell.strip("\"' ")
    if "/" not in text and ")(" not in text:
        return None
    try:
        frf_unit(clean_label(text))
    except FormatError:
        return None
    return text


def _bare_phase_unit(cell: str) -> str | None:
    """The phase unit a header cell is made of alone ("°", "deg", "rad"), else None."""
    text = clean_label(cell.strip("\"' ")).lower()
    return text if text in _PHASE_UNITS else None


#: A phase column with no unit whose values all lie within +-pi (with this slack for a
#: rounded 3.1416) and span more than RADIANS_SPAN looks like radians read as degrees.
RADIANS_SLACK = 1e-3
RADIANS_SPAN = 1.0


def _radians_note(table: Table, col: int, values: np.ndarray) -> str:
    """The note on a phase column ``col`` with no unit that looks like radians, or "".

    values: the column as read. Degrees stay the default (a unit-less phase is read as
    degrees, as documented); a phase that never leaves +-pi yet spans more than a
    radian is told, since read as degrees it would be a nearly real FRF. A small phase
    in degrees (a span below 1) is not told."""
    low, high = float(np.min(values)), float(np.max(values))
    if max(-low, high) > np.pi * (1 + RADIANS_SLACK) or high - low <= RADIANS_SPAN:
        return ""
    name = (table.header or [""] * (col + 1))[col]
    return (
        f"column {col + 1} {name!r} has no unit and all its values lie within ±π ({low:.4g} to {high:.4g}): "
        f"read as degrees, but it looks like radians; if it is, write the unit in the header, "
        f"'{name} [rad]' ('{name} [deg]' says degrees)"
    )


def _label(table: Table, col: int) -> str:
    return repr(table.header[col]) if table.header else f"index {col}"


def _form(
    name: str, units: list[str], option: str | None, row_units: set[str] | None = None, preamble_key: str = ""
) -> tuple[str, float, str]:
    """(form, SI factor, where from) of the table's FRFs. A unit of the units row
    (``row_units``) that is no FRF unit ("Ratio") is passed over: accelerance by default.
    ``preamble_key``: the preamble line the FRF unit came from, if it did."""
    row_units = row_units or set()
    parsed, unknown = [], []
    for unit in dict.fromkeys(units):
        try:
            parsed.append((unit, *frf_unit(unit)))
        except FormatError:
            if unit in row_units and not looks_like_frf_unit(unit):
                unknown.append(unit)
            elif option is None:
                raise FormatError(
                    f"{name}: {frf_unit_error(unit)}; or, if the values are in SI units, give --frf-form"
                ) from None
    if len({(form, factor) for _, form, factor in parsed}) > 1:
        shown = ", ".join(frf_unit_text(u) for u, *_ in parsed)
        raise FormatError(f"{name}: the FRF columns have different units ({shown})")
    where = "units row" if parsed and parsed[0][0] in row_units else "header"
    if preamble_key:
        where = f"preamble's {preamble_key!r}"
    if option is not None:
        said = f"option; the {where} says {frf_unit_text(parsed[0][0])}" if parsed else "option"
        same = [factor for _, form, factor in parsed if form == option]
        return option, same[0] if same else 1.0, said
    if parsed:
        return parsed[0][1], parsed[0][2], f"{where} ({frf_unit_text(parsed[0][0])})"
    if unknown:
        return (
            "accelerance",
            1.0,
            (f"default: the units row says {one_line(unknown[0])[:40]!r}, no FRF unit; (m/s^2)/N assumed"),
        )
    return "accelerance", 1.0, "default: nothing in the file says; (m/s^2)/N assumed"


def _check_first_data(name: str, layout: Layout) -> None:
    """A first row of numbers is data: refuse it in one line when the table reader would
    take it for a header (a cell it cannot read as written). Empty cells are no header
    (a delimiter at the end of the line): the table reader reads past them."""
    if layout.header is not None or layout.first_data is None:
        return
    where = f"{name} line {layout.first_data + 1}: a row of numbers, so data, not a header"
    for cell in layout.data_cells:
        if not cell:
            continue
        try:
            float(cell.replace(",", ".", 1) if cell.count(",") == 1 else cell)
        except ValueError:
            raise FormatError(
                f"{where}, but {one_line(cell)[:40]!r} is not a number as written "
                "(write plain numbers, e.g. 1.5 or -0.25)"
            ) from None


def _kept_preamble(metadata: list[tuple[str, str]]) -> dict[str, str]:
    """The preamble's key/values as text for the provenance: at most MAX_PREAMBLE_LINES
    entries, keys and values cut short; a key seen again keeps its first value."""
    kept: dict[str, str] = {}
    for key, value in metadata[:MAX_PREAMBLE_LINES]:
        key = one_line(key)[:MAX_PREAMBLE_KEY]
        value = one_line(value)
        kept.setdefault(
            key, value if len(value) <= MAX_PREAMBLE_VALUE else value[:MAX_PREAMBLE_VALUE] + "..."
        )
    return kept


def frf_unit_error(unit: str) -> str:
    try:
        frf_unit(unit)
    except FormatError as exc:
        return str(exc)
    return ""
