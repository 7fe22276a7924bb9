"""A mode of 4 % at 1230 Hz between the tool-holder-like FRFs' heavy modes at 1070 and
1965 Hz, larger than in tests/analysis/modal_id/test_heavily_damped_modes.py (as the
measured tool holder's 1227 Hz is): LSCF holds no chain for it, and the step that adds a
mode beside a heavily damped one (refine.missing_beside_heavy) finds it in every draw,
its frequency within 2.5 u of the truth.

Its damping is not yet honest: 4.2-4.7 % for 4.0 %, z 1.1 to 2.9 and all of one sign (8
draws). The window it is refined on (+-8 of its half-widths, 790-1670 Hz) holds the small
modes at 800 and 1500 Hz, which the result does not model; without them the damping is
right and the frequency reads 4-9 Hz high instead (z 1.4-3.0): what the window leaves out
biases the added pole, and neither the bootstrap over lines nor the zone ends' spread
sees it. Refining it on narrower or wider windows as an uncertainty term widened the
frequency's ± threefold and left the damping's z above 1 in 7 of 8 draws, so it was not
kept. The strict xfail below says so until it is mended."""

from __future__ import annotations

import numpy as np
import pytest

from analysis.run_analysis import analyze_frfs
from tests.analysis.modal_id.test_heavily_damped_modes import SMALL_HZ, tool_holder_like

F_HZ, ZETA = 1230.0, 0.04
SEEDS = (0, 1, 2, 3)


@pytest.fixture(scope="module")
def modes():
    """seed -> the mode read near 1230 Hz (or None)."""
    k = SMALL_HZ.index(1230)
    larger = {k: 0.15 * np.array([1.0, 0.8, 0.5, 0.2, -0.1])}
    out = {}
    for seed in SEEDS:
        f, h = tool_holder_like(seed, 0.4, larger)
        near = [
            m
            for m in analyze_frfs(f, h, None, "file").modes
            if abs(m.frequency_hz - F_HZ) <= 0.25 * ZETA * F_HZ
        ]
        out[seed] = near[0] if near else None
    return out


def test_the_mode_beside_the_heavy_ones_is_added_where_it_is(modes):
    for seed, mode in modes.items():
        assert mode is not None, seed
        assert mode.quality["added"], seed
        assert abs(mode.frequency_hz - F_HZ) <= 2.5 * mode.frequency_u_hz, (seed, mode.frequency_hz)


@pytest.mark.xfail(
    strict=True, reason="damping of a mode added beside heavy ones reads high by 1-3 u (docstring)"
)
def test_its_damping_is_within_one_u_in_half_the_draws(modes):
    z = [abs(m.damping_ratio - ZETA) / m.damping_u for m in modes.values()]
    assert np.mean(np.array(z) <= 1) >= 0.5, z
