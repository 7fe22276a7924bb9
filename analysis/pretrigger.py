"""A pre-trigger before the impact, and the bias it gives a response that has not died away.

Why: at the lines of a record of length T (k / T Hz), a decaying mode that starts at
the record's first sample and is cut off at its end keeps an exact pole: its cut-off
part only scales the residue. A mode that starts t0 into the record (a pre-trigger) and
is cut off at T is multiplied, line by line, by

    D(f) = 1 - r exp(j (omega_d (T - t0) + 2 pi f t0)),   r = exp(-sigma (T - t0)),

sigma = zeta 2 pi fn. Across the mode's half-power band (2 sigma wide in rad/s) D
changes by about 2 r sigma t0, relative to |D| = |1 - r exp(j omega_d T)| at the mode
(small for a lightly damped mode on a line, f T whole, where r is near 1). The FRF's
own pole stays where it is (D has no pole); the pole a fit reads moves. A file with
0.2 s of pre-trigger in 0.5 s records, a 45 Hz mode at 1.5 % (r = 0.28, sigma t0 =
0.85), read 1.89 +- 0.04 % from 3 hits: 9 u off, the same in every hit when the hits
share their pre-trigger, so no spread over hits shows it. Cut at the impact, the same
hits read 1.507 +- 0.014 %. An analyzer's exponential window makes r negligible, which
is why this only matters for records without windows (files that say none).

How large the bias is in a given case (noise, neighbours, the line grid) the measure
above ranks only roughly, so it only screens: where it is above SCREEN_LIMIT the hits
are analysed both ways, and the cut result is kept where such a mode moved by more than
MOVED_BY_U of its standard uncertainty (analysis/run_analysis.py).

Pure numpy; time records (n_hits, n_samples) at baseband.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: The pulse starts where the force first rises above this fraction of its peak, going
#: back from the peak (above the noise of a hammer's force channel).
START_FRACTION = 0.05
#: An earlier excursion above this fraction of the peak is an earlier tap of the same hit
#: (a double tap whose second tap is the larger; hit_checks' RISE_FRACTION): the start
#: is that tap's.
EARLIER_TAP_FRACTION = 0.20
#: Samples kept before that start, so the cut takes nothing of the pulse's rise.
MARGIN_SAMPLES = 2
#: A pre-trigger shorter than this many samples is left alone.
MIN_PRETRIGGER_SAMPLES = 8
#: Analyse the cut records too when some mode's measure (pretrigger_bias) exceeds this.
SCREEN_LIMIT = 1e-3
#: Keep the cut records' result when a screened mode's frequency or damping moved by more
#: than this many of its standard uncertainties (the cut's): cutting moves the lines, and
#: that alone moves modes by up to a u or two.
MOVED_BY_U = 3.0
#: A cut must leave at least this fraction of the record.
MIN_KEPT_FRACTION = 0.25


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
        earlier = np.flatnonzero(dev[k, :p] > EARLIER_TAP_FRACTION * dev[k, p])
        first = int(earlier[0]) if earlier.size else int(p)
        below = np.flatnonzero(dev[k, : first + 1] < START_FRACTION * dev[k, p])
        starts[k] = max(0, (int(below[-1]) + 1 if below.size else 0) - MARGIN_SAMPLES)
    return starts


def pretrigger_bias(
    frequency_hz: np.ndarray, damping_ratio: np.ndarray, pretrigger_s: float, record_s: float
) -> np.ndarray:
    """(n_modes,) 2 r sin(min(sigma t0, pi / 2)) / |1 - r exp(j omega_d T)|: how much D
    (module docstring) changes across each mode's half-power band, relative to its size.

    frequency_hz, damping_ratio: (n_modes,) Hz and 1; pretrigger_s: t0, s; record_s: T, s.
    """
    f = np.asarray(frequency_hz, dtype=float)
    zeta = np.clip(np.asarray(damping_ratio, dtype=float), 0.0, 1.0)
    sigma = zeta * 2 * np.pi * f
    left = np.exp(-sigma * max(record_s - pretrigger_s, 0.0))
    omega_d = 2 * np.pi * f * np.sqrt(1 - zeta**2)
    size = np.abs(1 - left * np.exp(1j * omega_d * record_s))
    turn = 2 * left * np.sin(np.minimum(sigma * pretrigger_s, np.pi / 2))
    return turn / np.maximum(size, 1e-12)


def cut_at_impact(
    force_n: np.ndarray, response: np.ndarray, starts: np.ndarray, n_keep: int | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Both (n_hits, n_samples) records cut to start at each hit's ``starts`` and to one
    length: ``n_keep`` samples (several runs cut to the same lines), else the shortest that
    remains; new arrays."""
    force, resp = np.atleast_2d(force_n), np.atleast_2d(response)
    n = force.shape[1] - int(np.max(starts)) if n_keep is None else int(n_keep)
    if not 0 < n <= force.shape[1] - int(np.max(starts)):
        raise ValueError(f"cannot keep {n} samples after the impacts of records of {force.shape[1]}")
    rows = np.asarray(starts, dtype=int)[:, np.newaxis] + np.arange(n)
    return np.take_along_axis(force, rows, axis=1), np.take_along_axis(resp, rows, axis=1)


@dataclass
class Screen:
    """What the screen says of modes read from whole records: pretrigger_s, the median
    pre-trigger (s); range_s (low, high) over the hits; kept_samples, the samples left
    after the latest impact; suspects, the modes whose measure passed SCREEN_LIMIT;
    too_short: a cut would keep less than MIN_KEPT_FRACTION of the record (caution_text
    says so), so none is made."""

    pretrigger_s: float
    range_s: tuple[float, float]
    kept_samples: int
    suspects: list
    too_short: bool

    def caution_text(self, record_s: float) -> str:
        low, high = self.range_s
        spread = f"{low:.4g} s" if low == high else f"{low:.4g}-{high:.4g} s"
        return (
            f"the hits' pre-trigger ({spread} of {record_s:.4g} s records) may bias the damping of modes "
            "that have not died away by the record's end, and cutting it would leave too little of the "
            "record: record with a shorter pre-trigger (docs/analysis.md)"
        )


def screen(modes: list, starts: np.ndarray, n_samples: int, rate_hz: float) -> Screen | None:
    """The screen of the module docstring over ``modes`` (objects with frequency_hz and
    damping_ratio, None where unknown) read from records of ``n_samples`` at ``rate_hz``
    whose pulses start at ``starts`` (any shape, samples): None when the pre-trigger is
    shorter than MIN_PRETRIGGER_SAMPLES or no mode passes."""
    starts = np.asarray(starts).ravel()
    if not modes or starts.size == 0 or starts.max() < MIN_PRETRIGGER_SAMPLES:
        return None
    pretrigger_s = float(np.median(starts)) / rate_hz
    zeta = np.array([np.nan if m.damping_ratio is None else m.damping_ratio for m in modes], dtype=float)
    bias = pretrigger_bias(np.array([m.frequency_hz for m in modes]), zeta, pretrigger_s, n_samples / rate_hz)
    if not bias.max() > SCREEN_LIMIT:
        return None
    kept = n_samples - int(starts.max())
    return Screen(
        pretrigger_s,
        (float(starts.min()) / rate_hz, float(starts.max()) / rate_hz),
        kept,
        [m for m, b in zip(modes, bias, strict=True) if b > SCREEN_LIMIT],
        kept < MIN_KEPT_FRACTION * n_samples,
    )


def moved(suspects: list, cut_modes: list, cut_frequency_hz: np.ndarray) -> bool:
    """True when a mode of the cut records (``cut_modes``, with frequency_hz,
    frequency_u_hz, damping_ratio, damping_u; read on the lines ``cut_frequency_hz``) lies
    more than MOVED_BY_U of its standard uncertainties from one of the ``suspects`` (the
    nearest within its half-power half-width, or a line), in frequency or damping: the
    pre-trigger changed what the data say. Only suspects count: a cut moves the lines, and
    with them any mode by up to a u or two (lvm-2ch, 2 hits: up to 1.75 u where nothing
    can be biased), so the threshold stands above that too."""
    line = float(np.median(np.diff(cut_frequency_hz))) if np.size(cut_frequency_hz) > 1 else 0.0
    for m in cut_modes:
        near = [w for w in suspects if abs(w.frequency_hz - m.frequency_hz) <= max(
            (m.damping_ratio or 0.0) * m.frequency_hz, line)]  # fmt: skip
        if not near:
            continue
        w = min(near, key=lambda w: abs(w.frequency_hz - m.frequency_hz))
        if m.frequency_u_hz and abs(w.frequency_hz - m.frequency_hz) > MOVED_BY_U * m.frequency_u_hz:
            return True
        both = m.damping_ratio is not None and w.damping_ratio is not None
        if both and m.damping_u and abs(w.damping_ratio - m.damping_ratio) > MOVED_BY_U * m.damping_u:
            return True
    return False


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
