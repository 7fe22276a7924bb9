"""analysis/damping/fit_limits.py: the noise floor of Psi and the search boxes of the
global fits, on arrays alone (no run, no store)."""

from __future__ import annotations

import numpy as np
import pytest

from analysis.damping.fit_limits import (
    DE_BOX_FACTOR,
    GA_BOUNDS,
    PRE_RINGING_SAMPLES,
    coded_scale,
    de_bounds,
    identified_poles,
    noise_floor,
)
from analysis.response import frequency_response
from analysis.ritz import RitzBeam

FS_HZ = 512.0
N = 1024


@pytest.fixture(scope="module")
def model():
    return RitzBeam.build(n_functions=2).structure()


def test_the_ga_keeps_the_seeds_box_and_de_grows_with_the_estimate():
    assert GA_BOUNDS == (-10.0, 10.0)
    small = np.diag([0.1, 0.2])
    assert de_bounds(small, psd=False) == (-10.0, 10.0)  # never below the seed's box
    large = np.array([[300.0, -20.0], [-20.0, 50.0]])
    assert coded_scale(large, psd=False) == 300.0
    assert de_bounds(large, psd=False) == (-DE_BOX_FACTOR * 300.0, DE_BOX_FACTOR * 300.0)
    # R = L L^T codes L's terms: sqrt(300) is the largest.
    assert coded_scale(large, psd=True) == pytest.approx(np.sqrt(300.0))


def _records(n_hits: int, peak_at: int, sigma_f: float, sigma_y: float, seed: int = 0):
    rng = np.random.default_rng(seed)
    force = sigma_f * rng.standard_normal((n_hits, N))
    response = sigma_y * rng.standard_normal((n_hits, N))
    force[:, peak_at] = 100.0  # the pulse: everything before it, less the pre-ringing, is quiet
    return force, response


def test_response_noise_alone_gives_its_sigma_over_the_root_of_the_samples(model):
    force, response = _records(3, 400, 0.0, 0.01)
    damping = np.diag([0.5, 0.5])
    floor = noise_floor(force, response, FS_HZ, model, damping)
    quiet = response[:, : 400 - PRE_RINGING_SAMPLES]
    sigma_y = np.sqrt(np.mean((quiet - quiet.mean(axis=1, keepdims=True)).ravel() ** 2))
    assert floor == pytest.approx(sigma_y / np.sqrt(response.size), rel=1e-12)


def test_force_noise_enters_through_the_models_response(model):
    force, response = _records(2, 600, 0.002, 0.0, seed=1)
    damping = np.diag([0.5, 0.5])
    floor = noise_floor(force, response, FS_HZ, model, damping)
    h = frequency_response(model, damping, np.linspace(0.0, FS_HZ / 2.56, N * 100 // 256 + 1))
    quiet = force[:, : 600 - PRE_RINGING_SAMPLES]
    quiet = (quiet - quiet.mean(axis=1, keepdims=True)).ravel()
    sigma_f = np.sqrt(np.mean(quiet**2))
    assert floor == pytest.approx(sigma_f * np.sqrt(np.mean(np.abs(h) ** 2)) / np.sqrt(force.size), rel=1e-12)
    # More damping, smaller |H| at resonance: a lower floor.
    assert noise_floor(force, response, FS_HZ, model, np.diag([50.0, 50.0])) < floor


def test_no_quiet_samples_no_floor(model):
    force, response = _records(2, PRE_RINGING_SAMPLES + 10, 0.01, 0.01)
    assert noise_floor(force, response, FS_HZ, model, np.eye(2)) is None
    assert noise_floor(force[:0], response[:0], FS_HZ, model, np.eye(2)) is None


def test_identified_poles():
    f = np.array([10.0, 100.0])
    zeta = np.array([0.01, 0.5])
    poles = identified_poles(f, zeta)
    np.testing.assert_allclose(np.abs(poles), 2 * np.pi * f)
    np.testing.assert_allclose(-poles.real / np.abs(poles), zeta)
    assert identified_poles(np.array([5.0]), np.array([2.0]))[0].imag == 0.0  # overdamped: on the axis
