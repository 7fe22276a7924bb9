"""A value and its standard uncertainty written as a measurement is (GUM 7.2.2): the
analysis' cautions and daq's text, report and page all write them this way, so one value
reads the same everywhere. Pure Python."""

from __future__ import annotations

import math


def with_uncertainty(value: float, u: float | None, spec: str = ".4f") -> tuple[str, str]:
    """(value, u) as a measurement is written: u to two significant digits and the value
    to the same decimal place (1073.2692 with u 2.5: "1073.3", "2.5"; 19.76852 with u
    0.0017: "19.7685", "0.0017"; 30.0 with u 123: "30", "120"). Without a usable u (None,
    not finite, not positive): the value as ``spec`` writes it, and "–"."""
    if u is None or not math.isfinite(u) or u <= 0 or not math.isfinite(value):
        return format(value, spec), "–"
    decimals = 1 - math.floor(math.log10(u))
    if decimals > 0:
        return f"{value:.{decimals}f}", f"{u:.{decimals}f}"
    step = 10.0 ** (-decimals)
    return f"{round(value / step) * step:.0f}", f"{round(u / step) * step:.0f}"
