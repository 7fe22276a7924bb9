"""Run the real `daq` console script in a subprocess."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

DAQ = Path(sys.executable).with_name("daq")


def run_daq(*args: str, timeout: float = 60, **kwargs) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "COLUMNS": "120", "NO_COLOR": "1"}
    env.pop("DAQ_DEBUG", None)
    return subprocess.run(
        [str(DAQ), *args], capture_output=True, text=True, timeout=timeout, env=env, **kwargs
    )


def assert_one_line_error(result: subprocess.CompletedProcess[str], *fragments: str) -> None:
    """Failed with a non-zero status, exactly one line on stderr, no traceback."""
    assert result.returncode != 0, result
    lines = result.stderr.splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("daq: error: "), lines[0]
    assert "Traceback" not in result.stderr
    for fragment in fragments:
        assert fragment in lines[0], lines[0]
