"""A mode LSCF missed beside a heavily damped one is added (refine.missing_beside_heavy).

Two overlapping heavily damped modes, 150 and 170 Hz at 5 and 8 % (a new user's known-truth
records, 3-10 hits at 2-5 % noise), were one mode in 9 of 15 files: LSCF held no chain at
170 Hz at any order and no caution said so. The heavy pole's wider window, fitted again with
one pole more, holds the second mode; a pole fitted to the noise beside a single heavy mode
does not pass the same test."""

from __future__ import annotations

import numpy as np
import pytest

from analysis.modal_id.refine import missing_beside_heavy
from analysis.run_analysis import analyze_hits
from analysis.windows import WindowSpec
from tests.analysis.impact_synth import impact_hits

UNIFORM = WindowSpec("uniform")
FN = np.array([150.0, 170.0, 320.0])
ZETA = np.array([0.05, 0.08, 0.005])
AMP = np.array([2.0, 2.0, 0.5])


def _modes(fn, zeta, amp, seed, noise=0.03, n_hits=5):
    """The modes of n_hits hits, the response's noise ``noise`` x its peak (as the user's
    logger records had it: a heavily damped response's peak stands far above its RMS)."""
    force, response = impact_hits(fn, zeta, amp, 2048.0, 2.0, n_hits, 0.0, 0.0015, seed)
    rng = np.random.default_rng(100 + seed)
    response = response + noise * np.abs(response).max(axis=1, keepdims=True) * rng.standard_normal(
        response.shape
    )
    return analyze_hits(force, response, 2048.0, np.ones(n_hits, dtype=bool), UNIFORM, UNIFORM).modes


# Draws in which LSCF held no chain at 170 Hz (5 of seeds 0-9; all 10 are found now).
@pytest.mark.parametrize("seed", [0, 3, 6, 9])
def test_two_overlapping_heavy_modes_are_both_found_within_their_uncertainty(seed):
    modes = _modes(FN, ZETA, AMP, seed)
    assert len(modes) == 3, [round(m.frequency_hz, 1) for m in modes]
    for m, fn, zeta in zip(modes, FN, ZETA, strict=True):
        # 3 u: a test that must hold on every draw, not a coverage figure.
        assert abs(m.frequency_hz - fn) <= 3 * m.frequency_u_hz, (m.frequency_hz, m.frequency_u_hz)
        assert abs(m.damping_ratio - zeta) <= 3 * m.damping_u, (m.damping_ratio, m.damping_u)
    added = modes[1]
    assert added.quality["added"]
    assert added.quality["refined"]
    assert added.uncertainty_from == "5 hits"


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_a_single_heavy_mode_gets_no_neighbour(seed):
    modes = _modes([300.0, 120.0], [0.08, 0.008], [3.0, 1.0], seed)
    assert sorted(round(m.frequency_hz, -1) for m in modes) == [120.0, 300.0]


def test_no_pole_is_added_to_a_noise_free_single_heavy_mode_or_to_light_ones():
    f = np.arange(0.0, 600.0, 0.5)
    w = 2 * np.pi * f
    poles = []
    h = np.zeros(f.size, dtype=complex)
    for fn, zeta, amp in ((150.0, 0.06, 2.0), (400.0, 0.01, 1.0)):
        wn = 2 * np.pi * fn
        h += amp * -(w**2) / (wn**2 - w**2 + 2j * zeta * wn * w)
        poles.append(-zeta * wn + 1j * wn * np.sqrt(1 - zeta**2))
    added, parent = missing_beside_heavy(f[1:], h[1:], np.array(poles), 0.5)
    assert added.size == 0
    assert parent.size == 0
