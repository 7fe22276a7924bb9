"""Table 2 of a multi-point test (analysis.table2.modal_test_table2): measured frequency
and damping with their ±, the exact and Ritz frequencies, and the MAC of each measured
shape against the exact and the Ritz shapes."""

from __future__ import annotations

import numpy as np
import pytest

from analysis.beam import TABLE_1
from analysis.table2 import identified_table2, modal_test_table2

BETA_L = np.array([1.8751040687, 4.6940911330, 7.8547574382, 10.9955407349])
LENGTH = TABLE_1.length_m
POINTS = LENGTH * np.arange(1, 8) / 7
EXACT_HZ = (
    BETA_L**2
    * np.sqrt(TABLE_1.flexural_rigidity_n_m2 / (TABLE_1.mass_per_length_kg_m * LENGTH**4))
    / (2 * np.pi)
)


def textbook(x) -> np.ndarray:
    """(4, n_points) cantilever shapes, written out here, any scaling (MAC ignores it)."""
    k = BETA_L[:, None]
    sigma = (np.cosh(k) + np.cos(k)) / (np.sinh(k) + np.sin(k))
    u = k * np.atleast_1d(x)[None, :] / LENGTH
    return np.cosh(u) - np.cos(u) - sigma * (np.sinh(u) - np.sin(u))


def test_table_of_a_test_measured_as_the_exact_beam():
    measured_hz = EXACT_HZ * (1 + np.array([2e-3, -1e-3, 5e-4, 0.0]))
    zeta = np.array([0.02, 0.01, 0.008, 0.006])
    shapes = textbook(POINTS) * np.array([1, -2, 1j, 3 - 1j])[:, None]  # any complex scale per mode
    t = modal_test_table2(
        measured_hz, zeta, shapes, POINTS,
        frequency_std_hz=[0.001, 0.002, 0.003, 0.004], damping_std=[1e-4, 2e-4, 3e-4, 4e-4], mpc=[1, 1, 1, 1],
    )  # fmt: skip
    np.testing.assert_array_equal(t.exact_mode, [0, 1, 2, 3])
    np.testing.assert_allclose(t.exact_hz, EXACT_HZ, rtol=1e-9)
    np.testing.assert_allclose(t.mac_exact, 1.0, rtol=1e-9)
    np.testing.assert_allclose(t.difference_pct(t.exact_hz), [0.2, -0.1, 0.05, 0.0], atol=1e-9)
    # The seed's 3-function Ritz model: three modes, the fourth measured mode unpaired;
    # its shapes at 7 points: MAC 0.99999, 0.9995, 0.9959 against the exact ones.
    np.testing.assert_array_equal(t.ritz_mode, [0, 1, 2, -1])
    assert np.isnan(t.ritz_hz[3])
    assert np.isnan(t.mac_ritz[3])
    np.testing.assert_allclose(t.ritz_hz[:3] / EXACT_HZ[:3] - 1, [0.0006, 0.0088, 0.0151], atol=2e-4)
    np.testing.assert_allclose(t.mac_ritz[:3], [0.99999, 0.9995, 0.9959], atol=2e-4)
    assert t.mac_exact_matrix.shape == (4, 6)
    assert t.mac_ritz_matrix.shape == (4, 3)
    np.testing.assert_allclose(np.diag(t.auto_mac), 1.0)
    assert t.auto_mac[~np.eye(4, dtype=bool)].max() < 0.1
    np.testing.assert_array_equal(t.frequency_std_hz, [0.001, 0.002, 0.003, 0.004])
    np.testing.assert_array_equal(t.damping_std, [1e-4, 2e-4, 3e-4, 4e-4])


def test_a_wrong_shape_shows_in_the_mac_not_in_the_pairing():
    """Modes are paired by frequency; a measured shape that is not the model's (here
    mode 2's shape reported at mode 3's frequency) keeps its row and gets a low MAC."""
    shapes = textbook(POINTS)[[0, 1, 1]]
    t = modal_test_table2(EXACT_HZ[:3], [0.01] * 3, shapes, POINTS)
    np.testing.assert_array_equal(t.exact_mode, [0, 1, 2])
    assert t.mac_exact[2] < 0.1
    assert t.mac_exact_matrix[2, 1] == pytest.approx(1.0)
    assert np.all(np.isnan(t.frequency_std_hz))


def test_one_point_gives_the_single_run_table():
    """A test with one point (the tip) holds the same frequencies, dampings and exact and
    Ritz columns as the single-run table (identified_table2) of the same modes."""
    freqs = np.array([5.5701, 34.89, 97.70])
    zeta = np.array([0.021, 0.011, 0.0081])
    t = modal_test_table2(freqs, zeta, textbook(LENGTH)[:3], [LENGTH])
    single = identified_table2(freqs, zeta)
    np.testing.assert_array_equal(t.frequency_hz, single.identified_hz)
    np.testing.assert_array_equal(t.damping_ratio, single.damping_ratio)
    np.testing.assert_allclose(t.exact_hz, single.exact_hz, rtol=1e-12)
    np.testing.assert_allclose(t.ritz_hz, single.ritz_hz, rtol=1e-12)
    np.testing.assert_allclose(t.mac_exact, 1.0)  # one point: every shape is parallel


def test_bad_table_inputs():
    with pytest.raises(ValueError, match="shapes of shape"):
        modal_test_table2(EXACT_HZ[:2], [0.01, 0.01], textbook(POINTS)[:3], POINTS)
    with pytest.raises(ValueError, match="one value per mode"):
        modal_test_table2(EXACT_HZ[:2], [0.01, 0.01], textbook(POINTS)[:2], POINTS, damping_std=[1e-4])
    with pytest.raises(ValueError, match="on the beam"):
        modal_test_table2(EXACT_HZ[:1], [0.01], textbook(POINTS)[:1], POINTS + 0.2)
