"""An SDF file as the parts of a run: time records become hits, FRFs (with their
coherence) become measured FRFs, spectra become the run's spectra; docs/sdf.md,
"What `daq import` makes of a file".

- Time records: data headers of data type "time" (0). Each trace belongs to the channel
  its vector names; the force channel is the one whose engineering unit is a force (by
  label, or by the SDF unit's dimensions), else the one marked as reference, else the
  first; the response is an acceleration channel, else the next. The k-th force trace
  and the k-th response trace make hit k (scan by scan for scanned data).
- FRFs: data type "frequency response" (4), the alias-protected lines of the
  measurement header (startFreqIndex..stopFreqIndex, what the analyzer shows), in
  (m/s^2)/N; coherence (data type 8) is paired with them in order when there is one
  coherence trace per FRF.
- Linear, auto-power and cross-power spectra, and coherence no FRF takes, become the
  run's spectra (spectra.py), in their own units: a power spectrum is not an FRF, and
  SDF does not say which channel a cross spectrum conjugates, so we do not form H1 from
  spectra. Everything else is listed in the provenance but not imported. A file with
  none of these is refused with one line saying what it holds.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from daq.formats.errors import FormatError
from daq.formats.imported import (
    MAX_IMPORT_BYTES,
    ImportedData,
    check_regular_file,
    make_frfs,
    make_hits,
    mtime_utc,
    show_path,
)
from daq.formats.sdf import codes
from daq.formats.sdf.convert import vector_unit
from daq.formats.sdf.describe import data_kind, describe, what_it_holds
from daq.formats.sdf.model import ACCELERATION_DIMS, FORCE_DIMS, Channel, DataHeader, SdfFile, Vector
from daq.formats.sdf.notes import Notes, decode_notes
from daq.formats.sdf.reader import read_sdf
from daq.formats.sdf.spectra import KINDS as SPECTRUM_KINDS
from daq.formats.sdf.spectra import read_spectra
from daq.formats.sdf.traces import alias_free_lines as _lines
from daq.formats.sdf.traces import scaled as _scaled
from daq.formats.sdf.traces import traces as _traces
from daq.formats.units import parse_unit

AXIS_TOLERANCE = 1e-9  # relative to the step: traces of one hit set share one time axis
FRF_DIMS = (-2, 0, 0, 0, 0, 0, 0, 0)  # (m/s^2)/N = 1/kg, SI exponents doubled


def read_sdf_run(path: Path | str, max_bytes: int = MAX_IMPORT_BYTES) -> ImportedData:
    """Hits (N, m/s^2), measured FRFs ((m/s^2)/N) and/or spectra from the SDF file at
    ``path``. FormatError (one line) when the file cannot be read or holds none of them."""
    path = Path(path)
    name = show_path(path)
    sdf = read_sdf(path, max_bytes=max_bytes)
    stamp = mtime_utc(check_regular_file(path, max_bytes))
    notes = decode_notes(sdf.comments) or Notes()
    details = describe(sdf)
    if sdf.next_file is not None:
        details["notes"].append("only the first logical SDF file is imported")
    frfs, paired = _frfs(path, name, sdf, notes, details)
    spectra = read_spectra(path, sdf, notes, details, with_coherence=not paired)
    hits, problem = _hits(path, name, sdf, notes, stamp, details)
    if problem and frfs is None and spectra is None:
        raise FormatError(f"{name}: {problem}")
    if problem:
        details["notes"].append(f"time records not imported: {problem}")
    if hits is None and frfs is None and spectra is None:
        raise FormatError(
            f"{name}: nothing to import as a run: no FRF, no spectrum and no force/response time "
            f"records; it holds {what_it_holds(sdf)}"
        )
    return ImportedData(hits=hits, measured_frfs=frfs, spectra=spectra, format="sdf", details=details)


def _channel_of(vector: Vector) -> int:
    return vector.row_channel if vector.row_channel >= 0 else vector.col_channel


def _kind(channel: Channel) -> str | None:
    for quantity in ("force", "response"):
        try:
            parse_unit(channel.eng_unit.label, quantity)
            return quantity
        except FormatError:
            pass
    dims = tuple(channel.eng_unit.dims)
    return "force" if dims == FORCE_DIMS else "response" if dims == ACCELERATION_DIMS else None


def _si_factor(channel: Channel, quantity: str, units: dict[str, str]) -> float:
    """SI factor of a channel's engineering unit: by its label, else by its dimensions
    and factor; 1 (values kept, and said so) when it is neither."""
    unit = channel.eng_unit
    try:
        factor = parse_unit(unit.label, quantity)
        units[quantity] = unit.label
        return factor
    except FormatError:
        pass
    dims = FORCE_DIMS if quantity == "force" else ACCELERATION_DIMS
    if tuple(unit.dims) == dims and math.isfinite(unit.factor) and unit.factor > 0:
        units[quantity] = f"{unit.label} (SDF factor {unit.factor:g})"
        return float(unit.factor)
    units[quantity] = f"channel {channel.label!r} in {unit.label!r}: not a {quantity} unit, values kept"
    return 1.0


def _hits(path, name, sdf, notes: Notes, stamp, details) -> tuple[Any, str]:
    """(Hits or None, "" or why the time records cannot make hits)."""
    found = _traces(sdf, lambda dh: dh.domain == codes.TIME_DOMAIN and dh.data_type == codes.TIME_DATA)
    found = [(dh, scans) for dh, scans in found if dh.y_per_point == 1]
    if not found:
        return None, ""
    by_channel: dict[int, list[np.ndarray]] = {}
    axes: dict[int, tuple[DataHeader, ...]] = {}
    for dh, scans in found:
        for channel in dict.fromkeys(_channel_of(v) for v in dh.vectors if _channel_of(v) >= 0):
            columns = [v for v, vector in enumerate(dh.vectors) if _channel_of(vector) == channel]
            block = dh.y[scans][:, columns].reshape(-1, dh.n_points)
            by_channel.setdefault(channel, []).append(block)
            axes[channel] = (*axes.get(channel, ()), dh)
    channels = list(by_channel)
    if len(channels) < 2:
        return None, f"its time records are of {len(channels)} channel(s); hits need a force and a response"
    kinds = {c: _kind(sdf.channels[c]) for c in channels}
    force = next((c for c in channels if kinds[c] == "force"), None)
    if force is None:
        marked = [c for c in channels if sdf.channels[c].attribute & codes.REFERENCE_ATTRIB]
        force = marked[0] if marked else channels[0]
    rest = [c for c in channels if c != force]
    response = next((c for c in rest if kinds[c] == "response"), rest[0])
    if len(channels) > 2:
        skipped = [sdf.channels[c].label for c in rest if c != response]
        details["notes"].append(f"time records of channels {skipped} not imported")
    f_blocks, r_blocks = by_channel[force], by_channel[response]
    lengths = {b.shape[1] for b in f_blocks + r_blocks}
    if len(lengths) != 1:
        return None, f"its force and response time records differ in length ({sorted(lengths)} samples)"
    force_y, response_y = np.concatenate(f_blocks), np.concatenate(r_blocks)
    if force_y.shape != response_y.shape:
        return None, f"it has {force_y.shape[0]} force and {response_y.shape[0]} response time records"
    if force_y.shape[1] < 2:
        return None, "its time records have fewer than 2 samples"
    if force_y.dtype != response_y.dtype:
        return None, "its force and response time records mix real and complex data"
    first = axes[force][0]
    for dh in axes[force] + axes[response]:
        if dh.x_resolution != codes.LINEAR_RES:
            return None, f"time records with a {codes.name_of(codes.X_RESOLUTIONS, dh.x_resolution)} x axis"
        step, start = first.delta_x, first.first_x
        if not (math.isfinite(step) and step > 0 and math.isfinite(start)):
            return None, f"its time records have no usable time axis (step {step!r} s)"
        if abs(dh.first_x - start) > AXIS_TOLERANCE * step or abs(dh.delta_x - step) > AXIS_TOLERANCE * step:
            return None, "its force and response time records have different time axes"
    rate, start = _exact_axis(notes, first.first_x, first.delta_x, details)
    center = 0.0
    if force_y.dtype.kind == "c":
        center = _number(notes.keys.get("center_hz"), sdf.meas.center_freq)
        if not (math.isfinite(center) and center >= 0):
            return None, f"its complex (zoom) time records have no usable centre frequency ({center!r} Hz)"
    units: dict[str, str] = {}
    force_y = _scaled(force_y, _si_factor(sdf.channels[force], "force", units))
    response_y = _scaled(response_y, _si_factor(sdf.channels[response], "response", units))
    if not (np.all(np.isfinite(force_y)) and np.all(np.isfinite(response_y))):
        raise FormatError(f"{name}: its time records hold NaN or infinite values")
    details.update(
        n_records=int(force_y.shape[0]),
        n_samples=int(force_y.shape[1]),
        time_units=units,
        zoom=force_y.dtype.kind == "c",
        force_channel=sdf.channels[force].label,
        response_channel=sdf.channels[response].label,
        windows={
            "hammer": _window_setting(sdf.channels[force].window, notes, "force"),
            "accelerometer": _window_setting(sdf.channels[response].window, notes, "response"),
        },
    )
    return make_hits(path, force_y, response_y, rate, start, center, stamp, notes.rejected), ""


#: SDF window types as the analyzer's window mnemonics (the analysis knows these five).
_WINDOW_MNEMONICS = {
    codes.UNIFORM_WINDOW: "UNIF", 1: "HANN", 2: "FLAT", codes.FORCE_WINDOW: "FORC",
    codes.EXPONENTIAL_WINDOW: "EXPO",
}  # fmt: skip


def _window_setting(window: Any, notes: Notes, role: str) -> dict[str, Any]:
    """A channel's window as the run's analysis reads an analyzer's settings: mnemonic,
    force width (the SDF truncation) and exponential time constant, s. Our own export's
    exact time constant (its comment) beats the header's float32. Unknown types: {}."""
    mnemonic = _WINDOW_MNEMONICS.get(window.type)
    if mnemonic is None:
        return {}
    out: dict[str, Any] = {"window": mnemonic}
    if mnemonic == "FORC" and math.isfinite(window.trunc) and window.trunc > 0:
        out["force_width_s"] = float(window.trunc)
    elif mnemonic == "EXPO":
        exact = _number(notes.keys.get("exp_decay_s")) if role == "response" else math.nan
        decay = exact if math.isfinite(exact) and exact > 0 else float(window.time_const)
        if math.isfinite(decay) and decay > 0:
            out["exp_decay_s"] = decay
    if mnemonic in ("FORC", "EXPO") and len(out) == 1:
        return {}  # a force or exponential window without its parameter cannot be undone
    return out


def _exact_axis(notes: Notes, start: float, step: float, details: dict) -> tuple[float, float]:
    """(sample rate Hz, start s): the DATA_HDR's, or our export's exact values when they fit."""
    rate, exact_start = _number(notes.keys.get("sample_rate_hz")), _number(notes.keys.get("start_s"))
    out_rate = 1.0 / step
    if math.isfinite(rate) and rate > 0 and abs(1.0 / rate - step) <= AXIS_TOLERANCE * step:
        out_rate = rate
    if math.isfinite(exact_start) and abs(exact_start - start) <= AXIS_TOLERANCE * max(abs(start), step):
        start = exact_start
    details["exact_axis_from_comment"] = out_rate == rate and start == exact_start
    return out_rate, start


def _number(text: str | None, default: float = math.nan) -> float:
    try:
        return float(text) if text is not None else default
    except ValueError:
        return default


def _frf_factor(sdf: SdfFile, dh: DataHeader, vector: Vector, units: list[str]) -> float:
    """SI factor of an FRF trace: from its response and force channels' unit labels, or
    the yUnit label "a/b", or the SDF unit's dimensions; 1 (values kept) otherwise."""
    pairs = []
    if not dh.y_unit_valid and (vector.row_power, vector.col_power) == (48, -48) and vector.col_channel >= 0:
        pairs.append(
            (sdf.channels[vector.row_channel].eng_unit.label, sdf.channels[vector.col_channel].eng_unit.label)
        )
    unit = vector_unit(dh, vector, sdf.channels)
    pairs += [
        (unit.label[:i].strip(" ()"), unit.label[i + 1 :].strip(" ()"))
        for i, c in enumerate(unit.label)
        if c == "/"
    ]
    for top, bottom in pairs:
        try:
            factor = parse_unit(top, "response") / parse_unit(bottom, "force")
        except FormatError:
            continue
        units.append(f"{top}/{bottom}")
        return factor
    if tuple(unit.dims) == FRF_DIMS and math.isfinite(unit.factor) and unit.factor > 0:
        units.append(f"{unit.label} (SDF factor {unit.factor:g})")
        return float(unit.factor)
    units.append(f"{unit.label!r}: not (m/s^2)/N, values kept")
    return 1.0


def _frfs(path, name, sdf: SdfFile, notes: Notes, details: dict) -> tuple[Any, bool]:
    """(MeasuredFrf or None, whether the file's coherence was paired with the FRFs)."""
    frequency = (codes.FREQ_DOMAIN,)
    found = _traces(sdf, lambda dh: dh.domain in frequency and dh.data_type == codes.FREQ_RESP_DATA)
    coh_found = _traces(sdf, lambda dh: dh.domain in frequency and dh.data_type == codes.ORD_COH_DATA)
    taken = (codes.TIME_DATA, codes.FREQ_RESP_DATA, *SPECTRUM_KINDS)
    skipped = sorted(
        {data_kind(dh) for dh in sdf.data if dh.data_type not in taken or dh.domain not in (0, 1)}
    )
    if skipped:
        details["notes"].append(f"not imported: {', '.join(skipped)}")
    frf, freq, labels, units = [], None, [], []
    for dh, scans in found:
        if dh.y_per_point != 1:
            details["notes"].append(f"FRF {dh.title!r} with {dh.y_per_point} values per point not imported")
            continue
        lines = _lines(sdf, dh)
        for s in scans:
            for v, vector in enumerate(dh.vectors):
                x = dh.x_of(v)[lines]
                if freq is None:
                    freq = x
                elif not np.array_equal(x, freq):
                    raise FormatError(
                        f"{name}: FRF {dh.title!r} has a different frequency axis from the first FRF"
                    )
                values = dh.y[s, v, lines].astype(np.complex128)
                frf.append(_scaled(values, _frf_factor(sdf, dh, vector, units)))
                many = len(scans) > 1 or len(dh.vectors) > 1
                labels.append(
                    notes.labels.get(len(labels), dh.title + (f" scan {s} trace {v}" if many else ""))
                )
    if not frf:
        return None, False  # coherence alone: the run's spectra
    values = np.stack(frf)
    if not np.all(np.isfinite(values)):
        raise FormatError(f"{name}: its FRFs hold NaN or infinite values")
    coherence = _coherence(sdf, coh_found, freq, len(frf), details)
    details.update(n_frf=len(frf), n_lines=int(freq.size), frf_units=sorted(set(units)))
    _window_decay(sdf, found, notes, details)
    return make_frfs(path, freq, values, coherence, labels), coherence is not None or not coh_found


def _coherence(sdf, found, freq, n_frf: int, details: dict) -> np.ndarray | None:
    traces = [
        dh.y[s, v, _lines(sdf, dh)] for dh, scans in found if dh.y_per_point == 1
        for s in scans for v in range(len(dh.vectors))
        if np.array_equal(dh.x_of(v)[_lines(sdf, dh)], freq)
    ]  # fmt: skip
    if not found:
        return None
    if len(traces) != n_frf:
        details["notes"].append(
            f"{len(traces)} coherence traces on the FRFs' axis for {n_frf} FRFs: kept as spectra"
        )
        return None
    coherence = np.stack(traces)
    if coherence.dtype.kind == "c":
        if np.any(coherence.imag):
            details["notes"].append("complex coherence values: kept as spectra")
            return None
        coherence = coherence.real.copy()
    if not np.all(np.isfinite(coherence)):
        details["notes"].append("coherence with NaN or infinite values: not paired with the FRFs")
        return None
    return coherence


def _window_decay(sdf: SdfFile, found, notes: Notes, details: dict) -> None:
    """exp_decay_s / pulse_s of the exponential window the FRFs went through: our export's
    comment, else the response channel's window (windowTimeConst of an exponential)."""
    decay, pulse = _number(notes.keys.get("exp_decay_s")), _number(notes.keys.get("pulse_s"), 0.0)
    if not (math.isfinite(decay) and decay > 0):
        vector = found[0][0].vectors[0]
        window = sdf.channels[vector.row_channel].window if vector.row_channel >= 0 else None
        if window is None or window.type != codes.EXPONENTIAL_WINDOW:
            return
        if not (math.isfinite(window.time_const) and window.time_const > 0):
            return
        decay, pulse = float(window.time_const), 0.0
    details.update(exp_decay_s=decay, pulse_s=pulse if math.isfinite(pulse) else 0.0)
