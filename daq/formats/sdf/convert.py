"""From stored numbers to engineering units and back (the guide's "Correcting Y-axis Data").

Stored y values are in the instrument's internal unit (usually volts) without the
engineering-unit (EU) or window correction. For a trace made from channels c with
powers p = pwrOfChan / 48 (VECTOR_HDR):

    EU value = stored value * prod_c (window_c / int2engrUnit_c) ** p_c

window_c is 1 outside the frequency and order domains and when the channel's
windowCorrMode says a correction has already been applied (1 narrow, 2 wide, 3 user);
when it says none has (0), it is the window's narrowBandCorr (the default ``window``
policy "narrow": the amplitude of a sinusoid, as the analyzers show spectra; "wide"
takes wideBandCorr, "none" leaves the data uncorrected). Integer y data (int16, int32)
are first turned into the internal unit with the trace's channel: channelOffset +
channelScale * stored (revision 2 and 3; revision 1 has no such fields: scale 1, offset 0).
docs/sdf.md explains the choice for windowCorrMode 0, which the guide's pages disagree on.
"""

from __future__ import annotations

import math

from daq.formats.sdf import codes
from daq.formats.sdf.model import Channel, DataHeader, Unit, Vector, Window

WINDOW_POLICIES = ("narrow", "wide", "none")
_WINDOWED_DOMAINS = (codes.FREQ_DOMAIN, codes.ORDER_DOMAIN)


def window_factor(window: Window, policy: str) -> float:
    """The window correction one channel contributes, before its power is applied."""
    if window.corr_mode != codes.CORR_NOT_APPLIED or policy == "none":
        return 1.0
    return float(window.narrow_band_corr if policy == "narrow" else window.wide_band_corr)


def used_channels(vector: Vector, n_channels: int) -> list[tuple[int, float]]:
    """(channel index, power) of the channels a trace uses; ValueError for a channel
    index outside the file's channel headers."""
    used = []
    for index, power48 in vector.channels:
        if index == -1 or index is None:
            continue
        if not 0 <= index < n_channels:
            raise ValueError(f"refers to channel header {index}, the file has {n_channels}")
        used.append((index, power48 / 48.0))
    return used


def vector_factor(dh: DataHeader, vector: Vector, channels: list[Channel], policy: str) -> float:
    """EU value = stored value * this factor. ValueError (one line) when the factor
    cannot be formed: an int2engrUnit or window correction of 0 or non-finite, a
    fractional power of a negative number, an overflow."""
    factor = 1.0
    for index, power in used_channels(vector, len(channels)):
        if power == 0:
            continue
        channel = channels[index]
        window = window_factor(channel.window, policy) if dh.domain in _WINDOWED_DOMAINS else 1.0
        eu = float(channel.int2engr)
        if not (math.isfinite(eu) and eu != 0 and math.isfinite(window) and window != 0):
            raise ValueError(
                f"channel header {index} has int2engrUnit {eu!r} and window correction {window!r}; "
                "neither may be 0 or non-finite"
            )
        try:
            factor *= math.pow(window / eu, power)
        except (ValueError, OverflowError):
            raise ValueError(
                f"the correction ({window!r} / {eu!r}) ** {power:g} of channel header {index} "
                "is not a real number"
            ) from None
    if not math.isfinite(factor) or factor == 0:
        raise ValueError(f"its correction factor is {factor!r}")
    return factor


def integer_scaling(vector: Vector, channels: list[Channel]) -> tuple[float, float]:
    """(scale, offset) turning stored integers into the internal unit: the first
    channel the trace uses (row, else column); (1, 0) when it uses none."""
    for index, _power in used_channels(vector, len(channels)):
        channel = channels[index]
        scale, offset = float(channel.scale), float(channel.offset)
        if not (math.isfinite(scale) and math.isfinite(offset)):
            raise ValueError(f"channel header {index} has channelScale {scale!r}, channelOffset {offset!r}")
        return scale, offset
    return 1.0, 0.0


def vector_unit(dh: DataHeader, vector: Vector, channels: list[Channel]) -> Unit:
    """The unit of a trace's EU values: the data header's yUnit when yUnitValid, else
    the product of its channels' engUnits raised to their powers (e.g. "m/s^2/N")."""
    if dh.y_unit_valid:
        return dh.y_unit
    top: list[str] = []
    bottom: list[str] = []
    factor, dims = 1.0, [0.0] * 8
    for index, power in used_channels(vector, len(channels)):
        if power == 0:
            continue
        unit = channels[index].eng_unit
        text = unit.label or "?"
        if abs(power) != 1:
            text = f"({text})^{abs(power):g}" if "/" in text or "^" in text else f"{text}^{abs(power):g}"
        (top if power > 0 else bottom).append(text)
        try:
            factor *= math.pow(abs(unit.factor), power)
        except (ValueError, OverflowError):
            factor = math.nan
        dims = [d + power * u for d, u in zip(dims, unit.dims, strict=True)]
    label = "*".join(top) or ("1" if bottom else "")
    label += "".join(f"/{text}" for text in bottom)
    return Unit(label, factor, tuple(int(d) if d == int(d) else d for d in dims))
