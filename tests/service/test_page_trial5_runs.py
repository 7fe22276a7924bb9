"""The runs page says what the command line says: each mode's value and ± written as
`daq analyze` writes them, the band to four digits, results stored from the command line
before the service started shown at once, only the exports a run can give, and a failed
fit as "failed" with its reason. The real `daq serve` and, for the page, a real Chromium
(tests/service/test_service_browser.py)."""

from __future__ import annotations

import re
from pathlib import Path

import httpx
import pytest

from daq.service.texts import band_text, damping_text, frequency_text, psi_text
from tests.cli_helpers import capture_sim, invoke_daq
from tests.service.service_helpers import import_noise_frf, serving, wait_for
from tests.service.test_service_browser import CHROMIUM, browser_page  # noqa: F401 (a fixture)

MODE_LINE = re.compile(r"^  mode \d+: (\S+) Hz(?: ± (\S+) Hz)?, damping (\S+) %(?: ± (\S+) %)?;", re.M)
BAND_LINE = re.compile(r"^  band (.+)$", re.M)


def terminal_modes(text: str) -> tuple[list[str], list[str]]:
    """('3896 ± 12', ...), ('2.18 ± 0.89', ...) of `daq analyze`'s mode lines, units left out
    (the page's column heads carry them)."""
    freqs, damps = [], []
    for f, fu, z, zu in MODE_LINE.findall(text):
        freqs.append(f"{f} ± {fu}" if fu else f)
        damps.append(f"{z} ± {zu}" if zu else z)
    return freqs, damps


def test_the_texts_round_as_the_terminal_does():
    # The finding's numbers: u to two significant digits, the value to its decimal place.
    assert frequency_text({"frequency_hz": 3896.14, "frequency_u_hz": 12.2}) == "3896 ± 12"
    assert frequency_text({"frequency_hz": 810.3031, "frequency_u_hz": 0.0161}) == "810.303 ± 0.016"
    assert frequency_text({"frequency_hz": 12.5, "frequency_u_hz": None}) == "12.5000"
    assert damping_text({"damping_ratio": 0.000347, "damping_u": 0.0000401}) == "0.0347 ± 0.0040"
    assert damping_text({"damping_ratio": 0.0218, "damping_u": 0.0089}) == "2.18 ± 0.89"
    assert damping_text({"damping_ratio": 0.01234, "damping_u": None}) == "1.23"
    assert damping_text({"damping_ratio": None}) == "n/a"
    band = {"low_hz": 1.0882, "high_hz": 399.371, "reason": "why"}
    assert band_text(band) == "band 1.088–399.4 Hz: why"
    assert psi_text({"psi": 0.38751, "domain": "time"}) == "0.3875 m/s²"
    assert psi_text({"psi": 0.38751, "domain": "frequency"}) == "0.3875 (m/s²)/N"


@pytest.mark.slow
def test_stored_results_show_at_once_and_bad_methods_get_405(tmp_path):
    """A run analysed from the command line before the service started is "done" with its
    numbers at the service's first answer, not "queued" with none (the fit still to do)."""
    store = tmp_path / "store"
    run_id = capture_sim(store, "realistic", 3, hits=3)
    analyzed = invoke_daq("analyze", run_id, "--store", str(store))
    assert analyzed.returncode == 0, analyzed.stderr
    frf_only = import_noise_frf(tmp_path, store)
    with serving(tmp_path, "--sim", "--workers", "1", store=store) as served:
        (row,) = [r for r in served.get("/api/runs").json() if r["run_id"] == run_id]
        assert row["analysis"] == "done", row
        assert row["frequencies_text"] == terminal_modes(analyzed.stdout)[0]
        assert row["cautions"] is not None
        assert row["exports"] == ["csv", "uff"]
        (other,) = [r for r in served.get("/api/runs").json() if r["run_id"] == frf_only]
        assert other["exports"] == ["uff"]  # an FRF has no time records to write as CSV

        # A method no route answers is 405 with or without the token; an existing one
        # without it is still 401.
        with httpx.Client(base_url=served.url, timeout=30) as bare:
            assert bare.delete("/api/runs/latest").status_code == 405
            assert bare.post("/api/runs").status_code == 405
            assert bare.post("/api/capture/stop").status_code == 401
        with served.client() as client:
            assert client.delete("/api/runs/latest").status_code == 405
        # No answer names the server's folders.
        health = served.get("/api/health")
        assert str(store) not in health.text
        assert "store" not in health.json()


@pytest.mark.slow
@pytest.mark.skipif(CHROMIUM is None, reason="no Chromium")
def test_the_runs_page_prints_what_daq_analyze_prints(tmp_path, browser_page):  # noqa: F811
    page, errors, outside = browser_page
    store = tmp_path / "store"
    run_id = capture_sim(store, "realistic", 5, hits=3)
    frf_only = import_noise_frf(tmp_path, store)
    with serving(tmp_path, "--sim", "--workers", "1", store=store) as served:
        page.goto(f"{served.url}/runs")
        row = page.locator(f'#runs-table tr[data-run-id="{run_id}"]')
        row.wait_for()
        page.wait_for_function(
            "(id) => document.querySelector(`#runs-table tr[data-run-id='${id}'] .analysis-state`)"
            ".textContent.trim() === 'done'",
            arg=run_id,
            timeout=120_000,
        )
        # The service's analysis is the one `daq analyze` now reads from the store (cached).
        analyzed = invoke_daq("analyze", run_id, "--store", str(store))
        assert analyzed.returncode == 0, analyzed.stderr
        assert "(cached)" in analyzed.stdout.splitlines()[0]
        freqs, damps = terminal_modes(analyzed.stdout)
        assert freqs
        assert all(" ± " in f for f in freqs)
        assert row.locator(".frequencies").inner_text().strip() == ", ".join(freqs[:3])
        assert row.locator(".damping").inner_text().strip() == ", ".join(damps[:3])
        band = BAND_LINE.search(analyzed.stdout).group(1)
        notes = page.locator(f'#runs-table tr[data-notes-for="{run_id}"]')
        facts = notes.locator(".run-facts").inner_text()
        assert facts.replace("–", "-").startswith(f"band {band}"), (facts, band)

        # The run of FRFs only offers no CSV, which it cannot give; the captured one does.
        other = page.locator(f'#runs-table tr[data-run-id="{frf_only}"]')
        assert other.locator("a", has_text="CSV").count() == 0
        assert other.locator("a", has_text="UFF").count() == 1
        assert row.locator("a", has_text="CSV").count() == 1

        # Psi with its unit once the fit is done; a failed fit says "failed" and why.
        wait_for(
            lambda: all(
                r["fit"] in ("done", "failed")
                for r in served.get("/api/runs").json()
                if r["run_id"] in (run_id, frf_only)
            ),
            300,
            "the fits",
        )
        page.reload()
        listing = {r["run_id"]: r for r in served.get("/api/runs").json()}
        for rid in (run_id, frf_only):
            r = listing[rid]
            psi = page.locator(f'#runs-table tr[data-run-id="{rid}"] .psi').inner_text().strip()
            if r["fit"] == "done":
                assert psi.endswith("m/s²") or psi.endswith("(m/s²)/N"), psi
            else:
                assert psi == "failed"
                assert r["fit_error"]
                line = page.locator(f'#runs-table tr[data-notes-for="{rid}"] .stage-failed').inner_text()
                assert line == f"fit failed: {r['fit_error']}"
    assert errors == []
    assert outside == []


def test_a_failed_fit_is_listed_with_its_reason(tmp_path):
    from types import SimpleNamespace

    from daq.service.app import _run_row
    from daq.store import Store

    store = tmp_path / "store"
    import_noise_frf(tmp_path, store)
    (summary,) = Store(store).list()
    service = SimpleNamespace(
        jobs=SimpleNamespace(
            state=lambda rid: {"analysis": "done", "fit": "failed"},
            error=lambda rid, stage: (
                "the run's modes do not look like this beam's" if stage == "fit" else None
            ),
            current=lambda rid, stage: False,
        ),
        analysis=lambda rid: None,
        default_fit=lambda rid: None,
        public=str,
    )
    row = _run_row(service, summary)
    assert row["fit"] == "failed"
    assert row["fit_error"] == "the run's modes do not look like this beam's"
    assert row["analysis_error"] is None
    assert row["exports"] == ["uff"]


def test_the_page_files_say_what_the_terminal_says():
    static = Path(__file__).parents[2] / "daq" / "service" / "static"
    index = (static / "index.html").read_text()
    assert "value ± standard deviation" not in index
    assert "the Fisher (Cramér-Rao) std" in index
