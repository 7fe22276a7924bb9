"""A multi-point test whose points were recorded without windows and with a long
pre-trigger: every point's hits are cut at their impacts, all to one length, as one
run's are (analysis.pretrigger), and the test says so in its text, JSON and report."""

from __future__ import annotations

import json

import numpy as np
import pytest

from analysis.run_analysis import AnalysisOptions
from daq.workflows import test_analysis as workflow
from tests.analysis.impact_synth import impact_hits
from tests.cli_helpers import invoke_daq

RATE_HZ = 1024.0
FN, ZETA = np.array([45.0, 120.0, 260.0]), np.array([0.015, 0.01, 0.008])
#: Each point's modal amplitudes (two points of a beam: the shapes differ).
AMPLITUDES = ([1.0, 0.7, 0.5], [0.6, -0.8, 0.4])


def daq_ok(*args: str):
    result = invoke_daq(*args)
    assert result.returncode == 0, result.stderr
    return result


def _write_hits(path, force, response) -> None:
    # Time starting over begins a new hit (docs/import-export.md).
    t = np.arange(force.shape[1]) / RATE_HZ
    rows = [
        f"{ti:.17g},{f:.17g},{r:.17g}"
        for fk, rk in zip(force, response, strict=True)
        for ti, f, r in zip(t, fk, rk, strict=True)
    ]
    path.write_text("time,force,response\n" + "\n".join(rows) + "\n")


@pytest.fixture(scope="module")
def pretriggered_test(tmp_path_factory):
    """Test "pre": two points, 3 hits each, 0.2 s of pre-trigger in 0.5 s records."""
    folder = tmp_path_factory.mktemp("pre")
    store = str(folder / "runs")
    daq_ok("test", "new", "pre", "--points", "p1=0.7,p2=0.5", "--store", store)
    for k, amp in enumerate(AMPLITUDES, start=1):
        force, response = impact_hits(FN, ZETA, amp, RATE_HZ, 0.5, 3, 0.02, 0.003, 40 + k, pretrigger_s=0.2)
        path = folder / f"p{k}.csv"
        _write_hits(path, force, response)
        daq_ok("import", str(path), "--test", "pre", "--point", f"p{k}", "--store", store)
    return folder / "runs"


def _mode_45(analysis):
    (mode,) = [m for m in analysis.result.modes if abs(m.frequency_hz - 45.0) < 1.0]
    return mode


def test_every_point_is_cut_at_its_impacts_and_the_damping_holds(pretriggered_test):
    analysis = workflow.analyze_test(pretriggered_test, "pre", AnalysisOptions())
    info = workflow.test_analysis_json(analysis)
    assert info["pretrigger_cut_s"] == pytest.approx(0.2, abs=0.005)
    assert info["record_after_cut_s"] == pytest.approx(0.3, abs=0.005)
    # The lines of the cut records: 1/0.3 Hz apart, one axis for both points.
    assert np.median(np.diff(analysis.data.frequency_hz)) == pytest.approx(1 / 0.3, rel=0.02)
    mode = _mode_45(analysis)
    assert abs(mode.damping_ratio - 0.015) <= 3 * mode.damping_u, (mode.damping_ratio, mode.damping_u)


def test_the_same_points_analysed_whole_were_biased(pretriggered_test, monkeypatch):
    """The test above can fail: with the screen switched off the 45 Hz damping reads
    over 15 % high (1.87 % for 1.5 %), where the cut reads it within 5 %."""
    cut = _mode_45(workflow.analyze_test(pretriggered_test, "pre", AnalysisOptions()))
    assert abs(cut.damping_ratio - 0.015) < 0.05 * 0.015, cut.damping_ratio
    monkeypatch.setattr("analysis.pretrigger.SCREEN_LIMIT", np.inf)
    analysis = workflow.analyze_test(pretriggered_test, "pre", AnalysisOptions())
    assert workflow.test_analysis_json(analysis)["pretrigger_cut_s"] == 0.0
    whole = _mode_45(analysis)
    assert whole.damping_ratio - 0.015 > 0.15 * 0.015, whole.damping_ratio


def test_the_cut_is_said_in_the_text_and_the_json(pretriggered_test):
    store = str(pretriggered_test)
    text = daq_ok("test", "analyze", "pre", "--store", store).stdout
    assert "every point's hits cut at their impacts: 0.199" in text
    info = json.loads(daq_ok("test", "analyze", "pre", "--json", "--store", store).stdout)
    assert info["pretrigger_cut_s"] > 0


def test_the_cut_is_said_in_the_report(pretriggered_test, tmp_path):
    folder = tmp_path / "report"
    daq_ok("test", "report", "pre", "-o", str(folder), "--store", str(pretriggered_test))
    (page,) = folder.glob("*.html")
    html = page.read_text()
    assert "<th>records</th><td>hits cut at their impacts: 0.199" in html
