"""A heavily damped mode among lightly damped ones: its chain's frequency wanders over the
orders by more than a lightly damped mode's may (2 %), yet by a small part of its own
half-power width; it is a mode (stability.WANDER_HALF_WIDTHS). A new user's known-truth
file (300 Hz at 8 % between 120 and 700 Hz at 0.8 and 1 %, 1 % response noise) lost it
with no caution."""

from __future__ import annotations

import numpy as np
import pytest

from analysis.run_analysis import analyze_hits
from analysis.windows import WindowSpec
from tests.analysis.impact_synth import impact_hits

UNIFORM = WindowSpec("uniform")
FN, ZETA, AMP = np.array([120.0, 300.0, 700.0]), np.array([0.008, 0.08, 0.01]), np.array([1.0, 3.0, 1.0])


# Seeds whose 300 Hz chain wanders by 2-4 %: the mode was left out before.
@pytest.mark.parametrize("seed", [11, 15])
def test_the_broad_mode_is_found(seed):
    force, response = impact_hits(FN, ZETA, AMP, 2048.0, 4.0, 5, 0.08, 0.001, seed, pretrigger_s=0.05)
    modes = analyze_hits(force, response, 2048.0, np.ones(5, dtype=bool), UNIFORM, UNIFORM).modes
    near = [m for m in modes if abs(m.frequency_hz - 300.0) <= 0.25 * 0.08 * 300.0]
    assert len(near) == 1, [round(m.frequency_hz, 1) for m in modes]
    assert abs(near[0].frequency_hz - 300.0) <= 3 * near[0].frequency_u_hz
