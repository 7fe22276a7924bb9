"""The remedies an unexplained peak's caution offers must lead somewhere.

A measured free-free beam (one hit, 0.1 s, 9.8 Hz lines) had a clear peak at 224.6 Hz
without a mode; the caution sent the user to `--band 9.766:468.8`, which found nothing and
suggested `--band 19.53:468.8`, which suggested itself. Now the caution also gives the
`--frequencies` that keep what the stability diagram holds there beside the modes found,
and where the result's own --band is hardly wider than the one it would suggest, it says
that band already looks at the peak instead of sending the user round.
Simulated here: one hit of 0.1 s, six modes, the first at 224.6 Hz with 0.01 % damping
(narrower than a line), which seed 2's noise leaves without a mode."""

from __future__ import annotations

import numpy as np
import pytest

from analysis.run_analysis import AnalysisOptions, _unexplained_caution, analyze_hits
from analysis.windows import WindowSpec
from tests.analysis.impact_synth import impact_hits

UNIFORM = WindowSpec("uniform")
FN_HZ = [224.6, 605.1, 1939.7, 2870.7, 4012.7, 5267.5]
ZETA = [0.0001, 0.001, 0.0032, 0.0046, 0.0058, 0.005]
AMP = [0.5, 1.0, 0.5, 0.8, 1.0, 1.0]
RATE_HZ = 20000.0


def analysed(options: AnalysisOptions | None = None):
    force, response = impact_hits(FN_HZ, ZETA, AMP, RATE_HZ, 0.1, 1, 0.01, 0.0003, seed=2)
    return analyze_hits(force, response, RATE_HZ, np.ones(1, bool), UNIFORM, UNIFORM, options=options)


@pytest.fixture(scope="module")
def first():
    return analysed()


def the_caution(result) -> str:
    (caution,) = [c for c in result.cautions if c.startswith("a clear peak")]
    return caution


def test_the_frequencies_the_caution_offers_keep_the_peaks_mode_and_the_others(first):
    assert not any(abs(m.frequency_hz - 224.6) < 10 for m in first.modes)
    caution = the_caution(first)
    assert "look at it with --band" in caution
    asked = caution.rsplit("--frequencies ", 1)[1].split()[0]
    frequencies = tuple(float(f) for f in asked.split(","))
    assert len(frequencies) == len(first.modes) + 1
    again = analysed(AnalysisOptions(frequencies_hz=frequencies))
    found = [m.frequency_hz for m in again.modes]
    assert any(abs(f - 224.6) < 9.77 for f in found), found
    for mode in first.modes:
        assert any(abs(f - mode.frequency_hz) < 1.0 for f in found), (mode.frequency_hz, found)


def test_a_band_as_narrow_as_the_one_it_would_suggest_is_not_suggested_again(first):
    peak = float(the_caution(first).split(" Hz ", 1)[0].rsplit(" ", 1)[1])
    caution = _unexplained_caution(first, [peak], AnalysisOptions(band_hz=(9.766, 468.8)))
    assert "its --band 9.766:468.8 already looks at it" in caution
    assert "look at it with --band" not in caution
    assert "record longer for finer lines" in caution
