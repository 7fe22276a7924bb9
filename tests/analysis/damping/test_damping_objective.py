"""analysis.damping.objective: eq (17) Psi, residuals and their FRF forms."""

from __future__ import annotations

import numpy as np
import pytest

from analysis.damping.objective import (
    FrequencyData,
    TimeData,
    batched_residuals,
    psi,
    psi_frf,
    residuals,
    residuals_frf,
)
from analysis.response import time_response
from tests.analysis.damping.damping_truth import frf_truth, truth


def _population(r_true: np.ndarray, size: int = 40, seed: int = 3) -> np.ndarray:
    rng = np.random.default_rng(seed)
    r = r_true + rng.normal(0.0, 2.0, size=(size, 3, 3))
    return 0.5 * (r + np.swapaxes(r, -1, -2))


def test_psi_of_the_truth_is_zero_on_noise_free_data():
    data, r_true = truth()
    rms = np.sqrt(np.mean(data.response_m_s2**2))
    assert psi(data, r_true) < 1e-12 * rms
    assert psi(data, r_true, exact=True) < 1e-12 * rms
    assert np.max(np.abs(residuals(data, r_true))) < 1e-12 * np.max(np.abs(data.response_m_s2))


def test_psi_is_eq17_one_over_n_root_sum_of_squares():
    data, r_true = truth()
    r = 0.7 * r_true
    expected = np.concatenate(
        [
            data.response_m_s2[h] - time_response(data.model, r, data.force_n[h], data.sample_rate_hz)
            for h in range(3)
        ]
    )
    np.testing.assert_allclose(residuals(data, r), expected, rtol=1e-10, atol=1e-10 * np.abs(expected).max())
    n = data.n_hits * data.n_samples
    np.testing.assert_allclose(psi(data, r), np.sqrt(np.sum(expected**2)) / n, rtol=1e-9)


def test_batched_psi_equals_a_loop_and_the_exact_route():
    data, r_true = truth(noise=0.01)
    pop = _population(r_true)
    batched = psi(data, pop)
    assert batched.shape == (40,)
    loop = np.array([psi(data, r) for r in pop])
    exact = psi(data, pop, exact=True)
    finite = np.isfinite(exact)
    assert np.array_equal(np.isfinite(batched), finite)
    np.testing.assert_allclose(batched[finite], loop[finite], rtol=1e-12)
    np.testing.assert_allclose(batched[finite], exact[finite], rtol=1e-8)
    assert psi(data, pop.reshape(4, 10, 3, 3)).shape == (4, 10)
    res = batched_residuals(data, pop[:5])
    assert res.shape == (5, 3 * 1024)
    np.testing.assert_array_equal(res[2], residuals(data, pop[2]))


def test_unstable_indefinite_and_odd_matrices_give_inf_or_finite_never_an_exception():
    data, r_true = truth()
    odd = np.array(
        [-r_true, np.diag([-10.0, 10.0, 10.0]), np.zeros((3, 3)), 1e6 * r_true, np.full((3, 3), np.nan)]
    )
    values = psi(data, odd)
    assert values.shape == (5,)
    assert not np.any(np.isnan(values))
    assert np.all(values > 0)
    assert np.isinf(values[4])  # NaN entries: rejected, not propagated
    assert np.isfinite(values[2])  # undamped: marginally stable, finite (goes the exact route)
    np.testing.assert_allclose(values[2], psi(data, np.zeros((3, 3)), exact=True), rtol=1e-9)
    assert np.all(np.isfinite(psi_frf(frf_truth()[0], odd[:4])))


def test_psi_frf_zero_at_truth_batched_and_weighted():
    data, r_true = frf_truth()
    assert psi_frf(data, r_true) < 1e-12 * np.abs(data.frf).max()
    pop = _population(r_true, 12)
    np.testing.assert_allclose(psi_frf(data, pop), [psi_frf(data, r) for r in pop], rtol=1e-12)
    res = residuals_frf(data, pop[0])
    assert res.shape == (2 * 401,)
    np.testing.assert_allclose(psi_frf(data, pop[0]), np.linalg.norm(res) / res.size)
    w = np.linspace(0.0, 1.0, 401)
    weighted = FrequencyData(data.model, data.frequency_hz, data.frf, w)
    np.testing.assert_allclose(residuals_frf(weighted, pop[0]), np.sqrt(np.tile(w, 2)) * res, rtol=1e-12)


def test_data_validation():
    data, _ = truth()
    with pytest.raises(ValueError, match="n_hits"):
        TimeData(data.model, data.force_n, data.response_m_s2[:, :10], 512.0)
    with pytest.raises(ValueError, match="sample_rate"):
        TimeData(data.model, data.force_n, data.response_m_s2, 0.0)
    with pytest.raises(ValueError, match="weights"):
        FrequencyData(data.model, [1.0, 2.0], [1.0, 2.0], [1.0, -1.0])
    with pytest.raises(ValueError, match="shape"):
        psi(data, np.eye(2))
