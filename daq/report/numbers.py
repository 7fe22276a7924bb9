"""Numbers and ranges as a person reads them, for the report and the command line
(daq/cli imports this module: the report cannot import the command line).

Python's ``g`` format turns to an exponent as soon as a number has more integer digits
than the significant digits asked for: 99.6 at two digits is "1e+02", 51200 Hz at four
is "5.12e+04". Those are the numbers a reader knows best, so they are written out.
"""

from __future__ import annotations

import math

# Written as measurements are, the same way in the analysis' cautions and here.
from analysis.measurement_text import with_uncertainty  # noqa: F401 (re-exported)

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
