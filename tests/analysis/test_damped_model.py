import numpy as np
import pytest

from analysis.modal import damped_modes
from analysis.ritz import RitzBeam
from analysis.seed import eq18_damping_matrix
from tests.reference import EQ18, EQ18_DAMPING_RATIOS, EQ18_EIGENVALUES, EQ18_POLE_MAGNITUDE_HZ


@pytest.fixture
def ritz3():
    return RitzBeam.build(n_functions=3).structure()


def test_seed_module_carries_eq18_verbatim():
    np.testing.assert_array_equal(eq18_damping_matrix(), np.array(EQ18))


def test_eq18_eigenvalues_and_summary():
    from analysis.table2 import damping_summary

    summary = damping_summary(np.array(EQ18))
    np.testing.assert_allclose(summary.symmetric_eigenvalues, EQ18_EIGENVALUES, rtol=1e-3)
    assert summary.definiteness == "positive definite"
    assert summary.symmetric
    np.testing.assert_allclose(summary.modes.damping_ratios, EQ18_DAMPING_RATIOS, atol=1e-5)


def test_eq18_poles_and_damping_ratios(ritz3):
    modes = damped_modes(ritz3, np.array(EQ18))
    np.testing.assert_allclose(modes.natural_frequencies_hz, EQ18_POLE_MAGNITUDE_HZ, atol=1e-5)
    np.testing.assert_allclose(modes.damping_ratios, EQ18_DAMPING_RATIOS, atol=1e-5)
    assert int(modes.n_real_poles) == 0
    assert int(modes.n_unstable_poles) == 0
    assert np.all(modes.poles.real < 0)


def test_state_matrix_has_the_minus_signs(ritz3):
    # With the seed's printed eq (16) (no minus signs) the model would be unstable;
    # ours must put every pole in the left half-plane for a positive definite R.
    a, _, _, _ = ritz3.state_space(np.array(EQ18))
    n = 3
    m_inv_k = np.linalg.solve(ritz3.mass, ritz3.stiffness)
    np.testing.assert_allclose(a[n:, :n], -m_inv_k)
    np.testing.assert_allclose(a[:n, n:], np.eye(n))
    assert np.all(np.linalg.eigvals(a).real < 0)


def test_modes_solve_the_quadratic_eigenproblem(ritz3):
    r = np.array(EQ18)
    modes = damped_modes(ritz3, r)
    for lam, psi in zip(modes.poles, modes.shapes, strict=True):
        residual = (lam**2 * ritz3.mass + lam * r + ritz3.stiffness) @ psi
        assert np.linalg.norm(residual) < 1e-9 * np.linalg.norm(ritz3.stiffness) * np.linalg.norm(psi)
        assert np.max(np.abs(psi)) == pytest.approx(1.0)


def test_undamped_limit_gives_ritz_frequencies(ritz3):
    modes = damped_modes(ritz3, np.zeros((3, 3)))
    np.testing.assert_allclose(
        modes.natural_frequencies_hz, RitzBeam.build(n_functions=3).frequencies_hz(), rtol=1e-10
    )
    np.testing.assert_allclose(modes.damping_ratios, 0.0, atol=1e-10)


def test_batched_modes_equal_one_at_a_time(ritz3):
    rng = np.random.default_rng(7)
    batch = rng.uniform(-1, 1, (4, 5, 3, 3))
    batch = batch @ np.swapaxes(batch, -1, -2) + 0.1 * np.eye(3)
    modes = damped_modes(ritz3, batch)
    assert modes.natural_frequencies_hz.shape == (4, 5, 3)
    single = damped_modes(ritz3, batch[2, 3])
    np.testing.assert_allclose(modes.damping_ratios[2, 3], single.damping_ratios, rtol=1e-12)


def test_overdamped_member_is_padded_not_crashing(ritz3):
    heavy = np.diag([1e4, 0.0, 0.0])  # kills the first mode's oscillation
    modes = damped_modes(ritz3, np.stack([np.array(EQ18), heavy]))
    assert int(modes.n_real_poles[0]) == 0
    assert int(modes.n_real_poles[1]) >= 2
    assert int(modes.n_unstable_poles[1]) == 0
    padded = np.isnan(modes.damping_ratios[1])
    assert padded.sum() >= 1
    assert np.all(np.isnan(modes.damped_frequencies_hz[1][padded]))
    assert np.all(np.isfinite(modes.damping_ratios[0]))


def test_unstable_poles_are_counted(ritz3):
    modes = damped_modes(ritz3, -1e6 * np.eye(3))
    assert int(modes.n_unstable_poles) >= 1


def test_rejects_wrong_damping_shape(ritz3):
    with pytest.raises(ValueError, match=r"\(\.\.\., 3, 3\)"):
        damped_modes(ritz3, np.eye(4))
    with pytest.raises(ValueError, match="non-finite"):
        damped_modes(ritz3, np.full((3, 3), np.nan))
