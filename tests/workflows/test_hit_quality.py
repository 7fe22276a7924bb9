"""The per-hit quality view (daq/workflows/hit_quality.py) against numbers from theory:
a rectangular force pulse's spectrum (a Dirichlet kernel), a discrete two-pole
resonator's FRF (its z-transform), the windows' definitions, and agreement with the
tip check it draws (analysis/hit_checks.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from analysis.hit_checks import force_rolloff
from daq.workflows.hit_quality import force_spectrum, hit_quality

FS = 1024.0  # Hz: 1 Hz lines on a 1024-sample record
N = 1024
SPAN = 400.0  # Hz: lines 0..400, the alias-free band (fs / 2.56)


def _pulse(width: int, amplitude: float = 10.0) -> np.ndarray:
    force = np.zeros(N)
    force[:width] = amplitude
    return force


def _dirichlet_power(k: np.ndarray, width: int, amplitude: float) -> np.ndarray:
    """|DFT|^2 of a rectangular pulse of ``width`` samples at line k: A^2 sin^2(pi k M/N) / sin^2(pi k/N)."""
    k = np.asarray(k, dtype=float)
    out = np.full(k.shape, (amplitude * width) ** 2)
    nz = k != 0
    out[nz] = amplitude**2 * np.sin(np.pi * k[nz] * width / N) ** 2 / np.sin(np.pi * k[nz] / N) ** 2
    return out


def test_a_rectangular_pulse_spectrum_is_the_dirichlet_kernel_relative_to_the_low_band():
    spectrum = force_spectrum(_pulse(2), FS, SPAN)
    assert spectrum["frequency_hz"].shape == spectrum["level_db"].shape == (401,)
    k = np.arange(401)
    power = _dirichlet_power(k, 2, 10.0)
    reference = power[1:41].mean()  # lines 1..40 Hz: the lowest 10 % of the span, DC out
    assert spectrum["level_db"] == pytest.approx(10 * np.log10(power / reference), abs=1e-9)
    # Two samples: 4 A^2 cos^2(pi k / N). At 400 Hz cos^2(400 pi / 1024) = 0.113495; the
    # mean of cos^2(pi k / 1024) over k = 1..40 is 0.994806: 10 log10(0.113495 / 0.994806).
    assert spectrum["level_db"][400] == pytest.approx(-9.42763, abs=1e-4)
    assert (spectrum["rolloff_limit_db"], spectrum["rolloff_hz"]) == (-10.0, 360.0)
    assert spectrum["low_band_hz"] == [1.0, 40.0]


def test_the_drawn_drop_is_the_tip_checks_value_and_a_null_shows():
    # A 4-sample pulse has its first null at N / 4 = 256 Hz, inside the span; its drop
    # across a 400 Hz span fails the 10 dB check.
    force = _pulse(4)
    spectrum = force_spectrum(force, FS, SPAN)
    check = force_rolloff(force, FS, SPAN)
    assert spectrum["drop_db"] == pytest.approx(check.value, rel=1e-12)
    assert not check.passed
    assert spectrum["level_db"][256] < -200  # the null (numerically zero)
    top = spectrum["frequency_hz"] >= spectrum["rolloff_hz"]
    mean_top_db = 10 * np.log10(np.mean(10 ** (spectrum["level_db"][top] / 10)))
    assert mean_top_db == pytest.approx(-check.value, rel=1e-12)
    assert mean_top_db < spectrum["rolloff_limit_db"]


def test_a_zoom_record_uses_the_band_around_the_centre():
    rng = np.random.default_rng(3)
    force = rng.normal(size=512) + 1j * rng.normal(size=512)
    spectrum = force_spectrum(force, 512.0, 400.0)
    assert spectrum["frequency_hz"][0] == -200.0
    assert spectrum["frequency_hz"][-1] == 200.0
    assert spectrum["drop_db"] == pytest.approx(force_rolloff(force, 512.0, 400.0).value, rel=1e-12)


def _resonator(rho: float, theta: float) -> np.ndarray:
    """Impulse response of 1 / (1 - 2 rho cos(theta) z^-1 + rho^2 z^-2):
    rho^n sin((n+1) theta) / sin(theta)."""
    n = np.arange(N)
    return rho**n * np.sin((n + 1) * theta) / np.sin(theta)


SETTINGS = {
    "span_hz": SPAN,
    "hammer": {"window": "FORC", "force_width_s": 0.1},
    "accelerometer": {"window": "UNIF"},
}


def test_one_hit_frf_is_the_resonators_transfer_function_and_the_windows_are_as_defined():
    rho, theta = 0.99, 2 * np.pi * 100 / FS  # a mode at 100 Hz, decaying to 0.99^1024 = 3e-5
    force = np.zeros(N)
    force[0] = 5.0
    response = 5.0 * _resonator(rho, theta)
    view = hit_quality(SETTINGS, [(force, response)], [None], 0, FS)
    frf = view["frf"]
    assert frf["frequency_hz"].shape == frf["magnitude"].shape == frf["phase_deg"].shape == (401,)
    z1 = np.exp(-2j * np.pi * frf["frequency_hz"] / FS)  # z^-1 on each line
    theory = 1 / (1 - 2 * rho * np.cos(theta) * z1 + rho**2 * z1**2)
    assert frf["magnitude"] == pytest.approx(np.abs(theory), rel=1e-4)
    assert frf["phase_deg"] == pytest.approx(np.degrees(np.angle(theory)), abs=1e-2)
    assert frf["frequency_hz"][np.argmax(frf["magnitude"])] == 100.0
    # At 100 Hz: 1 / |1 - rho e^{-2j theta}| / (1 - rho) = 1 / (0.01 * |1 - 0.99 e^{-j 0.3906 pi}|)
    assert frf["magnitude"][100] == pytest.approx(1 / (0.01 * abs(1 - 0.99 * np.exp(-2j * theta))), rel=1e-4)
    assert view["average"] is None  # not accepted (undecided)
    # Windows: force 1 for t < 0.1 s (samples 0..102 at 1024 Hz), response uniform.
    assert view["force_window"].shape == view["response_window"].shape == (N,)
    assert view["force_window"][:103].tolist() == [1.0] * 103
    assert not view["force_window"][103:].any()
    assert np.all(view["response_window"] == 1.0)


def test_the_average_runs_over_the_accepted_hits_up_to_this_one_with_coherence():
    rho, theta = 0.99, 2 * np.pi * 100 / FS
    g = _resonator(rho, theta)
    records, accepted = [], []
    for amplitude, verdict in ((5.0, True), (2.0, False), (8.0, True), (3.0, True)):
        force = np.zeros(N)
        force[0] = amplitude
        records.append((force, amplitude * g))
        accepted.append(verdict)
    settings = {**SETTINGS, "accelerometer": {"window": "EXPO", "exp_decay_s": 0.25}}
    view = hit_quality(settings, records, accepted, 2, FS)
    average = view["average"]
    assert average["n_averaged"] == 2  # hits 0 and 2; hit 3 comes later
    assert average["coherence"] == pytest.approx(np.ones(401), abs=1e-9)  # noiseless: 1
    # The exponential window at t = tau is 1/e.
    assert view["response_window"][256] == pytest.approx(math.exp(-1), rel=1e-9)
    # H1 of identical (scaled) hits is each hit's own H1.
    assert average["magnitude"] == pytest.approx(view["frf"]["magnitude"], rel=1e-9)
    with pytest.raises(IndexError):
        hit_quality(settings, records, accepted, 4, FS)
