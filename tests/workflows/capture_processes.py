"""Real `daq capture --sim` processes for the workflow tests that signal or kill them:
their environment, start, the hits they say were accepted, and the listing after."""

from __future__ import annotations

import json
import os
import select
import subprocess
import time
from pathlib import Path

from tests.cli_helpers import DAQ, ENV


def capture_env(tmp_path: Path) -> dict[str, str]:
    env = {**os.environ, **ENV, "DAQ_LOCK_DIR": str(tmp_path / "locks"), "DAQ_CONFIG": str(tmp_path / "none")}
    for name in ("DAQ_DEBUG", "DAQ_RESOURCE", "DAQ_STORE"):
        env.pop(name, None)
    return env


def start_capture(store: Path, env: dict[str, str], *extra: str) -> subprocess.Popen:
    # Paced (--time-scale 0.1: a hit every 0.3-0.5 s) so that a test acts between hits;
    # the 10 hits last 4 s, long after the two a test waits for.
    command = ["capture", "--sim", "--hits", "10", "--yes", "--time-scale", "0.1", "--store", str(store)]
    return subprocess.Popen(
        [str(DAQ), *command, *extra], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        stdin=subprocess.DEVNULL, env=env, text=True, bufsize=1, start_new_session=True,
    )  # fmt: skip


def wait_for_accepted(proc: subprocess.Popen, n: int, timeout_s: float = 40.0) -> list[str]:
    """Read the capture's output until ``n`` hits were accepted; the lines read."""
    lines: list[str] = []
    accepted = 0
    deadline = time.monotonic() + timeout_s
    while accepted < n and time.monotonic() < deadline:
        ready, _, _ = select.select([proc.stdout], [], [], 1.0)
        if ready:
            line = proc.stdout.readline()
            if not line:
                break
            lines.append(line)
            accepted += line.lstrip().startswith("-> accepted")
    assert accepted == n, f"{n} hits should have been accepted: {''.join(lines)}"
    return lines


def listed(store: Path, env: dict[str, str]) -> tuple[list[dict], str]:
    result = subprocess.run(
        [str(DAQ), "runs", "list", "--json", "--store", str(store)],
        capture_output=True, text=True, env=env, timeout=60,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout), result.stderr
