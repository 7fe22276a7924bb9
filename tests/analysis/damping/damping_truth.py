"""Noise-free and noisy 'measurements' of the seed model for the damping-fit tests.

The seed's model (Ritz N = 3, Table 1) with the eq (18) damping, struck by half-sine
hammer pulses (2 ms) recorded at 512 Hz (the analyzer's 200 Hz span), 1024 samples.
Each force sample is the pulse's mean over that sample (a 2 ms pulse is about one
sample long here, so point samples of it would miss most of the impulse).
"""

from __future__ import annotations

import numpy as np

from analysis.damping.objective import FrequencyData, TimeData
from analysis.response import frequency_response, time_response
from analysis.ritz import RitzBeam
from analysis.seed import eq18_damping_matrix

RATE_HZ = 512.0
N_SAMPLES = 1024
#: Damping ratios of eq (18) on this model (docs/method.md; analysis.modal.damped_modes).
EQ18_RATIOS = (0.036058, 0.203226, 0.161986)


def half_sine_force(peak_n: float, start_s: float, width_s: float = 2e-3) -> np.ndarray:
    """(N_SAMPLES,) N: cell averages of a half-sine pulse of the given peak and width."""
    edges = np.arange(N_SAMPLES + 1) / RATE_HZ
    # Integral of peak sin(pi (t - t0) / w) over [a, b], clipped to the pulse.
    a = np.clip(edges[:-1] - start_s, 0.0, width_s)
    b = np.clip(edges[1:] - start_s, 0.0, width_s)
    area = peak_n * width_s / np.pi * (np.cos(np.pi * a / width_s) - np.cos(np.pi * b / width_s))
    return area * RATE_HZ


def truth(n_hits: int = 3, noise: float = 0.0, seed: int = 0) -> tuple[TimeData, np.ndarray]:
    """TimeData of n_hits hits (peaks 100, 70, 130, ... N) and the true R (eq 18)."""
    model = RitzBeam.build(n_functions=3).structure()
    r_true = eq18_damping_matrix()
    peaks = [100.0, 70.0, 130.0, 85.0, 115.0][:n_hits]
    force = np.array([half_sine_force(p, (20 + 3 * i + 0.3) / RATE_HZ) for i, p in enumerate(peaks)])
    response = time_response(model, np.broadcast_to(r_true, (n_hits, 3, 3)), force, RATE_HZ)
    if noise:
        rng = np.random.default_rng(seed)
        response = response + noise * response.std() * rng.standard_normal(response.shape)
    return TimeData(model, force, response, RATE_HZ), r_true


def frf_truth() -> tuple[FrequencyData, np.ndarray]:
    """Noise-free accelerance on 401 lines over 0-200 Hz and the true R."""
    model = RitzBeam.build(n_functions=3).structure()
    r_true = eq18_damping_matrix()
    f = np.linspace(0.0, 200.0, 401)
    return FrequencyData(model, f, frequency_response(model, r_true, f)), r_true
