"""The band-edge caution says what to do only where something can be done: a band that
already reaches the run's first (or last) line cannot be widened (a new user, given
--band 0:100000 on a LabVIEW record, was told to widen it)."""

from __future__ import annotations

import numpy as np

from analysis.run_analysis import AnalysisOptions, analyze_frfs


def _accelerance(f_hz: np.ndarray, modes: list[tuple[float, float]]) -> np.ndarray:
    """(1, n_lines) accelerance of unit-residue modes (frequency Hz, damping ratio)."""
    w = 2 * np.pi * f_hz
    h = sum(-(w**2) / ((2 * np.pi * fn) ** 2 - w**2 + 2j * z * (2 * np.pi * fn) * w) for fn, z in modes)
    return np.atleast_2d(h)


def _edge_cautions(band_hz: tuple[float, float], first: tuple[float, float] = (6.0, 0.02)) -> list[str]:
    f = np.arange(1, 1601) * 0.25  # 0.25-400 Hz
    h = _accelerance(f, [first, (80.0, 0.01), (210.0, 0.01)])
    result = analyze_frfs(f, h, None, "measured_frf", AnalysisOptions(band_hz=band_hz))
    found = [m.frequency_hz for m in result.modes]
    assert any(abs(m - first[0]) < 0.1 for m in found), found
    return [c for c in result.cautions if "lies at an edge of the band" in c]


def test_a_band_inside_the_lines_is_to_be_widened():
    (caution,) = _edge_cautions((3.0, 300.0))
    assert caution.endswith("it may stand for modes outside; widen the band to check it")


def test_a_mode_far_above_a_low_edge_near_0_hz_is_no_edge_mode():
    """2 % of a wide band's width reached 209 Hz above its 36.5 Hz edge: a new user's
    150 Hz mode was told it lay at an edge. At the low edge the margin is no wider than
    twice the edge's distance from 0 Hz."""
    f = np.arange(1, 8001) * 1.0
    h = _accelerance(f, [(150.0, 0.01), (1000.0, 0.01), (3000.0, 0.01)])
    result = analyze_frfs(f, h, None, "measured_frf", AnalysisOptions(band_hz=(36.5, 7900.0)))
    assert any(abs(m.frequency_hz - 150.0) < 0.5 for m in result.modes)
    assert not [c for c in result.cautions if "lies at an edge of the band" in c]
    lower = analyze_frfs(f, h, None, "measured_frf", AnalysisOptions(band_hz=(70.0, 7900.0)))
    (caution,) = [c for c in lower.cautions if "lies at an edge of the band" in c]
    assert caution.startswith("the mode at 150")


def test_a_band_at_the_first_line_cannot_be_widened():
    # 0.6 Hz, 0.35 Hz above the first line: within twice the edge's distance from 0 Hz.
    (caution,) = _edge_cautions((0.0, 300.0), first=(0.6, 0.2))
    assert "widen" not in caution
    assert "outside the run's lines, which these data cannot show (they begin at 0.25 Hz)" in caution


def test_a_frequency_asked_for_beyond_the_chosen_band_gets_the_band_that_takes_it_in():
    """A force that falls 20 dB by 1.3 kHz, in a run whose lines reach 3.2 kHz: a new
    user's --frequencies beyond the chosen band was told only 'outside the analysed
    lines', with no word of --band. It now says the band was chosen from the data and
    which --band takes the frequency in; a frequency beyond the lines is told so."""
    import numpy as np
    import pytest

    from analysis.run_analysis import AnalysisOptions, analyze_hits
    from analysis.windows import WindowSpec
    from tests.analysis.impact_synth import impact_hits

    uniform = WindowSpec("uniform")
    force, response = impact_hits([120.0, 410.0], [0.01, 0.02], [1.0, 1.0], 8192.0, 0.5, 3, 0.01, 1e-3, 1)
    result = analyze_hits(force, response, 8192.0, np.ones(3, bool), uniform, uniform)
    assert result.band.high_hz < 3000.0 < result.frequency_hz[-1]
    said = (
        r"band analysed, .* chosen from the data; the run's lines span .*: give --band 12:3000 to take it in$"
    )
    with pytest.raises(ValueError, match=said):
        analyze_hits(force, response, 8192.0, np.ones(3, bool), uniform, uniform,
                     options=AnalysisOptions(frequencies_hz=(3000.0,)))  # fmt: skip
    with pytest.raises(ValueError, match=r"the run has no lines there \(they span 2-3200 Hz\)$"):
        analyze_hits(force, response, 8192.0, np.ones(3, bool), uniform, uniform,
                     options=AnalysisOptions(frequencies_hz=(5000.0,)))  # fmt: skip
