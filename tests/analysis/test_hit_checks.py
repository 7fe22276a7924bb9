"""The per-hit checks on synthetic pulses with known answers, and on the simulator's records."""

from __future__ import annotations

import math

import numpy as np
import pytest

from analysis.hit_checks import double_impact, force_rolloff, overload, run_checks, too_weak
from drivers.hp_mnemonic import HPMnemonicAnalyzer as HP35660A
from drivers.settings import ImpactSettings
from sims.instrument import Analyzer
from sims.sources import PhysicsSource
from sims.tcp_server import TcpServer

RATE_HZ = 25_600.0  # fine enough to draw a 1 ms half-sine; 2^16 samples give 0.39 Hz lines
N = 2**16


def half_sine(width_s: float, peak_n: float = 10.0, start_s: float = 0.01, rate_hz: float = RATE_HZ):
    t = np.arange(N) / rate_hz
    inside = (t >= start_s) & (t < start_s + width_s)
    return np.where(inside, peak_n * np.sin(np.pi * (t - start_s) / width_s), 0.0)


def half_sine_power(f_hz: np.ndarray, width_s: float) -> np.ndarray:
    """|F(f)|^2 of a half-sine of width T, up to a constant: cos(pi f T) / (1 - (2 f T)^2).
    Its first zero is at f = 1.5 / T."""
    x = 2 * f_hz * width_s
    singular = np.isclose(x, 1.0)  # 0/0 at f = 1 / (2T): the limit is pi/4
    denominator = np.where(singular, 1.0, 1 - x**2)
    amplitude = np.where(singular, np.pi / 4, np.cos(np.pi * f_hz * width_s) / denominator)
    return amplitude**2


def expected_drop_db(width_s: float, span_hz: float) -> float:
    f = np.fft.rfftfreq(N, 1 / RATE_HZ)
    low, top = (f > 0) & (f <= 0.1 * span_hz), (f <= span_hz) & (f >= 0.9 * span_hz)
    power = half_sine_power(f, width_s)
    return 10 * math.log10(power[low].mean() / power[top].mean())


def test_half_sine_formula_has_its_first_zero_at_1_5_over_width():
    assert half_sine_power(np.array([1.5 / 0.02]), 0.02)[0] == pytest.approx(0.0, abs=1e-25)


def test_short_pulse_passes_rolloff_at_200_hz():
    check = force_rolloff(half_sine(1e-3), RATE_HZ, 200.0)
    # cos(0.2 pi) / (1 - 0.16) = 0.963 at 200 Hz: about 0.2 dB on average over the top lines.
    assert check.passed
    assert check.value == pytest.approx(expected_drop_db(1e-3, 200.0), abs=0.05)
    assert check.value < 0.5


def test_long_pulse_fails_rolloff_at_200_hz():
    check = force_rolloff(half_sine(20e-3), RATE_HZ, 200.0)
    expected = expected_drop_db(20e-3, 200.0)
    assert expected > 30  # the span's top lies past the first zero (75 Hz), in the sidelobes
    assert not check.passed
    assert check.value == pytest.approx(expected, abs=0.5)


def test_single_pulse_passes_double_pulse_fails():
    single = double_impact(half_sine(2e-3), RATE_HZ)
    assert single.passed
    assert single.value < 0.10
    double = half_sine(2e-3) + half_sine(2e-3, peak_n=3.0, start_s=0.02)
    check = double_impact(double, RATE_HZ)
    assert not check.passed
    assert check.value == pytest.approx(0.3, abs=1e-3)  # the second pulse's peak over the first's


def test_band_limited_ringing_is_not_a_second_hit():
    # A pulse shorter than a sample, as the analyzer sees it at low spans: sinc ringing
    # (sidelobes -22 %, +13 %, -9 %...) must not count as a rebound.
    n = np.arange(-20, 100)
    check = double_impact(np.sinc(n - 0.3), 512.0)
    assert check.passed, check.detail


def test_overload_flags():
    assert overload((False, False)).passed
    assert not overload((True, False)).passed
    flagged = overload((False, True))
    assert not flagged.passed
    assert "response" in flagged.detail


def test_too_weak():
    pulse = half_sine(2e-3, peak_n=0.4)
    assert not too_weak(pulse, range_n=10.0).passed  # 4 % of the range
    assert too_weak(pulse, range_n=4.0).passed  # 10 %
    assert too_weak(pulse, range_n=None).passed  # autorange: not judged


def _simulated_hits(double_probability: float, n_hits: int = 4):
    analyzer = Analyzer(PhysicsSource("realistic", seed=5), time_scale=0.0)
    settings = ImpactSettings(span_hz=200.0, averages=n_hits)
    with TcpServer(analyzer) as server, HP35660A.open(server.resource) as dsa:
        dsa.send(f"SIM:HAMMER double_hit_probability={double_probability}")
        actual = dsa.configure(settings)
        dsa.start()
        for _ in range(n_hits):
            dsa.wait_for_hit(timeout_s=10)
            force, response = dsa.fetch_time_records()
            dsa.reject()
            range_n = actual.hammer.range_v / actual.hammer.sensitivity_v_per_eu
            flags = (force.header.overflow, response.header.overflow)
            yield run_checks(force.data, force.header.sample_rate_hz, actual.span_hz, flags, range_n)


def test_simulated_clean_hits_pass_every_check():
    for checks in _simulated_hits(0.0):
        assert all(c.passed for c in checks), [c.detail for c in checks]


def test_simulated_double_hits_fail_double_impact():
    for checks in _simulated_hits(1.0):
        verdict = {c.name: c.passed for c in checks}
        assert not verdict["double impact"], [c.detail for c in checks]
        assert verdict["overload"]
        assert verdict["too weak"]
