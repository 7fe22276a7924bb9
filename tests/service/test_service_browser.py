"""The live page in a real headless Chromium (Debian's, driven by Playwright): start
a capture, accept and reject hits by clicking, and see the run land with the right
flags and its results appear on the page; then the runs page.

Skipped, and said loudly at the end of the run (tests/conftest.py), where no
Chromium is installed; CI installs it (.ci/run).
"""

from __future__ import annotations

import os
import re
import shutil
from pathlib import Path

import pytest

from daq.store import Store
from tests.conftest import NO_BROWSER
from tests.service.service_helpers import import_noise_frf, serving, wait_for

CHROMIUM = os.environ.get("DAQ_CHROMIUM") or shutil.which("chromium") or shutil.which("chromium-browser")

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(CHROMIUM is None, reason=f"{NO_BROWSER} (apt-get install chromium)"),
]

#: What Chromium needs to start as root in a container with no network and no GPU.
CHROMIUM_ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-dev-shm-usage",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
]


@pytest.fixture
def browser_page(tmp_path: Path):
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        context = browser.new_context(viewport={"width": 1300, "height": 1000})
        page = context.new_page()
        errors: list[str] = []
        page.on("pageerror", lambda exc: errors.append(str(exc)))
        page.on("console", lambda msg: errors.append(msg.text) if msg.type == "error" else None)
        outside: list[str] = []
        local = "http://127.0.0.1"
        page.on("request", lambda r: None if r.url.startswith(local) else outside.append(r.url))
        page.set_default_timeout(60_000)
        yield page, errors, outside
        context.close()
        browser.close()


#: Table cells (and caution lines) whose right edge lies past the visible right edge of
#: their card or of a box that scrolls them sideways: what a reader does not see.
CUT_CELLS = """(cards) => {
  const cut = [];
  for (const card of document.querySelectorAll(cards)) {
    for (const cell of card.querySelectorAll('td, th, .caution')) {
      const box = cell.getBoundingClientRect();
      if (!box.width) continue;
      let right = card.getBoundingClientRect().right;
      for (let p = cell.parentElement; p && p !== card.parentElement; p = p.parentElement) {
        const style = getComputedStyle(p);
        if (style.overflowX !== 'visible') right = Math.min(right, p.getBoundingClientRect().right);
      }
      if (box.right > right + 0.5) cut.push(cell.textContent.trim().slice(0, 40));
    }
  }
  return cut;
}"""


def cut_cells(page, cards: str) -> list[str]:
    """What of the tables in ``cards`` lies beyond the visible right edge (nothing, at 1024 px)."""
    return page.evaluate(CUT_CELLS, cards)


def verdict(page, index: int) -> str:
    return page.locator(f'#hits-table tr[data-index="{index}"] .verdict').inner_text().strip()


def test_a_technician_captures_accepts_and_rejects_by_clicking(tmp_path, browser_page):
    page, errors, outside = browser_page
    with serving(tmp_path, "--sim", "--time-scale", "0.02") as served:
        page.goto(f"{served.url}/#token={served.token}")
        assert "#token" not in page.url  # the token leaves the address bar at once
        page.wait_for_function("() => document.querySelector('#capture-state').textContent.trim() === 'idle'")

        page.fill("#hits-wanted", "2")
        page.fill("#operator", "Grace")
        page.click("#start")
        plan = [(0, True, ""), (1, False, "glove slipped"), (2, True, "")]
        for index, accept, reason in plan:
            page.wait_for_selector(f'#hits-table tr[data-index="{index}"]')
            page.wait_for_function("() => !document.querySelector('#accept').disabled")
            assert page.locator("#pending-index").inner_text().strip() == f"Hit {index + 1}"
            assert page.locator("#checks li").count() == 4  # overload, double impact, roll-off, too weak
            if accept:
                page.click("#accept")
            else:
                page.fill("#reject-reason", reason)
                page.click("#reject")
            expected = "accepted" if accept else f"rejected: {reason}"
            page.wait_for_function(
                "([i, want]) => {"
                "const c = document.querySelector(`#hits-table tr[data-index='${i}'] .verdict`);"
                " return c && c.textContent.trim() === want;}",
                arg=[index, expected],
            )
        assert [verdict(page, i) for i in range(3)] == ["accepted", "rejected: glove slipped", "accepted"]

        # The run lands with the flags the clicks gave it.
        run_id = wait_for(lambda: served.get("/api/capture").json()["last_run_id"], 60, "the run")
        run = Store(served.store).open(run_id)
        assert run.complete
        assert run.operator == "Grace"
        assert run.hits.accepted.tolist() == [True, False, True]
        assert list(run.hits.reject_reason)[1] == "glove slipped"

        # The averaged FRF was drawn, and the results appear as the workers finish.
        assert "2 hits averaged" in page.locator("#n-averaged").inner_text()
        assert page.locator("#frf-plot canvas").count() >= 1
        assert page.locator("#force-plot canvas").count() >= 1
        assert run_id in page.locator("#last-run").inner_text()
        page.wait_for_selector("#modes-table tbody tr", timeout=120_000)
        page.wait_for_selector("#damping-matrix td", timeout=180_000)
        first_mode = page.locator("#modes-table tbody tr").first.inner_text()
        frequency = float(re.search(r"\d+\.\d{4}", first_mode).group())
        assert frequency == pytest.approx(5.569, rel=0.002)  # the realistic beam's first mode
        assert page.locator("#table2 tbody tr").count() >= 3
        assert page.locator("#damping-matrix tr").count() >= 3

        # Beside the numbers: ± the standard uncertainty, the band and why, the synthesis
        # error, and one "caution:" line for every caution of the analysis and the fit.
        analysis = served.get(f"/api/runs/{run_id}/analysis").json()
        assert " ± " in first_mode
        assert "standard uncertainty" in page.locator("#modes-note").inner_text()
        band = page.locator("#analysis-band").inner_text()
        assert band.startswith("band ")
        assert analysis["band"]["reason"] in band
        assert "synthesis error" in band
        shown = page.locator("#analysis-cautions .caution").all_inner_texts()
        assert shown == [f"caution: {c}" for c in analysis["cautions"]]
        fit = served.get(f"/api/runs/{run_id}/fits").json()["fit-ls"]
        shown = page.locator("#fit-cautions .caution").all_inner_texts()
        assert shown == [f"caution: {c}" for c in fit["cautions"]]

        # On a 1024 px screen no column of the results is cut at the card's edge (the
        # Damping columns were): the tables go one under the other.
        page.set_viewport_size({"width": 1024, "height": 700})
        page.wait_for_function(
            "() => document.querySelector('#run-card').getBoundingClientRect().width < 1000"
        )
        assert cut_cells(page, "#run-card") == []
        assert page.locator("#modes-table th", has_text="Damping").is_visible()
        page.set_viewport_size({"width": 1300, "height": 1000})

        # The runs page lists it with its results and report.
        page.goto(f"{served.url}/runs")
        row = page.locator(f'#runs-table tr[data-run-id="{run_id}"]')
        row.wait_for()
        page.wait_for_function(
            "(id) => document.querySelector(`#runs-table tr[data-run-id='${id}'] .analysis-state`)"
            ".textContent.trim() === 'done'",
            arg=run_id,
        )
        report = row.locator("a", has_text=re.compile("report", re.I)).first.get_attribute("href")
        assert report == f"/api/runs/{run_id}/report"  # on loopback no link carries the token
        assert served.get(report).status_code == 200
    assert errors == []
    assert outside == []  # every script and style came from the service itself


def test_the_runs_page_shows_the_cautions_of_a_run_of_pure_noise(tmp_path, browser_page):
    page, errors, outside = browser_page
    store = tmp_path / "store"
    run_id = import_noise_frf(tmp_path, store)
    with serving(tmp_path, "--sim", "--workers", "1", store=store) as served:
        page.goto(f"{served.url}/runs")
        notes = page.locator(f'#runs-table tr[data-notes-for="{run_id}"]')
        no_mode = notes.locator(".caution", has_text="caution: no mode found in 1-800 Hz")
        no_mode.wait_for(timeout=120_000)  # once its analysis is done
        assert no_mode.is_visible()
        lines = notes.locator(".caution").all_inner_texts()
        assert all(line.startswith("caution: ") for line in lines)
        assert any("synthesis error" in line for line in lines)
        facts = notes.locator(".run-facts").inner_text()
        assert facts.startswith("band 1–800 Hz: ")
        assert "synthesis error 99" in facts

        # On a 1024 px screen every column and caution line is in view, none cut at the
        # card's edge (the Damping column and the cautions were).
        page.set_viewport_size({"width": 1024, "height": 700})
        page.wait_for_function(
            "() => document.querySelector('#runs-table').getBoundingClientRect().width < 1000"
        )
        assert cut_cells(page, ".card") == []

        # The texts are text: a foreign run's caution cannot put markup on the page.
        (row,) = [r for r in served.get("/api/runs").json() if r["run_id"] == run_id]
        row["cautions"] = ["<img src=x onerror=window.pwned=1>"]
        row["fit_cautions"] = ["<b>bold</b>"]
        page.route(re.compile(r".*/api/runs$"), lambda route: route.fulfill(json=[row]))
        page.reload()
        notes.locator(".caution").first.wait_for()
        assert notes.locator(".caution").all_inner_texts() == [
            "caution: <img src=x onerror=window.pwned=1>",
            "caution: fit: <b>bold</b>",
        ]
        assert page.locator("#runs-table img, #runs-table b").count() == 0
        assert page.evaluate("() => window.pwned") is None
    assert errors == []
    assert outside == []
