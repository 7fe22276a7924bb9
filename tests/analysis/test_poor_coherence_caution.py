"""An FRF among several whose coherence says it is noise is named in a caution: the band
follows the FRFs' mean coherence, which the good ones keep above 0.5. A new user's UFF
of three FRFs, the third pure noise with coherence 0.1, was analysed with "the coherence
(0.5 or more ...) limits neither edge" and no word of the third (its 310 Hz mode's damping
3 u off)."""

from __future__ import annotations

import numpy as np
import pytest

from analysis.band_choice import MIN_COHERENCE, choose_band, poor_coherence
from analysis.run_analysis import analyze_frfs

F = np.arange(1, 1001) * 0.5
FN, ZETA = np.array([45.0, 120.0, 310.0]), np.array([0.01, 0.005, 0.02])


def _frf(scale: float) -> np.ndarray:
    w, wn = 2 * np.pi * F[:, None], 2 * np.pi * FN[None, :]
    return scale * np.sum(-(w**2) / (wn**2 - w**2 + 2j * ZETA * wn * w), axis=1)


def _run(noisy: bool):
    rng = np.random.default_rng(3)
    h = np.stack([_frf(1.0), _frf(0.6), _frf(0.3)])
    coherence = np.ones_like(h.real)
    if noisy:
        h[2] = np.abs(h[2]).mean() * (rng.standard_normal(F.size) + 1j * rng.standard_normal(F.size))
        coherence[2] = 0.1
    return analyze_frfs(F, h, coherence, "measured_frf")


def test_the_noisy_frf_is_named_and_the_band_says_it_follows_the_mean():
    result = _run(noisy=True)
    (caution,) = [c for c in result.cautions if c.startswith("FRF ")]
    assert caution.startswith("FRF 3 (below 0.5 over 100% of the band, median 0.10) is mostly noise")
    assert "mean of 3 FRFs'" in result.band.reason


def test_good_frfs_get_no_such_caution():
    assert not [c for c in _run(noisy=False).cautions if c.startswith("FRF ")]


@pytest.mark.parametrize(("poor_from", "named"), [(0.3, True), (0.6, False)])
def test_an_frf_is_named_when_more_than_half_the_band_is_poor(poor_from, named):
    c = np.ones((2, F.size))
    c[1, poor_from * F[-1] <= F] = 0.2  # poor over the top 70 % or 40 % of the lines
    got = poor_coherence(F, c, F[0], F[-1])
    assert [k for k, _, _ in got] == ([1] if named else [])
    if named:
        assert got[0][1] == pytest.approx(0.7, abs=0.01)


def test_one_frf_is_left_to_the_whole_band_caution():
    c = np.full((1, F.size), 0.1)
    assert poor_coherence(F, c, F[0], F[-1]) == []
    assert not choose_band(F, None, c).coherence_ok
    assert MIN_COHERENCE == 0.5
