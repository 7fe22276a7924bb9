"""Frequency zones: a wide band cut into overlapping sub-bands, each fitted on its own.

Why: one LSCF model over 26 lightly damped modes from 800 Hz to 9.3 kHz needs an order
near 100 before every mode is stable; this project's whole-band fit took 25 s and 1.2 GB
at order 200 and put poles on antiresonances (measured on a real 5-hit impact test
before zones), while the default order 40 found 4 modes. A sub-band of a few peaks needs
an order of about 20, fits in milliseconds, and its stability diagram is readable.
Commercial tools do the same (PolyMAX bands, ME'scope's sections).

How the zones are cut (plan_zones):
  * a mode indicator, the sum over the FRFs of |H|^2 (each FRF scaled to unit RMS),
    counts the resonance peaks: local maxima standing ``PEAK_PROMINENCE_DB`` above the
    higher of the valleys either side (scipy.signal.find_peaks, in dB);
  * the band is split into cores of at most ``PEAKS_PER_ZONE`` peaks, cut at the
    deepest valley of the indicator between the last peak of one core and the first
    of the next;
  * a core also spans at least MIN_CORE_LINES lines (a noisy FRF has peaks of noise a
    few lines apart; a zone that narrow cannot hold a heavily damped mode);
  * each zone is its core widened to take in the peak next to it on either side, up to
    the valley beyond it, and by at least EXTEND_FRACTION of the core (never by more
    than the core's width): the neighbouring modes are then modelled, not left to bend
    the core's poles. Only the modes whose frequency lies inside a zone's core are
    kept from that zone, so the overlap yields no duplicates.

The model order of a zone follows its content: 3 x its peaks + ORDER_MARGIN (a
complex-basis order is one pole, see analysis.modal_id.lscf; the indicator misses modes
hidden in a neighbour's skirt, hence 3 and not 1 per peak), between MIN_ORDER and
MAX_ORDER.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
from scipy.signal import find_peaks

#: A peak of the mode indicator must stand this far above its surroundings, dB.
PEAK_PROMINENCE_DB = 10.0
#: Peaks per zone core.
PEAKS_PER_ZONE = 4
#: A zone's core spans at least this many lines.
MIN_CORE_LINES = 200
#: At most about this many zones over a band (their cores widen on a long band).
MAX_ZONES = 24
#: A zone reaches at least this fraction of its core's width beyond it on each side.
EXTEND_FRACTION = 0.25
#: Orders a zone gets beyond two per peak: room for the noise and the modes just outside.
ORDER_MARGIN = 10
MIN_ORDER = 30
MAX_ORDER = 60
#: A zone starting closer to 0 Hz than this fraction of its width keeps the real basis:
#: near DC the mirror poles at negative frequencies lie next to the band.
REAL_BASIS_BELOW = 0.5


@dataclass(frozen=True)
class Zone:
    """low_hz, high_hz: the lines fitted; core_low_hz, core_high_hz: the modes kept
    (core_low_hz <= f < core_high_hz, the last core closed); n_peaks: indicator peaks in
    the zone; max_order: its LSCF order; basis: "real" or "complex"."""

    low_hz: float
    high_hz: float
    core_low_hz: float
    core_high_hz: float
    n_peaks: int
    max_order: int
    basis: str

    def in_core(self, frequency_hz: float, last: bool) -> bool:
        above = frequency_hz >= self.core_low_hz
        return above and (frequency_hz <= self.core_high_hz if last else frequency_hz < self.core_high_hz)


def mode_indicator(frf: np.ndarray) -> np.ndarray:
    """(n_lines,) sum over the FRFs of |H|^2, each FRF scaled to unit mean square."""
    h = np.atleast_2d(frf)
    power = np.abs(h) ** 2
    mean = power.mean(axis=1, keepdims=True)
    mean[mean == 0] = 1.0
    return (power / mean).sum(axis=0)


def indicator_peaks(mif: np.ndarray, prominence_db: float = PEAK_PROMINENCE_DB) -> np.ndarray:
    """Indices of the lines where the indicator peaks by ``prominence_db`` (see the module
    docstring)."""
    with np.errstate(divide="ignore"):
        level_db = 10 * np.log10(np.maximum(mif, np.finfo(float).tiny))
    peaks, _ = find_peaks(level_db, prominence=prominence_db)
    return peaks


def zone_order(n_peaks: int, max_order: int | None) -> int:
    """The LSCF order of a zone with ``n_peaks`` peaks, or the order the user fixed."""
    if max_order is not None:
        return int(max_order)
    return int(min(MAX_ORDER, max(MIN_ORDER, 3 * n_peaks + ORDER_MARGIN)))


def plan_zones(
    frequency_hz: np.ndarray,
    frf: np.ndarray,
    max_order: int | None = None,
    peaks_per_zone: int = PEAKS_PER_ZONE,
) -> list[Zone]:
    """Zones covering the lines ``frequency_hz`` (n_lines,) Hz of ``frf`` (n_frf, n_lines).

    max_order: every zone's order if given (else from its peaks). One zone when the band
    holds at most ``peaks_per_zone`` + 2 peaks or fewer than 2 x MIN_CORE_LINES lines.
    """
    f = np.asarray(frequency_hz, dtype=float)
    mif = mode_indicator(frf)
    peaks = indicator_peaks(mif)
    f_lo, f_hi = float(f[0]), float(f[-1])
    # A core spans MIN_CORE_LINES lines, or 1/MAX_ZONES of the band if more: a noisy FRF
    # of 51,201 lines counts peaks of noise by the hundred, and 95 zones of order 60
    # cost more than they find.
    min_core = max(MIN_CORE_LINES, f.size // MAX_ZONES)
    if peaks.size <= peaks_per_zone + 2 or f.size < 2 * min_core:
        return [_zone(f_lo, f_hi, f_lo, f_hi, peaks.size, max_order)]
    # Cores of `peaks_per_zone` peaks and at least MIN_CORE_LINES lines: a noisy FRF has
    # peaks of noise a few lines apart, and a zone a few lines wide cannot hold a
    # heavily damped mode.
    groups: list[list[int]] = [[]]
    for p in peaks:
        g = groups[-1]
        if len(g) >= peaks_per_zone and p - g[0] >= min_core:
            groups.append([])
        groups[-1].append(int(p))
    if len(groups) > 1 and (f.size - 1 - groups[-1][0]) < min_core:
        last = groups.pop()  # the last core too narrow: join it to the one before
        groups[-1] += last
    if len(groups) == 1:
        return [_zone(f_lo, f_hi, f_lo, f_hi, peaks.size, max_order)]
    cuts = [_valley(mif, a[-1], b[0]) for a, b in itertools.pairwise(groups)]
    bounds = [0, *cuts, f.size - 1]
    zones = []
    for k in range(len(groups)):
        core_lo, core_hi = bounds[k], bounds[k + 1]
        # Widen by the neighbouring peak on each side (up to the valley beyond it), and by
        # at least EXTEND_FRACTION of the core: the modes next door are then modelled.
        reach = int(EXTEND_FRACTION * (core_hi - core_lo))
        before, after = peaks[peaks < core_lo], peaks[peaks > core_hi]
        low = _valley(mif, before[-2], before[-1]) if before.size >= 2 else 0
        high = _valley(mif, after[0], after[1]) if after.size >= 2 else f.size - 1
        # ... but never by more than the core's width (a lone peak far off is not next door).
        width = core_hi - core_lo
        low = max(0, core_lo - width, min(low, core_lo - reach))
        high = min(f.size - 1, core_hi + width, max(high, core_hi + reach))
        n_in = int(np.count_nonzero((peaks >= low) & (peaks <= high)))
        zones.append(_zone(f[low], f[high], f[core_lo], f[core_hi], n_in, max_order))
    return zones


#: A zone of its own around a peak no mode accounts for (identify.unexplained_peaks) spans
#: this many lines either side, or this fraction of the peak's frequency if more: what a
#: user's --band around the peak takes in (20-45 Hz for 31 and 33 Hz on 0.5 Hz lines) ...
PEAK_ZONE_LINES = 25
PEAK_ZONE_FRACTION = 0.1
#: ... and only the modes within this many lines of the peak, or this fraction of its
#: frequency, are read from it: the modes around it stay those of the zone they were
#: found in.
PEAK_CORE_LINES = 5
PEAK_CORE_FRACTION = 0.005


def around_peaks(
    frequency_hz: np.ndarray, zones: list[Zone], peaks_hz: list[float], line_hz: float, max_order: int | None
) -> list[Zone]:
    """``zones`` with a zone of its own around each peak of ``peaks_hz`` (Hz; peaks closer
    than their zones' reach share one), each taking the modes of a narrow core round its
    peaks out of the core of the zone that held them (frequency_hz: the lines, Hz)."""
    f_lo, f_hi = float(frequency_hz[0]), float(frequency_hz[-1])

    def reach(p: float) -> float:
        return max(PEAK_ZONE_LINES * line_hz, PEAK_ZONE_FRACTION * p)

    def core(p: float) -> float:
        return max(PEAK_CORE_LINES * line_hz, PEAK_CORE_FRACTION * p)

    groups: list[list[float]] = []
    for p in sorted(peaks_hz):
        if groups and p - reach(p) <= groups[-1][-1] + reach(groups[-1][-1]):
            groups[-1].append(p)
        else:
            groups.append([p])
    local = []
    for g in groups:
        low, high = max(f_lo, g[0] - reach(g[0])), min(f_hi, g[-1] + reach(g[-1]))
        core_low, core_high = max(low, g[0] - core(g[0])), min(high, g[-1] + core(g[-1]))
        local.append(_zone(low, high, core_low, core_high, len(g), max_order))
    out = list(local)
    for z in zones:
        pieces = [(z.core_low_hz, z.core_high_hz)]
        for c in local:
            pieces = [
                piece
                for a, b in pieces
                for piece in ((a, min(b, c.core_low_hz)), (max(a, c.core_high_hz), b))
                if piece[1] > piece[0]
            ]
        out += [Zone(z.low_hz, z.high_hz, a, b, z.n_peaks, z.max_order, z.basis) for a, b in pieces]
    return sorted(out, key=lambda z: z.core_low_hz)


def _valley(mif: np.ndarray, i: int, j: int) -> int:
    """Index of the indicator's minimum between lines i and j (exclusive)."""
    if j - i < 2:
        return int(i)
    return int(i + 1 + np.argmin(mif[i + 1 : j]))


def _zone(low: float, high: float, core_low: float, core_high: float, n_peaks: int, max_order: int | None):
    basis = "real" if low < REAL_BASIS_BELOW * (high - low) else "complex"
    return Zone(float(low), float(high), float(core_low), float(core_high), int(n_peaks),
                zone_order(n_peaks, max_order), basis)  # fmt: skip
