"""A config file that is a FIFO, a device or huge: every command says so in one line at
once, instead of hanging (FIFO) or reading until memory runs out (/dev/zero). Issue item 12."""

from __future__ import annotations

import os
import resource
import subprocess
import sys
from pathlib import Path

import pytest

from daq.store import ConfigError
from daq.store.config import load_config

DAQ = Path(sys.executable).with_name("daq")


def _daq(config: Path, *args: str) -> subprocess.CompletedProcess[str]:
    def cap() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (1536 * 2**20,) * 2)

    env = {**os.environ, "DAQ_CONFIG": str(config), "COLUMNS": "200", "NO_COLOR": "1"}
    for name in ("DAQ_STORE", "DAQ_DEBUG"):
        env.pop(name, None)
    return subprocess.run(
        [str(DAQ), *args], capture_output=True, text=True, timeout=30, env=env, preexec_fn=cap
    )


def _fifo(tmp_path: Path) -> Path:
    path = tmp_path / "config.toml"
    os.mkfifo(path)
    return path


def _zero(tmp_path: Path) -> Path:
    path = tmp_path / "config.toml"
    path.symlink_to("/dev/zero")
    return path


def _huge(tmp_path: Path) -> Path:
    path = tmp_path / "config.toml"
    path.write_text("# " + "x" * 2**20 + "\n")  # a MiB of comment: no config file is that big
    return path


@pytest.mark.timeout(60)
@pytest.mark.parametrize(
    ("make", "words"),
    [(_fifo, "not a regular file"), (_zero, "not a regular file"), (_huge, "more than")],
    ids=["fifo", "dev-zero", "huge"],
)
def test_every_command_refuses_an_unreadable_config_file_at_once(tmp_path, make, words):
    config = make(tmp_path)
    with pytest.raises(ConfigError, match=words):
        load_config(config)
    for args in (["runs", "list"], ["config"]):
        result = _daq(config, *args)
        lines = result.stderr.splitlines()
        assert result.returncode == 1, result
        assert len(lines) == 1, result.stderr[-2000:]
        assert lines[0].startswith("daq: error: config file "), lines[0]
        assert words in lines[0], lines[0]


def test_a_symlink_to_a_regular_config_file_still_works(tmp_path):
    real = tmp_path / "real.toml"
    real.write_text('store = "/data/runs"\n')
    link = tmp_path / "config.toml"
    link.symlink_to(real)
    assert load_config(link).store == Path("/data/runs")
