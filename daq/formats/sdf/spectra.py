"""SDF spectra as a run's spectra (docs/sdf.md, "What `daq import` makes of a file").

Frequency-domain traces of data type linear spectrum (1), auto-power spectrum (2),
cross-power spectrum (3), ordinary coherence (8) when it is not paired with FRFs, and
"unknown" (-99, what our export writes for the kind "other") become
:class:`~daq.store.Spectra`: the alias-protected lines (as for FRFs), values in
engineering units with the window correction the reader applied, then in SI where the
unit is known:

- each channel a trace uses, at its power (pwrOfChan / 48), is a force (N), an
  acceleration (m/s^2) or a voltage (V) by its engineering unit's label, else by the
  SDF unit's dimensions and factor; the trace's unit is their product, e.g. "V^2" for
  the auto-power spectrum of a channel in volts, "(m/s^2)^2", "N*(m/s^2)";
- a data header with a valid yUnit: that label, read the same way ("g^2", "N*g");
- anything else keeps its values and its label verbatim (said in the provenance).

Our own export's COMMENT gives each spectrum's label and unit back (notes.py).
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np

from daq.formats.errors import FormatError
from daq.formats.imported import one_line, show_path
from daq.formats.sdf import codes
from daq.formats.sdf.convert import used_channels, vector_unit
from daq.formats.sdf.model import ACCELERATION_DIMS, FORCE_DIMS, Channel, DataHeader, SdfFile, Unit, Vector
from daq.formats.sdf.notes import Notes
from daq.formats.sdf.traces import alias_free_lines, scaled, traces
from daq.formats.units import parse_unit
from daq.store.model import Spectra

#: SDF data type -> the run's spectrum kind; coherence only when no FRF takes it.
KINDS = {
    codes.LINEAR_SPC_DATA: "linear",
    codes.AUTO_PWR_DATA: "power",
    codes.CROSS_PWR_DATA: "cross",
    codes.ORD_COH_DATA: "coherence",
    -99: "other",
}
#: The kind's SDF data type, for the export (the inverse of KINDS).
DATA_TYPES = {kind: code for code, kind in KINDS.items()}
VOLT_DIMS = (2, 4, -6, -2, 0, 0, 0, 0)  # V = kg m^2 s^-3 A^-1, SI exponents doubled
_VOLTS = {"V": 1.0, "mV": 1e-3}
_POWERED = re.compile(r"^(?:\((?P<inner>.+)\)|(?P<bare>[^()*]+?))\^(?P<power>[0-9]+(?:\.[0-9]+)?)$")


def read_spectra(
    path: Path, sdf: SdfFile, notes: Notes, details: dict, with_coherence: bool
) -> Spectra | None:
    """The file's spectra on the first one's frequency axis (module docstring), or None.
    ``with_coherence``: coherence traces are spectra too (no FRF took them)."""
    kinds = {code: kind for code, kind in KINDS.items() if with_coherence or kind != "coherence"}
    found = traces(sdf, lambda dh: dh.domain == codes.FREQ_DOMAIN and dh.data_type in kinds)
    freq, values, labels, units, kind_of = None, [], [], [], []
    skipped: list[str] = []
    for dh, scans in found:
        if dh.y_per_point != 1:
            skipped.append(f"{dh.title!r} ({dh.y_per_point} values per point)")
            continue
        lines = alias_free_lines(sdf, dh)
        many = len(scans) > 1 or len(dh.vectors) > 1
        for s in scans:
            for v, vector in enumerate(dh.vectors):
                x = np.asarray(dh.x_of(v)[lines], dtype=np.float64)
                if freq is None:
                    freq = x
                elif not np.array_equal(x, freq):
                    skipped.append(f"{dh.title!r} (another frequency axis)")
                    continue
                k = len(values)
                unit, factor = _unit(sdf, dh, vector, notes.spectrum_units.get(k))
                trace = scaled(dh.y[s, v, lines], factor)
                if not np.all(np.isfinite(trace)):
                    if dh.data_type != codes.ORD_COH_DATA:
                        raise FormatError(
                            f"{show_path(path)}: its spectrum {dh.title!r} holds NaN or infinite values"
                        )
                    skipped.append(f"{dh.title!r} (NaN or infinite coherence)")
                    continue
                values.append(trace)
                units.append(unit)
                kind_of.append(kinds[dh.data_type])
                labels.append(
                    notes.spectrum_labels.get(k, dh.title + (f" scan {s} trace {v}" if many else ""))
                )
    if skipped:
        details["notes"].append(f"spectra not imported: {', '.join(sorted(set(skipped)))}")
    if not values:
        return None
    stacked = np.stack(values)
    if (
        stacked.dtype.kind == "c"
        and all(k in ("power", "coherence") for k in kind_of)
        and not stacked.imag.any()
    ):
        stacked = stacked.real.copy()  # a real quantity stored as complex: keep it real
    stacked = stacked.astype(np.complex128 if stacked.dtype.kind == "c" else np.float64)
    details.update(n_spectra=len(values), spectrum_lines=int(freq.size), spectrum_units=sorted(set(units)))
    try:
        return Spectra(frequency_hz=freq, values=stacked, kinds=kind_of, units=units, labels=labels)
    except ValueError as exc:
        raise FormatError(f"{show_path(path)}: {one_line(str(exc))}") from None


def _unit(sdf: SdfFile, dh: DataHeader, vector: Vector, ours: str | None) -> tuple[str, float]:
    """(the trace's unit text, the factor to that unit) (module docstring). ``ours``: the
    unit our export noted, whose values are already in it."""
    if ours is not None:
        return ours, 1.0
    if dh.data_type == codes.ORD_COH_DATA:
        return "", 1.0
    if dh.y_unit_valid:
        return _from_label(dh.y_unit.label)
    powers: dict[str, float] = {}
    factor = 1.0
    try:
        for index, power in used_channels(vector, len(sdf.channels)):
            if power == 0:
                continue
            base, base_factor = _channel_si(sdf.channels[index])
            powers[base] = powers.get(base, 0.0) + power
            factor *= math.pow(base_factor, power)
    except (ValueError, OverflowError):
        powers = {}
    if powers and all(p > 0 for p in powers.values()) and math.isfinite(factor) and factor > 0:
        return _product(powers), factor
    return vector_unit(dh, vector, sdf.channels).label, 1.0


def _channel_si(channel: Channel) -> tuple[str, float]:
    """("N" | "m/s^2" | "V", SI factor) of a channel's engineering unit; ValueError
    when it is none of them."""
    unit: Unit = channel.eng_unit
    try:
        return _base(unit.label)
    except ValueError:
        pass
    for base, dims in (("N", FORCE_DIMS), ("m/s^2", ACCELERATION_DIMS), ("V", VOLT_DIMS)):
        if tuple(unit.dims) == dims and math.isfinite(unit.factor) and unit.factor > 0:
            return base, float(unit.factor)
    raise ValueError(f"unit {unit.label!r} is not a force, an acceleration or a voltage")


def _base(label: str) -> tuple[str, float]:
    text = label.strip()
    if text in _VOLTS:
        return "V", _VOLTS[text]
    for quantity, base in (("force", "N"), ("response", "m/s^2")):
        try:
            return base, parse_unit(text, quantity)
        except FormatError:
            continue
    raise ValueError(f"unit {label!r} is not a force, an acceleration or a voltage")


def _from_label(label: str) -> tuple[str, float]:
    """A yUnit label such as "V^2", "(m/s^2)^2", "g^2" or "N*g" in SI; verbatim (factor
    1) when a part of it is not a known unit."""
    parsed = _powers_of(label)
    return (label, 1.0) if parsed is None else (_product(parsed[0]), parsed[1])


def _powers_of(label: str) -> tuple[dict[str, float], float] | None:
    """({SI base: power}, factor to SI) of a label like "g^2" or "N*(m/s^2)"; None when
    a part of it is not a known unit."""
    powers: dict[str, float] = {}
    factor = 1.0
    for part in _top_level_split(label.strip()):
        try:
            base, base_factor, power = (*_base(part), 1.0)
        except ValueError:
            match = _POWERED.match(part.strip())
            if match is None:
                return None
            try:
                base, base_factor = _base(match.group("inner") or match.group("bare"))
            except ValueError:
                return None
            power = float(match.group("power"))
        powers[base] = powers.get(base, 0.0) + power
        factor *= base_factor**power
    if not powers or not (math.isfinite(factor) and factor > 0):
        return None
    return powers, factor


def unit_of(text: str) -> Unit:
    """The SDF_UNIT our export writes for a spectrum's unit: the label (SDF keeps 10
    characters; the COMMENT keeps it whole), factor 1, and the dimensions when the
    unit is a product of N, m/s^2 and V (none otherwise)."""
    parsed = _powers_of(text)
    dims = [0] * 8
    if parsed is not None and parsed[1] == 1.0:
        by_base = {"N": FORCE_DIMS, "m/s^2": ACCELERATION_DIMS, "V": VOLT_DIMS}
        for base, power in parsed[0].items():
            dims = [d + round(power * b) for d, b in zip(dims, by_base[base], strict=True)]
    return Unit(text[:10], 1.0, tuple(dims))


def _top_level_split(text: str) -> list[str]:
    """``text`` split at the "*" outside parentheses."""
    parts, depth, start = [], 0, 0
    for i, ch in enumerate(text):
        depth += {"(": 1, ")": -1}.get(ch, 0)
        if ch == "*" and depth == 0:
            parts.append(text[start:i])
            start = i + 1
    return [*parts, text[start:]]


def _product(powers: dict[str, float]) -> str:
    """E.g. {"V": 2} -> "V^2", {"m/s^2": 2} -> "(m/s^2)^2", {"N": 1, "m/s^2": 1} -> "N*(m/s^2)"."""
    parts = []
    for base, power in powers.items():
        shown = f"({base})" if "/" in base and (power != 1 or len(powers) > 1) else base
        parts.append(shown if power == 1 else f"{shown}^{power:g}")
    return "*".join(parts)
