"""Ctrl-C (SIGINT) in a real `daq capture --sim`: the hits taken so far are sealed as
an incomplete run, the one-line message says where, and the exit status is 130."""

from __future__ import annotations

import os
import re
import select
import signal
import subprocess
import time

import pytest

from daq.store import Store
from tests.cli_helpers import DAQ, ENV


@pytest.mark.timeout(60)
@pytest.mark.parametrize(
    "second_press_s", [None, 0.0, 0.01, 0.2], ids=["once", "twice-0ms", "twice-10ms", "twice-200ms"]
)
def test_ctrl_c_keeps_the_hits_so_far_as_an_incomplete_run(tmp_path, second_press_s):
    """Once, or twice in quick succession (a second Ctrl-C while the hits are sealed
    must not lose them, nor print a traceback)."""
    store = tmp_path / "runs"
    env = {**os.environ, **ENV, "DAQ_LOCK_DIR": str(tmp_path / "locks"), "DAQ_CONFIG": str(tmp_path / "none")}
    env.pop("DAQ_DEBUG", None)
    # Paced (time scale 0.1: a hit every 0.3-0.5 s) so that hits arrive while we watch.
    command = ["capture", "--sim", "--yes", "--hits", "50", "--time-scale", "0.1", "--store", str(store)]
    # A shell starts background jobs with SIGINT ignored and children inherit that;
    # restore the default so that this test works however pytest itself was started.
    proc = subprocess.Popen(
        [str(DAQ), *command], stdout=subprocess.PIPE, stderr=subprocess.PIPE, stdin=subprocess.DEVNULL,
        env=env, text=True, bufsize=1, preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )  # fmt: skip
    decided = 0
    deadline = time.monotonic() + 40
    while decided < 2 and time.monotonic() < deadline:
        ready, _, _ = select.select([proc.stdout], [], [], 1.0)
        if ready:
            line = proc.stdout.readline()
            decided += line.lstrip().startswith("-> ")
    assert decided == 2, "two hits should have been decided"
    proc.send_signal(signal.SIGINT)
    if second_press_s is not None:
        time.sleep(second_press_s)
        if proc.poll() is None:
            proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=20)
    assert proc.returncode == 130, err
    lines = err.splitlines()
    assert len(lines) == 1, err
    match = re.search(r"interrupted; (\d+) hits kept as incomplete run (\S+) in (\S+\.h5)", lines[0])
    assert match, lines[0]
    (summary,) = Store(store).list()
    assert summary.run_id == match.group(2)
    assert not summary.complete
    assert summary.n_hits == int(match.group(1)) >= 2
    assert Store(store).verify(summary.run_id) == []
    assert Store(store).temporaries() == []
