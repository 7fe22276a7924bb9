"""analysis.damping.ga and .local on simulated seed data with a known answer."""

from __future__ import annotations

import numpy as np
import pytest

import analysis.damping.objective as objective_module
from analysis.damping.ga import bits_per_variable, decode, fit_ga
from analysis.damping.local import fit_de, fit_least_squares, multi_start
from analysis.damping.objective import batched_residuals, psi, residuals
from analysis.modal import damped_modes
from tests.analysis.damping.damping_truth import EQ18_RATIOS, truth


def _rel(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


def _ls_inputs(data):
    return (lambda r: residuals(data, r)), (lambda r: batched_residuals(data, r))


def test_eq18_ratios_are_what_the_tests_assume():
    data, r_true = truth()
    np.testing.assert_allclose(damped_modes(data.model, r_true).damping_ratios, EQ18_RATIOS, atol=1e-6)


@pytest.mark.parametrize("start_kind", ["half_diagonal", "identity"])
def test_least_squares_recovers_the_truth_on_noise_free_data(start_kind):
    data, r_true = truth()
    start = 0.5 * np.diag(np.diag(r_true)) if start_kind == "half_diagonal" else np.eye(3)
    fun, batched = _ls_inputs(data)
    fit = fit_least_squares(fun, start, batched_residuals=batched)
    assert fit.success
    assert _rel(fit.damping_matrix, r_true) < 1e-6
    assert fit.n_evaluations < 200
    assert fit.jacobian.shape == (3 * 1024, 6)
    assert fit.residual.shape == (3 * 1024,)
    assert np.all(np.diff(fit.history) <= 0)


def test_least_squares_psd_coding_and_lm():
    data, r_true = truth()
    fun, batched = _ls_inputs(data)
    psd = fit_least_squares(fun, np.eye(3), psd=True, batched_residuals=batched)
    assert _rel(psd.damping_matrix, r_true) < 1e-6
    assert psd.psd
    lm = fit_least_squares(fun, np.eye(3), batched_residuals=batched, method="lm")
    assert _rel(lm.damping_matrix, r_true) < 1e-6
    plain = fit_least_squares(fun, np.eye(3))  # scipy's own finite differences
    assert _rel(plain.damping_matrix, r_true) < 1e-6


def test_least_squares_with_one_percent_noise_gives_eq18_damping_ratios_within_5_percent():
    data, _ = truth(n_hits=3, noise=0.01, seed=7)
    fun, batched = _ls_inputs(data)
    fit = fit_least_squares(fun, np.eye(3), batched_residuals=batched)
    ratios = damped_modes(data.model, fit.damping_matrix).damping_ratios
    np.testing.assert_allclose(ratios, EQ18_RATIOS, rtol=0.05)


def test_least_squares_reports_a_start_it_cannot_evaluate():
    fit = fit_least_squares(lambda r: np.full(10, np.nan), np.eye(3))
    assert not fit.success
    assert fit.psi == np.inf


def test_multi_start_converges_to_the_same_optimum():
    data, r_true = truth()
    fun, batched = _ls_inputs(data)
    fits = multi_start(fun, batched, 3, starts=3, seed=1)
    assert len(fits) == 3
    assert [f.psi for f in fits] == sorted(f.psi for f in fits)
    assert _rel(fits[0].damping_matrix, r_true) < 1e-6


def test_ga_coding_has_the_papers_four_decimal_precision():
    assert bits_per_variable((-10.0, 10.0)) == 18
    step = 20.0 / (2**18 - 1)
    targets = np.round(np.random.default_rng(0).uniform(-10, 10, 500), 4)
    k = np.round((targets + 10.0) / step).astype(np.int64)
    bits = ((k[:, None] >> np.arange(17, -1, -1)) & 1).astype(bool)
    decoded = decode(bits, 1, (-10.0, 10.0), 18)[:, 0]
    np.testing.assert_array_equal(decoded, targets)  # every 4-decimal value is reachable
    assert decode(np.zeros((1, 18), bool), 1, (-10, 10), 18)[0, 0] == -10.0
    assert decode(np.ones((1, 18), bool), 1, (-10, 10), 18)[0, 0] == 10.0


def test_ga_is_reproducible_batched_and_improves():
    data, _ = truth(noise=0.01)
    calls = []

    def objective(r):
        calls.append(r.shape)
        return psi(data, r)

    a = fit_ga(objective, 3, seed=5, cache=False)
    assert calls == [(50, 3, 3)] * 30  # one batched call per generation, the paper's 50 x 30
    assert a.n_evaluations == 1500
    assert a.history.shape == (30,)
    b = fit_ga(lambda r: psi(data, r), 3, seed=5, cache=False)
    c = fit_ga(lambda r: psi(data, r), 3, seed=6)
    np.testing.assert_array_equal(a.theta, b.theta)
    np.testing.assert_array_equal(a.history, b.history)
    assert not np.array_equal(a.theta, c.theta)
    assert a.psi <= a.history[0]
    assert a.psi == pytest.approx(float(psi(data, a.damping_matrix)))
    np.testing.assert_allclose(a.theta, np.round(a.theta, 4), atol=1e-12)


@pytest.mark.parametrize("seed", [0, 5])
def test_ga_cache_computes_each_distinct_member_once_and_changes_nothing(seed):
    data, _ = truth(noise=0.01)
    computed = []

    def objective(r):
        computed.extend(r.reshape(r.shape[0], -1).round(4).tolist())
        return psi(data, r)

    cached = fit_ga(objective, 3, seed=seed)
    again = fit_ga(lambda r: psi(data, r), 3, seed=seed)
    np.testing.assert_array_equal(cached.history, again.history)  # reproducible
    plain = fit_ga(lambda r: psi(data, r), 3, seed=seed, cache=False)
    np.testing.assert_array_equal(cached.theta, plain.theta)
    np.testing.assert_allclose(cached.history, plain.history, rtol=1e-12)
    assert cached.n_evaluations == plain.n_evaluations == 1500
    distinct = {tuple(row) for row in computed}
    assert len(computed) == len(distinct)  # never the same member twice
    assert len(computed) < 1000  # selection and crossover copy many members unchanged
    assert f"({len(computed)} distinct members computed)" in cached.message


def test_ga_with_elitism_never_gets_worse_and_beats_its_first_generation():
    data, _ = truth(noise=0.01)
    fit = fit_ga(lambda r: psi(data, r), 3, seed=2, elitism=True)
    assert np.all(np.diff(fit.history) <= 0)
    assert fit.history[-1] < fit.history[0]
    assert fit.psi == fit.history[-1]


def test_ga_calls_the_model_once_per_generation(monkeypatch):
    data, _ = truth()
    count = [0]
    fast = objective_module._fast_sse

    def counted(*args, **kwargs):
        count[0] += 1
        return fast(*args, **kwargs)

    monkeypatch.setattr(objective_module, "_fast_sse", counted)
    fit_ga(lambda r: psi(data, r), 3, seed=0, generations=7, cache=False)
    assert count[0] == 7


def test_de_vectorised_finds_the_truth_on_noise_free_data():
    data, r_true = truth()
    calls = []

    def objective(r):
        calls.append(r.shape[0])
        return psi(data, r)

    fit = fit_de(objective, 3, seed=0, maxiter=250)
    assert _rel(fit.damping_matrix, r_true) < 1e-3
    assert len(calls) == len(fit.history) + 1  # initial population, then one call per generation
    assert sum(calls) == fit.n_evaluations
