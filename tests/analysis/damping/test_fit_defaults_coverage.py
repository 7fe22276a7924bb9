"""The printed ± of `daq fit` covers the truth as a standard uncertainty should.

Simulated band-limited captures of the seed model (Ritz N = 3, eq (18) truth) with 1 %
noise on both the response and the force, fitted as `daq fit` does by default (least
squares, R = L L^T); the uncertainty of each term is the larger of the Fisher figure
and the per-hit refits' spread / sqrt(n) (analysis.damping.checks.combined_std).
Over the seeds, the truth must lie within ±1 u about 68 % of the time and within
±2 u about 95 % of the time (a little more: the larger of two figures is conservative).
"""

from __future__ import annotations

import numpy as np
import pytest

from analysis.damping import fit_least_squares, identifiability, matrix_to_theta
from analysis.damping.bandlimited import BandLimitedData, batched_residuals, model_response, residuals
from analysis.damping.checks import central_jacobian, combined_std, per_hit_std
from analysis.ritz import RitzBeam
from analysis.seed import eq18_damping_matrix
from tests.analysis.damping.damping_truth import RATE_HZ, half_sine_force

SEEDS = 16
PEAKS_N = (100.0, 70.0, 130.0, 85.0, 115.0)


def _normalised_errors(seed: int, model, force: np.ndarray, clean: np.ndarray, r_true: np.ndarray):
    rng = np.random.default_rng(seed)
    response = clean + 0.01 * clean.std() * rng.standard_normal(clean.shape)
    measured_force = force + 0.01 * force.std() * rng.standard_normal(force.shape)
    data = BandLimitedData(model, measured_force, response, RATE_HZ)
    batched = lambda m: batched_residuals(data, m)  # noqa: E731
    # Started from the truth's diagonal, as the modal estimate would be: a classical start.
    fit = fit_least_squares(
        lambda m: residuals(data, m), np.diag(np.diag(r_true)), psd=True, batched_residuals=batched
    )
    r = np.asarray(fit.damping_matrix)
    jac, res = central_jacobian(batched, r)
    fisher = identifiability(jac, res, matrix_to_theta(r), 3).std
    std, source = combined_std(fisher, per_hit_std(data, r, psd=True))
    assert np.all(std >= fisher)  # never below the Fisher figure ...
    return (matrix_to_theta(r) - matrix_to_theta(r_true)) / std, source


@pytest.mark.slow
def test_the_uncertainty_covers_the_truth_like_a_standard_uncertainty():
    model = RitzBeam.build(n_functions=3).structure()
    r_true = eq18_damping_matrix()
    force = np.array([half_sine_force(p, (20 + 3 * i + 0.3) / RATE_HZ) for i, p in enumerate(PEAKS_N)])
    clean = model_response(BandLimitedData(model, force, force, RATE_HZ), r_true[None])[0]
    errors, sources = [], []
    for seed in range(SEEDS):
        z, source = _normalised_errors(seed, model, force, clean, r_true)
        errors.append(z)
        sources += source
    z = np.abs(np.array(errors))  # (seeds, 6 terms)
    within_1, within_2 = float(np.mean(z <= 1)), float(np.mean(z <= 2))
    # 96 values, correlated within a seed (~16 to 96 independent): the binomial spread
    # of a 68 % share is 5 to 12 points. The larger of two estimates of one spread is
    # conservative by construction (measured: 82 % within ±1 u, 99 % within ±2 u), so
    # the upper bound is wider than the lower one: u must not be too small, and not
    # grossly too large either.
    assert 0.55 <= within_1 <= 0.92, (within_1, within_2)
    assert within_2 >= 0.88, (within_1, within_2)
    # ... and both figures take their turn: the force's noise, coloured by the model,
    # makes the refits spread wider than the Fisher figure on some terms.
    assert 0 < sources.count("hits") < len(sources)


def test_the_larger_figure_wins_term_by_term_and_says_which():
    fisher = np.array([1.0, 2.0, np.inf, np.nan])
    hits = np.array([0.5, 3.0, 1.0, 1.0])
    std, source = combined_std(fisher, hits)
    assert std[:3].tolist() == [1.0, 3.0, np.inf]  # an undetermined term stays undetermined
    assert source == ["fisher", "hits", "fisher", "hits"]
    alone, source = combined_std(fisher[:2], None)
    assert alone.tolist() == [1.0, 2.0]
    assert source == ["fisher", "fisher"]
