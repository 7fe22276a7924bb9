"""Run `daq` as a user does: in-process through daq.cli.app.main, or as the real
console script in a subprocess.

In-process is the default for tests: a subprocess pays about a second of
interpreter start-up and imports per call. Keep subprocesses for what only a
real process shows: the console-script entry point, exit statuses as the shell
sees them, signals, and servers that must outlive the call.
"""

from __future__ import annotations

import contextlib
import io
import logging
import os
import subprocess
import sys
from pathlib import Path
from unittest import mock

from daq.cli.app import main

DAQ = Path(sys.executable).with_name("daq")

#: What a technician's terminal would give the rich console; run_daq and invoke_daq agree.
ENV = {"COLUMNS": "120", "NO_COLOR": "1"}


def run_daq(*args: str, timeout: float = 60, **kwargs) -> subprocess.CompletedProcess[str]:
    """The real console script in a subprocess."""
    env = {**os.environ, **ENV}
    env.pop("DAQ_DEBUG", None)
    return subprocess.run(
        [str(DAQ), *args], capture_output=True, text=True, timeout=timeout, env=env, **kwargs
    )


def invoke_daq(*args: str, env: dict[str, str | None] | None = None) -> subprocess.CompletedProcess[str]:
    """daq.cli.app.main(args) in this process, with stdout and stderr captured.

    ``env`` adds variables, or removes those given as None, for this call only.
    Fails the test if the call leaves logging or the environment changed.
    """
    changes = {**ENV, "DAQ_DEBUG": None, **(env or {})}
    root = logging.getLogger()
    handlers, level = list(root.handlers), root.level
    out, err = io.StringIO(), io.StringIO()
    with mock.patch.dict(os.environ):
        for name, value in changes.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value
        before = dict(os.environ)
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            status = main(list(args))
        assert dict(os.environ) == before, "daq changed the environment"
    assert root.handlers == handlers, "daq left a logging handler behind"
    assert root.level == level, "daq left the root logger's level changed"
    return subprocess.CompletedProcess(["daq", *args], status, out.getvalue(), err.getvalue())


def assert_one_line_error(result: subprocess.CompletedProcess[str], *fragments: str) -> None:
    """Failed with a non-zero status, exactly one line on stderr, no traceback."""
    assert result.returncode != 0, result
    lines = result.stderr.splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("daq: error: "), lines[0]
    assert "Traceback" not in result.stderr
    for fragment in fragments:
        assert fragment in lines[0], lines[0]


def capture_sim(store: Path, scenario: str, seed: int, hits: int = 5) -> str:
    """`daq capture --sim` of ``hits`` accepted hits into ``store``; the new run's id."""
    from daq.store import Store

    result = invoke_daq(
        "capture", "--sim", "--yes", "--scenario", scenario, "--seed", str(seed), "--hits", str(hits),
        "--time-scale", "0", "--store", str(store),
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    return max(s.run_id for s in Store(store).list())


def daq_json(command: str, store: Path, *args: str) -> list[dict]:
    """`daq COMMAND ARGS --json --store STORE`, which must succeed; its JSON output."""
    import json

    result = invoke_daq(command, *args, "--json", "--store", str(store))
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout)


def daq_import(store: Path, *args) -> subprocess.CompletedProcess[str]:
    """`daq import ARGS --store STORE`, in this process."""
    return invoke_daq("import", *map(str, args), "--store", str(store))


def runs_in(store: Path) -> list[str]:
    """The run ids in ``store`` ([] when it does not exist)."""
    from daq.store import Store

    return [s.run_id for s in Store(store).list()] if store.exists() else []


def refused(result: subprocess.CompletedProcess[str], store: Path, *fragments: str) -> str:
    """One line on stderr with ``fragments``, exit status 1, no run in ``store``; the line."""
    assert_one_line_error(result, *fragments)
    assert result.returncode == 1
    assert "Traceback" not in result.stderr
    assert runs_in(store) == [], "a refused import stored a run"
    return result.stderr
