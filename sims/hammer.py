"""The simulated technician and impact hammer: when and how hard each hit lands."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from sims.pole_residue import HalfSinePulses


@dataclass(frozen=True)
class HammerModel:
    """Random half-sine hits.

    peak_force_n : mean peak force, N; each hit draws N(mean, rel_spread * mean), > 0.
    pulse_width_s : contact time of a hit, s (a soft tip: ~2 ms), +-10 % per hit.
    wait_s : (low, high) seconds the technician takes to hit once the analyzer is armed.
    double_hit_probability : chance that the hammer bounces and hits again.
    double_hit_delay_s : (low, high) seconds between the two contacts.
    double_hit_ratio : (low, high) second peak as a fraction of the first.
    """

    peak_force_n: float = 5.0
    rel_spread: float = 0.2
    pulse_width_s: float = 2e-3
    wait_s: tuple[float, float] = (0.5, 2.0)
    double_hit_probability: float = 0.0
    double_hit_delay_s: tuple[float, float] = (3e-3, 15e-3)
    double_hit_ratio: tuple[float, float] = (0.2, 0.5)

    def __post_init__(self) -> None:
        if not (self.peak_force_n > 0 and self.pulse_width_s > 0 and 0 <= self.double_hit_probability <= 1):
            raise ValueError("hammer: peak force and pulse width must be positive, probability in 0..1")
        if not 0 <= self.rel_spread <= 1:
            raise ValueError("hammer: rel_spread must be 0..1")
        if not (0 <= self.wait_s[0] <= self.wait_s[1]):
            raise ValueError("hammer: wait_s must be (low, high) with 0 <= low <= high")


@dataclass(frozen=True)
class Hit:
    """One strike: how long after arming it lands (s) and its force pulses (N)."""

    wait_s: float
    pulses: HalfSinePulses

    @property
    def start_s(self) -> float:
        return float(self.pulses.start_s[0])


def draw_hit(hammer: HammerModel, rng: np.random.Generator, earliest_s: float = 0.0) -> Hit:
    """A random hit landing no earlier than ``earliest_s`` after arming (physics time)."""
    wait = float(rng.uniform(*hammer.wait_s))
    start = max(wait, earliest_s)
    peak = float(
        max(
            0.05 * hammer.peak_force_n,
            rng.normal(hammer.peak_force_n, hammer.rel_spread * hammer.peak_force_n),
        )
    )
    width = float(hammer.pulse_width_s * rng.uniform(0.9, 1.1))
    starts, widths, peaks = [start], [width], [peak]
    if rng.uniform() < hammer.double_hit_probability:
        starts.append(start + width + float(rng.uniform(*hammer.double_hit_delay_s)))
        widths.append(width)
        peaks.append(peak * float(rng.uniform(*hammer.double_hit_ratio)))
    return Hit(wait, HalfSinePulses(np.array(starts), np.array(widths), np.array(peaks)))


#: What ``SIM:HAMMER`` and ``daq sim serve --hammer`` may change.
ADJUSTABLE = ("peak_force_n", "pulse_width_s", "double_hit_probability", "rel_spread")


def adjusted(hammer: HammerModel, spec: str) -> HammerModel:
    """``hammer`` with ``key=value,...`` changes applied; ValueError names a bad one."""
    changes = {}
    for pair in spec.split(","):
        key, sep, value = pair.partition("=")
        key = key.strip().lower()
        if key not in ADJUSTABLE or not sep:
            raise ValueError(
                f"hammer settings are key=value with keys {', '.join(ADJUSTABLE)}; got {pair.strip()!r}"
            )
        try:
            changes[key] = float(value)
        except ValueError:
            raise ValueError(f"hammer setting {key}: {value.strip()!r} is not a number") from None
        if not math.isfinite(changes[key]):
            raise ValueError(f"hammer setting {key} must be finite")
    return replace(hammer, **changes)
