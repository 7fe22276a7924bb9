"""Numbers and ranges as a person reads them, for the report and the command line
(daq/cli imports this module: the report cannot import the command line).

Python's ``g`` format turns to an exponent as soon as a number has more integer digits
than the significant digits asked for: 99.6 at two digits is "1e+02", 51200 Hz at four
is "5.12e+04". Those are the numbers a reader knows best, so they are written out.
"""

from __future__ import annotations

import math

#: From here up a number written out is longer than its exponent form helps anyone.
PLAIN_BELOW = 1e15


def plain(value: float, spec: str = ".4g") -> str:
    """``format(value, spec)``, but a ``g`` format's exponent for a number from 1 up to
    1e15 written out, rounded to the same significant digits: plain(99.6, ".2g") is
    "100", plain(51200, ".4g") is "51200". Numbers below 1 keep the exponent form that
    ``g`` gives them below 1e-4 (0.0000123 says less than 1.23e-05)."""
    text = format(value, spec)
    if "e" not in text or not spec.endswith("g") or not math.isfinite(value):
        return text
    if not 1 <= abs(value) < PLAIN_BELOW:
        return text
    # What g kept is a whole number here (its exponent is at least the digits kept).
    flags = spec[:-1].split(".", 1)[0]
    return format(float(text), f"{flags}.0f")


def span(low: float, high: float, spec: str = ".6g", unit: str = "Hz") -> str:
    """A range "LOW-HIGH UNIT", each end as :func:`plain` writes it; " to " instead of
    the hyphen when an end keeps an exponent or the high end is negative, whose own minus
    the hyphen would run into ("1.95313e-05 to 0.999981 Hz", not "1.95313e-05-0.999981 Hz")."""
    a, b = plain(low, spec), plain(high, spec)
    sep = " to " if "e" in a or "e" in b or b.startswith("-") else "-"
    return f"{a}{sep}{b} {unit}".rstrip()


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
