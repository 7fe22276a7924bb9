"""The report of a run captured at the test station (issue 24): the named setup and
its version, the transducers (model, serial, sensitivity, calibration, overdue), the
cautions the capture stored, a hit accepted against a failed check marked in the hits
table and the cautions, and a quality figure per hit (the first 3 and every marked
hit), in the HTML page and in the PDF alike."""

from __future__ import annotations

import re
from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest

from daq.report import figures
from daq.report.build import build_report_files
from daq.store import Store, new_run_id, seal
from tests.cli_helpers import invoke_daq
from tests.report.test_report import _pdf_lines, _rows

HAMMER = {
    "id": "h-12", "kind": "hammer", "model": "PCB 086C03", "serial": "SN-4711", "sensitivity": 2.25,
    "sensitivity_unit": "mV/N", "sensitivity_v_per_eu": 0.00225, "calibration_date": "2025-01-10",
    "due_date": "2026-01-01", "overdue": True,
}  # fmt: skip
ACCEL = {
    "id": "a-3", "kind": "accelerometer", "model": "PCB 352C33", "serial": "LW-0815", "sensitivity": 10.0,
    "sensitivity_unit": "mV/g", "sensitivity_v_per_eu": 0.0010197, "calibration_date": "2026-06-01",
    "due_date": "2027-06-01", "overdue": False,
}  # fmt: skip
AUTO_RANGE = {
    "practice_hits": 2, "peaks_force_n": [5.62, 4.73], "hammer_range_v": 0.0199526,
    "accelerometer_range_v": 0.794328, "trigger_level_eu": 0.473,
    "setup": {"hammer_range_v": 0.02, "accelerometer_range_v": None, "trigger_level_eu": 1.0},
}  # fmt: skip
CAUTION = "caution: hammer transducer h-12 calibration was due 2026-01-01"
N_HITS = 8
MARKED = 7  # 0-based: hit 8, accepted although its double-impact check failed


@pytest.fixture(scope="module")
def station(tmp_path_factory):
    """A simulated capture of 8 clean hits, stored again as a station run: transducers in
    the settings, the setup and the capture's caution in the provenance, hit 8's
    double-impact check failed though it was accepted; its report built in process."""
    root = tmp_path_factory.mktemp("station")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("DAQ_CONFIG", str(root / "none"))
        mp.delenv("DAQ_RESOURCE", raising=False)
        result = invoke_daq(
            "capture", "--sim", "--yes", "--hits", str(N_HITS), "--time-scale", "0", "--seed", "3",
            "--hammer", "double_hit_probability=0", "--store", str(root / "captured"),
        )  # fmt: skip
    assert result.returncode == 0, result.stderr
    captured = Store(root / "captured")
    run = captured.open(captured.list()[0].run_id)
    assert run.hits.n_hits == N_HITS
    assert run.hits.accepted.all()
    settings = dict(run.instrument.settings)
    settings["hammer"] = {**settings["hammer"], "transducer": HAMMER}
    settings["accelerometer"] = {**settings["accelerometer"], "transducer": ACCEL}
    checks = [dict(c) for c in run.hits.checks]
    checks[MARKED]["double impact"] = {
        "passed": False,
        "detail": "second pulse at 31 % of the peak",
        "value": 0.31,
    }
    station_run = replace(
        run,
        run_id=new_run_id(),
        instrument=replace(run.instrument, settings=settings),
        provenance={
            **run.provenance,
            "setup": {"name": "beam-A", "version": 3},
            "cautions": [CAUTION],
            "auto_range": AUTO_RANGE,
        },
        hits=replace(run.hits, checks=checks),
    )
    store = root / "store"
    seal(station_run, store)
    files = build_report_files(store, station_run.run_id)
    text = "\n".join(_pdf_lines(files.pdf))
    return SimpleNamespace(run=station_run, files=files, page=files.html, pdf_text=text)


def test_the_page_names_the_setup_and_the_transducers(station):
    rows = {row[0]: row[1:] for row in _rows(station.page) if row}
    assert rows["setup"] == ["beam-A, version 3"]
    transducers = [r for r in _rows(station.page) if r and r[0].startswith("CH") and len(r) == 6]
    transducers = [r for r in transducers if "(" in r[1] and r[2].startswith(("SN", "LW"))]
    assert transducers == [
        ["CH1 hammer (force)", "PCB 086C03 (h-12)", "SN-4711", "2.25 mV/N", "2025-01-10",
         "2026-01-01 OVERDUE"],
        ["CH2 accelerometer (response)", "PCB 352C33 (a-3)", "LW-0815", "1.02 mV/(m/s²) (= 10 mV/g)",
         "2026-06-01", "2027-06-01"],
    ]  # fmt: skip
    assert '<tr class="caution"><td>CH1 hammer (force)</td><td>PCB 086C03 (h-12)' in station.page
    # The setup and cautions are shown as such, not again as raw provenance.
    first_cells = [r[0] for r in _rows(station.page) if r]
    assert first_cells.count("setup") == 1
    assert "cautions" not in first_cells


def test_the_cautions_hold_the_capture_caution_and_the_marked_hit(station):
    page = station.page
    block = page[page.index("<h2>Cautions</h2>") : page.index("<h2>Acquisition</h2>")]
    assert "From the capture (its setup and transducers):" in block
    assert "caution: hammer transducer h-12 calibration was due 2026-01-01" in block
    assert "caution: caution:" not in block
    assert (
        f"caution: hit {MARKED + 1} was accepted although its check failed (double impact: second pulse"
        in block
    )
    assert sum(f"caution: hit {k} was" in block for k in range(1, N_HITS + 1)) == 1
    verdicts = [r[3] for r in _rows(page) if len(r) == 4 and r[0].isdigit()][:N_HITS]
    assert verdicts == ["accepted"] * MARKED + ["accepted against failed check: double impact"]
    assert (
        f"<tr class=\"caution\"><td class='num'>{MARKED + 1}</td>" in page
    )  # the marked row of the hits table


def test_a_quality_figure_for_the_first_three_hits_and_every_marked_one(station):
    assert figures.quality_indices(station.run) == [0, 1, 2, MARKED]
    names = sorted(name for name in station.files.pngs if name.startswith("hit_quality_"))
    assert names == sorted(f"hit_quality_{k}" for k in (1, 2, 3, MARKED + 1))
    page = station.page
    assert "<h2>Hit quality</h2>" in page
    assert "Drawn: hits 1-3, 8 (the first 3 and every hit accepted against a failed check, " in page
    assert "not drawn: hits 4-7, listed in the Hits table." in page
    assert f'alt="hit {MARKED + 1}: accepted against failed check: double impact"' in page


def test_the_quality_figure_draws_the_windows_the_rolloff_limit_and_the_average(station):
    run = station.run
    views, average = figures.hit_quality_views(run, [0])
    assert average["n_averaged"] == N_HITS  # every accepted hit
    fig = figures.draw_hit_quality(run, 0, views[0], average, "accepted")
    try:
        pulse, response, spectrum, magnitude, phase, coherence = fig.axes
        # The force window over the pulse, scaled to its peak; the pulse zoomed.
        force = run.hits.force_n[0]
        window_line = pulse.get_lines()[1]
        np.testing.assert_allclose(window_line.get_ydata(), np.max(np.abs(force)) * views[0]["force_window"])
        lo, hi = pulse.get_xlim()
        t_ms = 1e3 * run.hits.time_s()
        assert t_ms[0] <= lo < hi <= t_ms[-1]
        assert hi - lo < 0.5 * (t_ms[-1] - t_ms[0])
        assert lo < t_ms[int(np.argmax(force))] < hi
        # The exponential window over the response.
        assert views[0]["response_window"][-1] < 0.1 < views[0]["response_window"][0] + 1
        np.testing.assert_allclose(
            response.get_lines()[1].get_ydata(),
            np.max(np.abs(run.hits.response_m_s2[0])) * views[0]["response_window"],
        )
        # The roll-off limit: -10 dB from the top band's lower edge to the span's top.
        (limit,) = spectrum.collections[:1]
        segments = limit.get_segments()
        assert segments[0][0][1] == segments[0][1][1] == -10.0
        assert segments[0][0][0] == pytest.approx(views[0]["force_spectrum"]["rolloff_hz"])
        assert spectrum.get_ylabel() == "dB re low band"
        # This hit over the average; the average's coherence.
        assert [line.get_label() for line in magnitude.get_lines()] == [
            "hit 1",
            f"average of {N_HITS} accepted",
        ]
        assert len(phase.get_lines()) == 2
        np.testing.assert_array_equal(coherence.get_lines()[0].get_ydata(), average["coherence"])
        assert fig._suptitle.get_text().startswith(f"Run {run.run_id}, hit 1 of {N_HITS}")
    finally:
        figures._pyplot().close(fig)


def test_the_pdf_holds_the_same(station):
    text = station.pdf_text
    assert station.files.pdf.startswith(b"%PDF")
    for heading in ("Cautions", "Acquisition", "Hits", "Hit quality"):
        assert f"\n{heading}\n" in text, heading
    for pattern in (
        r"setup\s+beam-A, version 3",
        r"CH1 hammer \(force\)\s+PCB 086C03 \(h-12\)\s+SN-4711\s+2.25 mV/N\s+2025-01-10\s+2026-01-01 OVERDUE",
        r"CH2 accelerometer\s+PCB 352C33 \(a-3\)\s+LW-0815",  # "(response)" wraps under it
        r"caution: hammer transducer h-12 calibration was due 2026-01-01",
        rf"caution: hit {MARKED + 1} was accepted although its check failed \(double impact",
        rf"\n *{MARKED + 1}\s+\S+\s+[0-9.]+\s+accepted against failed check: double impact",
        r"Drawn: hits 1-3, 8",
    ):
        assert re.search(pattern, text), pattern
    # Every quality figure is a page of its own: text pages plus one page per figure.
    pages = len(re.findall(rb"/Type\s*/Page(?!s)", station.files.pdf))
    assert pages >= 2 + len(station.files.pngs)


def test_the_acquisition_says_what_the_practice_hits_chose(station):
    rows = {row[0]: row[1:] for row in _rows(station.page) if row}
    assert rows["auto-range"] == [
        "2 practice hits: hammer range 0.01995 V, accelerometer range 0.7943 V, trigger 0.473 N; "
        "the setup's own values were hammer range 0.02 V, accelerometer range auto, trigger 1 N"
    ]
    first_cells = [r[0] for r in _rows(station.page) if r]
    assert "auto range" not in first_cells  # not again as raw provenance
    assert "auto-range" in station.pdf_text
