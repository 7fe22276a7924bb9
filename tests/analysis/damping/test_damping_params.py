"""analysis.damping.params: theta <-> R codings."""

from __future__ import annotations

import numpy as np
import pytest

from analysis.damping.params import matrix_to_theta, n_params, parameter_names, theta_to_matrix
from analysis.seed import eq18_damping_matrix


def test_n_params():
    assert [n_params(n) for n in (1, 2, 3, 4)] == [1, 3, 6, 10]
    with pytest.raises(ValueError, match="positive"):
        n_params(0)


def test_upper_triangle_row_major_order():
    r = theta_to_matrix(np.arange(1.0, 7.0), 3)
    np.testing.assert_array_equal(r, [[1, 2, 3], [2, 4, 5], [3, 5, 6]])
    assert parameter_names(3) == ["R11", "R12", "R13", "R22", "R23", "R33"]
    assert parameter_names(3, psd=True) == ["L11", "L21", "L22", "L31", "L32", "L33"]


@pytest.mark.parametrize("psd", [False, True])
def test_round_trip_and_symmetry(psd):
    r = eq18_damping_matrix()  # positive definite, so both codings hold it
    theta = matrix_to_theta(r, psd)
    assert theta.shape == (6,)
    np.testing.assert_allclose(theta_to_matrix(theta, 3, psd), r, rtol=1e-13, atol=1e-13)
    batch = np.random.default_rng(0).normal(size=(4, 2, 6))
    m = theta_to_matrix(batch, 3, psd)
    assert m.shape == (4, 2, 3, 3)
    np.testing.assert_array_equal(m, np.swapaxes(m, -1, -2))
    np.testing.assert_allclose(matrix_to_theta(theta_to_matrix(batch[0, 0], 3), False), batch[0, 0])


def test_psd_coding_always_gives_positive_semidefinite_matrices():
    theta = np.random.default_rng(1).uniform(-10, 10, size=(1000, 6))
    eig = np.linalg.eigvalsh(theta_to_matrix(theta, 3, psd=True))
    assert np.all(eig >= -1e-12 * np.abs(eig).max(axis=-1, keepdims=True))
    # while the plain coding reaches indefinite matrices
    assert np.any(np.linalg.eigvalsh(theta_to_matrix(theta, 3))[:, 0] < 0)


def test_psd_inverse_handles_semidefinite_and_rejects_indefinite():
    v = np.array([1.0, 2.0, -1.0])
    singular = np.outer(v, v)
    np.testing.assert_allclose(
        theta_to_matrix(matrix_to_theta(singular, True), 3, True), singular, atol=1e-10
    )
    np.testing.assert_array_equal(matrix_to_theta(np.zeros((3, 3)), True), np.zeros(6))
    with pytest.raises(ValueError, match="indefinite"):
        matrix_to_theta(np.diag([1.0, -1.0, 1.0]), psd=True)
    with pytest.raises(ValueError, match="symmetric"):
        matrix_to_theta(np.array([[1.0, 2.0], [0.0, 1.0]]))
    with pytest.raises(ValueError, match="shape"):
        theta_to_matrix(np.ones(5), 3)
