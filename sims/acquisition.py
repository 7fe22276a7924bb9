"""From a hit on the specimen to the two digitised time records the analyzer holds.

Each channel is a chain of linear parts, combined exactly by partial fractions:

    ch1: force (N)            -> sensitivity -> [AC coupling] -> anti-alias filter
    ch2: specimen H (m/s^2/N) -> sensitivity -> [AC coupling] -> anti-alias filter

sampled at 2.56 x span, plus white noise, clipped at the input range and
quantised (16 bits at the full rate, see ``digitise``), then scaled back to
engineering units.

The anti-alias filter stands for the instrument's whole chain: a fixed analog
filter at the full sample rate, then linear-phase digital decimating filters
whose bulk delay the instrument removes. Seen from the record, that chain is a
zero-phase low-pass: the time record stays aligned with the trigger and the
in-band phase is flat at every span (docs/simulator.md, "Anti-alias filtering
and decimation"). It is modelled as H(s) H(-s) with H a 9th-order inverse
Chebyshev low-pass (0.05 dB at the span, 50 dB from 1.56 x span), so 0.1 dB to
the span and 104 dB from 1.56 x span, where aliases would fold into the
lines; its right half-plane poles act anti-causally
(``PoleResidueSystem.respond``). Both
channels share it, so it cancels in the frequency response as it does in the
instrument.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
import scipy.signal

from sims.hammer import Hit
from sims.pole_residue import HalfSinePulses, PoleResidueSystem
from sims.settings import ADC_BITS, MAX_SPAN_HZ, AnalyzerSettings

#: AC coupling: a first-order high-pass at this corner, Hz (proj).
AC_CORNER_HZ = 0.5


#: The prototype H: at most this loss (dB) to the span, at least this attenuation
#: (dB) from STOP_EDGE x span; squared into H(s) H(-s) they double. An inverse
#: Chebyshev rather than an elliptic filter: for the same specification its least
#: damped poles decay 1.6 times faster, so the ringing that a zero-phase filter
#: spreads before and after a hammer pulse fits in a short pre-trigger.
ANTI_ALIAS_PASS_DB, ANTI_ALIAS_STOP_DB, ANTI_ALIAS_STOP_EDGE = 0.05, 50.0, 1.56


@functools.lru_cache(maxsize=1)
def _normalised_anti_alias() -> PoleResidueSystem:
    """Zero-phase low-pass H(s) H(-s), passband edge at 1 rad/s: real and positive
    on the imaginary axis, so it neither delays nor shifts the phase of anything."""
    order, edge = scipy.signal.cheb2ord(
        1.0, ANTI_ALIAS_STOP_EDGE, ANTI_ALIAS_PASS_DB, ANTI_ALIAS_STOP_DB, analog=True
    )
    z, p, k = scipy.signal.cheby2(order, ANTI_ALIAS_STOP_DB, edge, analog=True, output="zpk")
    # H(-s) = k (-1)^(nz - np) prod(s + z) / prod(s + p): the sign keeps H(jw) H(-jw) = |H|^2.
    sign = (-1.0) ** (z.size - p.size)
    return PoleResidueSystem.from_zpk(np.concatenate([z, -z]), np.concatenate([p, -p]), sign * k * k)


def anti_alias(span_hz: float) -> PoleResidueSystem:
    """The (zero-phase) anti-alias filter for a span: passband edge at ``span_hz``."""
    norm = _normalised_anti_alias()
    w = 2 * np.pi * span_hz
    # Scaling s -> s / w moves poles to w p and residues to w r (strictly proper).
    return PoleResidueSystem(norm.poles * w, norm.residues * w, norm.direct)


def ac_coupling() -> PoleResidueSystem:
    """s / (s + w_c) = 1 - w_c / (s + w_c)."""
    wc = 2 * np.pi * AC_CORNER_HZ
    return PoleResidueSystem(np.array([-wc + 0j]), np.array([-wc + 0j]), 1.0)


UNITY = PoleResidueSystem(np.zeros(0, complex), np.zeros(0, complex), 1.0)


@dataclass(frozen=True)
class NoiseModel:
    """White noise at each input, RMS in engineering units (N and m/s^2)."""

    force_rms_n: float = 0.005
    acceleration_rms_m_s2: float = 0.02
    enabled: bool = True


@dataclass(frozen=True)
class Record:
    """Two digitised channels of one hit.

    force_n, acceleration_m_s2 : engineering units, quantised; (2.56 x lines,)
        float64 at baseband, (1.28 x lines,) complex128 in zoom (the band mixed down
        by the center); (1024,) and (512,) on the 35660A.
    start_s : time of the first sample relative to the trigger, s.
    sample_rate_hz : Hz.
    overload : (ch1, ch2) the input exceeded its range during the record.
    peak_v : (ch1, ch2) largest |input voltage| during the record, before clipping.
    """

    force_n: np.ndarray
    acceleration_m_s2: np.ndarray
    start_s: float
    sample_rate_hz: float
    overload: tuple[bool, bool]
    peak_v: tuple[float, float]


@dataclass(frozen=True)
class ChannelChains:
    """Force (N) -> volts at each input: ``raw`` as the input connector sees it (what
    the trigger and the overload detector watch), ``filtered`` after the anti-alias
    filter (what the ADC records)."""

    raw: tuple[PoleResidueSystem, PoleResidueSystem]
    filtered: tuple[PoleResidueSystem, PoleResidueSystem]


def channel_chains(specimen_acceleration: PoleResidueSystem, settings: AnalyzerSettings) -> ChannelChains:
    if settings.zoom:
        # The zoom filter keeps +-span/2 around the center once the band is mixed
        # down; before mixing that is the low-pass moved up to the center.
        aa = anti_alias(settings.span_hz / 2).moved(settings.center_hz)
    else:
        aa = anti_alias(settings.span_hz)
    raw, filtered = [], []
    for ch, first in ((1, UNITY), (2, specimen_acceleration)):
        sens = float(settings.channel("sensitivity", ch))  # type: ignore[arg-type]
        chain = first.scaled(sens)
        if settings.channel("ac_coupled", ch):
            chain = chain.then(ac_coupling())
        raw.append(chain)
        filtered.append(chain.then(aa))
    return ChannelChains((raw[0], raw[1]), (filtered[0], filtered[1]))


def digitise(
    volts: np.ndarray, range_v: float, span_hz: float, top_span_hz: float = MAX_SPAN_HZ
) -> np.ndarray:
    """Clip at the range and quantise, volts (real and imaginary parts apart).

    The ADC converts 16 bits at the full rate (2.56 x the model's top span,
    ``top_span_hz``); the analyzer's decimating filters then average its
    quantisation noise down by the ratio of the top span to this span. Quantising
    the record to a grid of lsb * sqrt(span / top span) gives that same noise
    power: exactly 16 bits at the top span, finer on narrow spans, as on the
    instrument.
    """
    if np.iscomplexobj(volts):
        return digitise(volts.real, range_v, span_hz, top_span_hz) + 1j * digitise(
            volts.imag, range_v, span_hz, top_span_hz
        )
    lsb = range_v / 2 ** (ADC_BITS - 1) * math.sqrt(span_hz / top_span_hz)
    top = range_v * (1 - 2.0 ** -(ADC_BITS - 1))
    return np.round(np.clip(volts, -range_v, top) / lsb) * lsb


#: Past the last contact, the raw signals only ring down; their largest values and
#: any trigger crossing come within this long after it.
RING_WINDOW_S = 0.5


def _watch_times(pulses: HalfSinePulses, system: PoleResidueSystem, t0: float, t1: float) -> np.ndarray:
    """Instants in [t0, t1] dense enough to catch the peaks and level crossings of the
    raw (unfiltered) response: 32 per contact while the hammer touches, 16 per
    period of the fastest pole up to RING_WINDOW_S after it, nothing later."""
    first = float(np.min(pulses.start_s))
    last = float(np.max(pulses.start_s + pulses.width_s))
    parts = []
    a, b = max(t0, first), min(t1, last)
    if b > a:
        parts.append(np.linspace(a, b, math.ceil((b - a) / (float(np.min(pulses.width_s)) / 32)) + 1))
    a, b = max(t0, last), min(t1, last + RING_WINDOW_S)
    fastest_hz = float(np.max(np.abs(system.poles))) / (2 * np.pi) if system.poles.size else 0.0
    if b > a and fastest_hz > 0:
        parts.append(np.linspace(a, b, math.ceil((b - a) * 16 * fastest_hz) + 1))
    return np.concatenate(parts) if parts else np.array([t0])


def _crossings(values: np.ndarray, level: float, slope: str) -> np.ndarray:
    prev, cur = values[:-1], values[1:]
    hit = (prev < level) & (cur >= level) if slope == "POS" else (prev > level) & (cur <= level)
    return np.flatnonzero(hit)


def trigger_time(
    hit: Hit,
    raw_trigger: PoleResidueSystem,
    settings: AnalyzerSettings,
    noise_rms_v: float,
    rng: np.random.Generator,
) -> float | None:
    """When the trigger fires, physics seconds after arming; None if it never does.

    The comparator watches the input itself, before the anti-alias filter, as an
    analog trigger does: a 2 ms hammer pulse triggers at its true height even on a
    12.5 Hz span. Before the hit only noise is there; a level inside the noise
    triggers on it (a false trigger, as on the instrument).
    """
    fs = settings.sample_rate_hz
    level, slope = settings.trigger_level_v, settings.trigger_slope
    armed_at = max(0.0, -settings.trigger_delay_s)  # the pre-trigger buffer must fill first
    start = hit.start_s
    if noise_rms_v > 0 and start > armed_at:
        k = np.arange(math.ceil(armed_at * fs), math.floor(start * fs) + 1)
        quiet = rng.normal(0.0, noise_rms_v, k.size)
        false = _crossings(quiet, level, slope)
        if false.size:
            return float(k[false[0] + 1] / fs)
    t = _watch_times(hit.pulses, raw_trigger, start, math.inf)
    v = raw_trigger.respond(hit.pulses, t)
    found = _crossings(v, level, slope)
    if found.size == 0:
        return None
    i = int(found[0])
    # Linear interpolation between the bracketing instants.
    frac = (level - v[i]) / (v[i + 1] - v[i]) if v[i + 1] != v[i] else 0.0
    return float(t[i] + frac * (t[i + 1] - t[i]))


def acquire(
    hit: Hit,
    chains: ChannelChains,
    settings: AnalyzerSettings,
    noise: NoiseModel,
    rng: np.random.Generator,
) -> Record | None:
    """Trigger, sample and digitise one hit; None when the hit never triggers.

    Physics time 0 is the moment the analyzer was armed. With a trigger, sample k
    is taken at t_trigger + delay + k / fs; in free run at k / fs.
    """
    fs = settings.sample_rate_hz
    sens = (float(settings.sensitivity1_v_per_eu), float(settings.sensitivity2_v_per_eu))
    ranges = (float(settings.range1_v), float(settings.range2_v))
    noise_v = (
        (noise.force_rms_n * sens[0], noise.acceleration_rms_m_s2 * sens[1]) if noise.enabled else (0.0, 0.0)
    )
    fired = 0.0
    if settings.trigger_source == "FREE":
        t_first, start_s = 0.0, 0.0
    else:
        ch = 0 if settings.trigger_source == "CH1" else 1
        fired = trigger_time(hit, chains.raw[ch], settings, noise_v[ch], rng)
        if fired is None:
            return None
        t_first, start_s = fired + settings.trigger_delay_s, settings.trigger_delay_s
    n = settings.record_points
    times = t_first + np.arange(n) / fs
    shift = settings.center_hz if settings.zoom else 0.0
    channels, overload, peaks = [], [], []
    for ch in range(2):
        volts = chains.filtered[ch].respond(hit.pulses, times, shift)
        if shift:
            # The zoom oscillator's phase counts from the trigger, so that every hit's
            # record (and linear spectrum) has the same phase and a vector average holds.
            volts = volts * np.exp(2j * np.pi * shift * fired)
        if noise_v[ch] > 0:
            if settings.zoom:
                volts = volts + rng.normal(0.0, noise_v[ch] / math.sqrt(2), (n, 2)) @ np.array([1.0, 1j])
            else:
                volts = volts + rng.normal(0.0, noise_v[ch], n)
        watch = _watch_times(hit.pulses, chains.raw[ch], times[0], times[-1])
        raw_peak = float(np.max(np.abs(chains.raw[ch].respond(hit.pulses, watch))))
        peaks.append(max(raw_peak, float(np.max(np.abs(volts)))))
        overload.append(peaks[-1] > ranges[ch])
        channels.append(digitise(volts, ranges[ch], settings.span_hz, settings.model.top_span_hz) / sens[ch])
    return Record(
        force_n=channels[0],
        acceleration_m_s2=channels[1],
        start_s=start_s,
        sample_rate_hz=fs,
        overload=(overload[0], overload[1]),
        peak_v=(peaks[0], peaks[1]),
    )
