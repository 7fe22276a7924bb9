"""SIGKILL a real `daq capture --sim` in every phase of its life: the store then holds
only whole, sealed runs that verify clean, an earlier run is untouched, and every
command ignores whatever temporary file a killed capture left (docs/run-format.md). A
capture killed after its first hit leaves a hit journal, which the next capture or the
first listing seals as an incomplete run (tests/test_capture_journal_kill.py checks
what those hold)."""

from __future__ import annotations

import hashlib
import json
import os
import random
import signal
import subprocess
import threading
import time
from pathlib import Path

import pytest

from daq.store import Store, open_run, verify
from tests.cli_helpers import DAQ, ENV, invoke_daq

#: What a capture prints as it enters each phase of its life (None: its start). A kill
#: aimed at a phase lands at a random moment of it, timed from a whole capture measured
#: on this machine as loaded now; blind moments (U(0, 1.1 whole capture)) took 30 kills
#: to reach the short phases (the hits and the seal take a tenth of a capture here).
MARKS = (
    None,  # start-up: interpreter, imports, earlier captures' journals sealed, the simulator
    "Simulated ",  # connecting: the analyzer identified (an *IDN? that times out, then ID?)
    "Analyzer: ",  # configuring the analyzer
    "Hammer away",  # hit 1 taken, no verdict yet (the hit journal opened)
    "Hit 1: ",  # hit 1's verdict being written to the journal
    "1/3 accepted",  # hit 2 taken, hit 1 journalled
    "2/3 accepted",  # hit 3 taken
    "3/3 accepted",  # the run being sealed
    "sealed: ",  # sealed, the capture exiting
)
#: The kills, in rounds of captures at once; each round starts when the one before has
#: ended. The second round's start-up kills land while those captures seal the journals
#: the first round's kills left; the seal, the phase whose kill could leave a half
#: run, is aimed at three times.
ROUNDS = (
    ("Hammer away", "Hit 1: ", "1/3 accepted", "2/3 accepted"),
    (None, None, "Simulated ", "Analyzer: "),
    ("3/3 accepted", "3/3 accepted", "3/3 accepted", "sealed: "),
)
KILLS = sum(len(r) for r in ROUNDS)


def _capture(store, seed: int, env: dict[str, str], output: Path) -> subprocess.Popen:
    command = ["capture", "--sim", "--yes", "--hits", "3", "--time-scale", "0", "--seed", str(seed)]
    with open(output, "w") as out:
        return subprocess.Popen(
            [str(DAQ), *command, "--store", str(store)],
            stdout=out,
            stderr=subprocess.DEVNULL,
            stdin=subprocess.DEVNULL,
            env=env,
        )


def _phases(proc: subprocess.Popen, output: Path) -> dict[str | None, float]:
    """How long each phase of a whole capture ``proc`` lasts, seconds, by its output."""
    started = time.monotonic()
    seen: dict[str | None, float] = {None: started}
    while proc.poll() is None:
        text = output.read_text()
        for mark in MARKS[1:]:
            if mark not in seen and mark in text:
                seen[mark] = time.monotonic()
        time.sleep(0.002)
    ended = time.monotonic()
    text = output.read_text()
    assert proc.returncode == 0, text
    assert all(mark in text for mark in MARKS[1:]), text
    times = [seen.get(mark, ended) for mark in MARKS] + [ended]
    return {mark: max(times[k + 1] - times[k], 0.001) for k, mark in enumerate(MARKS)}


def _kill_in(proc: subprocess.Popen, output: Path, mark: str | None, delay_s: float) -> bool:
    """SIGKILL ``proc`` ``delay_s`` after its output shows ``mark``; whether it was alive."""
    deadline = time.monotonic() + 60
    while mark is not None and mark not in output.read_text():
        if proc.poll() is not None:  # ended: its output is whole now
            assert mark in output.read_text(), f"the capture ended before {mark!r}: {output.read_text()}"
            break
        assert time.monotonic() < deadline, f"no {mark!r} within 60 s: {output.read_text()}"
        time.sleep(0.002)
    time.sleep(delay_s)
    if proc.poll() is not None:
        return False
    proc.send_signal(signal.SIGKILL)
    return True


@pytest.mark.timeout(300)
def test_sigkill_of_a_capture_at_random_moments_leaves_only_whole_runs(tmp_path):
    store = tmp_path / "runs"
    env = {**os.environ, **ENV, "DAQ_LOCK_DIR": str(tmp_path / "locks"), "DAQ_CONFIG": str(tmp_path / "none")}
    env.pop("DAQ_DEBUG", None)
    first = _capture(store, 0, env, tmp_path / "out-0.txt")
    phase_s = _phases(first, tmp_path / "out-0.txt")  # on this machine as loaded now
    (earlier,) = store.glob("*.h5")
    earlier_sha = hashlib.sha256(earlier.read_bytes()).hexdigest()

    rng = random.Random(20261123)
    landed: list[tuple[str | None, bool]] = []
    seed = 0
    for marks in ROUNDS:
        procs, killers = [], []
        for mark in marks:
            seed += 1
            output = tmp_path / f"out-{seed}.txt"
            proc = _capture(store, seed, env, output)
            delay = rng.uniform(0.0, phase_s[mark])  # a random moment of the phase

            def kill(proc=proc, output=output, mark=mark, delay=delay) -> None:
                landed.append((mark, _kill_in(proc, output, mark, delay)))

            procs.append(proc)
            killers.append(threading.Thread(target=kill))
        for killer in killers:
            killer.start()
        for killer, proc in zip(killers, procs, strict=True):
            killer.join(90)
            proc.wait(timeout=30)
    assert len(landed) == KILLS, landed  # no kill thread failed
    finished = sum(not alive for _, alive in landed)
    # Start-up and connecting last a second or more: those kills always land mid-capture.
    assert all(alive for mark, alive in landed if mark in (None, "Simulated ")), landed
    assert KILLS - finished >= KILLS // 3, landed  # most kills land mid-capture

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
