"""analysis.windows against scipy's windows, the simulated analyzer's definitions, and
poles built by hand (the exponential window's pole shift is worked out in the tests,
not taken from the code under test)."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.signal

from analysis.windows import WindowSpec, added_decay_rate, correct_pole, window
from sims.dsp import window as analyzer_window

N = 1024
RATE_HZ = 2560.0


def test_hann_and_flattop_are_scipys_periodic_windows():
    np.testing.assert_array_equal(
        window(WindowSpec("hann"), N, RATE_HZ), scipy.signal.windows.hann(N, sym=False)
    )
    np.testing.assert_array_equal(
        window(WindowSpec("flattop"), N, RATE_HZ), scipy.signal.windows.flattop(N, sym=False)
    )
    # Periodic, not symmetric: the last sample is not the first.
    assert window(WindowSpec("hann"), N, RATE_HZ)[-1] > 0


def test_uniform_is_ones():
    np.testing.assert_array_equal(window(WindowSpec("uniform"), 7, 1.0), np.ones(7))


def test_rectangular_force_window_is_one_up_to_the_width_and_zero_after():
    # 0.05 s at 2560 Hz = 128 samples: t = 0 .. 127/2560 s are inside, 128/2560 s = 0.05 s is not.
    w = window(WindowSpec("force", force_width_s=0.05), N, RATE_HZ)
    assert np.all(w[:128] == 1.0)
    assert np.all(w[128:] == 0.0)


def test_tapered_force_window_falls_as_a_half_cosine():
    # width 10 samples, taper 8 samples at 100 Hz: w = (1 + cos(pi k / 8)) / 2, k = 0..7 after the width.
    w = window(WindowSpec("force", force_width_s=0.10, taper_s=0.08), 40, 100.0)
    assert np.all(w[:10] == 1.0)
    k = np.arange(8)
    np.testing.assert_allclose(w[10:18], 0.5 * (1 + np.cos(np.pi * k / 8)), atol=1e-12)
    assert np.all(w[18:] == 0.0)
    assert np.all(np.diff(w) <= 0)


def test_exponential_window_is_exp_minus_t_over_tau():
    tau = 0.07
    t = np.arange(N) / RATE_HZ
    np.testing.assert_allclose(
        window(WindowSpec("exponential", exp_decay_s=tau), N, RATE_HZ), np.exp(-t / tau), rtol=1e-13
    )


@pytest.mark.parametrize(
    ("spec", "code"),
    [
        (WindowSpec("uniform"), "UNIF"),
        (WindowSpec("hann"), "HANN"),
        (WindowSpec("flattop"), "FLAT"),
        (WindowSpec("force", force_width_s=0.0123), "FORC"),
        (WindowSpec("exponential", exp_decay_s=0.0456), "EXPO"),
    ],
)
@pytest.mark.parametrize(("n", "rate"), [(1024, 2560.0), (512, 1280.0), (1024, 3.2)])
def test_windows_equal_the_simulated_analyzers(spec, code, n, rate):
    expected = analyzer_window(code, n, rate, spec.force_width_s or 0.0, spec.exp_decay_s or 1.0)
    np.testing.assert_array_equal(window(spec, n, rate), expected)


def test_added_decay_rate():
    assert added_decay_rate(WindowSpec("exponential", exp_decay_s=0.25)) == 4.0
    assert added_decay_rate(WindowSpec("force", force_width_s=0.1)) == 0.0
    assert added_decay_rate(WindowSpec("hann")) == 0.0


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"kind": "hanning"}, "unknown window kind"),
        ({"kind": "force"}, "force_width_s > 0"),
        ({"kind": "force", "force_width_s": -1.0}, "force_width_s > 0"),
        ({"kind": "force", "force_width_s": 0.1, "taper_s": -0.1}, "taper_s"),
        ({"kind": "exponential"}, "exp_decay_s > 0"),
        ({"kind": "exponential", "exp_decay_s": 0.0}, "exp_decay_s > 0"),
        ({"kind": "exponential", "exp_decay_s": float("nan")}, "exp_decay_s > 0"),
        ({"kind": "hann", "force_width_s": 0.1}, "force window only"),
        ({"kind": "uniform", "exp_decay_s": 0.1}, "exponential window only"),
    ],
)
def test_bad_specs_raise(kwargs, message):
    with pytest.raises(ValueError, match=message):
        WindowSpec(**kwargs)


def test_bad_window_geometry_raises():
    with pytest.raises(ValueError, match="n_samples"):
        window(WindowSpec("hann"), 0, 1.0)
    with pytest.raises(ValueError, match="sample_rate_hz"):
        window(WindowSpec("hann"), 8, 0.0)


# ------------------------------------------------------------------ correct_pole


def _modes(poles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(f_n Hz, zeta) of poles lambda = -sigma + j omega_d: |lambda| = omega_n, zeta = sigma/|lambda|."""
    return np.abs(poles) / (2 * np.pi), -poles.real / np.abs(poles)


def test_correct_pole_recovers_hand_built_poles():
    f_true = np.array([12.5, 80.0, 350.0, 1234.5])
    zeta_true = np.array([0.002, 0.01, 0.05, 0.3])
    omega_n = 2 * np.pi * f_true
    poles = -zeta_true * omega_n + 1j * omega_n * np.sqrt(1 - zeta_true**2)
    added = 1 / 0.2  # tau = 0.2 s
    f_meas, zeta_meas = _modes(poles - added)  # the window moves each pole left by 1/tau
    f, zeta = correct_pole(f_meas, zeta_meas, added)
    np.testing.assert_allclose(f, f_true, rtol=1e-12)
    np.testing.assert_allclose(zeta, zeta_true, rtol=1e-12)
    # Scalars work and nothing is changed without a window.
    f0, z0 = correct_pole(80.0, 0.01, 0.0)
    assert f0 == pytest.approx(80.0, rel=1e-15)
    assert z0 == pytest.approx(0.01, rel=1e-14)


def test_correct_pole_gives_nan_damping_when_the_window_took_more_than_measured():
    # sigma_meas = 0.001 * 2 pi 100 = 0.63 1/s < 1/tau = 5 1/s.
    f, zeta = correct_pole(np.array([100.0, 100.0]), np.array([0.001, 0.02]), 5.0)
    assert np.isnan(zeta[0])
    assert zeta[1] == pytest.approx((0.02 * 2 * np.pi * 100 - 5) / (2 * np.pi * f[1]), rel=1e-12)
    assert np.all(np.isfinite(f))


def test_correct_pole_rejects_bad_inputs():
    with pytest.raises(ValueError, match="damping_ratio"):
        correct_pole(100.0, -0.01, 1.0)
    with pytest.raises(ValueError, match="frequency_hz"):
        correct_pole(-1.0, 0.01, 1.0)
    with pytest.raises(ValueError, match="added_decay"):
        correct_pole(100.0, 0.01, -1.0)


def _half_power_width_hz(x: np.ndarray, rate_hz: float, n_fft: int) -> tuple[float, float]:
    """Peak frequency and half-power width of |FFT(x)|^2 (zero-padded), Hz."""
    power = np.abs(np.fft.rfft(x, n_fft)) ** 2
    freq = np.fft.rfftfreq(n_fft, 1 / rate_hz)
    k = int(np.argmax(power))
    half = power[k] / 2
    lo = k - int(np.argmax(power[k::-1] < half))
    hi = k + int(np.argmax(power[k:] < half))
    # Linear interpolation of the crossings between grid points.
    f_lo = np.interp(half, [power[lo], power[lo + 1]], [freq[lo], freq[lo + 1]])
    f_hi = np.interp(half, [power[hi], power[hi - 1]], [freq[hi], freq[hi - 1]])
    return freq[k], f_hi - f_lo


def test_correct_pole_undoes_a_windowed_decay_measured_by_half_power():
    """A decaying sinusoid is windowed and its spectral peak's half-power width measured
    (width = 2 sigma / 2 pi for a lightly damped pole): the width gives the windowed
    damping; correct_pole must return the signal's own."""
    rate, f_n, zeta, tau = 1000.0, 100.0, 0.005, 0.2
    omega_n = 2 * np.pi * f_n
    sigma, omega_d = zeta * omega_n, omega_n * np.sqrt(1 - zeta**2)
    t = np.arange(4000) / rate  # 4 s: exp(-(sigma + 1/tau) 4) ~ 1e-14, no truncation
    x = np.exp(-sigma * t) * np.cos(omega_d * t)
    w = window(WindowSpec("exponential", exp_decay_s=tau), t.size, rate)
    f_peak, width = _half_power_width_hz(x * w, rate, 2**21)
    sigma_meas = np.pi * width
    zeta_meas = sigma_meas / np.hypot(sigma_meas, 2 * np.pi * f_peak)
    f_meas = np.hypot(sigma_meas, 2 * np.pi * f_peak) / (2 * np.pi)
    assert zeta_meas > 2.5 * zeta  # the window's damping dominates: not correcting is far off
    f_fix, zeta_fix = correct_pole(
        f_meas, zeta_meas, added_decay_rate(WindowSpec("exponential", exp_decay_s=tau))
    )
    assert zeta_fix == pytest.approx(zeta, rel=1e-3)
    assert f_fix == pytest.approx(f_n, rel=1e-4)
