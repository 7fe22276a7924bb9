"""`daq report`: PNG figures and one self-contained HTML page per run."""

from __future__ import annotations

import json
import re

import numpy as np

from daq.store import MeasuredFrf, Store, seal
from tests.cli_helpers import assert_one_line_error, invoke_daq
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
    # fit, and its convergence.
    assert len(re.findall(r'src="data:image/png;base64,', page)) == 6
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
    # daq fit now fits the analysis the user made (one mode, one Ritz function).
    fitted = invoke_daq(*fit, "--json")
    assert fitted.returncode == 0, fitted.stderr
    assert json.loads(fitted.stdout)[0]["model"]["ritz_functions"] == 1


def test_report_of_an_unknown_run_is_one_line(tmp_path):
    assert_one_line_error(invoke_daq("report", "2031", "--store", str(tmp_path)), "no run matches")
