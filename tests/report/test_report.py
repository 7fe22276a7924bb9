"""`daq report`: PNG figures and one self-contained HTML page per run."""

from __future__ import annotations

import html
import json
import os
import re
import zlib
from html.parser import HTMLParser
from types import SimpleNamespace

import numpy as np
import pytest

from analysis.measurement_text import with_uncertainty
from daq.store import MeasuredFrf, Store, seal
from tests.cli_helpers import assert_one_line_error, invoke_daq, run_daq
from tests.store.store_helpers import make_run

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def test_report_of_a_captured_run(tmp_path):
    store = tmp_path / "store"
    result = invoke_daq(
        "capture", "--sim", "--yes", "--hits", "3", "--time-scale", "0",
        "--hammer", "double_hit_probability=0.4", "--seed", "7",
        "--operator", "<script>alert(1)</script>", "--store", str(store),
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    (run,) = Store(store).list()
    assert invoke_daq("fit", run.run_id, "--store", str(store)).returncode == 0
    out = tmp_path / "report"
    result = invoke_daq("report", run.run_id, "-o", str(out), "--store", str(store))
    assert result.returncode == 0, result.stderr
    page = (out / "index.html").read_text()
    for name in ("hits", "frf", "stability", "synthesis", "response_fit"):
        png = (out / f"{name}.png").read_bytes()
        assert png.startswith(PNG_SIGNATURE)
        assert len(png) > 10_000  # a drawn figure, not an empty canvas
    # Self-contained: every image is embedded, nothing is fetched.
    # The four analysis figures, the measured and model response of the stored damping
    # fit, and its convergence; and a quality figure per hit (the first 3 at least).
    quality = list(out.glob("hit_quality_*.png"))
    assert len(quality) >= min(run.n_hits, 3)
    assert len(re.findall(r'src="data:image/png;base64,', page)) == 6 + len(quality)
    assert "Damping matrix" in page
    assert not re.search(r'(src|href)="(https?:|//)', page)
    assert "<script>" not in page
    assert "&lt;script&gt;alert(1)&lt;/script&gt;" in page
    assert "Table 2" in page
    if run.n_accepted < run.n_hits:
        assert "rejected: " in page


def test_report_of_an_frf_only_run_has_no_hits_figure(tmp_path):
    f = np.linspace(0, 100, 401)
    w = 2 * np.pi * f
    wn = 2 * np.pi * 30.0
    h = -(w**2) / (wn**2 - w**2 + 2j * 0.02 * wn * w)
    run = make_run(kind="imported", measured=MeasuredFrf(f, h[np.newaxis, :], None, ["H"]))
    seal(run, tmp_path)
    result = invoke_daq("report", run.run_id, "-o", str(tmp_path / "r"), "--store", str(tmp_path))
    assert result.returncode == 0, result.stderr
    assert not (tmp_path / "r" / "hits.png").exists()
    assert not (tmp_path / "r" / "response_fit.png").exists()  # no time records to overlay
    page = (tmp_path / "r" / "index.html").read_text()
    assert "Analysed with default options (one frequency zone, LSCF order 30)." in page
    # FRF, stability, synthesis; no damping fit is made behind the user's back: the page
    # says how to make one.
    assert page.count("data:image/png;base64,") == 3
    assert "No damping fit is stored" in page
    assert not list(tmp_path.glob("*.fit-*.h5"))
    # Once fitted, the fit and its cautions are on the page (30 Hz is no mode of the beam).
    assert invoke_daq("fit", run.run_id, "--store", str(tmp_path)).returncode == 0
    result = invoke_daq("report", run.run_id, "-o", str(tmp_path / "r"), "--force", "--store", str(tmp_path))
    page = (tmp_path / "r" / "index.html").read_text()
    assert "Damping matrix" in page
    assert "caution: a poor fit" in page


def test_report_draws_the_stored_analysis_with_its_options_and_flags_a_stale_fit(tmp_path):
    f = np.linspace(0, 200, 801)
    w = 2 * np.pi * f
    h = sum(-(w**2) / ((2 * np.pi * r) ** 2 - w**2 + 2j * 0.01 * 2 * np.pi * r * w) for r in (40.0, 120.0))
    run = make_run(kind="imported", measured=MeasuredFrf(f, h[np.newaxis, :], None, ["H"]))
    seal(run, tmp_path)
    fit = ("fit", run.run_id, "--stiffness", "none", "--store", str(tmp_path))  # 40 Hz is no mode of the beam
    assert invoke_daq(*fit).returncode == 0
    # Tuned after the fit: only the mode near 120 Hz asked for.
    tuned = invoke_daq("analyze", run.run_id, "--frequencies", "120", "--store", str(tmp_path))
    assert tuned.returncode == 0, tuned.stderr
    result = invoke_daq("report", run.run_id, "-o", str(tmp_path / "r"), "--store", str(tmp_path))
    assert result.returncode == 0, result.stderr
    page = (tmp_path / "r" / "index.html").read_text()
    stored = Store(tmp_path).read_result(run.run_id, "analysis")["summary"]
    assert stored["options"]["frequencies_hz"] == [120.0]  # not re-analysed with defaults
    assert len(stored["modes"]) == 1
    assert "caution: this fit was made from an earlier analysis" in page
    # The page says which options the stored analysis was made with (a new user's report
    # of an analysis made with --max-order 60 read as a default one).
    assert "Analysed with --frequencies 120 (one frequency zone, LSCF order 30)." in page
    # daq fit now fits the analysis the user made (one mode, one Ritz function).
    fitted = invoke_daq(*fit, "--json")
    assert fitted.returncode == 0, fitted.stderr
    assert json.loads(fitted.stdout)[0]["model"]["ritz_functions"] == 1


def test_report_of_an_unknown_run_is_one_line(tmp_path):
    assert_one_line_error(invoke_daq("report", "2031", "--store", str(tmp_path)), "no run matches")


# --- a report a lab can file: acquisition, cautions, zoom and residual, convergence, PDF

#: The setup the simulated run below is captured with: every value differs from the
#: default setup, so a table showing defaults would fail.
SETUP = """
span_hz = 200.0
averages = 3
trigger_source = "CH1"
trigger_level_eu = 0.8
trigger_slope = "POS"
pre_trigger_s = 0.05

[hammer]
window = "FORC"
sensitivity_v_per_eu = 0.00225
range_v = 0.02
force_width_s = 0.1
ac_coupled = false

[accelerometer]
window = "EXPO"
sensitivity_v_per_eu = 0.00102
range_v = 1.0
exp_decay_s = 0.5
ac_coupled = true
"""


class _Tables(HTMLParser):
    """Every table row of a page as the list of its cells' texts."""

    def __init__(self) -> None:
        super().__init__()
        self.rows: list[list[str]] = []
        self._cell: list[str] | None = None

    def handle_starttag(self, tag, attrs):
        if tag == "tr":
            self.rows.append([])
        elif tag in ("td", "th"):
            self._cell = []

    def handle_endtag(self, tag):
        if tag in ("td", "th") and self._cell is not None:
            self.rows[-1].append("".join(self._cell).strip())
            self._cell = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell.append(data)


def _rows(page: str) -> list[list[str]]:
    parser = _Tables()
    parser.feed(page)
    return parser.rows


def _pdf_lines(data: bytes) -> list[str]:
    """The text lines drawn in a PDF matplotlib wrote: each text object's strings joined
    (enough for ASCII; matplotlib's fonts turn fi/fl into ligature codes)."""
    lines = []
    # Each stream is inflated from its start to the end of its own zlib data: cutting it at
    # the next "endstream" fails when the compressed bytes end in CR or hold that word.
    for start in re.finditer(rb"stream\r?\n", data):
        try:
            content = zlib.decompressobj().decompress(memoryview(data)[start.end() :])
        except zlib.error:
            continue
        for block in re.findall(rb"BT(.*?)ET", content, re.S):
            parts = re.findall(rb"\(((?:\\.|[^\\)])*)\)", block)
            lines.append(b"".join(re.sub(rb"\\(.)", rb"\1", p) for p in parts).decode("latin-1"))
    return lines


@pytest.fixture(scope="module")
def filed(tmp_path_factory):
    """A simulated run captured with SETUP at the keyboard, hits 1 and 2 (double hits)
    accepted against their failed check, fitted, and its report written."""
    root = tmp_path_factory.mktemp("filed")
    store = root / "store"
    (root / "setup.toml").write_text(SETUP)
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("DAQ_CONFIG", str(root / "none"))
        mp.delenv("DAQ_RESOURCE", raising=False)
        result = run_daq(
            "capture", "--sim", "--setup", str(root / "setup.toml"), "--time-scale", "0", "--seed", "7",
            "--hammer", "double_hit_probability=0.4", "--store", str(store), input="a\na\na\n",
        )  # fmt: skip
    assert result.returncode == 0, result.stderr
    run = Store(store).open(Store(store).list()[0].run_id)
    checks = [{name: c["passed"] for name, c in hit.items()} for hit in run.hits.checks]
    assert run.hits.accepted.all()
    assert [c["double impact"] for c in checks] == [False, False, True]  # what the report must flag
    assert invoke_daq("fit", run.run_id, "--store", str(store)).returncode == 0
    out = root / "report"
    result = invoke_daq("report", run.run_id, "-o", str(out), "--store", str(store))
    assert result.returncode == 0, result.stderr
    assert "report.pdf" in result.stdout
    return SimpleNamespace(store=store, run=run, out=out, page=(out / "index.html").read_text())


def test_the_acquisition_section_holds_the_setup_the_run_was_captured_with(filed):
    rows: dict[str, list[str]] = {}
    for row in _rows(filed.page):  # the first row of each name (the channel table's, not the transducers')
        if row:
            rows.setdefault(row[0], row[1:])
    assert "<h2>Acquisition</h2>" in filed.page
    assert rows["span"] == ["200 Hz"]
    assert rows["lines"] == ["400"]  # the 35660A's own
    assert rows["resolution (span / lines)"] == ["0.5 Hz"]
    assert rows["record length (lines / span)"] == ["2 s"]
    assert rows["centre"][0].startswith("baseband")
    assert rows["averages"][0].startswith("3 hits")
    assert rows["trigger source"] == ["CH1 (hammer)"]
    assert rows["trigger level"] == ["0.8 N"]
    assert rows["trigger slope"] == ["rising (POS)"]
    assert rows["pre-trigger"] == ["50 ms"]
    hammer, accelerometer = rows["CH1 hammer (force)"], rows["CH2 accelerometer (response)"]
    # sensitivity, range, coupling, window with its parameter
    assert hammer[0] == "2.25 mV/N"
    # The 35660A's input ranges are steps of whole dBV: 0.02 V asked for is -33 dBV.
    assert hammer[1] == f"{10 ** (-33 / 20):.4g} V (= {10 ** (-33 / 20) / 0.00225:.4g} N full scale)"
    assert hammer[2] == "DC"
    assert hammer[3] == "force (FORC), width 100 ms from the record's start"
    assert accelerometer[0] == "1.02 mV/(m/s²) (= 10 mV/g)"
    assert accelerometer[1] == f"1 V (= {1 / 0.00102:.4g} m/s² full scale)"
    assert accelerometer[2] == "AC"
    assert accelerometer[3] == "exponential (EXPO), time constant 500 ms (decay 2 1/s)"
    assert rows["analyzer"] == ["HP 35660A"]
    assert rows["resource"][0].startswith("TCPIP::127.0.0.1::")
    # Transducers as far as the run records them: the sensitivity; model, serial and
    # calibration are not in a run yet and the table says so.
    transducers = [r for r in _rows(filed.page) if r[0].startswith("CH") and r[1] == "not recorded"]
    assert [r[3] for r in transducers] == ["2.25 mV/N", "1.02 mV/(m/s²) (= 10 mV/g)"]
    assert all(r[1:3] == ["not recorded", "not recorded"] for r in transducers)
    # Points, the record and the simulator, hits counted from 1.
    assert rows["force point"] == ["tip: 0.7 m from the clamp, +z"]
    assert rows["response point 1"] == ["tip: 0.7 m from the clamp, +z"]
    assert rows["modal test"] == ["none"]
    assert rows["first sample"] == ["-50 ms after the trigger (pre-trigger)"]
    assert rows["sample rate"] == ["512 Hz"]
    assert rows["simulator seed"] == ["7"]
    assert rows["hits"] == ["3 (3 accepted), counted from 1"]


def test_the_cautions_name_the_hits_accepted_against_a_failed_check(filed):
    page = filed.page
    start, end = page.index("<h2>Cautions</h2>"), page.index("<h2>Acquisition</h2>")
    block = page[start:end]
    assert "caution: hit 1 was accepted although its check failed (double impact: " in block
    assert "caution: hit 2 was accepted although its check failed (double impact: " in block
    assert "hit 3 was accepted" not in block
    fit = Store(filed.store).read_result(filed.run.run_id, "fit-ls")["summary"]
    for text in fit["cautions"]:  # the fit's own, in the same block
        assert f"caution: {html.escape(text, quote=True)}" in block
    verdicts = [r[3] for r in _rows(page) if len(r) == 4 and r[0] in ("1", "2", "3")]
    assert verdicts[:3] == [
        "accepted against failed check: double impact",
        "accepted against failed check: double impact",
        "accepted",
    ]


def test_the_response_fit_has_a_zoom_on_the_first_decay_and_the_residual(filed):
    from daq.report import figures

    fit = Store(filed.store).read_result(filed.run.run_id, "fit-ls")
    data = figures.response_fit_data(filed.run, fit)
    k = int(fit["hit_index"][0])
    np.testing.assert_array_equal(data["residual"], filed.run.hits.response_m_s2[k] - fit["model_response"])
    assert data["hit"] == k + 1
    start, end = data["zoom_s"]
    t = filed.run.hits.time_s()
    assert start == t[0] == -0.05
    # The first decay: at most a fifth of the 2 s record, at most 3 periods of mode 1.
    f1 = fit["summary"]["modes"][0]["frequency_hz"]
    assert 0 < end <= min(t[0] + 0.2 * 2.0, 3 / f1) + 1e-12
    fig = figures.draw_response_fit(filed.run, fit)
    try:
        axes = fig.axes
        assert len(axes) == 4  # whole record and zoom, each over its residual
        assert [ax.get_ylabel() for ax in axes] == [
            "tip acceleration (m/s²)", "tip acceleration (m/s²)", "residual (m/s²)", "residual (m/s²)",
        ]  # fmt: skip
        assert axes[1].get_xlim() == pytest.approx((1e3 * start, 1e3 * end))
        assert axes[0].get_xlim()[1] > 1e3 * 1.9  # the whole record
        assert [ax.get_title(loc="left") for ax in axes[:2]] == ["whole record", "first decay (zoom)"]
    finally:
        figures._pyplot().close(fig)
    assert (filed.out / "response_fit.png").read_bytes().startswith(PNG_SIGNATURE)


def _fit(method: str, history, domain: str = "time") -> dict:
    return {
        "history": np.asarray(history),
        "summary": {"method": method, "domain": domain, "psi": history[-1]},
    }


def test_convergence_has_whole_iterations_psi_in_its_unit_and_log_when_it_spans_decades(filed):
    from daq.report import figures

    fits = {
        "fit-ls": Store(filed.store).read_result(filed.run.run_id, "fit-ls"),
        "fit-ga": _fit("ga", np.geomspace(3.0, 0.02, 7)),  # few points: ticks would be fractional
        "fit-frequency": _fit("de", [0.05, 0.04, 0.04], "frequency"),
    }
    fig = figures.draw_convergence(fits)
    try:
        ls, ga, frequency = fig.axes
        for ax in (ls, ga, frequency):
            ticks = ax.get_xticks()
            assert len(ticks) >= 2
            np.testing.assert_array_equal(ticks, np.round(ticks))
        # Psi of eq 17 has the unit of what it compares: the response, or the accelerance.
        assert ls.get_ylabel() == "Psi (m/s²)"
        assert ga.get_ylabel() == "Psi (m/s²)"
        assert frequency.get_ylabel() == "Psi ((m/s²)/N)"
        assert ga.get_yscale() == "log"  # 3 -> 0.02: two decades
        assert frequency.get_yscale() == "linear"
        assert ga.get_xlabel() == "generation, from 1"
    finally:
        figures._pyplot().close(fig)


def test_the_pdf_holds_the_same_sections_and_every_figure(filed):
    pdf = (filed.out / "report.pdf").read_bytes()
    assert pdf.startswith(b"%PDF")
    pages = len(re.findall(rb"/Type\s*/Page(?!s)", pdf))
    figure_names = ("hits", "frf", "stability", "synthesis", "response_fit", "convergence")
    assert all((filed.out / f"{name}.png").exists() for name in figure_names)
    assert pages >= 2 + len(figure_names)  # text pages, then a page per figure
    text = "\n".join(_pdf_lines(pdf))
    for heading in ("Cautions", "Acquisition", "Hits", "Modes", "Table 2", "Damping matrix"):
        assert f"\n{heading}\n" in text, heading
    for pattern in (
        r"span\s+200 Hz", r"trigger level\s+0.8 N", r"pre-trigger\s+50 ms", r"force \(FORC\), width 100",
        r"time constant 500 ms", r"CH1 hammer \(force\)\s+not recorded\s+not recorded\s+2.25 mV/N",
        r"caution: hit 1 was accepted although its check failed \(double impact",
    ):  # fmt: skip
        assert re.search(pattern, text), pattern
    assert not list(filed.out.glob(".*tmp*"))  # nothing left of the atomic writes


def test_a_report_that_cannot_be_written_whole_leaves_no_pdf_and_no_page(tmp_path, monkeypatch):
    f = np.linspace(0, 100, 401)
    w = 2 * np.pi * f
    h = -(w**2) / ((2 * np.pi * 30.0) ** 2 - w**2 + 2j * 0.02 * 2 * np.pi * 30.0 * w)
    run = make_run(kind="imported", measured=MeasuredFrf(f, h[np.newaxis, :], None, ["H"]))
    seal(run, tmp_path)
    real_replace = os.replace

    def replace(src, dst):
        if str(dst).endswith("report.pdf"):
            raise OSError(28, "No space left on device")
        return real_replace(src, dst)

    monkeypatch.setattr("daq.cli.commands.report.os.replace", replace)
    out = tmp_path / "r"
    assert_one_line_error(
        invoke_daq("report", run.run_id, "-o", str(out), "--store", str(tmp_path)),
        "cannot write",
        "report.pdf",
    )
    assert not (out / "report.pdf").exists()
    assert not (out / "index.html").exists()  # the page marks a whole report: not written
    assert not list(out.glob(".*tmp*"))


def test_the_fits_modes_are_numbered_as_the_analysis_numbers_them_beside_its_reading(filed):
    fit = Store(filed.store).read_result(filed.run.run_id, "fit-ls")["summary"]
    partners = [m["identified"] for m in fit["modes"]]
    rows = [r for r in _rows(filed.page) if len(r) == 4 and r[0] in {str(p["mode"]) for p in partners}]
    header = "<th>damping with R (%)</th><th>analysis (%)</th>"
    assert header in filed.page.replace("\n", "")
    for partner in partners:
        value, u = with_uncertainty(100 * partner["damping_ratio"], 100 * partner["damping_u"])
        (row,) = [r for r in rows if r[0] == str(partner["mode"]) and r[3] == f"{value} ± {u}"]
        assert float(row[2]) == pytest.approx(
            100 * next(m["damping_ratio"] for m in fit["modes"] if m["identified"] == partner), rel=0.01
        )
