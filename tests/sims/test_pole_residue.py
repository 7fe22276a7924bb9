"""The closed-form pulse responses against independent numerical integration and scipy."""

import itertools

import numpy as np
import pytest
import scipy.integrate
import scipy.signal

from sims.acquisition import anti_alias
from sims.pole_residue import HalfSinePulses, PoleResidueSystem


def _two_dof():
    m = np.diag([1.0, 0.5])
    k = np.array([[3000.0, -1000.0], [-1000.0, 1000.0]])
    c = 0.002 * k + 0.5 * m
    minv = np.linalg.inv(m)
    a = np.block([[np.zeros((2, 2)), np.eye(2)], [-minv @ k, -minv @ c]])
    b = np.concatenate([np.zeros(2), minv @ np.array([0.0, 1.0])])
    c_acc = np.concatenate([-(minv @ k)[1], -(minv @ c)[1]])
    d_acc = (minv @ np.array([0.0, 1.0]))[1]
    return a, b, c_acc, d_acc


def _integrate(a, b, c, d, pulses, times):
    """Reference: solve x' = A x + B u(t) numerically, y = C x + D u."""
    u = pulses.value
    breaks = sorted({0.0, *pulses.start_s, *(pulses.start_s + pulses.width_s), times[-1]})
    x = np.zeros(a.shape[0], dtype=complex if np.iscomplexobj(a) else float)
    out_t, out_x = [], []
    for t0, t1 in itertools.pairwise(breaks):
        sel = (times >= t0) & (times <= t1)
        sol = scipy.integrate.solve_ivp(
            lambda t, x: a @ x + b * u(t),
            (t0, t1),
            x,
            t_eval=times[sel],
            rtol=1e-11,
            atol=1e-14,
            method="DOP853",
        )
        out_t.append(sol.t)
        out_x.append(sol.y)
        x = scipy.integrate.solve_ivp(
            lambda t, x: a @ x + b * u(t), (t0, t1), x, rtol=1e-11, atol=1e-14, method="DOP853"
        ).y[:, -1]
    t_all = np.concatenate(out_t)
    x_all = np.concatenate(out_x, axis=1)
    _, idx = np.unique(t_all, return_index=True)
    return c @ x_all[:, idx] + d * u(t_all[idx])


def test_half_sine_response_equals_numerical_integration():
    a, b, c, d = _two_dof()
    system = PoleResidueSystem.from_state_space(a, b, c, d)
    pulses = HalfSinePulses([0.01, 0.05], [0.002, 0.003], [10.0, 4.0])
    times = np.linspace(0.0, 0.4, 801)
    got = system.respond(pulses, times)
    ref = _integrate(a, b, c, d, pulses, times)
    assert np.max(np.abs(got - ref)) < 1e-7 * np.max(np.abs(ref))


def test_mixed_down_response_is_the_response_times_the_oscillator():
    a, b, c, d = _two_dof()
    system = PoleResidueSystem.from_state_space(a, b, c, d)
    pulses = HalfSinePulses([0.02], [0.002], [5.0])
    times = np.linspace(0.0, 0.3, 301)
    f_c = 37.0
    mixed = system.respond(pulses, times, shift_hz=f_c)
    np.testing.assert_allclose(
        mixed, system.respond(pulses, times) * np.exp(-2j * np.pi * f_c * times), atol=1e-12 * 1e3
    )


def test_moved_filter_then_mixing_equals_filtering_the_mixed_signal():
    # Reference: a complex ODE. The mixed signal drives the (unmoved) low-pass.
    a, b, c, d = _two_dof()
    structure = PoleResidueSystem.from_state_space(a, b, c, d)
    lp_z, lp_p, lp_k = scipy.signal.butter(3, 2 * np.pi * 4.0, analog=True, output="zpk")
    low_pass = PoleResidueSystem.from_zpk(lp_z, lp_p, lp_k)
    f_c = 9.0
    chain = structure.then(low_pass.moved(f_c))
    pulses = HalfSinePulses([0.01], [0.002], [5.0])
    times = np.linspace(0.0, 0.5, 201)
    got = chain.respond(pulses, times, shift_hz=f_c)
    lp_a, lp_b, lp_c, _lp_d = scipy.signal.zpk2ss(lp_z, lp_p, lp_k)
    n = a.shape[0]
    w = 2 * np.pi * f_c
    # States: structure x (real), filter z (complex) fed by y(t) e^{-jwt}.

    def rhs(t, s):
        x, z = s[:n], s[n:]
        y = c @ x + d * pulses.value(t)
        return np.concatenate([a @ x + b * pulses.value(t), lp_a @ z + lp_b[:, 0] * y * np.exp(-1j * w * t)])

    sol = scipy.integrate.solve_ivp(
        rhs, (0, times[-1]), np.zeros(n + 3, complex), t_eval=times, rtol=1e-10, atol=1e-13,
        method="DOP853", max_step=2e-4,
    )  # fmt: skip
    ref = lp_c[0] @ sol.y[n:]
    assert np.max(np.abs(got - ref)) < 1e-6 * np.max(np.abs(ref))


def test_zpk_and_series_agree_with_scipy():
    z, p, k = scipy.signal.ellip(5, 0.5, 60, 2 * np.pi * 10, analog=True, output="zpk")
    system = PoleResidueSystem.from_zpk(z, p, k)
    w = 2 * np.pi * np.array([0.0, 1.0, 7.0, 10.0, 13.0, 50.0])
    _, ref = scipy.signal.freqs_zpk(z, p, k, w)
    np.testing.assert_allclose(system.evaluate(1j * w), ref, rtol=1e-9, atol=1e-12)
    a, b, c, d = _two_dof()
    structure = PoleResidueSystem.from_state_space(a, b, c, d)
    _, h_structure = scipy.signal.freqresp((a, b[:, None], c[None, :], [[d]]), w)
    np.testing.assert_allclose(structure.evaluate(1j * w), h_structure, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(
        structure.then(system).evaluate(1j * w), h_structure * ref, rtol=1e-8, atol=1e-9
    )


def test_anti_alias_filter_meets_its_specification():
    span = 200.0
    aa = anti_alias(span)
    f = np.array([0.0, 50.0, 100.0, 199.0, 200.0])
    gain_db = 20 * np.log10(np.abs(aa.evaluate(2j * np.pi * f)))
    assert np.all(gain_db > -0.1 - 1e-6)
    assert np.all(gain_db < 1e-6)
    stop = np.linspace(1.56 * span, 40 * span, 400)
    assert np.all(20 * np.log10(np.abs(aa.evaluate(2j * np.pi * stop))) < -100.0)


def test_pulse_value_and_validation():
    pulses = HalfSinePulses([1.0], [0.5], [3.0])
    np.testing.assert_allclose(
        pulses.value(np.array([0.9, 1.0, 1.25, 1.5, 1.6])), [0, 0, 3.0, 0, 0], atol=1e-12
    )
    with pytest.raises(ValueError, match="widths"):
        HalfSinePulses([0.0], [0.0], [1.0])
