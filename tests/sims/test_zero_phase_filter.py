"""The simulator's anti-alias model is zero-phase: it delays nothing and answers
before its input as much as after (docs/simulator.md, "Anti-alias filtering and
decimation"). Checked against numerical convolution and symmetry, not against the
closed form itself."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.integrate

from sims.acquisition import anti_alias
from sims.pole_residue import HalfSinePulses, PoleResidueSystem


def _impulse_response(system: PoleResidueSystem, t: np.ndarray) -> np.ndarray:
    """The two-sided inverse Laplace transform with the imaginary axis in the region of
    convergence, written out term by term: causal for Re p < 0, anti-causal for Re p > 0."""
    t = t[..., None]
    causal = np.where(
        (t >= 0) & (system.poles.real < 0), system.residues * np.exp(system.poles * np.maximum(t, 0)), 0
    )
    ahead = np.where(
        (t < 0) & (system.poles.real > 0), -system.residues * np.exp(system.poles * np.minimum(t, 0)), 0
    )
    return (causal + ahead).sum(axis=-1).real


@pytest.mark.parametrize("span_hz", [12.5, 200.0, 3200.0])
def test_filter_has_zero_phase_and_the_specified_magnitude(span_hz):
    aa = anti_alias(span_hz)
    f = np.linspace(0, 3 * span_hz, 601)
    g = aa.evaluate(2j * np.pi * f)
    assert np.max(np.abs(g.imag)) < 1e-9
    assert np.all(g.real > 0)
    db = 20 * np.log10(np.abs(g))
    assert db[f <= span_hz].min() >= -0.1 - 1e-9  # 0.1 dB to the span
    assert db[f >= 1.56 * span_hz].max() <= -100.0  # 100 dB from 1.56 x span
    assert np.any(aa.poles.real > 0)
    assert np.any(aa.poles.real < 0)


def test_a_symmetric_pulse_comes_out_symmetric_about_its_centre():
    aa = anti_alias(200.0)
    pulses = HalfSinePulses(np.array([0.010]), np.array([0.002]), np.array([1.0]))
    centre = 0.011
    offsets = np.linspace(0.0, 0.05, 201)
    before = aa.respond(pulses, centre - offsets)
    after = aa.respond(pulses, centre + offsets)
    np.testing.assert_allclose(before, after, atol=1e-9 * np.max(np.abs(after)))
    assert np.argmax(aa.respond(pulses, centre + np.linspace(-0.01, 0.01, 2001))) == 1000


def test_two_sided_response_equals_numerical_convolution():
    aa = anti_alias(200.0)
    start, width, peak = 0.0, 0.002, 3.0
    pulses = HalfSinePulses(np.array([start]), np.array([width]), np.array([peak]))
    times = np.array([-0.03, -0.004, 0.0005, 0.001, 0.0031, 0.02])
    tau = np.linspace(start, start + width, 40001)
    u = peak * np.sin(np.pi * (tau - start) / width)
    expected = [scipy.integrate.trapezoid(_impulse_response(aa, t - tau) * u, tau) for t in times]
    got = aa.respond(pulses, times)
    np.testing.assert_allclose(got, expected, rtol=1e-5, atol=1e-7 * np.max(np.abs(expected)))
