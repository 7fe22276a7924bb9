"""A run's numbers written for the pages exactly as ``daq analyze`` prints them (its
``_mode_text`` and band line, daq/cli/commands/analyze.py), with the same functions
(daq/report/numbers.py): the service sends the texts, so that the page, the terminal
and the report cannot drift apart. Each ± to two significant digits and its value to
the same decimal place; a band's edges to four significant digits.

The units are the pages' column heads (Hz, %), so the texts carry none.
"""

from __future__ import annotations

import math
from typing import Any

from daq.report.numbers import plain, with_uncertainty


def _number(value: Any) -> float | None:
    return float(value) if isinstance(value, int | float) and math.isfinite(value) else None


def frequency_text(mode: dict[str, Any]) -> str:
    """'3896 ± 12' (Hz) of a mode of an analysis summary; '1234.5678' without a u."""
    f = _number(mode.get("frequency_hz"))
    if f is None:
        return "–"
    f_text, u_text = with_uncertainty(f, _number(mode.get("frequency_u_hz")), ".4f")
    return f_text if u_text == "–" else f"{f_text} ± {u_text}"


def damping_text(mode: dict[str, Any]) -> str:
    """'2.18 ± 0.89' (%) of a mode of an analysis summary; '0.123' without a u; 'n/a'
    where the analysis gives no damping ratio (the window's decay is larger)."""
    zeta = _number(mode.get("damping_ratio"))
    if zeta is None:
        return "n/a"
    u = _number(mode.get("damping_u"))
    z_text, u_text = with_uncertainty(100 * zeta, None if u is None else 100 * u, ".3g")
    return plain(100 * zeta, ".3g") if u_text == "–" else f"{z_text} ± {u_text}"


def band_text(band: Any) -> str | None:
    """'band 1.088–399.4 Hz: <reason>' of an analysis summary's band (None: none). The
    edges as ``daq analyze`` writes them (four significant digits); the range with an
    en dash, as the pages write ranges, where the terminal has a hyphen."""
    if not isinstance(band, dict):
        return None
    low, high = _number(band.get("low_hz")), _number(band.get("high_hz"))
    if low is None or high is None:
        return None
    a, b = plain(low, ".4g"), plain(high, ".4g")
    sep = " to " if "e" in a or "e" in b or b.startswith("-") else "–"
    reason = band.get("reason")
    return f"band {a}{sep}{b} Hz" + (f": {reason}" if reason else "")


def synthesis_text(error: Any) -> str | None:
    """'synthesis error 38.2 %' (three significant digits, as daq analyze); None: unknown."""
    value = _number(error)
    return None if value is None else f"synthesis error {plain(100 * value, '.3g')} %"


def psi_text(fit: dict[str, Any]) -> str | None:
    """'0.3875 m/s²': a fit summary's Psi with its unit, as the report writes it (that of
    the response for a fit to time records, of the accelerance for one to the FRF)."""
    from daq.report.figures import psi_unit

    value = _number(fit.get("psi"))
    return None if value is None else f"{plain(value, '.4g')} {psi_unit(fit)}"
