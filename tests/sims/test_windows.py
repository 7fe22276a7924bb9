"""The analyzer's windows against their textbook definitions, periodic as a spectrum
analyzer applies them. The flat top is the 5-term cosine series tabulated for FFT
analyzers with the normalised coefficients 1, 1.93, 1.29, 0.388, 0.028 (Stanford
Research Systems' flat top); the analyzer uses the same series with more digits
(0.21557895, 0.41663158, 0.277263158, 0.083578947, 0.006947368), so the two agree
to the rounding of the short form."""

from __future__ import annotations

import numpy as np
import pytest

from sims.dsp import window

N = 1024
RATE_HZ = 512.0
K = np.arange(N)


def test_hanning_is_the_periodic_raised_cosine():
    np.testing.assert_allclose(window("HANN", N, RATE_HZ, 0.05, 1.0), np.sin(np.pi * K / N) ** 2, atol=1e-15)


def test_flat_top_is_the_five_term_cosine_series():
    a = (1.0, 1.93, 1.29, 0.388, 0.028)  # normalised coefficients, peak 4.636 at the centre
    expected = sum((-1) ** i * c * np.cos(2 * np.pi * i * K / N) for i, c in enumerate(a)) / sum(a)
    got = window("FLAT", N, RATE_HZ, 0.05, 1.0)
    np.testing.assert_allclose(got / got.max(), expected / expected.max(), atol=2e-3)


@pytest.mark.parametrize("decay_s", [0.1, 0.5, 1.5])
def test_exponential_falls_by_e_every_time_constant(decay_s):
    w = window("EXPO", N, RATE_HZ, 0.05, decay_s)
    assert w[0] == 1.0
    step = round(decay_s * RATE_HZ)
    assert w[step] == pytest.approx(np.exp(-step / RATE_HZ / decay_s), rel=1e-12)


def test_force_window_is_one_for_its_width_from_the_record_start():
    w = window("FORC", N, RATE_HZ, 0.05, 1.0)
    inside = int(np.ceil(0.05 * RATE_HZ))  # samples k with k / rate < 0.05 s
    assert w[:inside].tolist() == [1.0] * inside
    assert not w[inside:].any()


@pytest.mark.parametrize("kind", ["HANN", "FLAT"])
def test_cosine_windows_are_periodic_not_symmetric(kind):
    """DFT-even: the peak sits on sample N/2 and w[k] == w[N - k]; a symmetric window
    (period N - 1) would peak between samples and miss both."""
    w = window(kind, N, RATE_HZ, 0.05, 1.0)
    assert int(np.argmax(w)) == N // 2
    np.testing.assert_allclose(w[1:], w[1:][::-1], atol=1e-14)
    assert w[N // 2] == pytest.approx(1.0, rel=1e-8)  # both peak at 1 (the flat top's sum of a_i)


@pytest.mark.parametrize("decay_s", [0.05, 2.0])
def test_exponential_is_exp_of_minus_time_over_the_time_constant(decay_s):
    """Time constant in seconds, time from the record's first sample (k / 512 Hz)."""
    w = window("EXPO", N, RATE_HZ, 0.05, decay_s)
    np.testing.assert_allclose(w, np.exp(-K / RATE_HZ / decay_s), rtol=1e-12, atol=1e-300)
