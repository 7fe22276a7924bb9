"""Modal estimate, Pilkey-Inman-type pole matching, identifiability and the stiffness scale."""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np
import pytest

from analysis.damping.identifiability import cramer_rao_frf, identifiability
from analysis.damping.modal_estimate import match_modes, proportional_estimate, undamped_modes
from analysis.damping.pilkey_inman import pilkey_inman, product_mismatch
from analysis.damping.stiffness import frequency_errors, update_stiffness
from analysis.modal import damped_modes
from analysis.ritz import RitzBeam
from analysis.seed import eq18_damping_matrix


@pytest.fixture(scope="module")
def model():
    return RitzBeam.build(n_functions=3).structure()


@pytest.fixture(scope="module")
def eq18_poles(model):
    return damped_modes(model, eq18_damping_matrix()).poles


# --- proportional estimate -------------------------------------------------------------


def test_proportional_estimate_is_classical_with_the_given_ratios(model):
    omega, phi = undamped_modes(model)
    zeta = damped_modes(model, eq18_damping_matrix()).damping_ratios  # 0.036, 0.203, 0.162
    r, match = proportional_estimate(model, omega / (2 * np.pi), zeta)
    np.testing.assert_array_equal(match, [0, 1, 2])
    np.testing.assert_allclose(r, r.T, rtol=0, atol=1e-12 * np.abs(r).max())
    modal = phi.T @ r @ phi
    off = modal - np.diag(np.diag(modal))
    assert np.abs(off).max() < 1e-10 * np.abs(modal).max()
    np.testing.assert_allclose(np.diag(modal), 2 * zeta * omega, rtol=1e-10)
    modes = damped_modes(model, r)
    np.testing.assert_allclose(modes.damping_ratios, zeta, rtol=0, atol=1e-6)
    # A classically damped mode keeps the undamped natural frequency.
    np.testing.assert_allclose(modes.natural_frequencies_hz, omega / (2 * np.pi), rtol=1e-10)


def test_proportional_estimate_with_a_missing_mode(model):
    omega, _ = undamped_modes(model)
    f_model = omega / (2 * np.pi)
    # Modes 1 and 3 identified (listed out of order, frequencies 2 % off), mode 2 missed.
    f_id = np.array([f_model[2] * 0.98, f_model[0] * 1.02])
    zeta_id = np.array([0.05, 0.01])
    r, match = proportional_estimate(model, f_id, zeta_id)
    np.testing.assert_array_equal(match, [2, 0])
    ratios = damped_modes(model, r).damping_ratios
    # Mode 2 (35 Hz) takes the ratio of the identified mode nearest in log-frequency:
    # |log(35.2/5.68)| = 1.82 > |log(35.2/97.2)| = 1.02, so the 97 Hz one.
    np.testing.assert_allclose(ratios, [0.01, 0.05, 0.05], atol=1e-9)


def test_match_modes_more_identified_than_model():
    match = match_modes(np.array([10.0, 31.0, 5.0, 99.0]), np.array([5.2, 30.0, 100.0]))
    np.testing.assert_array_equal(match, [-1, 1, 0, 2])


# --- Pilkey-Inman ----------------------------------------------------------------------


def test_pilkey_inman_matches_eq18_poles(model, eq18_poles):
    r, info = pilkey_inman(model, eq18_poles)
    assert info["converged"]
    assert info["residual"] < 1e-8
    poles = damped_modes(model, r).poles
    np.testing.assert_allclose(poles, eq18_poles, rtol=1e-8)
    np.testing.assert_allclose(r, r.T)
    # The poles do not determine R (2N - 1 = 5 numbers for 6 terms, plus sign
    # branches): from the default start the answer is a different matrix.
    print("pilkey_inman from default start:\n", np.round(r, 4))
    assert not np.allclose(r, eq18_damping_matrix(), rtol=0.1)


def test_pilkey_inman_from_a_nearby_start_stays_near_eq18(model, eq18_poles):
    eq18 = eq18_damping_matrix()
    r, info = pilkey_inman(model, eq18_poles, start=eq18 + 0.01)
    assert info["residual"] < 1e-8
    np.testing.assert_allclose(r, eq18, atol=0.02)


def test_sign_branches_and_product_constraint_hold(model, eq18_poles):
    # The module docstring's two reasons why poles cannot give R uniquely.
    _, phi = undamped_modes(model)
    modal = phi.T @ eq18_damping_matrix() @ phi
    for signs in itertools.product([1.0, -1.0], repeat=2):
        s = np.diag([1.0, *signs])
        flipped = model.mass @ phi @ s @ modal @ s @ phi.T @ model.mass
        np.testing.assert_allclose(damped_modes(model, flipped).poles, eq18_poles, rtol=1e-10)
    assert abs(product_mismatch(model, eq18_poles)) < 1e-10


def test_pilkey_inman_noisy_poles(model, eq18_poles):
    rng = np.random.default_rng(1)
    noise = 0.001 * (rng.standard_normal(3) + 1j * rng.standard_normal(3)) / np.sqrt(2)
    noisy = eq18_poles * (1 + noise)
    r, info = pilkey_inman(model, noisy)
    assert info["converged"]
    # No R matches noisy poles exactly (their product is off); the best fit is close.
    assert abs(info["product_mismatch"]) > 1e-5
    poles = damped_modes(model, r).poles
    np.testing.assert_allclose(poles, noisy, rtol=5e-3)
    np.testing.assert_allclose(poles, eq18_poles, rtol=5e-3)


def test_lancaster_substitution_does_not_match_the_poles(model, eq18_poles):
    # The literal substitution enforces N of the 2N pole conditions (module docstring).
    start, _ = proportional_estimate(
        model, np.abs(eq18_poles) / (2 * np.pi), -eq18_poles.real / np.abs(eq18_poles)
    )
    _, info = pilkey_inman(model, eq18_poles, start=start, update="lancaster")
    assert info["converged"]
    assert info["residual"] > 1e-2


# --- identifiability -------------------------------------------------------------------


def test_identifiability_std_matches_linear_least_squares():
    rng = np.random.default_rng(0)
    n_res, n = 60, 3
    jac = rng.standard_normal((n_res, 6)) * np.array([1.0, 3.0, 0.2, 5.0, 1.0, 0.7])
    truth = np.array([5.0, 1.0, -0.5, 4.0, 0.3, 2.0])
    y = jac @ truth + 0.05 * rng.standard_normal(n_res)
    fit, *_ = np.linalg.lstsq(jac, y, rcond=None)
    residual = y - jac @ fit
    result = identifiability(jac, residual, fit, n)
    sigma = np.sqrt(residual @ residual / (n_res - 6))
    expected = sigma * np.sqrt(np.diag(np.linalg.inv(jac.T @ jac)))
    assert result.noise_std == pytest.approx(sigma, rel=1e-12)
    np.testing.assert_allclose(result.std, expected, rtol=1e-10)
    assert result.names == ["R11", "R12", "R13", "R22", "R23", "R33"]
    np.testing.assert_allclose(result.relative_std[1], result.std[1] / np.sqrt(fit[0] * fit[3]))
    assert result.determined.all()
    assert result.null_directions == []


def test_identifiability_names_a_null_direction():
    rng = np.random.default_rng(2)
    jac = rng.standard_normal((40, 6))
    jac[:, 2] = jac[:, 1]  # the data see R12 + R13 only
    value = np.array([2.0, 0.5, 0.4, 2.0, 0.1, 2.0])  # equal diagonals: R12, R13 scales equal
    result = identifiability(jac, 0.01 * rng.standard_normal(40), value, 3)
    assert np.isinf(result.std[1])
    assert np.isinf(result.std[2])
    assert np.all(np.isfinite(result.std[[0, 3, 4, 5]]))
    assert not result.determined[1]
    assert not result.determined[2]
    assert len(result.null_directions) == 1
    combo = result.null_directions[0]["combination"]
    assert combo["R12"] == pytest.approx(-combo["R13"], abs=1e-10)
    assert abs(combo["R12"]) == pytest.approx(np.sqrt(0.5), abs=1e-10)
    for name in ("R11", "R22", "R23", "R33"):
        assert abs(combo[name]) < 1e-10


def _analytic_jacobian(model, r, f):
    """Accelerance H = s^2 c^T Z^-1 b and dH/dR_ij = -s^3 c^T Z^-1 E_ij Z^-1 b, directly."""
    rows, cols = np.triu_indices(3)
    s = 2j * np.pi * f
    jac = np.empty((f.size, 6), complex)
    h = np.empty(f.size, complex)
    for k, sk in enumerate(s):
        z = sk**2 * model.mass + sk * r + model.stiffness
        zb = np.linalg.solve(z, model.force_shape)
        zc = np.linalg.solve(z.T, model.sensor_shape)
        h[k] = sk**2 * (model.sensor_shape @ zb)
        for p, (i, j) in enumerate(zip(rows, cols, strict=True)):
            quad = zc[i] * zb[j] + (zc[j] * zb[i] if i != j else 0.0)
            jac[k, p] = -(sk**3) * quad
    return jac, h


def test_cramer_rao_frf_eq18(model):
    f = np.linspace(0.0, 200.0, 401)
    r = eq18_damping_matrix()
    result = cramer_rao_frf(model, r, f, noise_rel=0.01)
    print("CRB relative std:", dict(zip(result.names, np.round(result.relative_std, 4), strict=True)))

    # Independent check of the finite-difference Jacobian: the analytic derivative.
    jac, h = _analytic_jacobian(model, r, f[1:])
    sigma = 0.01 * np.abs(h) / np.sqrt(2)
    white = np.concatenate([jac.real / sigma[:, None], jac.imag / sigma[:, None]])
    rows, cols = np.triu_indices(3)
    direct = identifiability(white, np.zeros(white.shape[0]), r[rows, cols], 3, noise_std=1.0)
    np.testing.assert_allclose(result.std, direct.std, rtol=1e-5)

    rel = dict(zip(result.names, result.relative_std, strict=True))
    off = [rel["R12"], rel["R13"], rel["R23"]]
    # The claim: some off-diagonal's CRB is >= 10 % of sqrt(R_ii R_jj).
    assert max(off) > 0.1
    # R11 (the first mode's damping) is the best-determined term of all.
    assert rel["R11"] < min(off)
    # Not every diagonal beats the off-diagonals: R33 is the least determined term,
    # and it dominates the one near-null direction.
    assert rel["R33"] == max(result.relative_std)
    assert len(result.null_directions) == 1
    combo = result.null_directions[0]["combination"]
    assert max(combo, key=lambda k: abs(combo[k])) == "R33"


# --- stiffness -------------------------------------------------------------------------


def test_update_stiffness_recovers_a_scale_on_e(model):
    true_model = dataclasses.replace(model, stiffness=1.03 * model.stiffness)
    omega, _ = undamped_modes(true_model)
    identified = omega / (2 * np.pi)
    updated, scale, info = update_stiffness(model, identified[::-1])
    assert scale == pytest.approx(1.03, rel=1e-9)
    np.testing.assert_allclose(updated.stiffness, true_model.stiffness, rtol=1e-9)
    np.testing.assert_allclose(info["error_after_pct"], 0.0, atol=1e-7)
    np.testing.assert_allclose(info["error_before_pct"], 100 * (1 / np.sqrt(1.03) - 1), rtol=1e-9)
    assert info["n_used"] == 3
    np.testing.assert_allclose(frequency_errors(model, identified), info["error_before_pct"])


def test_update_stiffness_ignores_far_modes(model):
    omega, _ = undamped_modes(model)
    f = omega / (2 * np.pi)
    identified = np.array([f[0] * 1.01, f[1] * 1.5])  # the second is no partner (> 20 %)
    _, scale, info = update_stiffness(model, identified)
    assert info["n_used"] == 1
    assert scale == pytest.approx(1.01**2, rel=1e-12)
    assert np.isnan(frequency_errors(model, identified)[1])
