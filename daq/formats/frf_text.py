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
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np

from daq.errors import UserError
from daq.formats.csv_text import Table, is_frequency_name
from daq.formats.imported import MAX_IMPORT_BYTES, ImportedData, make_frfs, open_checked, show_path
from daq.formats.units import FREQUENCY_UNITS, clean_label, frf_unit
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


def read_frf_text(path: Path, frf_form: str | None = None, max_bytes: int = MAX_IMPORT_BYTES) -> ImportedData:
    """FRFs from a delimited text table (frequency, then Re/Im or magnitude/phase per FRF).

    frf_form: "receptance", "mobility" or "accelerance" to say what the values are (wins
        over the header's units); None: the header's unit decides, else accelerance.
    Returns ImportedData with measured_frfs in SI units of their form. Any problem: UserError.
    """
    path = Path(path)
    name = show_path(path)
    if frf_form is not None and frf_form not in FRF_FORMS:
        raise UserError(f"FRF form {frf_form!r} is not one of {', '.join(FRF_FORMS)}")
    with open_checked(path, max_bytes) as (handle, _):
        table = Table(name)
        table.read(handle, max_bytes)
    data = table.data()
    lines = np.frombuffer(table.lines, dtype=np.int64)
    if table.header is None:
        kinds = ["freq"] + ["re", "im"] * ((table.n_cols - 1) // 2)
        if table.n_cols < 3 or (table.n_cols - 1) % 2:
            raise UserError(
                f"{name}: {table.n_cols} columns without a header; an FRF table needs frequency, "
                "then Re, Im for each FRF (or a header naming the columns)"
            )
        labels_of = [""] * table.n_cols
        units = [None] * table.n_cols
    else:
        kinds, labels_of = [], []
        for i, (cell_name, unit) in enumerate(zip(table.names, table.units, strict=True)):
            kind, label = _kind(cell_name, unit, i == 0)
            if kind is None:
                raise UserError(
                    f"{name}: column {table.header[i]!r} is not frequency, re, im, mag, phase or coherence"
                )
            kinds.append(kind)
            labels_of.append(label)
        units = table.units
    if kinds.count("freq") != 1 or kinds[0] != "freq":
        raise UserError(f"{name}: an FRF table needs exactly one frequency column, the first")
    freq_unit = units[0] or "Hz"
    if freq_unit not in FREQUENCY_UNITS:
        raise UserError(f"{name}: unknown frequency unit {freq_unit!r}; use Hz or kHz")
    freq = data[:, 0] * FREQUENCY_UNITS[freq_unit]
    bad = np.flatnonzero(np.diff(freq) <= 0)
    if bad.size:
        raise UserError(f"{name} line {lines[bad[0] + 1]}: frequency does not increase")
    frfs, labels, coherence, frf_units, layouts = [], [], [], [], set()
    col = 1
    while col < table.n_cols:
        pair = tuple(kinds[col : col + 2])
        if pair not in (("re", "im"), ("mag", "phase")):
            raise UserError(
                f"{name}: column {col + 1} ({_label(table, col)}) starts no FRF: each FRF is a "
                "re, im or a mag, phase pair (optionally followed by its coherence)"
            )
        layouts.add("re-im" if pair == ("re", "im") else "mag-phase")
        first, second = data[:, col], data[:, col + 1]
        if pair == ("re", "im"):
            values = first + 1j * second
            unit_text = units[col] or units[col + 1]
        else:
            mag_unit = units[col] or ""
            db = "db" in mag_unit.lower() or "db" in table.names[col].lower()
            magnitude = 10.0 ** (first / 20.0) if db else first
            if not db and np.any(first < 0):
                row = int(np.flatnonzero(first < 0)[0])
                raise UserError(f"{name} line {lines[row]}: negative magnitude {first[row]!r} (dB? say [dB])")
            phase_unit = (units[col + 1] or "deg").lower()
            if phase_unit not in _PHASE_UNITS:
                raise UserError(f"{name}: unknown phase unit {phase_unit!r}; use deg or rad")
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
            raise UserError(f"{name}: column {col + 1} ({_label(table, col)}) follows no FRF")
    form, factor, said = _form(name, [u for u in frf_units if u and "/" in u], frf_form)
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
    if coherence and coh is None:
        details["notes"] = [f"{len(coherence)} coherence columns for {len(frfs)} FRFs: coherence ignored"]
    measured = make_frfs(path, freq, frf, coh, labels, form)
    return ImportedData(hits=None, measured_frfs=measured, format="frf-text", details=details)


def _kind(cell: str, unit: str | None, first: bool) -> tuple[str | None, str]:
    """(kind, label) of a header cell: kind "freq", "re", "im", "mag", "phase", "coh"."""
    if first and is_frequency_name(cell, unit):
        return "freq", ""
    tokens = _TOKEN.findall(cell)
    kind = next((_KINDS[t.lower()] for t in tokens if t.lower() in _KINDS), None)
    if kind is None and unit is not None and clean_label(unit).lower() in ("db",):
        kind = "mag"
    if kind is None and unit is not None and clean_label(unit).lower() in _PHASE_UNITS:
        kind = "phase"
    label = " ".join(t for t in tokens if t.lower() not in _KINDS)
    return kind, label


def _label(table: Table, col: int) -> str:
    return repr(table.header[col]) if table.header else f"index {col}"


def _form(name: str, units: list[str], option: str | None) -> tuple[str, float, str]:
    """(form, SI factor, where from) of the table's FRFs."""
    parsed = []
    for unit in dict.fromkeys(units):
        try:
            parsed.append((unit, *frf_unit(unit)))
        except UserError:
            if option is None:
                raise UserError(f"{name}: {frf_unit_error(unit)}; or give --frf-form") from None
    if len({(form, factor) for _, form, factor in parsed}) > 1:
        raise UserError(f"{name}: the FRF columns have different units ({', '.join(u for u, *_ in parsed)})")
    if option is not None:
        same = [factor for _, form, factor in parsed if form == option]
        said = f"option (the header says {parsed[0][0]})" if parsed else "option"
        return option, same[0] if same else 1.0, said
    if parsed:
        return parsed[0][1], parsed[0][2], f"header ({parsed[0][0]})"
    return "accelerance", 1.0, "default: nothing in the file says; (m/s^2)/N assumed"


def frf_unit_error(unit: str) -> str:
    try:
        frf_unit(unit)
    except UserError as exc:
        return str(exc)
    return ""
