"""What ``CALC<n>:DATA?`` and ``CALC<n>:X:DATA?`` answer on the simulated 35670A
(docs/instrument-scpi.md, "Feeds", "Coordinates", "Blocks").

A feed's points are complex or real (``points``); the trace format turns each
into one value, or two (re, im) for NYQ and POL (``coordinates``); FORM:DATA
turns the values into an IEEE 488.2 definite block of big-endian float64 or
float32, or comma-separated ASCII (``encode``).
"""

from __future__ import annotations

import numpy as np

from sims.acquisition import Record
from sims.dsp import Average
from sims.settings import AnalyzerSettings
from sims.traces import NoData

#: Feed -> (the averaged function of sims.dsp.Average, or TIM for a time record, channel).
FEED_FUNCTIONS = {
    "XTIM:VOLT 1": ("TIM", 1),
    "XTIM:VOLT 2": ("TIM", 2),
    "XFR:POW:LIN 1": ("LSP1", 1),
    "XFR:POW:LIN 2": ("LSP2", 2),
    "XFR:POW 1": ("PSP1", 1),
    "XFR:POW 2": ("PSP2", 2),
    "XFR:POW:RAT 2,1": ("FRSP", 0),
    "XFR:POW:COH 1,2": ("COHR", 0),
}
#: dB of these are 10 log10 (power-like); of the others 20 log10.
POWER_FEEDS = ("XFR:POW 1", "XFR:POW 2", "XFR:POW:COH 1,2")
#: SCPI's value for minus infinity, for the dB of 0.
NINF = -9.9e37


def n_points(settings: AnalyzerSettings, feed: str) -> int:
    """Points a feed holds with these settings: lines + 1, or the record's samples."""
    if FEED_FUNCTIONS[feed][0] == "TIM":
        return settings.record_points
    return settings.lines + 1


def points(
    settings: AnalyzerSettings, average: Average, last: Record | None, feed: str, eu: tuple[bool, bool]
) -> tuple[np.ndarray, np.ndarray]:
    """(x, z) of a feed: x in s from the trigger or in Hz, z its points (complex or
    real) in engineering units, or in volts at the input for a channel whose
    ``eu`` is off. NoData if nothing is measured yet."""
    function, ch = FEED_FUNCTIONS[feed]
    sens = (float(settings.sensitivity1_v_per_eu), float(settings.sensitivity2_v_per_eu))
    volts = tuple(1.0 if on else s for on, s in zip(eu, sens, strict=True))
    if function == "TIM":
        if last is None:
            raise NoData(f"{feed}: no time record yet")
        data = last.force_n if ch == 1 else last.acceleration_m_s2
        x = last.start_s + np.arange(data.size) / last.sample_rate_hz
        return x, np.asarray(data) * volts[ch - 1]
    try:
        z = average.trace(function)
    except LookupError:
        raise NoData(f"{feed}: nothing averaged yet") from None
    if function.startswith("LSP"):
        z = z * volts[ch - 1]
    elif function.startswith("PSP"):
        z = z * volts[ch - 1] ** 2
    elif function == "FRSP":
        z = z * (volts[1] / volts[0])
    x = settings.start_hz + np.arange(z.size) * settings.line_spacing_hz
    return x, z


def coordinates(z: np.ndarray, fmt: str, power: bool) -> np.ndarray:
    """The values CALC:DATA? sends for points ``z`` in format ``fmt`` (short form)."""
    z = np.asarray(z)
    if fmt in ("NYQ", "POL"):
        zc = z.astype(complex)
        return np.column_stack([zc.real, zc.imag]).ravel()
    if fmt == "REAL":
        return np.real(z).astype(float)
    if fmt == "IMAG":
        return np.imag(z).astype(float)
    magnitude = np.abs(z).astype(float)
    if fmt == "MLIN":
        return magnitude
    if fmt == "MLOG":
        with np.errstate(divide="ignore"):
            db = (10.0 if power else 20.0) * np.log10(magnitude)
        return np.where(magnitude > 0, db, NINF)
    if fmt == "PHAS":
        degrees = np.degrees(np.angle(z))
        return np.where(degrees <= -180.0, degrees + 360.0, degrees)  # (-180, 180]
    if fmt == "UPH":
        return np.degrees(np.unwrap(np.angle(z)))
    raise ValueError(f"unknown format {fmt}")  # pragma: no cover - the table offers no other


def encode(values: np.ndarray, data_format: str) -> tuple[bytes, bool]:
    """(bytes without the terminator, binary?) of ``values`` in FORM:DATA's format."""
    values = np.asarray(values, dtype=float)
    if data_format == "ASC":
        return ",".join(f"{v:+.16E}" for v in values).encode("ascii"), False
    payload = values.astype(">f8" if data_format == "REAL,64" else ">f4").tobytes()
    length = str(len(payload))
    return b"#" + str(len(length)).encode("ascii") + length.encode("ascii") + payload, True
