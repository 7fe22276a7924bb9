"""Killing `daq analyze --all` or `daq fit --all` kills its worker processes too (issue item 10).

Each command runs in a new session, so its workers are the session's other processes;
after SIGKILL of the command, none of them may be left alive a few seconds later.
"""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import time
from dataclasses import replace
from pathlib import Path

import pytest

from daq.store import Store, new_run_id, seal
from tests.cli_helpers import DAQ, ENV, capture_sim

pytestmark = pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs Linux /proc")


@pytest.fixture(scope="module")
def store(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("store")
    # Enough runs that the batch is still at work when it is killed (one run analyses in
    # well under a second): one capture, sealed again under 7 new ids. Each is a whole
    # run file the batch analyses and fits from scratch (--recompute), as much work as
    # a capture of its own, for a seal instead of a capture (8 captures took 13 s).
    store = Store(folder)
    run = store.open(capture_sim(folder, "realistic", 1, hits=5))
    for _ in range(7):
        seal(replace(run, run_id=new_run_id()), folder)
    assert len(store.list()) == 8
    return folder


def _session(sid: int) -> dict[int, tuple[int, str]]:
    """{pid: (ppid, state)} of the live (not zombie) processes of session ``sid``."""
    found = {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            text = Path(f"/proc/{entry}/stat").read_text()
        except OSError:
            continue
        fields = text[text.rindex(")") + 2 :].split()  # after "pid (comm) "
        state, ppid, session = fields[0], int(fields[1]), int(fields[3])
        if session == sid and state not in ("Z", "X"):
            found[int(entry)] = (ppid, state)
    return found


@pytest.mark.timeout(120)
@pytest.mark.parametrize("command", ["analyze", "fit"])
def test_killing_the_batch_command_kills_its_workers(store, command):
    env = {**os.environ, **ENV}
    env.pop("DAQ_SCHEDULER", None)
    args = [str(DAQ), command, "--all", "--recompute", "--jobs", "2", "--store", str(store)]
    parent = subprocess.Popen(
        args, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env, start_new_session=True
    )
    try:
        deadline = time.monotonic() + 60
        while len([p for p, (pp, _) in _session(parent.pid).items() if pp == parent.pid]) < 2:
            assert parent.poll() is None, "the command ended before its workers started"
            assert time.monotonic() < deadline, "no workers started"
            time.sleep(0.05)
        time.sleep(0.1)  # the workers are at work now
        assert parent.poll() is None, "the command ended before it could be killed"
        workers = set(_session(parent.pid)) - {parent.pid}
        os.kill(parent.pid, signal.SIGKILL)
        parent.wait(timeout=10)
        deadline = time.monotonic() + 5
        while (left := set(_session(parent.pid)) & workers) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert not left, f"workers {sorted(left)} outlived their killed parent"
    finally:
        for pid in _session(parent.pid):
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)
        if parent.poll() is None:
            parent.kill()
            parent.wait()


def test_one_hit_is_said_in_the_singular(capsys):
    from daq.cli.commands.analyze import _print

    info = {
        "run_id": "r", "kind": "captured", "source": "hits", "n_averages": 1, "estimator": "h1",
        "modes": [], "table2": {"rows": [], "beam": "none"},
    }  # fmt: skip
    _print(info)
    out = capsys.readouterr().out
    assert "(captured, 1 hit, h1)" in out, out
