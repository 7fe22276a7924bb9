"""The test station's API over real HTTP on the simulated analyzer (issue 24): undo of
a held decision, hit numbers for people beside the 0-based index, a hit's quality
(windows, force spectrum, its own FRF and the running average), tests and their
points, named setups and transducers."""

from __future__ import annotations

import time

import pytest

from daq.store import Store
from tests.service.service_helpers import EventReader, serving, wait_for

pytestmark = pytest.mark.slow


def _pending(served, index: int, timeout_s: float = 30.0) -> None:
    wait_for(lambda: served.get("/api/capture").json()["pending"] == index, timeout_s, f"hit {index} pending")


def test_a_held_decision_is_undone_within_the_window_and_refused_after_it(tmp_path, monkeypatch):
    monkeypatch.setenv("DAQ_UNDO_WINDOW_S", "2")
    with serving(tmp_path, "--sim", "--seed", "1", "--time-scale", "0") as served:
        events = EventReader(served)
        assert served.post("/api/capture/undo").status_code == 409  # nothing to undo
        run_id = served.post("/api/capture", {"hits": 2}).json()["run_id"]
        _pending(served, 0)
        state = served.get("/api/capture").json()
        assert state["hit_index_base"] == 0
        (hit,) = state["hits"]
        assert (hit["index"], hit["number"], hit["accepted_against_checks"]) == (0, 1, False)

        # Hit 1 rejected by mistake, then taken back within the window: pending again.
        assert (
            served.post("/api/capture/decision", {"index": 0, "accept": False, "reason": "oops"}).status_code
            == 200
        )
        held = served.get("/api/capture").json()
        assert held["pending"] is None
        assert 0 < held["undo_until_s"] <= 2
        assert held["hits"][0]["held"] is True
        # which verdict is held, for a page opened during the hold
        assert (held["hits"][0]["held_accepted"], held["hits"][0]["held_reason"]) == (False, "oops")
        answer = served.post("/api/capture/undo")
        assert answer.status_code == 200, answer.text
        assert answer.json() == {"index": 0, "number": 1, "undone": "rejected"}
        again = served.get("/api/capture").json()
        assert (again["pending"], again["undo_until_s"], again["hits"][0]["decided"]) == (0, None, False)
        assert events.wait_for_kind("decision_undone", run_id, 10)["number"] == 1

        # Accepted for good: after the window the hit is in the analyzer's average.
        started = time.monotonic()
        assert served.post("/api/capture/decision", {"index": 0, "accept": True}).status_code == 200
        _pending(served, 1)
        assert time.monotonic() - started >= 1.9  # held for the window before the analyzer had it
        late = served.post("/api/capture/undo")
        assert late.status_code == 409
        assert late.json() == {"detail": "hit 1 is already in the analyzer's average"}
        decided = served.get("/api/capture").json()["hits"][0]
        assert (decided["decided"], decided["accepted"], decided["held"]) == (True, True, False)

        # Stop while a decision is held: the decision is kept in the sealed run.
        assert served.post("/api/capture/decision", {"index": 1, "accept": True}).status_code == 200
        assert served.post("/api/capture/stop").status_code == 202
        ended = events.wait_for_kind("capture_ended", run_id, 30)
        assert ended["outcome"] in ("sealed", "incomplete"), ended
        run = Store(served.store).open(run_id)
        assert run.hits.accepted.tolist() == [True, True]
        events.close()


def test_abort_during_a_held_decision_discards_the_hits(tmp_path, monkeypatch):
    monkeypatch.setenv("DAQ_UNDO_WINDOW_S", "30")
    with serving(tmp_path, "--sim", "--seed", "1", "--time-scale", "0") as served:
        served.post("/api/capture", {"hits": 2})
        _pending(served, 0)
        assert served.post("/api/capture/decision", {"index": 0, "accept": True}).status_code == 200
        assert served.post("/api/capture/abort").status_code == 202
        wait_for(lambda: served.get("/api/capture").json()["state"] == "idle", 20, "idle")
        state = served.get("/api/capture").json()
        assert state["last_outcome"] == "aborted"
        assert state["undo_until_s"] is None


def test_a_hits_quality_arrays_have_the_records_and_spans_shapes(tmp_path, monkeypatch):
    monkeypatch.setenv("DAQ_UNDO_WINDOW_S", "0")
    with serving(tmp_path, "--sim", "--seed", "1", "--time-scale", "0") as served:
        served.post("/api/capture", {"hits": 2})
        for index in (0, 1):
            _pending(served, index)
            assert served.post("/api/capture/decision", {"index": index, "accept": True}).status_code == 200
        wait_for(lambda: served.get("/api/capture").json()["state"] == "idle", 30, "idle")
        settings = served.get("/api/capture").json()["settings"]
        hit = served.get("/api/capture/hits/1").json()
        assert (hit["index"], hit["number"], hit["hit_index_base"]) == (1, 2, 0)
        n = len(hit["force_n"])
        assert n == 1024  # the 35660A's record: 2.56 x 400 lines
        assert len(hit["force_window"]) == len(hit["response_window"]) == n
        assert min(hit["force_window"]) >= 0
        assert max(hit["response_window"]) <= 1
        # The force window is 1 for t < its width (sample i at i / fs), 0 after.
        width_s = settings["hammer"]["force_width_s"]
        ones = sum(1 for i in range(n) if i / hit["sample_rate_hz"] < width_s)
        assert hit["force_window"] == [1.0] * ones + [0.0] * (n - ones)
        spectrum = hit["force_spectrum"]
        lines = 401  # 0..span in 400 lines
        assert len(spectrum["frequency_hz"]) == len(spectrum["level_db"]) == lines
        assert spectrum["rolloff_limit_db"] == -10.0
        assert spectrum["rolloff_hz"] == pytest.approx(0.9 * settings["span_hz"])
        frf, average = hit["frf"], hit["average"]
        assert len(frf["frequency_hz"]) == len(frf["magnitude"]) == len(frf["phase_deg"]) == lines
        assert average["n_averaged"] == 2
        assert len(average["coherence"]) == lines
        # The running average after the last hit is the live FRF the service publishes.
        live = served.get("/api/capture/frf").json()
        assert average["magnitude"] == pytest.approx(live["frf_abs"], rel=1e-9, nan_ok=True)
        assert served.get("/api/capture/hits/2").status_code == 404


def test_a_capture_at_the_next_point_of_a_test_moves_the_simulator_and_joins_the_test(tmp_path, monkeypatch):
    from daq.workflows.test import new_test

    monkeypatch.setenv("DAQ_UNDO_WINDOW_S", "0")
    store = tmp_path / "store"
    new_test(store, "beam", None, "p1=0.1,p2=0.2", "tip", "hammer")
    with serving(tmp_path, "--sim", "--seed", "1", "--time-scale", "0", store=store) as served:
        (listed,) = served.get("/api/tests").json()["tests"]
        assert listed["name"] == "beam"
        assert listed["next"] == "p1"
        assert [(p["name"], p["position_m"], p["measured"]) for p in listed["points"]] == [
            ("p1", 0.1, False),
            ("p2", 0.2, False),
        ]
        bad = served.post("/api/capture", {"hits": 1, "test": "beam", "point": "p9"})
        assert bad.status_code == 422
        assert bad.json()["detail"].startswith("point: test beam has no point 'p9'")
        assert served.post("/api/capture", {"hits": 1, "test": "nope", "point": "next"}).status_code == 422
        assert served.post("/api/capture", {"hits": 1, "point": "next"}).json()["detail"].startswith("test:")

        answer = served.post("/api/capture", {"hits": 1, "auto": True, "test": "beam", "point": "next"})
        assert answer.status_code == 202, answer.text
        run_id = answer.json()["run_id"]
        assert served.get("/api/capture").json()["test"] == {"name": "beam", "point": "p1"}
        wait_for(lambda: served.get("/api/capture").json()["state"] == "idle", 60, "idle")
        state = served.get("/api/capture").json()
        assert state["last_outcome"] == "sealed", state
        assert "joined test beam at point p1" in state["last_message"]
        run = Store(store).open(run_id)
        assert run.points.force_point.name == "p1"
        simulator = run.provenance["simulator"]
        assert simulator["force_at_m"] == pytest.approx(0.1)  # the hammer struck at p1
        assert run.sample.force_position_m == pytest.approx(0.1)

        detail = served.get("/api/tests/beam").json()
        assert detail["next"] == "p2"
        (p1,) = [p for p in detail["points"] if p["name"] == "p1"]
        assert p1["measured"] is True
        assert p1["counted_run"] == run_id
        assert served.get("/api/tests/nope").status_code == 404

        # Without a test the simulator plays its own positions again (the tip).
        again = served.post("/api/capture", {"hits": 1, "auto": True}).json()["run_id"]
        wait_for(lambda: served.get("/api/capture").json()["state"] == "idle", 60, "idle")
        home = Store(store).open(again).provenance["simulator"]
        assert home["force_at_m"] == pytest.approx(run.sample.length_m)


def test_setups_are_versioned_checked_against_the_analyzer_and_recorded_with_their_transducers(
    tmp_path, monkeypatch
):
    monkeypatch.setenv("DAQ_UNDO_WINDOW_S", "0")
    with serving(tmp_path, "--sim", "--seed", "1", "--time-scale", "0") as served:
        listed = served.get("/api/setups").json()["setups"]
        assert {"name": "default", "version": 0, "saved_utc": ""} in listed
        default = served.get("/api/setups/default").json()
        assert default["settings"]["hammer"]["sensitivity_v_per_eu"] == pytest.approx(2.25e-3)
        assert served.get("/api/setups/nope").status_code == 404

        # A hammer of our own, calibration past due.
        hammer = {
            "kind": "hammer", "model": "PCB 086C01", "serial": "SN-4711", "sensitivity": 2.3,
            "sensitivity_unit": "mV/N", "calibrated": "2020-01-01", "due": "2021-01-01",
        }  # fmt: skip
        with served.client() as c:
            put = c.put("/api/transducers/h-12", json=hammer)
            bad = c.put("/api/transducers/h-13", json={**hammer, "sensitivity": -1})
        assert put.status_code == 200, put.text
        assert put.json()["sensitivity_v_per_eu"] == pytest.approx(2.3e-3)
        assert put.json()["overdue"] is True
        ids = [t["id"] for t in served.get("/api/transducers").json()["transducers"]]
        assert {"hammer-default", "accel-default", "h-12"} <= set(ids)
        assert bad.status_code == 422
        assert bad.json()["detail"].startswith("sensitivity:")

        # The 35660A offers 400 lines only; a trigger above the hammer's range is refused.
        with served.client() as c:
            data = {"span_hz": 400.0, "hammer": {"transducer": "h-12"}, "accelerometer": {}}
            too_fine = c.put("/api/setups/bench", json={"setup": {**data, "lines": 800}, "version": 0})
            assert too_fine.status_code == 422
            assert too_fine.json()["detail"] == "lines: the 35660A offers 400 lines only, not 800"
            too_high = c.put(
                "/api/setups/bench", json={"setup": {**data, "trigger_level_eu": 1000}, "version": 0}
            )
            assert too_high.status_code == 422
            assert too_high.json()["detail"].startswith(
                "trigger_level_eu: 1000 N is above the hammer's range"
            )
            negative = c.put("/api/setups/bench", json={"setup": {**data, "span_hz": -5}, "version": 0})
            assert negative.json()["detail"].startswith("span_hz:")

            saved = c.put("/api/setups/bench", json={"setup": data, "version": 0})
            assert saved.status_code == 200, saved.text
            assert saved.json()["version"] == 1
            assert saved.json()["settings"]["hammer"]["sensitivity_v_per_eu"] == pytest.approx(2.3e-3)
            assert saved.json()["cautions"]  # the hammer's calibration is past due
            stale = c.put("/api/setups/bench", json={"setup": data, "version": 0})
            assert stale.status_code == 409
            again = c.put("/api/setups/bench", json={"setup": {**data, "span_hz": 200.0}, "version": 1})
            assert again.json()["version"] == 2
        assert served.get("/api/setups/bench").json()["setup"]["span_hz"] == 200.0
        conflict = served.post("/api/capture", {"hits": 1, "setup": "bench", "setup_version": 1})
        assert conflict.status_code == 409
        unknown = served.post("/api/capture", {"hits": 1, "setup": "nope"})
        assert unknown.status_code == 422
        assert unknown.json()["detail"].startswith("setup: no setup 'nope'")

        # A capture with the named setup records it, its transducers and cautions.
        run_id = served.post("/api/capture", {"hits": 1, "setup": "bench", "setup_version": 2}).json()[
            "run_id"
        ]
        state = served.get("/api/capture").json()
        assert state["setup"] == {"name": "bench", "version": 2}
        assert state["transducers"]["hammer"]["serial"] == "SN-4711"
        assert any("calibration" in c for c in state["cautions"])
        _pending(served, 0)
        assert served.post("/api/capture/decision", {"index": 0, "accept": True}).status_code == 200
        wait_for(lambda: served.get("/api/capture").json()["state"] == "idle", 30, "idle")
        run = Store(served.store).open(run_id)
        assert run.provenance["setup"] == {"name": "bench", "version": 2}
        recorded = run.instrument.settings["hammer"]["transducer"]
        assert (recorded["id"], recorded["serial"], recorded["due_date"]) == ("h-12", "SN-4711", "2021-01-01")
        assert run.instrument.settings["hammer"]["sensitivity_v_per_eu"] == pytest.approx(2.3e-3)
        assert any("calibration" in c for c in run.provenance["cautions"])


def test_practice_hits_choose_ranges_and_a_trigger_level(tmp_path):
    with serving(tmp_path, "--sim", "--seed", "1", "--time-scale", "0") as served:
        answer = served.post("/api/capture/practice", {"setup": "default", "hits": 2})
        assert answer.status_code == 202, answer.text
        wait_for(lambda: served.get("/api/capture").json()["state"] == "idle", 60, "idle")
        practice = served.get("/api/capture").json()["practice"]
        assert practice["state"] == "done", practice
        assert practice["hits_taken"] == 2
        assert len(practice["peaks_force_n"]) == 2
        assert practice["trigger_level_eu"] == pytest.approx(0.1 * min(practice["peaks_force_n"]), rel=0.01)
        assert practice["hammer_range_v"] >= 1.5 * max(practice["peaks_force_n"]) * 2.25e-3
        assert served.post("/api/capture/practice", {"hits": 0}).status_code == 422


def test_the_station_routes_describe_their_error_answers(tmp_path):
    from tests.service.test_service_openapi import _error_codes

    with serving(tmp_path, "--sim", "--seed", "1", "--time-scale", "0") as served:
        spec = served.get("/openapi.json").json()
        assert _error_codes(spec, "/api/capture/undo", "post") == {"401", "409", "411", "413", "422"}
        assert _error_codes(spec, "/api/capture/practice", "post") == {
            "401",
            "409",
            "411",
            "413",
            "422",
            "503",
        }
        assert _error_codes(spec, "/api/setups/{name}", "put") == {"401", "409", "411", "413", "422"}
        assert _error_codes(spec, "/api/setups/{name}", "get") == {"404", "422"}
        assert _error_codes(spec, "/api/transducers/{ident}", "put") == {"401", "411", "413", "422"}
        assert _error_codes(spec, "/api/tests/{name}", "get") == {"404", "422"}
        assert _error_codes(spec, "/api/tests", "get") == set()
        answers = {
            "409": served.post("/api/capture/undo"),
            "404": served.get("/api/setups/nope"),
            "422": served.post("/api/capture", {"hits": 1, "test": "nope", "point": "next"}),
        }
        for code, answer in answers.items():
            assert str(answer.status_code) == code, (code, answer.text)
            assert set(answer.json()) == {"detail"}
