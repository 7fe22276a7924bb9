"""Numeric arguments with unit suffixes, the 3562A way: ``2 KHZ``, ``-10 MS``, ``20 MV``.

Independent of the driver's encoder on purpose (docs/simulator.md): a bug in a
shared helper would pass every end-to-end test.
"""

from __future__ import annotations

import math
import re
from typing import Literal

Dimension = Literal["frequency", "time", "voltage", "count", "none"]

#: Suffix -> factor to SI, per dimension. DBV is handled separately (logarithmic).
UNIT_FACTORS: dict[str, dict[str, float]] = {
    "frequency": {"HZ": 1.0, "KHZ": 1e3},
    "time": {"S": 1.0, "SEC": 1.0, "MS": 1e-3, "US": 1e-6},
    "voltage": {"V": 1.0, "MV": 1e-3, "UV": 1e-6},
    "count": {},
    "none": {},
}

_NUMBER = re.compile(r"^\s*([+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)\s*([A-Za-z/]*)\s*$")


class ArgumentError(ValueError):
    """A malformed argument or a unit that does not fit the command (error 3 or 4)."""

    def __init__(self, message: str, code: int) -> None:
        super().__init__(message)
        self.code = code


def parse_quantity(text: str, dimension: Dimension) -> float:
    """The SI value of ``text`` (a number with an optional unit suffix)."""
    match = _NUMBER.match(text)
    if not match:
        raise ArgumentError(f"not a number: {text.strip()!r}", 3)
    value = float(match.group(1))
    unit = match.group(2).upper()
    if not unit:
        return value
    if dimension == "voltage" and unit == "DBV":
        return 10.0 ** (value / 20.0)
    factors = UNIT_FACTORS[dimension]
    if unit not in factors:
        raise ArgumentError(f"unit {unit} does not apply here", 4)
    result = value * factors[unit]
    if not math.isfinite(result):
        raise ArgumentError(f"not a finite number: {text.strip()!r}", 3)
    return result


def format_number(value: float) -> str:
    """A numeric query reply: 10 significant digits, HP style (``+2.000000000E+03``)."""
    return f"{value:+.9E}"


def format_exact(value: float) -> str:
    """A float64 in ASCII that reads back bit-exactly (17 significant digits)."""
    return f"{value:+.16E}"
