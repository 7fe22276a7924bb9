"""`daq serve --sim` end to end over real HTTP: captures decided through the API,
the runs they seal, their analysis and fit as they land, downloads, Stop and Abort,
and `daq capture` beside a running service."""

from __future__ import annotations

import csv
import io
import subprocess

import h5py
import numpy as np
import pytest
import pyuff

from daq.store import Store
from tests.cli_helpers import DAQ, assert_one_line_error
from tests.reference import REALISTIC_DAMPING_RATIOS
from tests.service.service_helpers import EventReader, service_env, serving, sim_server, wait_for

pytestmark = pytest.mark.slow

#: The realistic simulated beam's first modes (the exact cantilever of Table 1, as
#: docs/method.md computes them by hand from the Euler-Bernoulli roots), Hz.
REALISTIC_MODES_HZ = (5.569, 34.899, 97.717)


def test_a_capture_decided_through_the_api_lands_with_the_right_flags_and_gets_its_results(tmp_path):
    # --seed 1: the hits whose modes and damping the checks below were measured on.
    with serving(tmp_path, "--sim", "--seed", "1", "--time-scale", "0.02") as served:
        health = served.get("/api/health").json()
        assert health["instrument"]["connected"] is True
        assert health["instrument"]["simulated"] is True
        spec = served.get("/openapi.json").json()
        assert {"/api/runs", "/api/capture", "/api/capture/decision", "/api/events"} <= set(spec["paths"])
        events = EventReader(served)
        body = {"hits": 3, "operator": "Ada", "note": "bench 2"}
        run_id = served.post("/api/capture", body).json()["run_id"]
        decisions = [(True, ""), (False, "hand slipped"), (True, ""), (True, "")]
        for index, (accept, reason) in enumerate(decisions):
            wait_for(lambda i=index: served.get("/api/capture").json()["pending"] == i, 30, f"hit {index}")
            decision = {"index": index, "accept": accept, "reason": reason}
            answer = served.post("/api/capture/decision", decision)
            assert answer.status_code == 200, answer.text
        hit = events.wait_for_kind("hit", run_id, 30)
        assert len(hit["force_n"]) == len(hit["response_m_s2"]) == 1024
        ended = events.wait_for_kind("capture_ended", run_id, 30)
        assert ended["outcome"] == "sealed"
        fit = events.wait_for_kind("fit_done", run_id, 180)
        assert fit["method"] == "ls"

        run = Store(served.store).open(run_id)
        assert run.complete
        assert run.operator == "Ada"
        assert run.note == "bench 2"
        assert run.hits.accepted.tolist() == [True, False, True, True]
        assert run.hits.reject_reason[1] == "hand slipped"
        kinds = events.kinds(run_id)
        assert kinds.count("hit") == 4
        assert kinds.count("hit_decided") == 4
        assert kinds.count("frf") == 3  # the average builds up with each accepted hit
        order = [
            "capture_started",
            "configured",
            "hit",
            "run_sealed",
            "capture_ended",
            "analysis_done",
            "fit_done",
        ]
        assert [kinds.index(k) for k in order] == sorted(kinds.index(k) for k in order)
        ids = [i for i, _, _ in events.events if i is not None]
        assert ids == list(range(ids[0], ids[0] + len(ids)))  # none lost, none twice
        events.close()

        (row,) = [r for r in served.get("/api/runs").json() if r["run_id"] == run_id]
        assert (row["analysis"], row["fit"], row["n_hits"], row["n_accepted"]) == ("done", "done", 4, 3)
        assert row["frequencies_hz"][:3] == pytest.approx(REALISTIC_MODES_HZ, rel=0.002)
        analysis = served.get(f"/api/runs/{run_id}/analysis").json()
        assert [r["mode"] for r in analysis["table2"]["rows"]][:3] == [1, 2, 3]
        fits = served.get(f"/api/runs/{run_id}/fits").json()
        zetas = [m["damping_ratio"] for m in fits["fit-ls"]["modes"]][:3]  # one function per identified mode
        assert zetas == pytest.approx(REALISTIC_DAMPING_RATIOS[:3], rel=0.25)
        detail = served.get(f"/api/runs/{run_id}").json()
        assert detail["run"]["file"] == f"{run_id}.h5"  # never the server's path
        assert detail["analysis_state"] == "done"

        # Downloads: the sealed file itself, its exports, its report.
        file = served.get(f"/api/runs/{run_id}/file")
        assert file.content == (served.store / f"{run_id}.h5").read_bytes()
        with h5py.File(io.BytesIO(file.content), "r") as h5:
            assert h5.attrs["schema"] == b"cantilever-daq.run"
        text = served.get(f"/api/runs/{run_id}/export", params={"format": "csv"}).text
        rows = [r for r in csv.reader(io.StringIO(text)) if r and not r[0].startswith("#")]
        assert len(rows) == 1 + 4 * 1024  # a header and every sample of every hit
        uff = served.get(f"/api/runs/{run_id}/export", params={"format": "uff"})
        path = tmp_path / "run.uff"
        path.write_bytes(uff.content)
        assert {s["type"] for s in pyuff.UFF(str(path)).read_sets()} == {58}
        # A report draws a dozen figures (seconds each on a loaded machine): wait for it.
        report = served.get(f"/api/runs/{run_id}/report", timeout=120)
        assert report.headers["content-type"].startswith("text/html")
        assert run_id in report.text
        assert "data:image/png;base64," in report.text


def test_stop_seals_the_hits_so_far_and_abort_discards_them(tmp_path):
    with serving(tmp_path, "--sim", "--time-scale", "0.02") as served:
        events = EventReader(served)
        run_id = served.post("/api/capture", {"hits": 5}).json()["run_id"]
        wait_for(lambda: served.get("/api/capture").json()["pending"] == 0, 30, "the first hit")
        assert served.post("/api/capture/decision", {"index": 0, "accept": True}).status_code == 200
        wait_for(lambda: served.get("/api/capture").json()["pending"] == 1, 30, "the second hit")
        assert served.post("/api/capture/stop").status_code == 202
        ended = events.wait_for_kind("capture_ended", run_id, 30)
        assert ended["outcome"] == "incomplete"
        run = Store(served.store).open(run_id)
        assert not run.complete
        assert run.hits.accepted.tolist() == [True, False]  # the undecided hit is kept, rejected
        assert run.hits.reject_reason[1] == "interrupted before a decision"

        second = served.post("/api/capture", {"hits": 5}).json()["run_id"]
        wait_for(lambda: served.get("/api/capture").json()["pending"] == 0, 30, "a hit")
        assert served.post("/api/capture/abort").status_code == 202
        assert events.wait_for_kind("capture_ended", second, 30)["outcome"] == "aborted"
        assert not (served.store / f"{second}.h5").exists()
        assert served.post("/api/capture/stop").status_code == 409  # nothing runs now
        events.close()


def test_an_auto_capture_decides_by_the_checks_and_a_second_start_is_refused(tmp_path):
    with serving(tmp_path, "--sim", "--time-scale", "0.05") as served:
        run_id = served.post("/api/capture", {"hits": 2, "auto": True}).json()["run_id"]
        refused = served.post("/api/capture", {"hits": 2})
        assert refused.status_code == 409
        assert run_id in refused.json()["detail"]
        wait_for(lambda: served.get("/api/capture").json()["state"] == "idle", 60, "the capture to end")
        run = Store(served.store).open(run_id)
        assert run.complete
        assert int(np.count_nonzero(run.hits.accepted)) == 2


def test_capture_beside_a_running_service_names_the_service(tmp_path):
    with (
        sim_server("--scenario", "seed", "--time-scale", "0.05") as (_, resource),
        serving(tmp_path, "--resource", resource) as served,
    ):
        command = [str(DAQ), "capture", "--resource", resource, "--yes", "--store", str(tmp_path / "other")]
        result = subprocess.run(
            command, capture_output=True, text=True, env=service_env(tmp_path), timeout=60
        )
        assert_one_line_error(result, f"daq serve at {served.url}")
        assert not (tmp_path / "other").exists() or not any((tmp_path / "other").glob("*.h5"))
        assert served.get("/api/health").json()["instrument"]["connected"] is True
