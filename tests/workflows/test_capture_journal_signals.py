"""Real processes, real signals: SIGTERM, SIGHUP and SIGKILL of `daq capture` and of
`daq serve` mid-capture lose no accepted hit (docs/capture.md, "No hit lost").

Each capture runs paced (--time-scale 0.1: a hit every 0.3-0.5 s) and is
signalled once two hits were accepted, which the capture says only after the verdict
is fsynced in its journal. The next `daq runs list` must then show one verified
incomplete run holding both.
"""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
from pathlib import Path

import pytest

from daq.store import Store, open_run
from tests.cli_helpers import DAQ
from tests.service.service_helpers import serving, wait_for
from tests.workflows.capture_processes import capture_env, listed, start_capture, wait_for_accepted

EXIT = {signal.SIGTERM: 143, signal.SIGHUP: 129, signal.SIGKILL: -signal.SIGKILL}


@pytest.fixture(autouse=True)
def hangup_not_ignored():
    """The processes these tests start inherit SIGHUP's disposition, and daq keeps an
    ignored SIGHUP ignored (a capture under nohup must survive its terminal): a suite run
    under nohup would see no SIGHUP at all. Set it to the default for what they start."""
    old = signal.signal(signal.SIGHUP, signal.SIG_DFL)
    yield
    signal.signal(signal.SIGHUP, old)


WHY = {signal.SIGTERM: "terminated (SIGTERM)", signal.SIGHUP: "hung up (SIGHUP)"}


def assert_one_incomplete_run(store: Path, env: dict[str, str], accepted_at_least: int) -> dict:
    runs, _ = listed(store, env)
    assert len(runs) == 1, runs
    (run,) = runs
    assert run["error"] is None
    assert not run["complete"]
    assert run["n_accepted"] >= accepted_at_least
    assert Store(store).verify(run["run_id"]) == []
    assert not [p for p in store.iterdir() if p.name.startswith(".journal-")]
    verified = subprocess.run(
        [str(DAQ), "runs", "verify", "--store", str(store)],
        capture_output=True,
        text=True,
        env=env,
        timeout=60,
    )
    assert verified.returncode == 0, verified.stdout + verified.stderr
    return run


@pytest.mark.timeout(90)
@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGHUP, signal.SIGKILL], ids=lambda s: s.name)
def test_a_signalled_capture_keeps_every_accepted_hit(tmp_path, signum):
    store = tmp_path / "runs"
    env = capture_env(tmp_path)
    proc = start_capture(store, env)
    try:
        wait_for_accepted(proc, 2)
        os.kill(proc.pid, signum)
        _, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()
    assert proc.returncode == EXIT[signum], err
    if signum == signal.SIGKILL:  # nothing sealed it: the journal did
        journals = [p for p in store.iterdir() if p.name.startswith(".journal-")]
        assert len(journals) == 1
        assert not list(store.glob("*.h5"))
        _, said = listed(store, env)
        assert "recovered an interrupted capture from its hit journal" in said
        run = assert_one_incomplete_run(store, env, 2)
        assert open_run(store / run["file"]).provenance["recovered_from_journal"] == journals[0].name
    else:  # sealed at once, as Ctrl-C does
        lines = err.splitlines()
        assert len(lines) == 1, err
        assert f"{WHY[signum]}; " in lines[0]
        assert "hits kept as incomplete run" in lines[0]
        run = assert_one_incomplete_run(store, env, 2)
        assert run["run_id"] in lines[0]
        assert "recovered_from_journal" not in open_run(store / run["file"]).provenance


@pytest.mark.timeout(120)
@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGHUP, signal.SIGKILL], ids=lambda s: s.name)
def test_a_signalled_service_keeps_every_accepted_hit(tmp_path, signum):
    """`daq serve` mid-capture: SIGTERM and SIGHUP seal the capture as it stops; SIGKILL
    ends the process, and the journal gives the hits back at the next listing."""
    with serving(tmp_path, "--sim", "--time-scale", "0.1") as served:
        reply = served.post("/api/capture", {"hits": 10, "auto": True})
        assert reply.status_code == 202, reply.text
        run_id = reply.json()["run_id"]
        wait_for(lambda: served.get("/api/capture").json()["accepted"] >= 2, 60, "two accepted hits")
        os.kill(served.proc.pid, signum)
        served.proc.wait(30)
        if signum != signal.SIGKILL:  # sealed by the service itself: no journal left to recover
            assert not list(served.store.glob(".journal-*"))
        env = served.env
        store = served.store
    with contextlib.suppress(ProcessLookupError):  # workers a killed service left behind
        os.killpg(served.proc.pid, signal.SIGKILL)
    run = assert_one_incomplete_run(store, env, 2)
    assert run["run_id"] == run_id
