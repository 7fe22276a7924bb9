"""`daq runs list/show/verify` never print control characters from a run file.

A run written elsewhere (another tool, an older version, a hand-edited file) may carry
terminal escapes in its operator, note or reject reasons: `--operator $'\\e]0;OWNED\\a'`
retitles the terminal, `$'\\e[2J'` clears it. The CLI prints them escaped (``\\x1b``),
on a terminal (a pty, where rich draws the table) and into a pipe; --json carries them
as JSON escapes. The run is written through the store's API, as a foreign tool would.
"""

from __future__ import annotations

import dataclasses
import json
import os
import pty
import re
import select
import subprocess
import time

import pytest

from daq.store import seal
from tests.cli.run_files import make_run
from tests.cli_helpers import DAQ, ENV

RUN_ID = "20261123T101503.123Z-0000aaaa"
OPERATOR = "\x1b]0;OWNED\x07"
NOTE = "\x1b[2J\x9b31m cleared"
REASON = "\x1b[31mdouble\x07 hit\x08"

#: Bytes that must never reach the terminal: ESC, BEL, BS, and the C1 CSI in UTF-8.
FORBIDDEN = (b"\x1b", b"\x07", b"\x08", "\x9b".encode())


@pytest.fixture
def store(tmp_path):
    run = make_run(RUN_ID)
    run.operator = OPERATOR
    run.note = NOTE
    reasons = [str(r) for r in run.hits.reject_reason]
    run.hits = dataclasses.replace(run.hits, reject_reason=[*reasons[:-1], REASON])
    path = tmp_path / "store"
    seal(run, path)
    return path


def _env(tmp_path) -> dict[str, str]:
    env = {**os.environ, **ENV, "DAQ_CONFIG": str(tmp_path / "absent.toml")}
    for name in ("DAQ_DEBUG", "DAQ_STORE", "NO_COLOR"):
        env.pop(name, None)
    return env


def _piped(tmp_path, *args: str) -> bytes:
    result = subprocess.run([str(DAQ), *args], capture_output=True, env=_env(tmp_path), timeout=60)
    assert result.returncode == 0, result.stderr
    return result.stdout + result.stderr


def _on_a_terminal(tmp_path, *args: str) -> bytes:
    """What `daq ...` writes to a terminal (a pty as its stdout and stderr)."""
    main, secondary = pty.openpty()
    env = {**_env(tmp_path), "TERM": "xterm-256color", "COLUMNS": "200"}
    env.pop("NO_COLOR", None)
    proc = subprocess.Popen([str(DAQ), *args], stdout=secondary, stderr=secondary, env=env)
    os.close(secondary)
    out = bytearray()
    deadline = time.monotonic() + 60
    try:
        while time.monotonic() < deadline:
            ready, _, _ = select.select([main], [], [], 0.5)
            if ready:
                try:
                    chunk = os.read(main, 65536)
                except OSError:  # EIO: the process closed the terminal
                    break
                if not chunk:
                    break
                out += chunk
            elif proc.poll() is not None:
                break
    finally:
        os.close(main)
        proc.wait(10)
    assert proc.returncode == 0, bytes(out)
    return bytes(out)


def _assert_clean(output: bytes, what: str) -> None:
    for byte in FORBIDDEN:
        assert byte not in output, (what, byte, output)
    assert b"\\x1b" in output, (what, output)  # shown, escaped: not dropped


@pytest.mark.parametrize("command", [("runs", "show", RUN_ID), ("runs", "verify")])
def test_show_and_verify_print_no_control_characters(tmp_path, store, command):
    output = _piped(tmp_path, *command, "--store", str(store))
    if command[1] == "show":
        _assert_clean(output, command)
        text = output.decode()
        assert "operator      \\x1b]0;OWNED\\x07" in text, text
        assert "rejected: \\x1b[31mdouble\\x07 hit\\x08" in text, text
    else:
        for byte in FORBIDDEN:
            assert byte not in output, output


def test_list_prints_no_control_characters_into_a_pipe(tmp_path, store):
    _assert_clean(_piped(tmp_path, "runs", "list", "--store", str(store)), "list | cat")


def test_list_and_show_print_no_control_characters_on_a_terminal(tmp_path, store):
    listing = _on_a_terminal(tmp_path, "runs", "list", "--store", str(store))
    # rich may colour its own header on a terminal: its escapes are SGR sequences that
    # end in "m" and hold nothing of ours. Those aside, no ESC, BEL or BS at all.
    ours = re.sub(rb"\x1b\[[0-9;]*m", b"", listing)
    _assert_clean(ours, "list on a terminal")
    assert b"OWNED" in ours, listing
    shown = _on_a_terminal(tmp_path, "runs", "show", RUN_ID, "--store", str(store))
    _assert_clean(shown, "show on a terminal")


def test_json_carries_the_text_escaped_and_whole(tmp_path, store):
    result = subprocess.run(
        [str(DAQ), "runs", "show", RUN_ID, "--json", "--store", str(store)],
        capture_output=True,
        env=_env(tmp_path),
        timeout=60,
    )
    assert result.returncode == 0, result.stderr
    for byte in FORBIDDEN:
        assert byte not in result.stdout, result.stdout
    data = json.loads(result.stdout)
    assert data["operator"] == OPERATOR
    assert data["note"] == NOTE
    assert data["hits"]["hits"][-1]["reject_reason"] == REASON
