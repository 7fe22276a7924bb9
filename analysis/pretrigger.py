"""A pre-trigger before the impact, and the bias it gives a response that has not died away.

Why: at the lines of a record of length T (k / T Hz), a decaying mode that starts at
the record's first sample and is cut off at its end keeps an exact pole: its cut-off
part only scales the residue. A mode that starts t0 into the record (a pre-trigger) and
is cut off at T is multiplied, line by line, by

    D(f) = 1 - r exp(i 2 pi f t0),   r = exp(-sigma (T - t0)),   sigma = zeta 2 pi fn,

which turns across the mode's half-power band (2 sigma wide in rad/s) by about
2 sigma t0: its pole moves. A file with 0.2 s of pre-trigger in 0.5 s records, a 45 Hz
mode at 1.5 % (r = 0.28, sigma t0 = 0.85), read 1.89 +- 0.04 % from 3 hits: 9 u off,
the same in every hit, so no spread over hits shows it. Cut at the impact, the same hits
read 1.507 +- 0.014 %. An analyzer's exponential window makes r negligible, which is why
this only matters for records without windows (files that say none).

Pure numpy; time records (n_hits, n_samples) at baseband.
"""

from __future__ import annotations

import numpy as np

#: The pulse starts where the force first rises above this fraction of its peak, going
#: back from the peak (above the noise of a hammer's force channel).
START_FRACTION = 0.05
#: Samples kept before that start, so the cut takes nothing of the pulse's rise.
MARGIN_SAMPLES = 2
#: A pre-trigger shorter than this many samples is left alone.
MIN_PRETRIGGER_SAMPLES = 8
#: Cut when some mode's bias measure r * min(sigma t0, 1) exceeds this: a 1 % turn of D
#: across the half-power band.
BIAS_LIMIT = 0.01


def impact_starts(force_n: np.ndarray) -> np.ndarray:
    """(n_hits,) int: the sample each hit's pulse starts at, less MARGIN_SAMPLES (at least 0).

    force_n: (n_hits, n_samples) N. The baseline is the median of the record; the pulse
    is the largest excursion from it, of either sign.
    """
    force = np.atleast_2d(np.asarray(force_n, dtype=float))
    dev = np.abs(force - np.median(force, axis=1, keepdims=True))
    peak = np.argmax(dev, axis=1)
    starts = np.empty(force.shape[0], dtype=int)
    for k, p in enumerate(peak):
        below = np.flatnonzero(dev[k, : p + 1] < START_FRACTION * dev[k, p])
        starts[k] = max(0, (int(below[-1]) + 1 if below.size else 0) - MARGIN_SAMPLES)
    return starts


def pretrigger_bias(
    frequency_hz: np.ndarray, damping_ratio: np.ndarray, pretrigger_s: float, record_s: float
) -> np.ndarray:
    """(n_modes,) r * min(sigma t0, 1): how much D turns across each mode's half-power band.

    frequency_hz, damping_ratio: (n_modes,) Hz and 1; pretrigger_s: t0, s; record_s: T, s.
    """
    f = np.asarray(frequency_hz, dtype=float)
    zeta = np.clip(np.asarray(damping_ratio, dtype=float), 0.0, None)
    sigma = zeta * 2 * np.pi * f
    left = np.exp(-sigma * max(record_s - pretrigger_s, 0.0))
    return left * np.minimum(sigma * pretrigger_s, 1.0)


def cut_at_impact(
    force_n: np.ndarray, response: np.ndarray, starts: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Both (n_hits, n_samples) records cut to start at each hit's ``starts`` and to one
    length (the shortest that remains); new arrays."""
    force, resp = np.atleast_2d(force_n), np.atleast_2d(response)
    n = force.shape[1] - int(np.max(starts))
    rows = np.asarray(starts, dtype=int)[:, np.newaxis] + np.arange(n)
    return np.take_along_axis(force, rows, axis=1), np.take_along_axis(resp, rows, axis=1)


#: The first half of the pre-trigger must hold at least this many samples to read each
#: channel's noise from.
MIN_NOISE_SAMPLES = 8


def single_hit_noise(
    force_n: np.ndarray,
    response: np.ndarray,
    force_dft: np.ndarray,
    frf: np.ndarray,
    w_force: np.ndarray,
    w_response: np.ndarray,
) -> np.ndarray | None:
    """(n_lines,) the standard deviation of the noise of one hit's FRF at each line, from
    each channel's noise read in the first half of its pre-trigger; None when that half
    is shorter than MIN_NOISE_SAMPLES.

    force_n, response: (n_samples,) the hit's records; force_dft: (n_lines,) the DFT of
    the windowed force on the FRF's lines; frf: (n_lines,) X / F there; w_force,
    w_response: (n_samples,) the windows. White noise of standard deviation s in a
    channel under a window w puts s^2 sum(w^2) on every line of its DFT, whatever the
    window does to its correlation between lines, so that H = X / F carries
    (s_x^2 sum(w_x^2) + |H|^2 s_f^2 sum(w_f^2)) / |F|^2. Why not the FRF's second
    differences: a force window keeps a short stretch of the force's noise, smooth over
    many lines, which the differences between lines do not see.
    """
    # The first half only: an analyzer's decimating filters ring ahead of the pulse (the
    # simulated 35660A's response rises 30 times above its noise in the 16 samples before it).
    quiet = int(impact_starts(np.asarray(force_n)[np.newaxis, :])[0]) // 2
    if quiet < MIN_NOISE_SAMPLES:
        return None
    s_f = float(np.std(force_n[:quiet]))
    s_x = float(np.std(response[:quiet]))
    with np.errstate(divide="ignore", invalid="ignore"):
        var = (s_x**2 * np.sum(w_response**2) + np.abs(frf) ** 2 * s_f**2 * np.sum(w_force**2)) / np.abs(
            force_dft
        ) ** 2
    return np.where(np.isfinite(var), np.sqrt(var), np.nan)
