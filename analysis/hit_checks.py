"""Per-hit checks of an impact test, shared by capture and analysis. Pure numpy, no I/O.

Each check takes one hit's record and returns a :class:`HitCheck`. Records are the
analyzer's time records: (n_samples,) float64 at baseband, or complex128 (the complex
envelope around the centre frequency) in zoom; force in N.

Thresholds and why (docs/capture.md):

- double impact: the analyzer's decimating filters spread a short hammer pulse over
  a few samples with band-limited ringing. Measured on the simulator at a 200 Hz
  span (2 ms pulse, 1.95 ms samples), a clean pulse rings at -24 %, +13 %, -7 %,
  +4 % of its peak after it, and up to 10 % before it. A hit is called double when,
  outside the main pulse (the samples around the peak down to, and including, the
  first sample below FALL_FRACTION = 10 % of the peak on either side), the force rises above
  RISE_FRACTION = 20 % of the peak again: above the filter's largest positive
  sidelobe (13 %) with margin. A rebound weaker than 20 % of the main peak is not
  told from ringing at spans where the pulse covers only a sample or two.
- force roll-off: the force auto-spectrum at the top 10 % of the span is more than
  ``max_drop_db`` (10 dB) below its level over the lowest 10 % (DC excluded): the
  tip is too soft for the span, the modes near its top are barely excited.
- too weak: the peak force uses less than WEAK_FRACTION = 5 % of the force
  channel's range (-26 dB): the record is mostly the converter's noise. The
  decimating filters lower a short pulse's recorded peak at low spans; lower the
  range there.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: double impact: the main pulse ends where the force first falls below this fraction of the peak.
FALL_FRACTION = 0.10
#: double impact: outside the main pulse, a rise above this fraction of the peak is a second hit.
RISE_FRACTION = 0.20
#: force roll-off: largest tolerated drop of the force spectrum across the span, dB.
MAX_DROP_DB = 10.0
#: force roll-off: the share of the span averaged at each end.
BAND_FRACTION = 0.10
#: too weak: a hit's peak below this fraction of the force channel's range is too weak.
WEAK_FRACTION = 0.05

#: clipped: a record at its largest magnitude in at least this many samples.
CLIP_SAMPLES = 4

#: The names of the checks, as used in reject reasons.
OVERLOAD, DOUBLE_IMPACT, FORCE_ROLLOFF, TOO_WEAK = "overload", "double impact", "force roll-off", "too weak"
#: The check of records from a file, which carry no analyzer overload flags.
CLIPPED = "clipped"
#: A file's force that is no hammer pulse (IMPULSE_CREST): noise, or random excitation.
NO_IMPACT = "no impact"
#: A file whose response column looks like the hammer pulse and force column like a
#: decaying response (channels_swapped): the columns were read the wrong way round.
SWAPPED = "swapped columns"
#: A file whose response moves before the hammer strikes, or long after (response_timing):
#: the channels are skewed.
RESPONSE_TIMING = "response timing"


@dataclass(frozen=True)
class HitCheck:
    """One check's verdict on one hit.

    name : the check's name ("overload", "double impact", "force roll-off", "too weak").
    passed : True when the hit is fine in this respect.
    detail : one line for a technician, e.g. "second pulse at 34 % of the peak, 12 ms later".
    value : the number the verdict rests on (units in the check's docstring), or None.
    """

    name: str
    passed: bool
    detail: str
    value: float | None = None

    def as_dict(self) -> dict[str, object]:
        """JSON-able form, as stored in a run's per-hit ``checks``."""
        return {"passed": self.passed, "detail": self.detail, "value": self.value}


def _magnitude_or_signed(force_n: np.ndarray) -> np.ndarray:
    force = np.asarray(force_n)
    if force.ndim != 1 or force.size == 0:
        raise ValueError(f"a force record must be a non-empty 1-D array, got shape {force.shape}")
    # A zoom record is a complex envelope: its magnitude is the pulse's outline.
    if np.iscomplexobj(force):
        return np.abs(force)
    # A force gauge wired the other way round (files from other systems) records the
    # pulse negative: turned so that the largest excursion is the positive peak.
    force = force.astype(np.float64)
    return force if force[np.argmax(np.abs(force))] >= 0 else -force


def overload(flags: tuple[bool, bool]) -> HitCheck:
    """The analyzer's overload flag on (force, response) channel; value: channels overloaded."""
    force_flag, response_flag = (bool(f) for f in flags)
    which = [name for name, flag in (("force", force_flag), ("response", response_flag)) if flag]
    detail = f"{' and '.join(which)} channel overloaded" if which else "no overload"
    return HitCheck(OVERLOAD, not which, detail, float(len(which)))


def double_impact(
    force_n: np.ndarray,
    sample_rate_hz: float,
    fall_fraction: float = FALL_FRACTION,
    rise_fraction: float = RISE_FRACTION,
) -> HitCheck:
    """A second force pulse in the record; value: its height as a fraction of the peak (0 if none).

    force_n : (n_samples,) N, real (baseband) or complex (zoom: its magnitude is used).
    sample_rate_hz : samples per second, Hz (for the delay in the detail).
    """
    if not 0 < fall_fraction < rise_fraction < 1:
        raise ValueError("double impact needs 0 < fall_fraction < rise_fraction < 1")
    force = _magnitude_or_signed(force_n)
    i_peak = int(np.argmax(force))
    peak = float(force[i_peak])
    if not peak > 0:
        return HitCheck(DOUBLE_IMPACT, True, "no force pulse", 0.0)
    first, last = _main_pulse(force, i_peak, fall_fraction)
    outside = np.concatenate([force[:first], force[last:]])
    positions = np.concatenate([np.arange(first), np.arange(last, force.size)])
    if outside.size == 0:
        return HitCheck(DOUBLE_IMPACT, True, "single pulse", 0.0)
    k = int(np.argmax(outside))
    ratio = float(outside[k]) / peak
    if ratio > rise_fraction:
        delay_ms = (positions[k] - i_peak) / sample_rate_hz * 1e3
        return HitCheck(
            DOUBLE_IMPACT,
            False,
            f"second pulse at {ratio:.0%} of the peak, {delay_ms:+.1f} ms from it",
            ratio,
        )
    return HitCheck(DOUBLE_IMPACT, True, f"single pulse (largest rebound {max(ratio, 0.0):.0%})", ratio)


def _main_pulse(force: np.ndarray, i_peak: int, fall_fraction: float = FALL_FRACTION) -> tuple[int, int]:
    """[first, last) samples of the pulse around ``i_peak``: down to, and including, the
    first sample below ``fall_fraction`` of the peak on either side (the samples where
    the force crossed it belong to the pulse's edges)."""
    below = force < fall_fraction * force[i_peak]
    after = np.flatnonzero(below[i_peak + 1 :])
    before = np.flatnonzero(below[:i_peak])
    end = i_peak + 1 + int(after[0]) if after.size else force.size  # first sample past the pulse
    start = int(before[-1]) if before.size else -1  # last sample before the pulse
    return max(start, 0), min(end + 1, force.size)


def force_rolloff(
    force_n: np.ndarray, sample_rate_hz: float, span_hz: float, max_drop_db: float = MAX_DROP_DB
) -> HitCheck:
    """The force spectrum's drop across the span, dB (value), against ``max_drop_db``.

    Compares the mean force auto-spectrum over the top BAND_FRACTION of the span with
    its mean over the lowest BAND_FRACTION (DC excluded). In zoom (complex records),
    the band is centre +- span/2 and the comparison is its top against its bottom.
    force_n : (n_samples,) N; sample_rate_hz, span_hz : Hz.
    """
    force = np.asarray(force_n)
    if force.ndim != 1 or force.size < 2:
        raise ValueError(f"a force record must be a 1-D array of 2 or more samples, got {force.shape}")
    if not (sample_rate_hz > 0 and span_hz > 0 and span_hz <= sample_rate_hz):
        raise ValueError("force roll-off needs 0 < span_hz <= sample_rate_hz")
    if np.iscomplexobj(force):
        offsets = np.fft.fftfreq(force.size, 1.0 / sample_rate_hz)
        power = np.abs(np.fft.fft(force)) ** 2
        low = (offsets >= -span_hz / 2) & (offsets <= -span_hz / 2 + BAND_FRACTION * span_hz)
        top = (offsets <= span_hz / 2) & (offsets >= span_hz / 2 - BAND_FRACTION * span_hz)
    else:
        freq = np.fft.rfftfreq(force.size, 1.0 / sample_rate_hz)
        power = np.abs(np.fft.rfft(force)) ** 2
        low = (freq > 0) & (freq <= BAND_FRACTION * span_hz)
        top = (freq <= span_hz) & (freq >= (1 - BAND_FRACTION) * span_hz)
    if not (low.any() and top.any()):
        raise ValueError("the record is too short to resolve the span's ends: no spectral lines there")
    low_level, top_level = float(power[low].mean()), float(power[top].mean())
    if not low_level > 0:
        return HitCheck(FORCE_ROLLOFF, False, "no force at low frequency", None)
    drop_db = math.inf if top_level <= 0 else 10 * math.log10(low_level / top_level)
    passed = drop_db <= max_drop_db
    detail = f"force spectrum falls {drop_db:.1f} dB across the span" + (
        "" if passed else f" (more than {max_drop_db:g} dB: use a harder tip or a lower span)"
    )
    return HitCheck(FORCE_ROLLOFF, passed, detail, drop_db if math.isfinite(drop_db) else None)


def too_weak(force_n: np.ndarray, range_n: float | None, min_fraction: float = WEAK_FRACTION) -> HitCheck:
    """The peak |force| as a fraction of the channel's range (value); fails below ``min_fraction``.

    force_n : (n_samples,) N. range_n : the force channel's full scale in N (range in V
    over the hammer's sensitivity in V/N); None (autorange) passes unjudged.
    """
    peak = float(np.max(np.abs(np.asarray(force_n))))
    if range_n is None:
        return HitCheck(TOO_WEAK, True, f"peak {peak:.3g} N (autorange: not judged)", None)
    if not range_n > 0:
        raise ValueError(f"range_n must be positive, got {range_n!r}")
    used = peak / range_n
    passed = used >= min_fraction
    detail = f"peak {peak:.3g} N is {used:.0%} of the {range_n:.3g} N range" + (
        "" if passed else f" (below {min_fraction:.0%}: hit harder or lower the range)"
    )
    return HitCheck(TOO_WEAK, passed, detail, used)


def _samples_at_extreme(record: np.ndarray) -> int:
    """How many samples of ``record`` (real or complex) sit exactly at its largest
    magnitude (0 for an all-zero record)."""
    magnitude = np.abs(np.asarray(record))
    if magnitude.size == 0 or not magnitude.max() > 0:
        return 0
    return int(np.count_nonzero(magnitude == magnitude.max()))


def clipped(force_n: np.ndarray, response: np.ndarray, min_samples: int = CLIP_SAMPLES) -> HitCheck:
    """A channel at its largest magnitude in ``min_samples`` or more samples: the converter
    or the recorder cut the signal there, at each peak that went past the limit (a file's
    records carry no overload flags). value: the most such samples of the two channels.
    A clean record reaches its largest value once, or in two or three samples where
    the converter's steps are coarse near a slow peak."""
    counts = {name: _samples_at_extreme(r) for name, r in (("force", force_n), ("response", response))}
    name, most = max(counts.items(), key=lambda item: item[1])
    if most >= min_samples:
        detail = f"the {name} reaches its largest value in {most} samples: cut off at a limit"
        return HitCheck(CLIPPED, False, detail, float(most))
    return HitCheck(CLIPPED, True, "no cut-off peaks", float(most))


#: A force whose crest factor (peak over RMS over the record) is below this is no
#: hammer hit (random or continuous excitation; white noise of 65,536 samples reaches
#: about 4.7), and a double impact means nothing there. A hammer pulse of 15 samples in
#: a record of 1,024 has about 12.
IMPULSE_CREST = 7.0


#: swapped columns: the span around a channel's peak, each side, as a share of the record
#: (16 samples of 1,024, 80 of 5,120: 15.6 ms at 5,120 Hz, 31 ms at 512 Hz), at least
#: SWAP_MIN_HALF samples; records shorter than SWAP_MIN_SAMPLES are not judged (the span
#: would be much of the record).
SWAP_SPAN_FRACTION = 1 / 64
SWAP_MIN_HALF = 2
SWAP_MIN_SAMPLES = 128
#: swapped columns: the response column holds at least SWAP_PULSE_SHARE of its energy in
#: that span (a hammer pulse does) and the force column at most SWAP_DECAY_SHARE of its
#: (a response ringing on does). Why these figures (measured with this span):
#: - a response is the force convolved with the structure's impulse response, so in a
#:   file read the right way round it is never much more concentrated than the force:
#:   the force holds 0.93-1.00 of its energy in the span in every correctly ordered file
#:   we hold (the synthetic trial files, tests/analysis/impact_synth.py, the simulator's
#:   captures on every analyzer and scenario, the measured pyfrf-impact and lvm-2ch
#:   sets), and 0.6 is well below that: a double tap far from the first (outside the span)
#:   at 60 % of its peak still leaves 0.74;
#: - responses reach 0.95 in the span (the seed scenario's heavy damping) and 0.77 in
#:   the synthetic close modes, so the response's share alone tells nothing: only with
#:   the force's low share does it mean a swap; a real hammer pulse holds 0.93-1.00, and
#:   0.85 keeps a noisy one;
#: - a swapped file of a lightly damped beam gives 1.00 and 0.47 (the trial's swapped.csv);
#:   one of a heavily damped structure (its response holding 0.9 in the span) is not told
#:   from a right one, and is let through rather than a right one flagged.
SWAP_PULSE_SHARE = 0.85
SWAP_DECAY_SHARE = 0.6
#: ... or, whatever the force's share, the force column swings to the other side of zero
#: by SWAP_FORCE_SWING of its peak within the span and the response column by no more
#: than SWAP_RESPONSE_SWING of its: a hammer pulse pushes one way (0.00-0.16 in every
#: correctly ordered file above, the lvm-2ch hits' filter ringing the most), an
#: acceleration swings both ways (0.49-1.00). This tells a swapped file of a more damped
#: structure, whose response holds 0.66 of its energy in the span (a new user's, 1.5-2 %
#: damping: the force column swung 0.91, the response 0.00, and every hit was reported as
#: a double impact instead).
SWAP_FORCE_SWING = 0.5
SWAP_RESPONSE_SWING = 0.25


def _peak_share(record: np.ndarray, half: int) -> float:
    """The share of ``record``'s energy (real or complex) within ``half`` samples of its
    largest magnitude; NaN for a record of no energy."""
    magnitude = np.abs(np.asarray(record))
    peak = float(magnitude.max()) if magnitude.size else 0.0
    if not peak > 0:
        return float("nan")
    energy = (magnitude / peak) ** 2  # scaled first: values near 1e200 must not overflow
    i = int(np.argmax(magnitude))
    return float(energy[max(0, i - half) : i + half + 1].sum() / energy.sum())


def _swing(record: np.ndarray, half: int) -> float:
    """How far ``record`` (real) goes to the other side of zero from its largest magnitude,
    within ``half`` samples of it, as a share of that magnitude; NaN for a zero record
    and for a complex one (a zoomed record, shifted to baseband, has no sides of zero)."""
    if np.iscomplexobj(record):
        return float("nan")
    x = np.asarray(record, dtype=float)
    i = int(np.argmax(np.abs(x)))
    peak = abs(float(x[i]))
    if not peak > 0:
        return float("nan")
    window = x[max(0, i - half) : i + half + 1] * np.sign(x[i]) / peak
    return float(max(0.0, -window.min()))


def channels_swapped(force_n: np.ndarray, response: np.ndarray, sample_rate_hz: float) -> HitCheck:
    """Failed when the response column looks like the hammer pulse (SWAP_PULSE_SHARE or
    more of its energy near its peak) and the force column like a decaying response
    (SWAP_DECAY_SHARE or less of its, or swinging to both sides of zero by
    SWAP_FORCE_SWING while the response swings by SWAP_RESPONSE_SWING at most): the
    file's columns were read the wrong way round (a --columns matter). value: the
    response's share less the force's."""
    n = int(np.asarray(force_n).size)
    if n < SWAP_MIN_SAMPLES:
        return HitCheck(SWAPPED, True, f"not judged: {n} samples are too few", None)
    half = max(SWAP_MIN_HALF, round(SWAP_SPAN_FRACTION * n))
    f_share, r_share = _peak_share(force_n, half), _peak_share(response, half)
    if not (math.isfinite(f_share) and math.isfinite(r_share)):
        return HitCheck(SWAPPED, True, "not judged: a channel is zero throughout", None)
    span = f"{1e3 * half / sample_rate_hz:.3g} ms" if sample_rate_hz > 0 else f"{half} samples"
    if r_share >= SWAP_PULSE_SHARE and f_share <= SWAP_DECAY_SHARE:
        detail = (
            f"{r_share:.0%} of the response's energy lies within {span} of its peak, as a hammer "
            f"pulse's does, and {f_share:.0%} of the force's, as a decaying response's"
        )
        return HitCheck(SWAPPED, False, detail, r_share - f_share)
    f_swing, r_swing = _swing(force_n, half), _swing(response, half)
    if r_share >= SWAP_PULSE_SHARE and f_swing >= SWAP_FORCE_SWING and r_swing <= SWAP_RESPONSE_SWING:
        detail = (
            f"within {span} of its peak the response pushes one way, as a hammer pulse does (to "
            f"{r_swing:.0%} of its peak the other way), and the force swings both ways, as a response "
            f"does (to {f_swing:.0%})"
        )
        return HitCheck(SWAPPED, False, detail, r_share - f_share)
    detail = (
        f"within {span} of their peaks: {f_share:.0%} of the force's energy, {r_share:.0%} of the response's"
    )
    return HitCheck(SWAPPED, True, detail, r_share - f_share)


#: response timing: the force pulse starts where the force first rises above this share
#: of its peak excursion (about the record's median), as pretrigger.impact_starts reads it.
TIMING_START_FRACTION = 0.05
#: ... and the response where it first reaches this share of its own peak excursion. In
#: every correctly aligned record we hold it does so within 0-4 ms of the force's start
#: (measured: pyfrf-impact 0.1-0.2 ms, tool-holder-impact 0.0 ms, free-beam 0.25 ms,
#: lvm-2ch 0-3 ms at 1024 Hz, the simulator's captures 2-4 ms at 512 Hz, the synthetic
#: plates 1.3-1.6 ms at 48 kHz); 25 % before the force's start never more than 0 samples.
TIMING_ONSET_FRACTION = 0.10
TIMING_LEAD_FRACTION = 0.25
#: The response moving this many samples before the hammer strikes is a skew between the
#: channels: nothing moves before it is hit, and both channels pass the same filters (their
#: ringing ahead of a pulse is the same in both). Two samples of slack: the force's start
#: is read on a sampled edge.
TIMING_LEAD_SAMPLES = 2
#: The response still quiet this long after the force's start, s: a bending wave crosses a
#: lab-sized structure (metres of beam or plate) in a few ms at the frequencies an impact
#: test reads, so a longer wait is a channel delay or records from different triggers.
TIMING_LAG_S = 0.010
#: ... and never fewer than this many samples (a response one sample late at a low rate).
TIMING_LAG_SAMPLES = 3
#: The response counts as quiet before its onset when its RMS excursion there stays under
#: this share of its peak excursion: a response that is noise (a dead channel) is never
#: quiet, and its "onset" says nothing.
TIMING_QUIET_SHARE = 0.05
#: The force's first tap: its first sample at this share of the peak (as
#: pretrigger.EARLIER_TAP_FRACTION), walked back to TIMING_START_FRACTION.
TIMING_TAP_FRACTION = 0.20
#: Records shorter than this are not judged.
TIMING_MIN_SAMPLES = 64
#: A response whose largest value stands alone (everything beyond TIMING_SPIKE_SAMPLES
#: samples of it under TIMING_SPIKE_SHARE of it) peaks on a glitch: not judged. A response
#: rings on after its peak at a good share of it.
TIMING_SPIKE_SAMPLES = 2
TIMING_SPIKE_SHARE = 0.1


def _sustained(r_dev: np.ndarray, level: float) -> int:
    """The first sample at or above ``level`` whose next two samples reach half of it (a
    response that has started goes on; a lone glitched sample in a pre-trigger does not),
    or the first at or above it where none is so."""
    above = r_dev >= level
    after = np.maximum(np.r_[r_dev[1:], 0.0], np.r_[r_dev[2:], 0.0, 0.0]) >= 0.5 * level
    both = np.flatnonzero(above & after)
    return int(both[0]) if both.size else int(np.argmax(above))


def response_timing(force_n: np.ndarray, response: np.ndarray, sample_rate_hz: float) -> HitCheck:
    """Failed when the response moves before the hammer strikes (it reaches
    TIMING_LEAD_FRACTION of its peak excursion more than TIMING_LEAD_SAMPLES samples before
    the force's first tap starts), or stays quiet for more than TIMING_LAG_S, and at least
    TIMING_LAG_SAMPLES samples, after it (its first TIMING_ONSET_FRACTION of its peak comes
    that late): a skew between the channels, which turns the FRF's phase by 360 degrees
    every 1/skew Hz, a turn no modal model follows. Judged only where the response is quiet
    before its onset. value: the response's onset less the force's start, s (negative:
    before the hit); None where not judged.

    force_n, response : (n_samples,) real records (a zoomed, complex record is not judged:
    its envelope is smeared over the band's width). sample_rate_hz : Hz.
    """
    force, resp = np.asarray(force_n), np.asarray(response)
    n = int(force.size)
    if np.iscomplexobj(force) or np.iscomplexobj(resp):
        return HitCheck(RESPONSE_TIMING, True, "not judged: a zoomed record", None)
    if n < TIMING_MIN_SAMPLES or not sample_rate_hz > 0:
        return HitCheck(RESPONSE_TIMING, True, f"not judged: {n} samples are too few", None)
    f_dev = np.abs(force - np.median(force))
    r_dev = np.abs(resp - np.median(resp))
    f_peak, r_peak = float(f_dev.max()), float(r_dev.max())
    if not (f_peak > 0 and r_peak > 0):
        return HitCheck(RESPONSE_TIMING, True, "not judged: a channel is constant", None)
    r_at = int(np.argmax(r_dev))
    beside = np.concatenate(
        [r_dev[: max(r_at - TIMING_SPIKE_SAMPLES, 0)], r_dev[r_at + TIMING_SPIKE_SAMPLES + 1 :]]
    )
    if beside.size and float(beside.max()) < TIMING_SPIKE_SHARE * r_peak:
        # A lone sample far above the rest (a glitch) is no onset: timed by it, a clean
        # file's response "started 250 ms after the hammer" (a new user's trial).
        return HitCheck(RESPONSE_TIMING, True, "not judged: the response's peak is a lone spike", None)
    # The hammer strikes where its first tap starts, not its largest (a double impact's
    # second strike, larger, made the response to the first "move 14.6 ms before the hammer").
    first_tap = int(np.argmax(f_dev >= TIMING_TAP_FRACTION * f_peak))
    calm = np.flatnonzero(f_dev[: first_tap + 1] < TIMING_START_FRACTION * f_peak)
    start = int(calm[-1]) + 1 if calm.size else 0
    lead_at = _sustained(r_dev, TIMING_LEAD_FRACTION * r_peak)
    onset = _sustained(r_dev, TIMING_ONSET_FRACTION * r_peak)

    # Only a response quiet before its onset says when it started: a dead channel's noise
    # or a previous hit's ring-down never is.
    quiet = onset >= 8 and float(np.sqrt(np.mean((r_dev[:onset] / r_peak) ** 2))) <= TIMING_QUIET_SHARE
    ms = 1e3 / sample_rate_hz
    if start - lead_at > TIMING_LEAD_SAMPLES and quiet:
        lead = start - lead_at
        detail = f"the response moves {lead * ms:.3g} ms ({lead} samples) before the hammer strikes"
        return HitCheck(RESPONSE_TIMING, False, detail, -lead / sample_rate_hz)
    lag_s = (onset - start) / sample_rate_hz
    # At least TIMING_LAG_SAMPLES samples: at 64 Hz one sample is 15.6 ms.
    limit_s = max(TIMING_LAG_S, TIMING_LAG_SAMPLES / sample_rate_hz)
    if lag_s > limit_s and quiet:
        detail = (
            f"the response starts {lag_s * 1e3:.3g} ms after the hammer strikes "
            f"({limit_s * 1e3:.3g} ms at most on a lab-sized structure)"
        )
        return HitCheck(RESPONSE_TIMING, False, detail, lag_s)
    return HitCheck(
        RESPONSE_TIMING,
        True,
        f"the response starts {(onset - start) * ms:+.3g} ms from the force",
        (onset - start) / sample_rate_hz,
    )


#: force glitch: the force's largest value is a lone sample (both neighbours under
#: GLITCH_NEIGHBOUR_SHARE of it) and the response within GLITCH_WINDOW_S of it stays under
#: GLITCH_RESPONSE_SHARE of its own largest excursion: no hammer put it there. A one-sample
#: hammer pulse (a hard tip at 4 kHz) sets the response ringing at once, usually at its peak.
GLITCH_NEIGHBOUR_SHARE = 0.1
GLITCH_WINDOW_S = 0.005
GLITCH_RESPONSE_SHARE = 0.05
#: The check's name.
FORCE_GLITCH = "force glitch"


def force_glitch(force_n: np.ndarray, response: np.ndarray, sample_rate_hz: float) -> HitCheck:
    """Failed when the force's largest value (about the record's median) is a lone sample
    that the response does not answer (GLITCH_NEIGHBOUR_SHARE, GLITCH_WINDOW_S,
    GLITCH_RESPONSE_SHARE): a glitch of the recorder, which then stands for the hit in every
    other check and in the band chosen from the force spectrum. value: the glitch over the
    largest force elsewhere. Zoomed (complex) records are not judged."""
    force, resp = np.asarray(force_n), np.asarray(response)
    if np.iscomplexobj(force) or np.iscomplexobj(resp) or force.size < 8 or not sample_rate_hz > 0:
        return HitCheck(FORCE_GLITCH, True, "not judged", None)
    f_dev = np.abs(force - np.median(force))
    r_dev = np.abs(resp - np.median(resp))
    i = int(np.argmax(f_dev))
    peak, r_peak = float(f_dev[i]), float(r_dev.max())
    if not (peak > 0 and r_peak > 0):
        return HitCheck(FORCE_GLITCH, True, "not judged: a channel is constant", None)
    neighbours = f_dev[max(i - 1, 0) : i + 2]
    lone = float(np.sort(neighbours)[-2]) < GLITCH_NEIGHBOUR_SHARE * peak if neighbours.size > 1 else False
    reach = max(1, round(GLITCH_WINDOW_S * sample_rate_hz))
    answered = float(r_dev[max(i - reach, 0) : i + reach + 1].max()) >= GLITCH_RESPONSE_SHARE * r_peak
    if lone and not answered:
        rest = np.concatenate([f_dev[: max(i - 1, 0)], f_dev[i + 2 :]])
        other = float(rest.max()) if rest.size else 0.0
        detail = (
            f"the force's largest value, {peak:.3g} N at {i / sample_rate_hz:.4g} s, is a lone sample the "
            f"response does not answer (the largest force elsewhere is {other:.3g} N): a glitch, not a hit"
        )
        return HitCheck(FORCE_GLITCH, False, detail, peak / other if other > 0 else None)
    return HitCheck(FORCE_GLITCH, True, "the force's peak is answered by the response", None)


def file_checks(force_n: np.ndarray, response: np.ndarray, sample_rate_hz: float) -> list[HitCheck]:
    """The checks a hit read from a file can have without the analyzer's settings and
    flags: double impact for a force that is a pulse (else "no impact", failed: noise or
    random excitation, where modes read from the FRF may be the noise's), clipped, and
    swapped columns (the response a pulse, the force a decaying response); none for a
    record holding a non-finite value (the store refuses those)."""
    force = np.asarray(force_n)
    if force.size == 0 or not (np.all(np.isfinite(force)) and np.all(np.isfinite(response))):
        return []
    zero = not np.any(force)
    # About the record's median, not zero: a gauge's offset (8 N under 100 N taps, a
    # trial's logger) raised the RMS and failed clean taps as "no hammer pulse".
    force = np.abs(force - np.median(force)) if np.isrealobj(force) else np.abs(force)
    peak = float(force.max())
    # Scaled by the peak first: a file's values near 1e200 must not overflow the square.
    crest = 1.0 / float(np.sqrt(np.mean((force / peak) ** 2))) if peak > 0 else 0.0
    if zero:
        impact = HitCheck(NO_IMPACT, False, "the force is zero in every sample", crest)
    elif crest < IMPULSE_CREST:
        detail = (
            f"the force is no hammer pulse: its peak is {crest:.1f} times its RMS, under "
            f"{IMPULSE_CREST:g} (noise or random excitation)"
        )
        impact = HitCheck(NO_IMPACT, False, detail, crest)
    else:
        impact = double_impact(force_n, sample_rate_hz)
    glitch = force_glitch(force_n, response, sample_rate_hz)
    return [
        impact,
        clipped(force_n, response),
        channels_swapped(force_n, response, sample_rate_hz),
        # A glitch stands for the hammer in the timing too: said once, as the glitch.
        response_timing(force_n, response, sample_rate_hz)
        if glitch.passed
        else HitCheck(RESPONSE_TIMING, True, "not judged: the force holds a glitch", None),
        glitch,
    ]


def run_checks(
    force_n: np.ndarray,
    sample_rate_hz: float,
    span_hz: float,
    overload_flags: tuple[bool, bool],
    range_n: float | None,
    max_drop_db: float = MAX_DROP_DB,
) -> list[HitCheck]:
    """Every check on one hit, in a fixed order: overload, double impact, roll-off, too weak."""
    return [
        overload(overload_flags),
        double_impact(force_n, sample_rate_hz),
        force_rolloff(force_n, sample_rate_hz, span_hz, max_drop_db),
        too_weak(force_n, range_n),
    ]


def failed_names(checks: list[HitCheck]) -> str:
    """The failed checks' names, comma-separated ("" when every check passed): a reject reason."""
    return ", ".join(c.name for c in checks if not c.passed)
