"""`daq serve` from a new user's trial: how it starts and stops, what it refuses, and
what the API says about hits a Stop or an Abort leaves undecided."""

from __future__ import annotations

import os
import signal
import subprocess

import pytest

from daq.store import Store
from tests.cli_helpers import DAQ, assert_one_line_error, capture_sim
from tests.service.service_helpers import EventReader, service_env, serving, wait_for

pytestmark = pytest.mark.slow


def test_text_a_run_cannot_store_is_refused_at_the_request(tmp_path):
    with serving(tmp_path, "--sim", "--workers", "1") as served:
        for body in (
            {"hits": 1, "operator": "a\x00b"},  # a NUL cannot be stored at all
            {"hits": 1, "operator": "a\x1b[2Jb"},  # an escape sequence would drive a terminal
            {"hits": 1, "operator": "two\nlines"},
            {"hits": 1, "note": "bell\x07"},
        ):
            answer = served.post("/api/capture", body)
            assert answer.status_code == 422, (body, answer.text)
            assert "control characters" in answer.json()["detail"]
        assert served.get("/api/capture").json()["state"] == "idle"
        assert not list(served.store.glob("*.h5"))
        run_id = served.post("/api/capture", {"hits": 1, "auto": True, "note": "line 1\nline 2\ttab"}).json()
        wait_for(lambda: served.get("/api/capture").json()["state"] == "idle", 60, "the capture")
        assert Store(served.store).open(run_id["run_id"]).note == "line 1\nline 2\ttab"


def test_stop_and_abort_give_the_waiting_hit_a_verdict_the_api_and_the_run_agree_on(tmp_path):
    with serving(tmp_path, "--sim", "--time-scale", "0.02", "--workers", "1") as served:
        events = EventReader(served)
        run_id = served.post("/api/capture", {"hits": 5}).json()["run_id"]
        wait_for(lambda: served.get("/api/capture").json()["pending"] == 0, 30, "hit 1")
        served.post("/api/capture/decision", {"index": 0, "accept": True})
        wait_for(lambda: served.get("/api/capture").json()["pending"] == 1, 30, "hit 2")
        served.post("/api/capture/stop")
        events.wait_for_kind("capture_ended", run_id, 30)
        hits = served.get("/api/capture").json()["hits"]
        stored = Store(served.store).open(run_id).hits
        assert [h["accepted"] for h in hits] == stored.accepted.tolist() == [True, False]
        assert hits[1]["reason"] == list(stored.reject_reason)[1] == "interrupted before a decision"
        decided = [d for _, k, d in events.events if k == "hit_decided" and d["run_id"] == run_id]
        assert [d["index"] for d in decided] == [0, 1]

        second = served.post("/api/capture", {"hits": 5}).json()["run_id"]
        wait_for(lambda: served.get("/api/capture").json()["pending"] == 0, 30, "hit 1")
        served.post("/api/capture/decision", {"index": 0, "accept": True})
        wait_for(lambda: served.get("/api/capture").json()["pending"] == 1, 30, "hit 2")
        served.post("/api/capture/abort")
        ended = events.wait_for_kind("capture_ended", second, 30)
        assert ended["outcome"] == "aborted"
        assert ended["message"] == "2 hits discarded"  # the one waiting for a decision too
        assert [h["reason"] for h in served.get("/api/capture").json()["hits"]][
            1
        ] == "discarded (capture aborted)"
        events.close()


def test_sigterm_seals_the_capture_in_progress_and_stops_cleanly(tmp_path):
    with serving(tmp_path, "--sim", "--time-scale", "0.02", "--workers", "1") as served:
        run_id = served.post("/api/capture", {"hits": 5}).json()["run_id"]
        wait_for(lambda: served.get("/api/capture").json()["pending"] == 0, 30, "hit 1")
        served.post("/api/capture/decision", {"index": 0, "accept": True})
        wait_for(lambda: served.get("/api/capture").json()["pending"] == 1, 30, "hit 2")
        served.proc.send_signal(signal.SIGTERM)  # systemd, kill, a shutdown
        assert served.proc.wait(30) == 0
        run = Store(served.store).open(run_id)
        assert not run.complete
        assert run.hits.accepted.tolist() == [True, False]
        assert "daq serve: stopped\n" in served.stderr_lines
        # Said at once, before the half minute start-up can take on a loaded machine (a
        # new user's redirected log stayed empty 18 s): the port the address line names.
        port = served.url.rsplit(":", 1)[1]
        assert served.stderr_lines[0] == (
            f"daq serve: starting on port {port} of 127.0.0.1; the address to open follows once it is ready\n"
        )


def test_serve_refuses_to_guess_the_analyzer_and_a_second_service_on_one_store(tmp_path):
    env = service_env(tmp_path)
    env.pop("DAQ_RESOURCE", None)
    command = [str(DAQ), "serve", "--port", "0", "--store", str(tmp_path / "store")]
    result = subprocess.run(command, capture_output=True, text=True, env=env, timeout=60)
    assert_one_line_error(result, "no analyzer configured", "--sim")
    assert result.returncode == 2
    with serving(tmp_path, "--sim", "--workers", "1") as served:
        second = subprocess.run([*command, "--sim"], capture_output=True, text=True, env=env, timeout=60)
        assert_one_line_error(second, "is in use by", f"daq serve at {served.url}")


def test_a_run_another_process_seals_into_the_store_is_analysed_while_the_service_runs(tmp_path):
    with serving(tmp_path, "--sim", "--workers", "1") as served:
        events = EventReader(served)
        env = service_env(tmp_path)
        command = [str(DAQ), "capture", "--sim", "--hits", "2", "--yes", "--time-scale", "0"]
        subprocess.run([*command, "--store", str(served.store)], env=env, check=True, capture_output=True)
        (run_id,) = [p.name.removesuffix(".h5") for p in served.store.glob("*.h5") if p.name.count(".") == 2]
        events.wait_for_kind("fit_done", run_id, 120)
        (row,) = served.get("/api/runs").json()
        assert (row["run_id"], row["analysis"], row["fit"]) == (run_id, "done", "done")
        events.close()


def test_ctrl_c_in_the_terminal_stops_the_service_at_once_even_with_a_worker_busy(tmp_path):
    # A terminal's Ctrl-C goes to the whole process group, the analysis workers too: they
    # must leave stopping to the service (no KeyboardInterrupt traceback through the
    # pool) and end with it, not keep it alive until their runs are done.
    store = tmp_path / "store"
    for seed in (1, 2, 3):
        capture_sim(store, "realistic", seed)
    with serving(tmp_path, "--sim", "--jobs", "1", store=store) as served:
        wait_for(lambda: served.get("/api/health").json()["jobs"]["running"] >= 1, 60, "an analysis running")
        os.killpg(served.proc.pid, signal.SIGINT)
        assert served.proc.wait(10) == 0
        assert "daq serve: stopped\n" in served.stderr_lines
        assert not any("Traceback" in line or "not stopped after" in line for line in served.stderr_lines)
