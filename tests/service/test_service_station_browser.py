"""The live page as a test station (issue 24), in a real headless Chromium: a setup made
on the page (another span, line count and transducer) that a capture then uses and the
sealed run records; impossible setups refused with the field named beside it; accept,
reject and undo from the keyboard alone; the decision buttons on a 1024 x 700 screen;
the large display.

With DAQ_WRITE_SCREENSHOTS=1 the tests also write docs/images/station-*.png (not in CI,
so that a run does not rewrite the repository).
"""

from __future__ import annotations

import os
import re
import subprocess
from pathlib import Path

import pytest

from daq.store import Store
from tests.conftest import NO_BROWSER
from tests.service.service_helpers import DAQ, service_env, serving, wait_for
from tests.service.test_service_browser import CHROMIUM, CHROMIUM_ARGS, cut_cells

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(CHROMIUM is None, reason=f"{NO_BROWSER} (apt-get install chromium)"),
]

SCREENSHOTS = os.environ.get("DAQ_WRITE_SCREENSHOTS") == "1"
IMAGES = Path(__file__).resolve().parents[2] / "docs" / "images"
SMALL_SCREEN = {"width": 1024, "height": 700}

#: What the browser logs for an answer the page expects and shows (a refused setup: 422;
#: an undo too late: 409).
EXPECTED_REFUSAL = re.compile(r"Failed to load resource: the server responded with a status of (409|422)")


def screenshot(page, name: str, down_to: str | None = None, element: str | None = None) -> None:
    """The viewport; or the page from its top down to the bottom of ``down_to``; or one element."""
    if not SCREENSHOTS:
        return
    IMAGES.mkdir(parents=True, exist_ok=True)
    path = str(IMAGES / name)
    if element:  # from the page's top (the header sticks there), not under the header
        page.evaluate("() => window.scrollTo(0, 0)")
        box = page.locator(element).bounding_box()
        clip = {"x": box["x"], "y": box["y"], "width": box["width"], "height": box["height"]}
        page.screenshot(path=path, full_page=True, clip=clip)
    elif down_to:
        page.evaluate("() => window.scrollTo(0, 0)")
        box = page.locator(down_to).bounding_box()
        width = page.viewport_size["width"]
        page.screenshot(
            path=path,
            full_page=True,
            clip={"x": 0, "y": 0, "width": width, "height": box["y"] + box["height"] + 16},
        )
    else:
        page.screenshot(path=path)


@pytest.fixture
def station_page(tmp_path: Path):
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        context = browser.new_context(viewport=SMALL_SCREEN)
        page = context.new_page()
        errors: list[str] = []
        page.on("pageerror", lambda exc: errors.append(str(exc)))
        page.on(
            "console",
            lambda msg: (
                errors.append(msg.text)
                if msg.type == "error" and not EXPECTED_REFUSAL.search(msg.text)
                else None
            ),
        )
        outside: list[str] = []
        local = "http://127.0.0.1"
        page.on("request", lambda r: None if r.url.startswith(local) else outside.append(r.url))
        page.set_default_timeout(60_000)
        yield page, errors, outside
        context.close()
        browser.close()


def open_live_page(page, served) -> None:
    page.goto(f"{served.url}/#token={served.token}")
    page.wait_for_function("() => document.querySelector('#capture-state').textContent.trim() === 'idle'")


def open_setup_editor(page) -> None:
    page.click("#setup-toggle")
    page.wait_for_function("() => document.querySelector('#setup-version').textContent.includes('default')")


def inside_viewport(page, selector: str) -> bool:
    box = page.locator(selector).bounding_box()
    size = page.viewport_size
    return (
        box is not None
        and box["x"] >= 0
        and box["y"] >= 0
        and box["x"] + box["width"] <= size["width"]
        and box["y"] + box["height"] <= size["height"]
    )


def wait_pending(page, number: int) -> None:
    page.wait_for_function(
        "(n) => document.querySelector('#pending-index').textContent.trim() === `Hit ${n}`"
        " && !document.querySelector('#accept').disabled",
        arg=number,
    )


def decision_boxes(page) -> list[dict]:
    """Where Accept, Reject and Undo are, and how large (rounded to the pixel)."""
    boxes = [page.locator(b).bounding_box() for b in ("#accept", "#reject", "#undo")]
    return [{k: round(v) for k, v in box.items()} for box in boxes]


def wait_verdict(page, index: int, text: str, held: bool | None = None) -> None:
    page.wait_for_function(
        "([i, want, held]) => {"
        " const row = document.querySelector(`#hits-table tr[data-index='${i}']`);"
        " if (!row) return false;"
        " const text = row.querySelector('.verdict').textContent.trim();"
        " const ok = text === want || text.startsWith(want + ': ');"
        " return ok && (held === null || row.classList.contains('row-held') === held);}",
        arg=[index, text, held],
    )


def test_a_setup_made_on_the_page_is_the_one_the_run_records(tmp_path, station_page, monkeypatch):
    page, errors, outside = station_page
    monkeypatch.setenv("DAQ_UNDO_WINDOW_S", "0")
    with serving(tmp_path, "--sim", "--analyzer", "35670A", "--time-scale", "0.02") as served:
        open_live_page(page, served)
        open_setup_editor(page)

        # A transducer the service refuses: its one line shown once, under the form, and the
        # fields of the form stay where they were (the line in the grid reflowed them).
        form = page.locator("#transducer-form")
        fields = form.locator(".field")

        def field_boxes():  # within the form (focus on the field named may scroll the page)
            top = form.bounding_box()
            boxes = [fields.nth(i).bounding_box() for i in range(fields.count())]
            return [
                (round(b["x"] - top["x"]), round(b["y"] - top["y"]), round(b["width"]), round(b["height"]))
                for b in boxes
            ]

        form.locator('[name="id"]').fill("h-30")
        form.locator('[name="sensitivity"]').fill("0.23")
        before = field_boxes()
        for name, value, want in [
            ("sensitivity_unit", "mV/g", "sensitivity_unit: "),
            ("calibrated", "2026-03-01", "due: "),
        ]:
            if name == "calibrated":
                form.locator('[name="sensitivity_unit"]').select_option("mV/N")
                form.locator('[name="calibrated"]').fill(value)
                form.locator('[name="due"]').fill("2026-02-01")
            else:
                form.locator(f'[name="{name}"]').select_option(value)
            page.click("#transducer-save")
            page.wait_for_function(
                "(w) => document.querySelector('#transducer-error').textContent.startsWith(w)", arg=want
            )
            message = page.locator("#transducer-error").inner_text()
            key = want.rstrip(": ")
            assert page.locator("#transducer-error").get_attribute("data-for") == key
            assert form.locator(f'[data-key="{key}"]').get_attribute("class").split().count("invalid") == 1
            shown_in_editor = page.evaluate(
                "(m) => [...document.querySelectorAll('#setup-editor *')]"
                ".filter(e => e.children.length === 0 && e.textContent.includes(m)).length",
                message,
            )
            assert shown_in_editor == 1, message
            assert field_boxes() == before
        form.locator('[name="calibrated"]').fill("")
        form.locator('[name="due"]').fill("")

        # Two transducers of the lab: a hammer, and an accelerometer past its calibration.
        for ident, kind, model, serial, sens, unit, cal, due in [
            ("hammer-7", "hammer", "PCB 086C01", "H7-2231", "11.2", "mV/N", "2026-01-12", "2027-01-12"),
            ("accel-3", "accelerometer", "PCB 352C33", "LW-118", "101.4", "mV/g", "2023-05-02", "2024-05-02"),
        ]:
            form.locator('[name="id"]').fill(ident)
            form.locator('[name="kind"]').select_option(kind)
            form.locator('[name="model"]').fill(model)
            form.locator('[name="serial"]').fill(serial)
            form.locator('[name="sensitivity"]').fill(sens)
            form.locator('[name="sensitivity_unit"]').select_option(unit)
            form.locator('[name="calibrated"]').fill(cal)
            form.locator('[name="due"]').fill(due)
            page.click("#transducer-save")
            page.wait_for_selector(f'#transducers-table tr[data-transducer="{ident}"]')
        overdue = page.locator('#transducers-table tr[data-transducer="accel-3"] td.overdue')
        assert "overdue" in overdue.inner_text()
        assert cut_cells(page, "#setup-editor") == []  # the table whole on a 1024 px screen

        # Another span, line count and transducers than the default setup.
        setup = page.locator("#setup-form")
        setup.locator('[name="span_hz"]').fill("400")
        setup.locator('[name="lines"]').select_option("800")
        setup.locator('[name="trigger_level_eu"]').fill("0.5")
        setup.locator('[name="hammer.transducer"]').select_option("hammer-7")
        setup.locator('[name="hammer.range_v"]').fill("0.05")
        setup.locator('[name="accelerometer.transducer"]').select_option("accel-3")
        info = page.locator('[data-info-for="hammer"]').inner_text()
        assert "PCB 086C01" in info
        assert "11.2 mV/N" in info
        assert "2027-01-12" in info
        assert "OVERDUE" in page.locator('[data-info-for="accelerometer"]').inner_text()
        page.fill("#setup-name", "bench-b")
        page.click("#setup-save")
        page.wait_for_function(
            "() => document.querySelector('#setup-status').textContent.includes('Saved bench-b')"
        )
        assert "version 1" in page.locator("#setup-status").inner_text()
        # the overdue calibration is said where it cannot be missed
        caution = page.locator("#setup-cautions .caution")
        assert "accel-3" in caution.first.inner_text()
        assert "due 2024-05-02" in caution.first.inner_text()
        # Saved meanwhile elsewhere (another tab, a colleague): Load shows the newer version
        # in the header and in the list alike; coming back to the page refreshes the list.
        with served.client() as c:
            saved = c.get("/api/setups/bench-b").json()["setup"]
            assert c.put("/api/setups/bench-b", json={"setup": saved, "version": 1}).status_code == 200
            page.click("#setup-load")
            page.wait_for_function(
                "() => document.querySelector('#setup-version').textContent.includes('version 2')"
            )
            page.wait_for_function(
                "() => document.querySelector('#setup-list').selectedOptions[0].textContent"
                " === 'bench-b (v2)'"
            )
            assert c.put("/api/setups/bench-b", json={"setup": saved, "version": 2}).status_code == 200
        page.evaluate("() => window.dispatchEvent(new Event('focus'))")
        page.wait_for_function(
            "() => document.querySelector('#setup-list').selectedOptions[0].textContent === 'bench-b (v3)'"
        )
        assert "Load shows it" in page.locator("#setup-status").inner_text()
        page.click("#setup-load")
        page.wait_for_function(
            "() => document.querySelector('#setup-version').textContent.includes('version 3')"
        )

        # What the next capture uses, said as such (not the last capture's setup).
        next_line = page.locator("#capture-setup-note [data-setup-line='next']")
        service_own = served.get("/api/capture").json().get("next_setup")
        if service_own:
            assert (
                next_line.inner_text()
                == f"Next capture: setup {service_own['name']} v{service_own['version']}"
            )
        page.click("#setup-use")
        assert page.locator("#capture-setup").input_value() == "bench-b"
        assert next_line.inner_text() == "Next capture: setup bench-b v3"
        screenshot(page, "station-setup.png", element="#setup-editor")
        page.click("#setup-close")
        page.wait_for_selector("#station-cautions .caution")

        page.fill("#hits-wanted", "1")
        page.click("#start")
        wait_pending(page, 1)
        page.click("#accept")
        run_id = wait_for(lambda: served.get("/api/capture").json()["last_run_id"], 60, "the run")
        # idle again: the last capture's setup and transducers, and the next capture's setup,
        # each said for what it is
        page.wait_for_function("() => document.querySelector('#capture-state').textContent.trim() === 'idle'")
        page.wait_for_selector("#capture-setup-note [data-setup-line='last']")
        assert page.locator("#capture-setup-note [data-setup-line='last']").inner_text() == (
            "Last capture: setup bench-b v3 · hammer hammer-7 · accelerometer accel-3"
        )
        assert next_line.inner_text() == "Next capture: setup bench-b v3"
        assert "This capture" not in page.locator("#capture-setup-note").inner_text()

    run = Store(served.store).open(run_id)
    assert run.provenance["setup"] == {"name": "bench-b", "version": 3}
    assert any("accel-3" in c for c in run.provenance["cautions"])
    settings = run.instrument.settings
    assert settings["span_hz"] == pytest.approx(400)
    assert settings["lines"] == 800
    assert settings["trigger_level_eu"] == pytest.approx(0.5)
    hammer = settings["hammer"]["transducer"]
    assert (hammer["id"], hammer["model"], hammer["serial"]) == ("hammer-7", "PCB 086C01", "H7-2231")
    assert settings["hammer"]["sensitivity_v_per_eu"] == pytest.approx(0.0112)
    accel = settings["accelerometer"]["transducer"]
    assert (accel["id"], accel["due_date"], accel["overdue"]) == ("accel-3", "2024-05-02", True)
    assert errors == []
    assert outside == []


def test_an_impossible_setup_is_refused_with_the_field_named(tmp_path, station_page, monkeypatch):
    page, errors, outside = station_page
    monkeypatch.setenv("DAQ_UNDO_WINDOW_S", "0")
    with serving(tmp_path, "--sim", "--time-scale", "0.02") as served:  # the 35660A
        open_live_page(page, served)
        open_setup_editor(page)
        setup = page.locator("#setup-form")
        page.fill("#setup-name", "too-much")

        setup.locator('[name="trigger_level_eu"]').fill("1000")
        page.click("#setup-save")
        field = setup.locator('[data-key="trigger_level_eu"]')
        field.locator(".field-error").wait_for()
        assert field.locator(".field-error").inner_text().startswith("trigger_level_eu: ")
        assert "1000 N" in field.locator(".field-error").inner_text()
        assert field.get_attribute("class").split().count("invalid") == 1
        assert page.locator("#setup-error").get_attribute("data-for") == "trigger_level_eu"

        setup.locator('[name="trigger_level_eu"]').fill("")
        setup.locator('[name="lines"]').select_option("800")
        page.click("#setup-save")
        field = setup.locator('[data-key="lines"]')
        field.locator(".field-error").wait_for()
        assert field.locator(".field-error").inner_text().startswith("lines: ")
        assert "35660A" in field.locator(".field-error").inner_text()
        assert setup.locator(".field.invalid").count() == 1  # the earlier mark is gone
        assert page.locator("#setup-error").get_attribute("data-for") == "lines"

        # nothing was saved
        names = [s["name"] for s in served.get("/api/setups").json()["setups"]]
        assert "too-much" not in names
    assert errors == []
    assert outside == []


def test_accept_reject_and_undo_from_the_keyboard_on_a_small_screen(tmp_path, station_page, monkeypatch):
    page, errors, outside = station_page
    monkeypatch.setenv("DAQ_UNDO_WINDOW_S", "4")
    with serving(tmp_path, "--sim", "--time-scale", "0.02") as served:
        open_live_page(page, served)
        page.fill("#hits-wanted", "2")
        page.keyboard.press("Escape")  # out of the field: keys are commands again
        page.keyboard.press("s")
        wait_pending(page, 1)

        # Everything needed to decide is on a 1024 x 700 screen without scrolling.
        assert page.evaluate("() => window.scrollY") == 0
        for selector in ("#accept", "#reject", "#undo", "#pending-index", "#suggested"):
            assert inside_viewport(page, selector), selector
        assert page.locator("#accept").inner_text().replace("\n", " ").strip() == "Accept A"
        assert "A accept" in page.locator("#key-help").inner_text()

        # A: accepted, held; U takes it back: hit 1 waits again.
        page.keyboard.press("a")
        wait_verdict(page, 0, "accepted", held=True)
        page.wait_for_function("() => !document.querySelector('#undo').disabled")
        assert "held" in page.locator("#undo-note").inner_text()
        page.keyboard.press("u")
        wait_verdict(page, 0, "pending")
        wait_pending(page, 1)

        # R: rejected (the reason field is empty: the service's own reason), for good once held long enough.
        page.keyboard.press("r")
        wait_verdict(page, 0, "rejected", held=True)
        wait_verdict(page, 0, "rejected", held=False)

        # The pending hit's quality: pulse zoom, force spectrum, its FRF over the average.
        wait_pending(page, 2)
        page.wait_for_function("() => document.querySelector('#quality-hit').textContent.trim() === 'hit 2'")
        for plot in ("#pulse-plot", "#spectrum-plot", "#hit-frf-plot", "#hit-phase-plot"):
            page.wait_for_function("(p) => !document.querySelector(p).classList.contains('empty')", arg=plot)

        # The large display: the count, the pending hit, its verdict and big buttons.
        page.keyboard.press("l")
        assert "display=large" in page.url
        assert page.locator(".large-count").is_visible()
        assert page.locator("#large-accepted").inner_text() == "0"
        assert page.locator("#hits-card").is_hidden()
        for selector in ("#accept", "#reject", "#undo", "#suggested"):
            assert inside_viewport(page, selector), selector
        assert page.locator("#accept").bounding_box()["height"] >= 100
        screenshot(page, "station-large.png")
        page.keyboard.press("l")
        assert "display=large" not in page.url

        # Typing in a field is typing: "a" there is a letter, not an accept.
        page.click("#reject-reason")
        page.keyboard.type("a")
        assert page.locator("#reject-reason").input_value() == "a"
        assert not page.locator("#accept").is_disabled()
        page.keyboard.press("Escape")
        page.fill("#reject-reason", "")
        page.keyboard.press("Escape")

        page.keyboard.press("a")
        wait_verdict(page, 1, "accepted", held=False)
        wait_pending(page, 3)
        # hit 3 over the average of hit 2, with its coherence
        page.wait_for_function("() => document.querySelector('#quality-hit').textContent.trim() === 'hit 3'")
        page.wait_for_function(
            "() => !document.querySelector('#hit-coherence-plot').classList.contains('empty')"
        )
        screenshot(page, "station-live.png", down_to="#quality-card")
        # an undo after the window is refused, and says why (hit 2 went to the analyzer)
        page.keyboard.press("u")
        page.wait_for_function(
            "() => document.querySelector('#error').textContent"
            '.includes("already in the analyzer\'s average")'
        )
        # the message goes by itself after a few seconds (it stayed over the next hits)
        page.wait_for_function("() => document.querySelector('#error').textContent === ''", timeout=10_000)
        page.keyboard.press("a")
        run_id = wait_for(lambda: served.get("/api/capture").json()["last_run_id"], 60, "the run")
        wait_verdict(page, 2, "accepted", held=False)
        assert page.locator("#hits-table tbody tr .hit-number").all_inner_texts() == ["1", "2", "3"]

    run = Store(served.store).open(run_id)
    assert run.complete
    assert run.hits.accepted.tolist() == [False, True, True]
    assert errors == []
    assert outside == []


def test_the_large_display_from_the_address(tmp_path, station_page, monkeypatch):
    page, errors, outside = station_page
    monkeypatch.setenv("DAQ_UNDO_WINDOW_S", "0")
    with serving(tmp_path, "--sim", "--time-scale", "0.02") as served:
        page.goto(f"{served.url}/?display=large#token={served.token}")
        page.wait_for_function("() => document.querySelector('#capture-state').textContent.trim() === 'idle'")
        assert page.evaluate("() => document.body.classList.contains('large')")
        assert page.locator("#large-toggle").get_attribute("aria-pressed") == "true"
        # sound is off until asked, and the choice is kept
        assert page.locator("#sound-toggle").inner_text() == "Sound: off"
        page.click("#sound-toggle")
        assert page.evaluate("() => localStorage.getItem('daq-sound')") == "on"
        page.reload()
        page.wait_for_function("() => document.querySelector('#sound-toggle').textContent === 'Sound: on'")
        # the event stream is up: the hit comes as an event, with its beep
        page.wait_for_function("() => document.querySelector('#conn-status').textContent.trim() === 'live'")
        page.wait_for_function("() => document.querySelector('#capture-state').textContent.trim() === 'idle'")
        # the whole width of the screen, and the buttons where they were before the hit
        before = decision_boxes(page)
        assert page.locator("#pending").bounding_box()["width"] >= SMALL_SCREEN["width"] - 60
        page.keyboard.press("s")
        wait_pending(page, 1)
        assert page.evaluate("() => document.body.dataset.lastSound") == "hit"
        assert decision_boxes(page) == before
        assert page.locator("#pending").bounding_box()["width"] >= SMALL_SCREEN["width"] - 60
        # a message floats over the bottom: it moves nothing either
        page.evaluate("() => window.DAQ.showError('a message of the moment')")
        assert decision_boxes(page) == before
        page.evaluate("() => window.DAQ.clearError()")
        page.keyboard.press("x")  # stop: the hit waiting is kept, rejected
        page.wait_for_function("() => document.querySelector('#capture-state').textContent.trim() === 'idle'")
    assert errors == []
    assert outside == []


def test_a_capture_at_the_next_point_of_a_test_and_practice_hits_for_the_ranges(
    tmp_path, station_page, monkeypatch
):
    from daq.workflows.test import new_test

    page, errors, outside = station_page
    monkeypatch.setenv("DAQ_UNDO_WINDOW_S", "0")
    store = tmp_path / "store"
    new_test(store, "beam", None, "p1=0.1,p2=0.2", "tip", "hammer")
    with serving(tmp_path, "--sim", "--seed", "1", "--time-scale", "0.02", store=store) as served:
        open_live_page(page, served)
        page.wait_for_selector("#capture-test-field:not([hidden])")
        page.select_option("#capture-test", "beam")
        points = page.locator("#capture-point option").all_inner_texts()
        assert points[0] == "next: p1"
        assert page.locator("#capture-point").input_value() == "next"
        page.fill("#hits-wanted", "1")
        page.check("#auto")
        page.click("#start")
        run_id = wait_for(lambda: served.get("/api/capture").json()["last_run_id"], 60, "the run")
        assert Store(served.store).open(run_id).points.force_point.name == "p1"
        # the point is measured now, and the next one is offered
        page.wait_for_function(
            "() => document.querySelector('#capture-point option').textContent === 'next: p2'"
        )
        assert any(t.startswith("✓ p1") for t in page.locator("#capture-point option").all_inner_texts())
        page.uncheck("#auto")

        # Practice hits: their peaks, the ranges and trigger level proposed, applied to a setup.
        open_setup_editor(page)
        page.fill("#setup-name", "ranged")
        page.fill("#practice-hits", "2")
        page.click("#practice-start")
        page.wait_for_selector("#practice-apply:not([hidden])")
        result = page.locator("#practice-result").inner_text()
        assert result.startswith("2 practice hits · peaks ")
        assert "Proposed: hammer range" in result
        practice = served.get("/api/capture").json()["practice"]
        page.click("#practice-apply")
        page.wait_for_function(
            "() => document.querySelector('#setup-status').textContent.includes('Saved ranged')"
        )
        saved = served.get("/api/setups/ranged").json()["setup"]
        assert saved["hammer"]["range_v"] == pytest.approx(practice["hammer_range_v"])
        assert saved["accelerometer"]["range_v"] == pytest.approx(practice["accelerometer_range_v"])
        assert saved["trigger_level_eu"] == pytest.approx(practice["trigger_level_eu"], rel=0.01)
    assert errors == []
    assert outside == []


def test_a_hit_accepted_against_a_failed_check_is_marked_on_the_page_and_in_the_run(
    tmp_path, station_page, monkeypatch
):
    """A hammer that always bounces (the simulator's double hit): the check fails, the
    technician accepts anyway; the page marks the hit, and the sealed run says so."""
    page, errors, outside = station_page
    monkeypatch.setenv("DAQ_UNDO_WINDOW_S", "0")
    hammer = "double_hit_probability=1"
    with serving(tmp_path, "--sim", "--time-scale", "0.02", "--seed", "3", "--hammer", hammer) as served:
        open_live_page(page, served)
        page.fill("#hits-wanted", "1")
        page.keyboard.press("Escape")
        page.keyboard.press("s")
        wait_pending(page, 1)
        page.keyboard.press("a")
        run_id = wait_for(lambda: served.get("/api/capture").json()["last_run_id"], 60, "the run")
        wait_verdict(page, 0, "accepted", held=False)
        mark = page.locator("#hits-table tr[data-index='0'] .against-mark")
        mark.wait_for()
        assert mark.get_attribute("aria-label") == "accepted against a failed check"
        assert served.get("/api/capture").json()["hits"][0]["accepted_against_checks"] is True

    shown = subprocess.run(
        [str(DAQ), "runs", "show", run_id, "--store", str(served.store)],
        capture_output=True, text=True, env=service_env(tmp_path), timeout=60,
    )  # fmt: skip
    assert shown.returncode == 0, shown.stderr
    assert "hit   1" in shown.stdout
    assert "accepted although the double" in shown.stdout
    assert errors == []
    assert outside == []
