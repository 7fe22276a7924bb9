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


def _edge_cautions(band_hz: tuple[float, float]) -> list[str]:
    f = np.arange(1, 1601) * 0.25  # 0.25-400 Hz
    h = _accelerance(f, [(6.0, 0.02), (80.0, 0.01), (210.0, 0.01)])
    result = analyze_frfs(f, h, None, "measured_frf", AnalysisOptions(band_hz=band_hz))
    assert any(abs(m.frequency_hz - 6.0) < 0.1 for m in result.modes), [m.frequency_hz for m in result.modes]
    return [c for c in result.cautions if "lies at an edge of the band" in c]


def test_a_band_inside_the_lines_is_to_be_widened():
    (caution,) = _edge_cautions((3.0, 300.0))
    assert caution.endswith("it may stand for modes outside; widen the band to check it")


def test_a_band_at_the_first_line_cannot_be_widened():
    (caution,) = _edge_cautions((0.0, 300.0))
    assert "widen" not in caution
    assert "outside the run's lines, which these data cannot show (they begin at 0.25 Hz)" in caution
