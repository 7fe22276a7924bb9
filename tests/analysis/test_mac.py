"""MAC (analysis.mac) and the beam's own unit-modal-mass shapes (analysis.beam_shapes),
checked against the textbook cantilever written out here, not against our modules."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.optimize

from analysis.beam import TABLE_1
from analysis.beam_shapes import exact_shapes, ritz_shapes
from analysis.mac import align, auto_mac, mac

# beta_n L of the clamped-free beam, from the tables (Blevins; 1 + cos cosh = 0).
BETA_L = np.array([1.8751040687, 4.6940911330, 7.8547574382, 10.9955407349])
POINTS = TABLE_1.length_m * np.arange(1, 8) / 7


def textbook_shapes(x: np.ndarray, n: int = 4) -> np.ndarray:
    """Unit-modal-mass cantilever shapes (n, x.size), 1/sqrt(kg), sign as the formula
    gives it: (cosh - cos - sigma (sinh - sin)) / sqrt(rho A L)."""
    length, k = TABLE_1.length_m, BETA_L[:n, None]
    sigma = (np.cosh(k) + np.cos(k)) / (np.sinh(k) + np.sin(k))
    u = k * np.asarray(x)[None, :] / length
    return (np.cosh(u) - np.cos(u) - sigma * (np.sinh(u) - np.sin(u))) / np.sqrt(TABLE_1.mass_kg)


def test_mac_basic_properties():
    rng = np.random.default_rng(0)
    a = rng.standard_normal((3, 7)) + 1j * rng.standard_normal((3, 7))
    m = mac(a, (2 - 5j) * a)  # any complex scale: still the same shapes
    np.testing.assert_allclose(np.diag(m), 1.0, rtol=1e-12)
    assert m.shape == (3, 3)
    assert np.all((m >= 0) & (m <= 1))
    # Hand-computed: e1 against (1, 1)/sqrt2 -> 1/2; orthogonal -> 0.
    assert mac([1.0, 0.0], [1.0, 1.0])[0, 0] == pytest.approx(0.5)
    assert mac([1.0, 1.0], [1.0, -1.0])[0, 0] == pytest.approx(0.0, abs=1e-15)
    assert mac([1.0, 1j], [1.0, -1j])[0, 0] == pytest.approx(0.0, abs=1e-15)  # complex: a^H b
    assert np.isnan(mac([0.0, 0.0], [1.0, 2.0])[0, 0])
    # Not symmetric in rows: (2, 7) against (4, 7) is (2, 4), the transpose of the reverse.
    np.testing.assert_allclose(mac(a[:2], a), mac(a, a[:2]).T)


def test_mac_rejects_mismatched_sets():
    with pytest.raises(ValueError, match="different numbers of points"):
        mac(np.ones((2, 5)), np.ones((2, 6)))
    with pytest.raises(ValueError, match="non-finite"):
        mac([1.0, np.nan], [1.0, 1.0])


def test_align_fixes_sign_and_phase_only():
    ref = textbook_shapes(POINTS, 3)
    turned = ref * np.array([-1.0, 1j, np.exp(0.7j)])[:, None]
    np.testing.assert_allclose(align(turned, ref), ref, atol=1e-12)
    np.testing.assert_allclose(np.abs(align(turned, ref)), np.abs(turned))


def test_exact_shapes_are_the_textbook_ones_at_unit_modal_mass():
    got = exact_shapes(POINTS, 4)
    want = textbook_shapes(POINTS) * np.array([1, -1, 1, -1])[:, None]  # made positive at the tip
    np.testing.assert_allclose(got.shapes, want, rtol=1e-9, atol=1e-12)
    # Unit modal mass, integrated here: rho A int u^2 dx = 1 kg.
    x = np.linspace(0, TABLE_1.length_m, 20001)
    u = exact_shapes(x, 4).shapes
    modal_mass = TABLE_1.mass_per_length_kg_m * np.trapezoid(u**2, x, axis=1)
    np.testing.assert_allclose(modal_mass, 1.0, rtol=1e-6)
    # Tip value 2 / sqrt(rho A L) for every mode.
    np.testing.assert_allclose(got.shapes[:, -1], 2 / np.sqrt(TABLE_1.mass_kg), rtol=1e-9)


def test_exact_frequency_ratios_and_node_of_mode_2():
    f = exact_shapes(POINTS, 3).frequencies_hz
    np.testing.assert_allclose(f / f[0], [1.0, 6.267, 17.55], rtol=2e-4)
    node = scipy.optimize.brentq(lambda x: exact_shapes(x, 2).shapes[1, 0], 0.5, 0.69)
    assert node / TABLE_1.length_m == pytest.approx(0.7834, abs=5e-5)


def test_ritz_shapes_unit_modal_mass_and_against_exact():
    ritz = ritz_shapes(POINTS, 10)
    exact = exact_shapes(POINTS, 10)
    # Rayleigh-Ritz: every frequency an upper bound; 10 functions close the first three.
    assert np.all(ritz.frequencies_hz >= exact.frequencies_hz * (1 - 1e-12))
    np.testing.assert_allclose(ritz.frequencies_hz[:3], exact.frequencies_hz[:3], rtol=1e-3)
    # Unit modal mass in the continuous beam's own mass, integrated here.
    x = np.linspace(0, TABLE_1.length_m, 20001)
    u = ritz_shapes(x, 10).shapes
    modal_mass = TABLE_1.mass_per_length_kg_m * np.trapezoid(u**2, x, axis=1)
    np.testing.assert_allclose(modal_mass, 1.0, rtol=1e-6)
    # Shapes: the same modes at 7 points, value by value within 1 % of the tip value.
    m = mac(ritz.shapes[:3], exact.shapes[:3])
    assert np.all(np.diag(m) > 0.99999)
    np.testing.assert_allclose(ritz.shapes[:3], exact.shapes[:3], atol=0.002 * exact.shapes[0, -1])
    node = scipy.optimize.brentq(lambda x: ritz_shapes(x, 10).shapes[1, 0], 0.5, 0.69)
    assert node / TABLE_1.length_m == pytest.approx(0.7834, abs=2e-4)


def test_ritz_three_functions_against_exact():
    """The seed's N = 3 model: 0.06 %, 0.9 % and 1.5 % above the exact beam, its shapes
    at 7 points MAC 0.99999, 0.9995 and 0.996 against the exact ones, the node of mode 2
    at x/L = 0.7817 instead of 0.7834: the third mode is where three functions show."""
    ritz = ritz_shapes(POINTS, 3)
    exact = exact_shapes(POINTS, 3)
    error = ritz.frequencies_hz / exact.frequencies_hz - 1
    np.testing.assert_allclose(error, [0.0006, 0.0088, 0.0151], atol=2e-4)
    np.testing.assert_allclose(np.diag(mac(ritz.shapes, exact.shapes)), [0.99999, 0.9995, 0.9959], atol=2e-4)
    node = scipy.optimize.brentq(lambda x: ritz_shapes(x, 3).shapes[1, 0], 0.5, 0.69)
    assert node / TABLE_1.length_m == pytest.approx(0.7817, abs=2e-4)


def test_auto_mac_of_exact_shapes_at_seven_points():
    am = auto_mac(exact_shapes(POINTS, 4).shapes)
    np.testing.assert_allclose(np.diag(am), 1.0, rtol=1e-12)
    off = am[~np.eye(4, dtype=bool)]
    # 7 points tell the first four modes apart: no pair above 0.1 (a 2-point set would not).
    assert off.max() < 0.1
    two = auto_mac(exact_shapes(TABLE_1.length_m * np.array([0.5, 1.0]), 4).shapes)
    assert two[~np.eye(4, dtype=bool)].max() > 0.5


def test_positions_off_the_beam_are_refused():
    with pytest.raises(ValueError, match="on the beam"):
        exact_shapes([0.1, 0.8], 3)
    with pytest.raises(ValueError, match="on the beam"):
        ritz_shapes([-0.1], 3)
