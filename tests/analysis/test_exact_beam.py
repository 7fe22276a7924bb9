import numpy as np
import pytest
import scipy.integrate

from analysis.beam import TABLE_1
from analysis.exact_beam import (
    ExactCantilever,
    cantilever_frequencies_hz,
    cantilever_mode_shapes,
    cantilever_roots,
)
from tests.reference import CANTILEVER_BETA_L, EXACT_DERIVED_HZ, EXACT_TABULATED_HZ, SEED_EXPERIMENTAL_HZ


def test_roots_match_design():
    np.testing.assert_allclose(cantilever_roots(4), CANTILEVER_BETA_L, atol=1e-7)


def test_high_roots_approach_odd_half_pi():
    roots = cantilever_roots(30)
    n = np.arange(1, 31)
    np.testing.assert_allclose(roots[10:], (2 * n[10:] - 1) * np.pi / 2, atol=1e-8)
    assert np.all(np.abs(1 + np.cos(roots) * np.cosh(roots))[:8] < 1e-6 * np.cosh(roots[:8]))


def test_frequencies_with_tabulated_and_derived_section():
    np.testing.assert_allclose(cantilever_frequencies_hz(TABLE_1, 4), EXACT_TABULATED_HZ, atol=1e-5)
    derived = TABLE_1.with_section("derived")
    np.testing.assert_allclose(cantilever_frequencies_hz(derived, 3), EXACT_DERIVED_HZ, atol=1e-5)


def test_seed_experimental_column_is_the_exact_beam():
    derived = cantilever_frequencies_hz(TABLE_1.with_section("derived"), 3)
    np.testing.assert_allclose(derived, SEED_EXPERIMENTAL_HZ, rtol=2e-5)


def _classical_shape(x, beta_l, length):
    # The textbook formula, fine for low modes where nothing cancels.
    b = beta_l / length
    sigma = (np.cosh(beta_l) + np.cos(beta_l)) / (np.sinh(beta_l) + np.sin(beta_l))
    return np.cosh(b * x) - np.cos(b * x) - sigma * (np.sinh(b * x) - np.sin(b * x))


def test_stable_shapes_equal_textbook_formula_for_low_modes():
    x = np.linspace(0, 0.7, 101)
    shapes = cantilever_mode_shapes(x, 4, 0.7)
    for k, beta_l in enumerate(CANTILEVER_BETA_L):
        np.testing.assert_allclose(shapes[k], _classical_shape(x, beta_l, 0.7), atol=1e-6)


def test_shapes_are_normalised_orthogonal_and_free_at_the_tip_even_for_high_modes():
    n = 25
    length = 0.7
    x = np.linspace(0, length, 40001)
    shapes = cantilever_mode_shapes(x, n, length)
    assert np.all(np.isfinite(shapes))
    gram = scipy.integrate.simpson(shapes[:, None, :] * shapes[None, :, :], x=x, axis=-1) / length
    np.testing.assert_allclose(gram, np.eye(n), atol=1e-6)
    np.testing.assert_allclose(np.abs(shapes[:, -1]), 2.0, atol=1e-9)
    np.testing.assert_allclose(shapes[:, 0], 0.0, atol=1e-12)


def test_modal_model_reproduces_frequencies_and_damping():
    beam = ExactCantilever.build(n_modes=6)
    model = beam.structure()
    w2 = np.linalg.eigvals(np.linalg.solve(model.mass, model.stiffness))
    np.testing.assert_allclose(np.sort(np.sqrt(w2.real)) / (2 * np.pi), beam.frequencies_hz(), rtol=1e-12)
    r = beam.modal_damping_matrix([0.002, 0.004, 0.006, 0.008, 0.01, 0.01])
    assert r.shape == (6, 6)
    assert np.count_nonzero(r - np.diag(np.diag(r))) == 0
    with pytest.raises(ValueError, match="expected 6 damping ratios"):
        beam.modal_damping_matrix([0.01, 0.02])


def test_modal_damping_matrix_gives_back_the_ratios():
    from analysis.modal import damped_modes

    beam = ExactCantilever.build(n_modes=6)
    zeta = np.array([0.002, 0.004, 0.006, 0.008, 0.01, 0.05])
    modes = damped_modes(beam.structure(), beam.modal_damping_matrix(zeta))
    np.testing.assert_allclose(modes.damping_ratios, zeta, rtol=1e-9)
    np.testing.assert_allclose(modes.natural_frequencies_hz, beam.frequencies_hz(), rtol=1e-9)


def test_static_tip_compliance_is_l3_over_3ei():
    # Textbook statics: a tip load P deflects a cantilever's tip by P L^3 / (3 E I).
    # The modal sum converges to it (slowly, as 1/n^4 per mode).
    from analysis.response import frequency_response

    beam = ExactCantilever.build(n_modes=60)
    h0 = frequency_response(beam.structure(), np.zeros((60, 60)), [0.0], "displacement")[0]
    expected = TABLE_1.length_m**3 / (3 * TABLE_1.flexural_rigidity_n_m2)
    assert h0.real == pytest.approx(expected, rel=1e-6)


def test_structure_defaults_to_the_tip_and_is_reciprocal():
    from analysis.response import frequency_response

    beam = ExactCantilever.build(n_modes=6)
    tip = beam.structure()
    np.testing.assert_allclose(np.abs(tip.force_shape), 2.0, atol=1e-9)
    np.testing.assert_array_equal(tip.force_shape, tip.sensor_shape)
    damping = beam.modal_damping_matrix(0.01)
    f = np.linspace(1, 300, 50)
    h_ab = frequency_response(beam.structure(force_at_m=0.3, sensor_at_m=0.7), damping, f)
    h_ba = frequency_response(beam.structure(force_at_m=0.7, sensor_at_m=0.3), damping, f)
    np.testing.assert_allclose(h_ab, h_ba, rtol=1e-10)


def test_very_high_modes_stay_finite():
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        roots = cantilever_roots(300)
        shapes = cantilever_mode_shapes(np.linspace(0, 0.7, 11), 300, 0.7)
    np.testing.assert_allclose(roots[-1], (2 * 300 - 1) * np.pi / 2, rtol=1e-12)
    assert np.all(np.isfinite(shapes))
    np.testing.assert_allclose(np.abs(shapes[:, -1]), 2.0, atol=1e-9)
