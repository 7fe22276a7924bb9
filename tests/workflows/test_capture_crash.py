"""SIGKILL a real `daq capture --sim` at random moments: the store then holds only whole,
sealed runs that verify clean, an earlier run is untouched, and every command
ignores whatever temporary file a killed capture left (docs/run-format.md). A capture
killed after its first hit leaves a hit journal, which the first listing seals as an
incomplete run (tests/test_capture_journal_kill.py checks what those hold)."""

from __future__ import annotations

import hashlib
import json
import os
import random
import signal
import subprocess
import time

import pytest

from daq.store import Store, open_run, verify
from tests.cli_helpers import DAQ, ENV, invoke_daq

# 30 kills at moments spread over a whole capture's life, start-up to seal; timed from a
# capture measured here, so that a loaded machine's slower start-up does not take them
# all (timed U(0, 2 s), all 50 kills landed before the first hit with the suite running).
KILLS = 30


def _capture(store, seed: int, env: dict[str, str]) -> subprocess.Popen:
    command = ["capture", "--sim", "--yes", "--hits", "3", "--time-scale", "0", "--seed", str(seed)]
    return subprocess.Popen(
        [str(DAQ), *command, "--store", str(store)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        stdin=subprocess.DEVNULL,
        env=env,
    )


@pytest.mark.timeout(300)
def test_sigkill_of_a_capture_at_random_moments_leaves_only_whole_runs(tmp_path):
    store = tmp_path / "runs"
    env = {**os.environ, **ENV, "DAQ_LOCK_DIR": str(tmp_path / "locks"), "DAQ_CONFIG": str(tmp_path / "none")}
    env.pop("DAQ_DEBUG", None)
    started = time.monotonic()
    first = _capture(store, 0, env)
    assert first.wait(timeout=60) == 0
    whole_s = time.monotonic() - started  # a whole capture, on this machine as loaded now
    (earlier,) = store.glob("*.h5")
    earlier_sha = hashlib.sha256(earlier.read_bytes()).hexdigest()

    rng = random.Random(20261123)
    finished = killed = 0
    for seed in range(1, KILLS + 1):
        proc = _capture(store, seed, env)
        time.sleep(rng.uniform(0.0, 1.1 * whole_s))  # any moment of its life, a few after it
        if proc.poll() is None:
            proc.send_signal(signal.SIGKILL)
            killed += 1
        else:
            finished += 1
        proc.wait(timeout=30)
    assert killed >= KILLS // 3, (killed, finished)  # most kills land mid-capture

    Store(store).recover_journals()  # the journals of captures killed mid-way, as incomplete runs
    runs = sorted(store.glob("*.h5"))
    assert earlier in runs
    assert hashlib.sha256(earlier.read_bytes()).hexdigest() == earlier_sha
    for path in runs:
        assert verify(path) == [], path
        run = open_run(path)
        assert run.kind == "simulated"
        assert run.hits is not None
        if run.complete:
            assert int(run.hits.accepted.sum()) == 3
        else:
            assert "recovered_from_journal" in run.provenance
            assert run.hits.n_hits >= 1
    assert len(runs) >= 1 + finished  # every capture that ended on its own sealed its run

    listed = Store(store).list()
    assert [s.file_name for s in listed] == [p.name for p in runs]  # no temporary file listed
    assert all(s.error is None for s in listed)
    no_config = {"DAQ_CONFIG": env["DAQ_CONFIG"]}
    result = invoke_daq("runs", "list", "--json", "--store", str(store), env=no_config)
    assert result.returncode == 0, result.stderr
    assert len(json.loads(result.stdout)) == len(runs)
    checked = invoke_daq("runs", "verify", "--store", str(store), env=no_config)
    assert checked.returncode == 0, checked.stdout + checked.stderr
