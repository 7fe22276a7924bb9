"""The analysis band chosen from the data when the user gives none.

An impact test excites what the hammer tip puts energy into: the force autospectrum is
flat up to a corner and then falls (a steel tip further than a rubber one). Above the
point where it has fallen ``FORCE_DROP_DB`` below its low-frequency level, the FRF is
a ratio of noise to little force; below the first lines where the coherence is usable
(the accelerometer's and the amplifiers' low-frequency noise), the same. The band is
therefore

  high = the first line at which the force autospectrum, smoothed over SMOOTH_FRACTION
         of the lines, falls FORCE_DROP_DB below its median over the lowest
         LOW_FRACTION of the lines (no force spectrum: the last line);
  low  = the first line above 0 Hz from which the coherence, a running median over
         SMOOTH_FRACTION of the lines, reaches MIN_COHERENCE (no coherence: the first
         line above 0 Hz);
  high is also lowered to the last line where that running median is still at least
         MIN_COHERENCE (a lightly damped structure's coherence dips at every
         antiresonance: the running median steps over those dips, not over a band
         where the response is noise).

The rule and its figures are those of the common guidance for hammer tests (a tip is
adequate where the force spectrum is within 10-20 dB of its plateau; Brüel & Kjær,
Avitabile). Every choice says why in ``reason``.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
from scipy.ndimage import median_filter, uniform_filter1d

FORCE_DROP_DB = 20.0
MIN_COHERENCE = 0.5
SMOOTH_FRACTION = 0.01
LOW_FRACTION = 0.05
_FORCE_WITHIN = f"the force spectrum stays within {FORCE_DROP_DB:g} dB of its low-frequency level"
#: The chosen band must hold at least this many lines, else every line is used.
MIN_LINES = 40


@dataclass(frozen=True)
class BandChoice:
    """low_hz, high_hz: the band; reason: one sentence, how it was chosen;
    coherence_ok: False when no part of the band reaches MIN_COHERENCE (a caution)."""

    low_hz: float
    high_hz: float
    reason: str
    coherence_ok: bool = True


def choose_band(
    frequency_hz: np.ndarray,
    force_autospectrum: np.ndarray | None = None,
    coherence: np.ndarray | None = None,
) -> BandChoice:
    """The band to identify modes in, from the lines (n_lines,) Hz, the averaged force
    autospectrum (n_lines,) (any units: only its shape counts) and the coherence
    (n_lines,) or (n_frf, n_lines), 0..1 (several FRFs: their mean)."""
    f = np.asarray(frequency_hz, dtype=float)
    lines = np.flatnonzero(np.isfinite(f) & (f > 0))
    if lines.size == 0:
        raise ValueError("no line above 0 Hz to analyse")
    first, last = int(lines[0]), int(lines[-1])
    width = max(3, round(SMOOTH_FRACTION * lines.size) | 1)
    why = []
    low, high = first, last
    if force_autospectrum is not None:
        g = np.asarray(force_autospectrum, dtype=float)[lines]
        g = np.where(np.isfinite(g) & (g > 0), g, 0.0)
        smooth = uniform_filter1d(g, width, mode="nearest")
        ref = float(np.median(g[: max(3, int(LOW_FRACTION * g.size))]))
        if ref > 0:
            below = np.flatnonzero(smooth < ref * 10 ** (-FORCE_DROP_DB / 10))
            if below.size:
                high = int(lines[max(below[0] - 1, 0)])
                why.append(f"{_FORCE_WITHIN} up to {edge_text(f[high])} Hz")
            else:
                why.append(f"{_FORCE_WITHIN} over every line")
    coherence_ok = True
    if coherence is not None:
        c = np.asarray(coherence, dtype=float)
        # Several FRFs: their mean is what the band follows, and the reason says so.
        whose = f"the mean of {c.shape[0]} FRFs': " if c.ndim == 2 and c.shape[0] > 1 else ""
        if c.ndim == 2:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)  # a line with no finite value: NaN, then 0
                c = np.nanmean(c, axis=0)
        c = np.where(np.isfinite(c), c, 0.0)[lines]
        running = median_filter(c, size=width, mode="nearest")
        good = np.flatnonzero(running >= MIN_COHERENCE)
        if good.size == 0:
            coherence_ok = False
            why.append(f"the coherence never reaches {MIN_COHERENCE:g}: every line is used")
        else:
            c_low, c_high = int(lines[good[0]]), int(lines[good[-1]])
            if c_low <= low and c_high >= high:
                # Checked, and limiting neither edge: said, not passed over as if absent.
                usable = f"{whose}{MIN_COHERENCE:g} or more from the lowest line up to the top"
                why.append(f"the coherence ({usable}) limits neither edge")
            said_low = c_low > low
            if said_low:
                low = c_low
                why.append(f"the coherence reaches {MIN_COHERENCE:g} from {edge_text(f[low])} Hz")
            if c_high < high:
                high = c_high
                what = "it" if said_low else "the coherence"
                why.append(f"{what} stays usable up to {edge_text(f[high])} Hz")
    if high - low + 1 < MIN_LINES:
        if low == first and high == last:
            # Nothing was cut: the run itself is that short (a new user's 30-sample file
            # was told its whole span "suggested" a band too narrow, in two contradicting
            # halves).
            return BandChoice(float(f[first]), float(f[last]),
                              f"every line above 0 Hz: the run holds only {lines.size} lines, fewer than the "
                              f"{MIN_LINES} a band chosen from the data needs", coherence_ok)  # fmt: skip
        suggested = f"{edge_text(f[low])}-{edge_text(f[high])} Hz"
        return BandChoice(float(f[first]), float(f[last]),
                          f"every line above 0 Hz: the band the data suggest ({suggested}) "
                          f"holds fewer than {MIN_LINES} lines", coherence_ok)  # fmt: skip
    if force_autospectrum is None and coherence is not None and high == last:
        why.append("there is no force spectrum to limit the top")
    if not why:
        why.append("nothing in the run limits it (no force spectrum, no coherence)")
    return BandChoice(float(f[low]), float(f[high]), "; ".join(why), coherence_ok)


#: An FRF among several whose coherence (its running median) is below MIN_COHERENCE over
#: more than this share of the band is named in a caution: the band follows the FRFs'
#: mean coherence, which one good FRF beside a noisy one keeps above it.
POOR_SHARE = 0.5


def poor_coherence(
    frequency_hz: np.ndarray, coherence: np.ndarray | None, low_hz: float, high_hz: float
) -> list[tuple[int, float, float]]:
    """(index, share of the band's lines, median coherence) of each FRF, among two or more
    (coherence (n_frf, n_lines), 0..1), whose running median coherence (over
    SMOOTH_FRACTION of the lines) stays below MIN_COHERENCE over more than POOR_SHARE of
    the lines from low_hz to high_hz (Hz). [] for one FRF (coherence_ok says it) or none."""
    if coherence is None:
        return []
    c = np.atleast_2d(np.asarray(coherence, dtype=float))
    f = np.asarray(frequency_hz, dtype=float)
    lines = np.flatnonzero(np.isfinite(f) & (f >= low_hz) & (f <= high_hz))
    if c.shape[0] < 2 or lines.size == 0:
        return []
    width = max(3, round(SMOOTH_FRACTION * lines.size) | 1)
    out = []
    for k, row in enumerate(c):
        values = np.where(np.isfinite(row[lines]), row[lines], 0.0)
        share = float(np.mean(median_filter(values, size=width, mode="nearest") < MIN_COHERENCE))
        if share > POOR_SHARE:
            out.append((k, share, float(np.median(values))))
    return out


def edge_text(value: float) -> str:
    """A band edge as a person reads it: four significant digits, never an exponent
    (1.75 Hz, not the line's 1.75021 Hz; 12800 Hz, not 1.28e+04)."""
    return f"{value:.4g}" if abs(value) < 1e4 else f"{value:.0f}"
