"""Clear peaks of the FRF no mode accounts for (analysis.modal_id.identify.unexplained_peaks):
looked at again in zones of their own, and named in a caution where that finds nothing.

The case is a new user's file: modes at 31 and 33 Hz (0.4 and 0.6 %, 4 lines apart on
0.5 Hz lines) beside 12.5 Hz at 2 % and a large 180 Hz at 5 %, 4 hits, response noise
2 % of its RMS. One zone over 1-436 Hz at order 30 held neither: its chains there blend
the pair (31.96 Hz at 0.79 %) or fall an order or two short; --band 20:45 found both."""

from __future__ import annotations

import numpy as np
import pytest

import analysis.modal_id.identify as identify
from analysis.run_analysis import AnalysisOptions, analyze_hits
from analysis.windows import WindowSpec
from tests.analysis.impact_synth import impact_hits

UNIFORM = WindowSpec("uniform")
FN, ZETA, AMP = (
    np.array([12.5, 31.0, 33.0, 180.0]),
    np.array([0.02, 0.004, 0.006, 0.05]),
    np.array([1.0, 0.4, 0.4, 3.0]),
)


def _analyse(seed: int, options: AnalysisOptions | None = None):
    force, response = impact_hits(FN, ZETA, AMP, 2048.0, 2.0, 4, 0.02, 3e-3, seed, pretrigger_s=0.02)
    return analyze_hits(force, response, 2048.0, np.ones(4, bool), UNIFORM, UNIFORM, options=options)


def _near(result, f_hz: float):
    return [m for m in result.modes if abs(m.frequency_hz - f_hz) < 0.5]


@pytest.mark.parametrize("seed", [0, 1])
def test_a_close_pair_the_first_pass_missed_is_found_in_a_zone_of_its_own(seed):
    result = _analyse(seed)
    for f_true, zeta_true in zip(FN, ZETA, strict=True):
        (mode,) = _near(result, f_true)
        assert abs(mode.frequency_hz - f_true) <= 3 * mode.frequency_u_hz, (mode.frequency_hz, f_true)
        assert abs(mode.damping_ratio - zeta_true) <= 3 * mode.damping_u, (mode.damping_ratio, zeta_true)
    assert any(
        z.core_low_hz <= 33.0 < z.core_high_hz and z.high_hz - z.low_hz < 30 for z in result.modal.zones
    )
    assert result.modal.unexplained_peaks_hz == []
    assert not any("clear peak" in c for c in result.cautions)


def test_without_the_second_pass_the_pair_is_lost_and_the_caution_names_its_peak(monkeypatch):
    """The test above can fail: with the zones left as planned (and no third pass), neither
    31 nor 33 Hz is a mode, and the caution names the peak with the --band that finds them."""
    monkeypatch.setattr(identify, "around_peaks", lambda f, zones, *args: zones)
    monkeypatch.setattr(identify, "_kept_for_peaks", lambda fu, hu, zones, result, *args: result)
    result = _analyse(0)
    assert _near(result, 31.0) == []
    assert _near(result, 33.0) == []
    assert [round(p) for p in result.modal.unexplained_peaks_hz] == [31, 33]
    (caution,) = [c for c in result.cautions if "clear peak" in c]
    assert caution.startswith(
        "clear peaks of the FRF at 31, 33 Hz (25 dB or more above the noise) have no mode"
    )
    assert "; look at each with --band, e.g. --band 18.5:43.5 for 31 Hz; " in caution, caution
    assert caution.endswith("keep what the diagram holds there with --frequencies 12.5027,31,33,180.088")


def test_frequencies_asked_for_take_the_chain_at_them_not_a_blend_of_two_modes():
    """--frequencies 33 returned 31.96 Hz at 0.78 %, an accepted chain between the two
    modes, where the chain at 33.02 Hz fell an order short. The clear peak at 33 Hz is
    now read in a zone of its own, as without --frequencies: a stable mode at 33.00 Hz,
    0.60 % for 0.6 %."""
    result = _analyse(0, AnalysisOptions(frequencies_hz=(33.0,)))
    (mode,) = result.modes
    assert abs(mode.frequency_hz - 33.0) <= 3 * mode.frequency_u_hz
    assert abs(mode.damping_ratio - 0.006) <= 3 * mode.damping_u
    assert mode.quality["accepted"]


@pytest.mark.parametrize("seed", [0, 1])
def test_a_clear_peak_near_a_low_edge_at_0_hz_is_looked_at_again(seed):
    """A new user's file: 3 Hz at 3 % beside 45 and 160 Hz at 1 %, 5 hits of 4 s at
    2048 Hz, band 0.25-800 Hz. The first pass holds no 3 Hz chain (its half-power band is
    0.7 of a line) and the 2 % edge guard (16 Hz) kept the second pass away: the mode was
    left out unsaid. A band from 0.25 Hz has no modes below it for poles to stand in for:
    the low guard is never wider than the gap below the band."""
    fn, zeta, amp = np.array([3.0, 45.0, 160.0]), np.array([0.03, 0.01, 0.01]), np.array([1.0, 1.0, 1.0])
    force, response = impact_hits(fn, zeta, amp, 2048.0, 4.0, 5, 0.01, 1.5e-3, seed)
    result = analyze_hits(force, response, 2048.0, np.ones(5, bool), UNIFORM, UNIFORM)
    assert result.band.low_hz < 1.0
    found = [[m for m in result.modes if abs(m.frequency_hz - f_true) < 0.05 * f_true] for f_true in fn]
    assert [len(near) for near in found] == [1, 1, 1]
    (mode,) = found[0]
    assert abs(mode.frequency_hz - 3.0) <= 2 * mode.frequency_u_hz, (mode.frequency_hz, mode.frequency_u_hz)
    assert abs(mode.damping_ratio - 0.03) <= 2 * mode.damping_u, (mode.damping_ratio, mode.damping_u)
    assert mode.damping_u < 0.15 * 0.03  # a reading, not a shrug


def test_a_frequency_asked_for_at_a_clear_peak_near_0_hz_is_read_in_a_zone_of_its_own():
    """--frequencies 3,45,160 on the case above gave 3.02 Hz at 8.4 +- 1.9 % from a chain
    over 2 orders, said to fail a selection rule, for 3 %."""
    fn, zeta, amp = np.array([3.0, 45.0, 160.0]), np.array([0.03, 0.01, 0.01]), np.array([1.0, 1.0, 1.0])
    force, response = impact_hits(fn, zeta, amp, 2048.0, 4.0, 5, 0.01, 1.5e-3, 0)
    options = AnalysisOptions(frequencies_hz=(3.0, 45.0, 160.0))
    result = analyze_hits(force, response, 2048.0, np.ones(5, bool), UNIFORM, UNIFORM, options=options)
    mode = min(result.modes, key=lambda m: abs(m.frequency_hz - 3.0))
    assert mode.quality["accepted"]
    assert abs(mode.damping_ratio - 0.03) <= 2 * mode.damping_u
    assert mode.damping_u < 0.15 * 0.03
