import numpy as np
import pytest

from analysis.beam import TABLE_1
from analysis.exact_beam import cantilever_frequencies_hz
from analysis.ritz import RitzBeam, admissible_functions, ritz_frequencies_hz, ritz_matrices
from tests.reference import PHI_AT_TIP, RITZ_N3_HZ, RITZ_N6_HZ, RITZ_N10_HZ


@pytest.mark.parametrize(("n", "expected"), [(3, RITZ_N3_HZ), (6, RITZ_N6_HZ), (10, RITZ_N10_HZ)])
def test_ritz_frequencies_match_design(n, expected):
    got = ritz_frequencies_hz(TABLE_1, n)
    assert got.shape == (n,)
    np.testing.assert_allclose(got[:3], expected, atol=1e-4, rtol=0)


@pytest.mark.parametrize("n", [1, 2, 3, 4, 5, 6])
def test_quadrature_equals_closed_form(n):
    m_q, k_q = ritz_matrices(TABLE_1, n, "quadrature")
    m_c, k_c = ritz_matrices(TABLE_1, n, "closed_form")
    np.testing.assert_allclose(m_q, m_c, rtol=1e-9, atol=0)
    np.testing.assert_allclose(k_q, k_c, rtol=1e-9, atol=0)


def test_closed_form_mass_scales_with_rho_a_l_not_rho_l():
    # Eq (10)'s leading "rho L" is mass per length times length: doubling A doubles M.
    from dataclasses import replace

    m1, _ = ritz_matrices(TABLE_1, 3, "closed_form")
    m2, _ = ritz_matrices(replace(TABLE_1, area_m2=2 * TABLE_1.area_m2), 3, "closed_form")
    np.testing.assert_allclose(m2, 2 * m1, rtol=1e-14)


def test_admissible_functions_at_tip_and_clamp():
    np.testing.assert_allclose(admissible_functions(0.7, 3, 0.7), PHI_AT_TIP, atol=1e-6)
    # Geometric boundary conditions at the clamp, zero moment at the free end.
    np.testing.assert_allclose(admissible_functions(0.0, 5, 0.7), 0.0, atol=1e-15)
    np.testing.assert_allclose(admissible_functions(0.0, 5, 0.7, derivative=1), 0.0, atol=1e-12)
    np.testing.assert_allclose(admissible_functions(0.7, 5, 0.7, derivative=2), 0.0, atol=1e-9)


def test_derivatives_match_finite_differences():
    x = np.linspace(0.05, 0.65, 7)
    h = 1e-4
    f = lambda x: admissible_functions(x, 4, 0.7)  # noqa: E731
    d1 = (f(x + h) - f(x - h)) / (2 * h)
    d2 = (f(x + h) - 2 * f(x) + f(x - h)) / h**2
    d1_exact = admissible_functions(x, 4, 0.7, 1)
    d2_exact = admissible_functions(x, 4, 0.7, 2)
    np.testing.assert_allclose(d1_exact, d1, atol=1e-6 * np.abs(d1_exact).max())
    np.testing.assert_allclose(d2_exact, d2, atol=1e-5 * np.abs(d2_exact).max())


def test_rayleigh_ritz_converges_from_above():
    exact = cantilever_frequencies_hz(TABLE_1, 3)
    previous = None
    for n in (3, 4, 6, 10, 20):
        f = ritz_frequencies_hz(TABLE_1, n)[:3]
        assert np.all(f >= exact)
        if previous is not None:
            assert np.all(f <= previous + 1e-12)
        previous = f
    np.testing.assert_allclose(previous, exact, rtol=2e-4)


def test_matrices_are_symmetric_positive_definite():
    m, k = ritz_matrices(TABLE_1, 8)
    assert np.array_equal(m, m.T)
    assert np.array_equal(k, k.T)
    assert np.all(np.linalg.eigvalsh(m) > 0)
    assert np.all(np.linalg.eigvalsh(k) > 0)


def test_structure_defaults_to_tip_force_and_sensor():
    model = RitzBeam.build(n_functions=3).structure()
    np.testing.assert_allclose(model.force_shape, PHI_AT_TIP, atol=1e-6)
    np.testing.assert_allclose(model.sensor_shape, PHI_AT_TIP, atol=1e-6)
    mid = RitzBeam.build(n_functions=3).structure(force_at_m=0.35)
    np.testing.assert_allclose(mid.force_shape, admissible_functions(0.35, 3, 0.7))


@pytest.mark.parametrize("n", [0, -1, 2.5])
def test_rejects_bad_n(n):
    with pytest.raises(ValueError, match="positive integer"):
        ritz_matrices(TABLE_1, n)


def test_rejects_positions_off_the_beam():
    with pytest.raises(ValueError, match="on the beam"):
        RitzBeam.build().structure(sensor_at_m=0.8)


def test_ritz_static_tip_compliance_approaches_l3_over_3ei():
    # Independent statics: P L^3 / (3 E I). The Ritz model is stiffer (an upper bound).
    from analysis.response import frequency_response

    expected = TABLE_1.length_m**3 / (3 * TABLE_1.flexural_rigidity_n_m2)
    h3 = frequency_response(
        RitzBeam.build(n_functions=3).structure(), np.zeros((3, 3)), [0.0], "displacement"
    )
    h12 = frequency_response(
        RitzBeam.build(n_functions=12).structure(), np.zeros((12, 12)), [0.0], "displacement"
    )
    assert h3[0].real < h12[0].real <= expected * (1 + 1e-9)
    assert h12[0].real == pytest.approx(expected, rel=1e-3)
