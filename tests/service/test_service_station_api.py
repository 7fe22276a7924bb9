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
