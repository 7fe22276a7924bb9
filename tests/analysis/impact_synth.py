"""Simulated impact tests with known modes, for the identification defaults and the
uncertainty coverage: half-sine force pulses and the exact accelerance of a sum of
viscously damped modes, convolved linearly (the record truncates the decay, as a real
record does), with white noise on both channels."""

from __future__ import annotations

import numpy as np


def impact_hits(
    fn_hz,
    zeta,
    amp,
    fs_hz: float,
    duration_s: float,
    n_hits: int,
    noise: float,
    pulse_s: float,
    seed: int,
    pretrigger_s: float = 0.002,
) -> tuple[np.ndarray, np.ndarray]:
    """(force N, acceleration m/s^2), each (n_hits, n_samples). noise: standard deviation of
    the response noise relative to the response's; the force gets a tenth of that. Each
    pulse starts pretrigger_s (plus up to 0.5 ms) into its record."""
    rng = np.random.default_rng(seed)
    n = round(fs_hz * duration_s)
    t = np.arange(n) / fs_hz
    m = 4 * n  # a longer record, cut: the linear, not circular, convolution
    w = 2 * np.pi * np.fft.rfftfreq(m, 1 / fs_hz)
    wn = 2 * np.pi * np.asarray(fn_hz, dtype=float)
    h = sum(a * -(w**2) / (wr**2 - w**2 + 2j * z * wr * w) for a, wr, z in zip(amp, wn, zeta, strict=True))
    force = np.zeros((n_hits, n))
    response = np.zeros((n_hits, n))
    for k in range(n_hits):
        gain = 100 * (1 + 0.2 * rng.standard_normal())
        t0 = pretrigger_s + 0.0005 * rng.random()
        pulse = np.where((t >= t0) & (t < t0 + pulse_s), np.sin(np.pi * (t - t0) / pulse_s), 0.0) * gain
        response[k] = np.fft.irfft(np.fft.rfft(pulse, m) * h, m)[:n]
        response[k] += noise * np.std(response[k]) * rng.standard_normal(n)
        force[k] = pulse + 0.1 * noise * gain * rng.standard_normal(n)
    return force, response


def wideband_modes() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """26 lightly damped modes (0.02-0.2 %) between 800 Hz and 9.3 kHz, some 0.4 % apart:
    the wide-band impact test of the issue, with known truth."""
    rng = np.random.default_rng(42)
    fn = np.sort(rng.uniform(800, 9300, 26))
    zeta = 10 ** rng.uniform(np.log10(2e-4), np.log10(2e-3), 26)
    amp = 10 ** rng.uniform(-1, 1, 26) * rng.choice([-1, 1], 26)
    return fn, zeta, amp


#: Impact tests to check hit checks on: (modes Hz, damping, amplitudes, fs Hz, record s,
#: pulse s). Light and heavy damping, close modes, a short record, a soft tip.
IMPACT_CASES = [
    ([42.0, 155.0, 388.0, 710.0], [0.012, 0.006, 0.02, 0.004], [1.0, -0.6, 0.4, 0.3], 5120.0, 1.0, 1e-3),
    ([45.0, 132.0, 310.0], [0.015, 0.008, 0.02], [1.0, -0.6, 0.4], 2048.0, 2.0, 2e-3),
    ([100.0, 104.0], [0.002, 0.002], [1.0, 0.8], 1024.0, 4.0, 3e-3),
    ([30.0, 300.0], [0.1, 0.08], [1.0, 0.5], 1024.0, 1.0, 5e-3),
    ([800.0, 2500.0], [0.01, 0.02], [1.0, 0.5], 25600.0, 0.08, 2e-4),
]

#: More damped structures, whose response rings down within the span: 1.5-2 % at 80-560 Hz
#: (a new user's file), 3-5 % at 300-1100 Hz, 2-2.5 % at 1.2 kHz on 25.6 kHz.
DAMPED_CASES = [
    ([80.0, 210.0, 560.0], [0.015, 0.01, 0.02], [1.0, 1.0, 2.0], 4096.0, 1.0, 1.5e-3),
    ([300.0, 420.0, 1100.0], [0.03, 0.05, 0.04], [1.0, 1.5, 3.0], 8192.0, 1.0, 8e-4),
    ([250.0, 1200.0, 1250.0, 3300.0], [0.01, 0.02, 0.025, 0.03], [1.0, 2.0, 1.5, 3.0], 25600.0, 0.5, 3e-4),
]
