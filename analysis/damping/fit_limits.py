"""The limits a damping fit is held to: the noise floor of Psi, and the box the global
searches (GA, differential evolution) look in. Pure numerics: arrays in, numbers out;
daq/workflows/fit.py applies them to a stored run.

Units: forces in N, accelerations in m/s^2, sample rates in Hz, damping matrices
(N x N) in N s/m; a "coded term" is one entry of the vector a search varies
(analysis/damping/params.py: R's upper triangle, or with R = L L^T the entries of
its Cholesky factor L), in the same N s/m (or sqrt(N s/m) for L).
"""

from __future__ import annotations

import numpy as np

from analysis.damping.params import matrix_to_theta
from analysis.response import frequency_response
from analysis.structure import StructuralModel

#: Samples before each hit's force peak that the analyzer's anti-alias filters may
#: already have touched (their linear-phase pre-ringing spreads about ten samples).
PRE_RINGING_SAMPLES = 16
#: The fewest quiet samples before a hit's pulse for it to count in the noise estimate.
MIN_QUIET_SAMPLES = 16
#: Real samples per analyzer line (a baseband record of 1024 samples has 400 lines + DC).
SAMPLES_PER_LINE = 2.56

#: DE searches a box this many times the largest term of the modal estimate (at
#: least the seed's [-10, 10]): a realistic beam's R has terms in the hundreds.
DE_BOX_FACTOR = 10.0
#: The seed's coding range of every term (Table 3): the GA keeps it, to be the paper's.
GA_BOUNDS = (-10.0, 10.0)


def coded_scale(start: np.ndarray, psd: bool) -> float:
    """The largest coded term the modal estimate ``start`` needs.

    start : (N, N) damping matrix, N s/m. psd : code R as L L^T (then the terms are
    those of its Cholesky factor L), else R's own upper triangle.
    Returns max |theta|, a float >= 0.
    """
    return float(np.max(np.abs(matrix_to_theta(start, psd))))


def de_bounds(start: np.ndarray, psd: bool) -> tuple[float, float]:
    """(lo, hi), the same for every coded term, of the box differential evolution
    searches: DE_BOX_FACTOR times ``coded_scale(start, psd)``, never smaller than
    GA_BOUNDS. start : (N, N), N s/m."""
    half = max(GA_BOUNDS[1], DE_BOX_FACTOR * coded_scale(start, psd))
    return -half, half


def noise_floor(
    force_n: np.ndarray,
    response_m_s2: np.ndarray,
    sample_rate_hz: float,
    model: StructuralModel,
    damping: np.ndarray,
) -> float | None:
    """Psi (eq 17) that the measurement noise alone would leave at the true R.

    force_n, response_m_s2 : (n_hits, n_samples) real time records of the hits the
    fit compares with (N, m/s^2). sample_rate_hz : their sample rate (Hz). model : the
    structure fitted. damping : (N, N) damping matrix (N s/m) giving the |H| below;
    the modal estimate, so that every method of one run is held to the same floor.

    Both channels' noise is taken from the samples before each hit's pulse (and the
    filters' pre-ringing). The response's noise enters Psi directly; the force's
    enters through the model, white over the span: sigma^2 = sigma_y^2 + sigma_f^2
    mean|H|^2 (lines 0..span, H of the model with ``damping``). With a 2.25 mV/N
    hammer the second term dominates at the seed beam's |H| of tens of (m/s^2)/N.
    Returns sigma / sqrt(n_hits * n_samples), in m/s^2; None when no hit has
    MIN_QUIET_SAMPLES quiet samples.
    """
    force = np.real(np.asarray(force_n))
    response = np.real(np.asarray(response_m_s2))
    ends = [int(np.argmax(np.abs(force[k]))) - PRE_RINGING_SAMPLES for k in range(force.shape[0])]
    quiet = [(force[k, :end], response[k, :end]) for k, end in enumerate(ends) if end >= MIN_QUIET_SAMPLES]
    if not quiet:
        return None
    sigma_f = float(np.sqrt(np.mean(np.concatenate([q[0] - q[0].mean() for q in quiet]) ** 2)))
    sigma_y = float(np.sqrt(np.mean(np.concatenate([q[1] - q[1].mean() for q in quiet]) ** 2)))
    span_hz = sample_rate_hz / SAMPLES_PER_LINE
    # The lines of the run's own record (2.56 samples a line), whichever analyzer made it.
    n_points = force.shape[1] * 100 // 256 + 1
    h = frequency_response(model, damping, np.linspace(0.0, span_hz, n_points), "acceleration")
    sigma = np.sqrt(sigma_y**2 + sigma_f**2 * float(np.mean(np.abs(h) ** 2)))
    return float(sigma / np.sqrt(response.size))


def identified_poles(f_hz: np.ndarray, zeta: np.ndarray) -> np.ndarray:
    """The poles (rad/s, complex, upper half plane) of modes at ``f_hz`` (Hz) with
    damping ratios ``zeta`` (same shape): -zeta w + j w sqrt(1 - zeta^2), w = 2 pi f
    (an overdamped ratio's imaginary part clipped at 0)."""
    w = 2 * np.pi * f_hz
    return -zeta * w + 1j * w * np.sqrt(np.clip(1 - zeta**2, 0, None))
