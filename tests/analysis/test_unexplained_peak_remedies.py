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

from dataclasses import replace

import numpy as np
import pytest

import analysis.modal_id.identify as identify
from analysis.modal_id import identify_modes
from analysis.run_analysis import AnalysisOptions, _for_peak_caution, _unexplained_caution, analyze_hits
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
    """The analysis as it was before the third pass kept the peak's mode: the caution's
    remedies are what a user gets wherever that pass does not keep it."""
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(identify, "_kept_for_peaks", lambda fu, hu, zones, result, *args: result)
        return analysed()


def test_by_default_the_peaks_mode_is_kept_and_marked(first):
    """The third pass (identify._kept_for_peaks) keeps what the diagram holds at the clear
    peak beside the modes found, as the caution's --frequencies did: within a line of the
    true 224.6 Hz, marked as kept for a peak, the synthesis error lower (14 % -> 10 %)."""
    band = (first.frequency_hz >= first.band.low_hz) & (first.frequency_hz <= first.band.high_hz)
    modal = identify_modes(first.frequency_hz[band], first.frf[:, band])
    (mode,) = [m for m in modal.modes if abs(m.frequency_hz - 224.6) < first.frequency_hz[1]]
    assert mode.quality.for_peak
    assert not mode.quality.accepted  # the diagram alone would not have kept it
    assert [m.quality.for_peak for m in modal.modes].count(True) == 1
    assert modal.synthesis_error <= identify.PEAK_PASS_GAIN * first.modal.synthesis_error
    for other in first.modes:
        assert any(abs(m.frequency_hz - other.frequency_hz) < 1.0 for m in modal.modes), other.frequency_hz


def test_the_whole_analysis_finds_the_peaks_mode_by_default():
    """Kept for its peak, the light mode makes the records be read again cut at the impact
    (analysis.pretrigger), where the diagram holds it over 21 orders: 224.7 Hz."""
    result = analysed()
    (mode,) = [m for m in result.modes if abs(m.frequency_hz - 224.6) < 9.77]
    assert abs(mode.frequency_hz - 224.6) <= 2 * mode.frequency_u_hz + 0.2, (
        mode.frequency_hz,
        mode.frequency_u_hz,
    )
    assert not [c for c in result.cautions if c.startswith("a clear peak")]


def test_the_caution_for_a_kept_peak_says_how_to_leave_it_out(first):
    quality = {**first.modes[0].quality, "for_peak": True, "n_stable_orders": 2, "accepted": False}
    kept = replace(first.modes[0], quality=quality)
    result = replace(first, modes=[kept, *first.modes[1:]])
    caution = _for_peak_caution(result, [kept], AnalysisOptions())
    assert caution.startswith(f"the mode at {kept.frequency_hz:.4g} Hz is kept for a clear peak of the FRF")
    assert "holds it over 2 orders, too few or too unsteady" in caution
    # A chain that passed the selection rules in its own zone is not blamed for too few orders.
    steady = replace(kept, quality={**quality, "n_stable_orders": 25, "accepted": True})
    caution_steady = _for_peak_caution(
        replace(first, modes=[steady, *first.modes[1:]]), [steady], AnalysisOptions()
    )
    assert "too few" not in caution_steady
    assert "in a zone of its own, where the passes before did not" in caution_steady
    others = ",".join(f"{m.frequency_hz:.6g}" for m in first.modes[1:])
    assert caution.endswith(f"to leave it out, --frequencies {others}")


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
