"""Peak picking with half-power damping: the paper's single-degree-of-freedom baseline.

Works on |H| averaged over the FRFs (the mean of magnitudes, so FRFs of opposite
sign do not cancel). Each peak's frequency is refined by a parabola through the peak
line and its neighbours (in log |H|, exact for a Gaussian-shaped top, good to
O(zeta^2) for a resonance). Half-power points are where |H| falls to peak / sqrt 2,
linearly interpolated between lines on each side; damping

    zeta = (f_b - f_a) / (2 f_r).

The peak of |H| sits at f_n sqrt(1 - 2 zeta^2) for receptance, f_n for mobility and
f_n / sqrt(1 - 2 zeta^2) for accelerance: within 0.02 % of f_n for zeta < 1 %, which
is this method's domain. When the half-power band is narrower than about two lines, or
a neighbouring peak interrupts it, the damping is NaN (not resolved).
"""

from __future__ import annotations

import numpy as np
from scipy.signal import find_peaks


def _magnitude(frf: np.ndarray) -> np.ndarray:
    h = np.atleast_2d(np.asarray(frf, dtype=complex))
    return np.mean(np.abs(h), axis=0)


def _crossing(f: np.ndarray, mag: np.ndarray, start: int, level: float, step: int) -> float:
    """Frequency where mag first drops below ``level`` walking from ``start`` by ``step``."""
    idx = np.arange(start, -1 if step < 0 else mag.size, step)
    below = np.flatnonzero(mag[idx] < level)
    if below.size == 0:
        return np.nan
    k = idx[below[0]]
    prev = k - step
    # A rise before the crossing means another peak interrupts the band.
    seg = mag[idx[: below[0] + 1]]
    if np.any(np.diff(seg) > 0):
        return np.nan
    return float(np.interp(level, [mag[k], mag[prev]], [f[k], f[prev]]))


def peak_pick(
    frequency_hz: np.ndarray,
    frf: np.ndarray,
    band: tuple[float, float] | None = None,
    prominence: float = 0.1,
    max_peaks: int | None = None,
) -> list[tuple[float, float]]:
    """Resonance peaks of the mean |H| with half-power damping.

    frequency_hz (n_lines,) Hz, uniform. frf (n_lines,) or (n_frf, n_lines) any form.
    band (f1, f2) Hz limits where peaks are looked for. prominence: how far a peak must
    stand above its surroundings, in decades of |H| (0.1 decade = 2 dB). max_peaks keeps
    the highest ones. Returns [(frequency Hz, damping ratio or NaN), ...] by frequency.
    """
    f = np.asarray(frequency_hz, dtype=float)
    mag = _magnitude(frf)
    if f.ndim != 1 or f.size != mag.size or f.size < 3:
        raise ValueError("frequency_hz must be 1-D with one entry per FRF line (at least 3)")
    f1, f2 = (f[0], f[-1]) if band is None else band
    with np.errstate(divide="ignore"):
        logmag = np.log10(np.where(mag > 0, mag, np.nan))
    logmag = np.nan_to_num(logmag, nan=np.nanmin(logmag) if np.any(mag > 0) else 0.0)
    peaks, _props = find_peaks(logmag, prominence=prominence)
    peaks = peaks[(f[peaks] >= f1) & (f[peaks] <= f2)]
    if max_peaks is not None:
        peaks = np.sort(peaks[np.argsort(-mag[peaks])[:max_peaks]])
    out = []
    df = f[1] - f[0]
    for k in peaks:  # a handful of peaks, not lines
        if 0 < k < f.size - 1:
            y0, y1, y2 = logmag[k - 1 : k + 2]
            curv = y0 - 2 * y1 + y2
            shift = 0.5 * (y0 - y2) / curv if curv < 0 else 0.0
            fr = f[k] + shift * df
            peak_level = 10 ** (y1 - 0.25 * (y0 - y2) * shift)
        else:
            fr, peak_level = f[k], mag[k]
        level = peak_level / np.sqrt(2)
        fa = _crossing(f, mag, k, level, -1)
        fb = _crossing(f, mag, k, level, +1)
        zeta = (fb - fa) / (2 * fr)
        if not np.isfinite(zeta) or (fb - fa) < 2 * df:
            zeta = np.nan
        out.append((float(fr), float(zeta)))
    return out
