"""`daq serve` when things break: the instrument link drops mid-capture, and the
service itself is SIGKILLed mid-capture and mid-analysis. The hits taken are kept
as an incomplete run, the service stays up and says what happened, the next
capture reconnects; after a kill the store verifies clean, no worker outlives the
service, and a restart analyses and fits whatever the kill interrupted. Real
processes, real signals, a real `daq sim serve` analyzer over TCP."""

from __future__ import annotations

import os
import signal
from pathlib import Path

import pytest

from daq.store import Store
from tests.cli_helpers import capture_sim
from tests.service.hardening_helpers import (
    children_of,
    free_port,
    kill_service,
    live_group_members,
    run_daq_env,
    running,
    unexpected_store_entries,
)
from tests.service.service_helpers import EventReader, Served, service_env, serving, sim_server, wait_for

pytestmark = pytest.mark.slow

LINK_WORDS = ("connection", "refused", "reset", "closed", "broken pipe", "timed out", "no answer")


def _verify_clean(env: dict[str, str], store: Path, n_runs: int) -> None:
    """`daq runs verify` of the whole store: every run OK, and nothing odd in the folder."""
    result = run_daq_env(env, "runs", "verify", "--store", str(store))
    assert result.returncode == 0, result.stdout + result.stderr
    assert f"{n_runs} run(s) checked: {n_runs} OK, 0 with problems" in result.stdout, result.stdout
    assert unexpected_store_entries(store) == []


def _decide(served: Served, index: int, accept: bool = True) -> None:
    wait_for(lambda: served.get("/api/capture").json()["pending"] == index, 60, f"hit {index}")
    answer = served.post("/api/capture/decision", {"index": index, "accept": accept})
    assert answer.status_code == 200, answer.text


def _all_analysed(served: Served, run_ids: list[str]) -> bool:
    rows = {r["run_id"]: r for r in served.get("/api/runs").json()}
    return all(
        rows[r]["analysis"] == "done" and rows[r]["fit"] == "done" and rows[r]["frequencies_hz"]
        for r in run_ids
    )


def test_a_dropped_instrument_link_keeps_the_hits_so_far_and_the_next_capture_reconnects(tmp_path):
    port = free_port()
    with sim_server("--scenario", "realistic", "--time-scale", "0.5", port=port) as (sim, resource):
        assert resource.endswith(f"::{port}::SOCKET"), resource
        with serving(tmp_path, "--resource", resource, "--workers", "1") as served:
            events = EventReader(served)
            run_id = served.post("/api/capture", {"hits": 5}).json()["run_id"]
            _decide(served, 0)
            _decide(served, 1)
            events.wait_for_kind("frf", run_id, 30)
            wait_for(lambda: events.kinds(run_id).count("hit_decided") == 2, 30, "the second decision")
            os.killpg(sim.pid, signal.SIGKILL)  # the analyzer's link drops while hit 2 is awaited
            sim.wait(10)

            def ended_or_pending() -> str | None:
                if "capture_ended" in events.kinds(run_id):
                    return "ended"
                return "pending" if served.get("/api/capture").json()["pending"] == 2 else None

            if wait_for(ended_or_pending, 60, "the capture to notice the dropped link") == "pending":
                # Hit 2 came in just before the kill: its decision is what meets the dead link.
                assert served.post("/api/capture/decision", {"index": 2, "accept": True}).status_code == 200
            ended = events.wait_for_kind("capture_ended", run_id, 60)
            assert ended["outcome"] == "incomplete", ended
            message = ended["message"].lower()
            assert any(word in message for word in LINK_WORDS) or resource.lower() in message, ended
            assert "hits kept as an incomplete run" in message, ended

            run = Store(served.store).open(run_id)
            assert not run.complete
            accepted = run.hits.accepted.tolist()
            assert accepted in ([True, True], [True, True, False]), accepted
            if len(accepted) == 3:
                assert run.hits.reject_reason[2] == "interrupted before a decision"
            (sealed,) = [d for _, k, d in events.events if k == "run_sealed" and d["run_id"] == run_id]
            assert (sealed["complete"], sealed["n_hits"], sealed["n_accepted"]) == (False, len(accepted), 2)
            assert Store(served.store).verify(run_id) == []

            # The service stays up and says so: the instrument is not connected, and why.
            instrument = served.get("/api/instrument").json()
            assert instrument["connected"] is False, instrument
            assert instrument["last_error"], instrument
            down = [d for _, k, d in events.events if k == "instrument" and d["connected"] is False]
            assert down, events.kinds()
            capture = served.get("/api/capture").json()
            assert (capture["state"], capture["last_outcome"]) == ("idle", "incomplete"), capture
            assert capture["last_error"], capture
            health = served.get("/api/health").json()
            assert health["status"] == "ok"
            assert health["instrument"]["connected"] is False

            # A capture while the analyzer is away: a clear 503, and nothing stuck.
            refused = served.post("/api/capture", {"hits": 1, "auto": True})
            assert refused.status_code == 503, refused.text
            assert "cannot be reached" in refused.json()["detail"]
            assert served.get("/api/capture").json()["state"] == "idle"
            assert events.kinds().count("capture_started") == 1

            # The analyzer comes back on the same port: the next capture reconnects.
            with sim_server("--scenario", "realistic", "--time-scale", "0.05", port=port) as (_, again):
                assert again == resource
                second = served.post("/api/capture", {"hits": 2, "auto": True})
                assert second.status_code == 202, second.text
                second_id = second.json()["run_id"]
                ended = events.wait_for_kind("capture_ended", second_id, 60)
                assert ended["outcome"] == "sealed", ended
                assert Store(served.store).open(second_id).complete
                instrument = served.get("/api/instrument").json()
                assert instrument["connected"] is True, instrument
                assert instrument["last_error"] is None, instrument
                states = [d["connected"] for _, k, d in events.events if k == "instrument"]
                assert states[-1] is True, states  # and the page was told
                wait_for(lambda: _all_analysed(served, [run_id, second_id]), 120, "both runs analysed")
                _verify_clean(served.env, served.store, 2)
            events.close()


def test_sigkill_mid_capture_leaves_a_clean_store_and_a_service_that_starts_again(tmp_path):
    store = tmp_path / "store"
    # An analyzer of its own, which outlives the service (as the lab's does): the
    # restarted service must be able to take it again (the kernel freed the lock).
    with sim_server("--scenario", "realistic", "--time-scale", "0.05") as (_, resource):
        with serving(tmp_path, "--resource", resource, "--workers", "1", store=store) as served:
            events = EventReader(served)
            kept = served.post("/api/capture", {"hits": 1}).json()["run_id"]
            _decide(served, 0)
            assert events.wait_for_kind("capture_ended", kept, 30)["outcome"] == "sealed"
            events.wait_for_kind("fit_done", kept, 120)
            killed = served.post("/api/capture", {"hits": 3}).json()["run_id"]
            _decide(served, 0)
            wait_for(lambda: served.get("/api/capture").json()["pending"] == 1, 60, "hit 1")
            kill_service(served)  # waits until no process of its group runs
            events.close()
        # Nothing was being sealed: the store holds the first run, and the killed
        # capture's hit journal, which the next listing seals as an incomplete run.
        assert sorted(p.name for p in store.glob("*.h5") if p.name.count(".") == 2) == [f"{kept}.h5"]
        assert Store(store).temporaries() == []
        assert not (store / f"{killed}.h5").exists()
        _verify_clean(service_env(tmp_path), store, 2)
        recovered = Store(store).open(killed)
        assert not recovered.complete
        assert recovered.hits.accepted.tolist() == [True, False]  # hit 1 was waiting for a decision
        with serving(tmp_path, "--resource", resource, "--workers", "1", store=store) as served:
            health = served.get("/api/health").json()
            assert health["status"] == "ok"
            assert health["instrument"]["connected"] is True, health
            assert served.get("/api/capture").json()["state"] == "idle"
            assert _all_analysed(served, [kept])
            events = EventReader(served)
            again = served.post("/api/capture", {"hits": 1, "auto": True})
            assert again.status_code == 202, again.text
            ended = events.wait_for_kind("capture_ended", again.json()["run_id"], 60)
            assert ended["outcome"] == "sealed", ended
            events.close()
            _verify_clean(served.env, store, 3)


def test_sigkill_mid_analysis_kills_the_workers_and_a_restart_analyses_every_run(tmp_path):
    store = tmp_path / "store"
    # One run more than the two workers: the kill, at the first analysis done, finds
    # runs begun and not yet begun (a fourth run only queued behind the third).
    run_ids = [capture_sim(store, "seed", seed, hits=2) for seed in range(1, 4)]
    with serving(tmp_path, "--sim", "--workers", "2", store=store) as served:
        events = EventReader(served, since=0)  # the backlog may start before we listen
        events.wait_for_kind("analysis_done", None, 120)  # the workers are at it
        pgid = served.proc.pid
        workers = children_of(served.proc.pid)
        assert workers, "no worker process"
        kill_service(served)
        events.close()
        # No worker outlives the service: its process group is empty (zombies aside,
        # which only wait for whoever inherited them to reap them).
        assert [pid for pid in workers if running(pid)] == []
        assert live_group_members(pgid) == []
    unfinished = [r for r in run_ids if not (store / f"{r}.fit-ls.h5").exists()]
    assert unfinished, "every run was done before the kill: nothing was interrupted"
    _verify_clean(service_env(tmp_path), store, len(run_ids))
    with serving(tmp_path, "--sim", "--workers", "2", store=store) as served:
        events = EventReader(served, since=0)
        for run_id in unfinished:
            events.wait_for_kind("fit_done", run_id, 180)
        wait_for(lambda: _all_analysed(served, run_ids), 120, "every run analysed and fitted")
        assert not [k for k in events.kinds() if k.endswith("_failed")], events.kinds()
        events.close()
        for run_id in run_ids:
            assert Store(store).read_result(run_id, "analysis")["summary"]["modes"]
        _verify_clean(served.env, store, len(run_ids))
