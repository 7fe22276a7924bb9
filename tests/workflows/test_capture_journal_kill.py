"""SIGKILL a real `daq capture --sim` at 18 random moments (nine at a time into one
store), aimed at each hit and the seal, then list the store once: no half run (every
run verifies, no journal is left), and no capture lost a hit it had said was accepted
(the capture says so only after the verdict is fsynced in its journal). Then a store
on a small real filesystem: too small for the run is refused before the first hit, and
a disk that fills during the capture keeps the journal and says where.
"""

from __future__ import annotations

import contextlib
import os
import random
import re
import signal
import subprocess
import threading
import time
from pathlib import Path

import pytest

from daq.store import open_run, verify
from tests.cli_helpers import DAQ
from tests.workflows.capture_processes import capture_env, listed, start_capture, wait_for_accepted

# 18 kills: 15 aimed at the hits and the seal (below), 3 from the start. Blind moments
# (U(0, 1 s) after "Hammer away") took 36 kills to leave about 20 incomplete runs holding
# hits, a third landing after the capture had ended; aimed, each kill lands at a random
# moment of the phase it is aimed at. Those mid-capture kills are what can catch a hit
# said accepted but not kept.
#: (what the capture prints as the phase starts, the longest it lasts here in s) per
#: phase: each of the 4 hits at --time-scale 0.05 (0.2-0.3 s here), then the seal.
PHASES = (
    ("Hammer away", 0.3),  # hit 1 taken and judged
    ("1/4 accepted", 0.25),  # hit 2, hit 1 said accepted
    ("2/4 accepted", 0.25),
    ("3/4 accepted", 0.25),
    ("4/4 accepted", 0.05),  # the run being sealed
)
AIMED = 3  # kills per phase
KILLS = AIMED * len(PHASES) + 3
AT_ONCE = 9


def _kill_when(proc: subprocess.Popen, output: Path, ready: str | None, delay_s: float) -> None:
    """SIGKILL ``proc`` ``delay_s`` after its output shows ``ready`` (None: after start)."""
    deadline = time.monotonic() + 30
    while ready is not None and ready not in output.read_text() and time.monotonic() < deadline:
        if proc.poll() is not None:
            return
        time.sleep(0.01)
    time.sleep(delay_s)
    if proc.poll() is None:
        proc.send_signal(signal.SIGKILL)


@pytest.mark.slow
@pytest.mark.timeout(240)
def test_sigkill_at_random_moments_never_loses_an_accepted_hit(tmp_path):
    """Most kills land while hits are taken, three at each hit and three at the seal (a
    random moment of it: the 4 hits at --time-scale 0.05 and the seal take about 0.9 s
    here, longer on a loaded machine), one in six anywhere from the start (start-up,
    connecting, configuring)."""
    store = tmp_path / "runs"
    env = capture_env(tmp_path)
    rng = random.Random(20261124)
    moments = [(mark, rng.uniform(0.0, span)) for mark, span in PHASES for _ in range(AIMED)]
    moments += [(None, rng.uniform(0.0, 3.0)) for _ in range(KILLS - len(moments))]
    rng.shuffle(moments)  # the phases mixed over the rounds
    outputs: dict[int, Path] = {}
    for first in range(0, KILLS, AT_ONCE):
        procs, killers = [], []
        for seed in range(first, first + AT_ONCE):
            outputs[seed] = tmp_path / f"out-{seed}.txt"
            command = [
                "capture",
                "--sim",
                "--yes",
                "--hits",
                "4",
                "--time-scale",
                "0.05",
                "--seed",
                str(seed),
            ]
            with open(outputs[seed], "w") as out:
                proc = subprocess.Popen(
                    [str(DAQ), *command, "--store", str(store)], stdout=out, stderr=subprocess.DEVNULL,
                    stdin=subprocess.DEVNULL, env=env, start_new_session=True,
                )  # fmt: skip
            procs.append(proc)
            ready, delay = moments[seed]
            killers.append(threading.Thread(target=_kill_when, args=(proc, outputs[seed], ready, delay)))
        for killer in killers:
            killer.start()
        for killer, proc in zip(killers, procs, strict=True):
            killer.join(60)
            proc.wait(30)

    runs, said = listed(store, env)  # the one listing seals every journal
    assert not [p for p in store.iterdir() if p.name.startswith(".journal-")]
    assert all(r["error"] is None for r in runs)
    by_seed = {}
    for r in runs:
        path = store / r["file"]
        assert verify(path) == [], path
        run = open_run(path)
        by_seed[run.provenance["simulator"]["seed"]] = run
        if run.complete:
            assert int(run.hits.accepted.sum()) == 4
        else:
            assert "recovered_from_journal" in run.provenance
    # (captures of later rounds recovered the journals of earlier ones as they started)
    assert said.count("recovered an interrupted capture") <= sum(not r["complete"] for r in runs)
    lost = []
    for seed, path in outputs.items():
        said_accepted = sum(line.lstrip().startswith("-> accepted") for line in path.read_text().splitlines())
        kept = int(by_seed[seed].hits.accepted.sum()) if seed in by_seed else 0
        if kept < said_accepted:
            lost.append((seed, said_accepted, kept))
    assert lost == []
    incomplete = sum(not r.complete for r in by_seed.values())
    assert incomplete >= KILLS // 6, incomplete  # kills landed mid-capture (fewer on a loaded machine)


@contextlib.contextmanager
def small_filesystem(where: Path, size: str):
    """A tmpfs of ``size`` at ``where``; skips when it cannot be mounted (not root)."""
    where.mkdir()
    result = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(where)], capture_output=True, text=True
    )
    if result.returncode != 0:
        pytest.skip(f"cannot mount a small tmpfs here: {result.stderr.strip()}")
    try:
        yield where
    finally:
        subprocess.run(["umount", "-l", str(where)], capture_output=True)


@pytest.mark.timeout(60)
def test_a_store_without_room_for_the_run_is_refused_before_the_first_hit(tmp_path):
    with small_filesystem(tmp_path / "small", "200k") as small:
        store = small / "runs"
        result = subprocess.run(
            [str(DAQ), "capture", "--sim", "--yes", "--hits", "10", "--time-scale", "0", "--store", store],
            capture_output=True, text=True, env=capture_env(tmp_path), timeout=60,
        )  # fmt: skip
        assert result.returncode == 1, result.stderr
        lines = result.stderr.splitlines()
        assert len(lines) == 1
        assert re.search(r"store .* has .* free, the run needs about", lines[0]), lines[0]
        assert "Hit 1" not in result.stdout
        assert list(store.iterdir()) == []


@pytest.mark.timeout(90)
def test_a_disk_that_fills_during_the_capture_keeps_the_journal_and_says_where(tmp_path):
    env = capture_env(tmp_path)
    with small_filesystem(tmp_path / "small", "2m") as small:
        store = small / "runs"
        proc = start_capture(store, env)
        try:
            wait_for_accepted(proc, 2)
            filler = small / "filler"
            fd = os.open(filler, os.O_WRONLY | os.O_CREAT, 0o600)
            with contextlib.suppress(OSError):
                while True:
                    os.write(fd, b"\0" * 4096)
            os.close(fd)
            _, err = proc.communicate(timeout=30)
        finally:
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGKILL)
                proc.communicate()
        assert proc.returncode == 1, err
        (line,) = err.splitlines()
        (journal,) = [p for p in store.iterdir() if p.name.startswith(".journal-")]
        assert "No space left on device" in line
        assert str(journal) in line
        assert "daq runs list" in line
        filler.unlink()
        runs, said = listed(store, env)
        assert "recovered an interrupted capture" in said
        (run,) = runs
        assert not run["complete"]
        assert run["n_accepted"] >= 2
        assert verify(store / run["file"]) == []
        assert not journal.exists()
