"""Crash safety with real processes: a child sealing runs in a loop is killed with
SIGKILL at random moments; whatever it leaves must be whole runs or ignored temporaries."""

from __future__ import annotations

import os
import random
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from daq.store import Store, open_run, verify
from daq.store.store import is_run_file_name, is_temporary_name

HERE = Path(__file__).parent

# One process imports the store once, then forks a child per line it reads (the first
# seed of the child's runs); each child seals runs in a loop until it is killed, and the
# forking process reaps it and says how it ended. A child costs a fork, not an
# interpreter's start-up and imports (0.7 s, 50 times or more).
SEAL_FOREVER = textwrap.dedent(
    """
    import os
    import sys
    from store_helpers import make_run
    from daq.store import new_run_id, seal
    store = sys.argv[1]
    print("ready", flush=True)
    for line in iter(sys.stdin.readline, ""):
        first_seed = int(line)
        pid = os.fork()
        if pid == 0:
            runs = [make_run(seed=first_seed + i, n_hits=8, n_samples=2048) for i in range(3)]
            i = 0
            while True:
                run = runs[i % 3]
                run.run_id = new_run_id()
                seal(run, store)
                if i == 0:
                    print("sealed", os.getpid(), flush=True)
                i += 1
        _, status = os.waitpid(pid, 0)
        print("ended", pid, os.WTERMSIG(status) if os.WIFSIGNALED(status) else None, flush=True)
    """
)


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(HERE), env.get("PYTHONPATH", "")])
    return env


@pytest.mark.slow
def test_sigkill_at_random_moments_leaves_only_whole_runs(tmp_path):
    store_dir = tmp_path / "store"
    rng = random.Random(1123)
    env = _env()
    kill = 0
    forker = subprocess.Popen(
        [sys.executable, "-c", SEAL_FOREVER, str(store_dir)],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
        env=env,
    )
    pid = None
    try:
        assert forker.stdout.readline().strip() == "ready"
        # At least 50 kills, and more (up to 200) until one has landed inside a seal: how
        # often one does depends on how long the machine takes to write and fsync.
        while kill < 50 or (kill < 200 and not any(is_temporary_name(n) for n in os.listdir(store_dir))):
            kill += 1
            forker.stdin.write(f"{kill}\n")
            forker.stdin.flush()
            # Wait for one whole seal, so every child contributes a run however loaded
            # the machine is; the kill then lands at a random point of later seals.
            said, pid = forker.stdout.readline().split()
            assert said == "sealed"
            time.sleep(rng.uniform(0.0, 0.06))  # a seal of this run takes a few ms
            os.kill(int(pid), signal.SIGKILL)
            assert forker.stdout.readline().split() == ["ended", pid, str(int(signal.SIGKILL))]
            pid = None
        forker.stdin.close()
        assert forker.wait(timeout=30) == 0
    finally:
        if pid is not None:  # a failed check left a child sealing
            os.kill(int(pid), signal.SIGKILL)
        forker.kill()
        forker.wait()
        forker.stdout.close()
        if not forker.stdin.closed:
            forker.stdin.close()

    names = os.listdir(store_dir)
    runs = sorted(n for n in names if is_run_file_name(n))
    temporaries = sorted(n for n in names if is_temporary_name(n))
    assert sorted(runs + temporaries) == sorted(names)  # nothing else was left behind
    assert len(runs) >= kill  # every child sealed at least one run before its kill
    assert temporaries, "no kill landed inside a seal: the test did not test anything"
    for name in runs:
        assert verify(store_dir / name) == [], name
        assert open_run(store_dir / name).hits.n_samples == 2048

    store = Store(store_dir)
    listing = store.list()
    assert [s.file_name for s in listing] == runs
    assert all(s.error is None and s.n_hits == 8 for s in listing)
    assert store.temporaries() == [store_dir / n for n in temporaries]

    assert store.clean_temporaries(older_than_s=3600) == []  # all fresh: kept
    removed = store.clean_temporaries(older_than_s=0)
    assert removed == [store_dir / n for n in temporaries]
    assert sorted(os.listdir(store_dir)) == sorted([*runs, ".index.sqlite", *_sqlite_side_files(store_dir)])
    assert [s.file_name for s in store.list()] == runs


def _sqlite_side_files(store_dir: Path) -> list[str]:
    return [n for n in os.listdir(store_dir) if n.startswith(".index.sqlite-")]
