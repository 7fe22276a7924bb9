"""`daq sim serve --model` and `daq sim commands --model` as a user runs them."""

from __future__ import annotations

import contextlib
import os
import select
import signal
import subprocess
import time
from pathlib import Path

import h5py
import numpy as np
import pytest
import pyvisa

from tests.cli_helpers import DAQ, ENV, assert_one_line_error, invoke_daq

pytestmark = pytest.mark.timeout(60)


@contextlib.contextmanager
def serving(*args: str):
    """A `daq sim serve` subprocess; yields the resource line it printed."""
    env = {**os.environ, **ENV}
    env.pop("DAQ_DEBUG", None)
    proc = subprocess.Popen(
        [str(DAQ), "sim", "serve", *args],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        env=env,
    )
    try:
        buffer = b""
        deadline = time.monotonic() + 30
        while b"\n" not in buffer:
            ready, _, _ = select.select([proc.stdout], [], [], max(0.0, deadline - time.monotonic()))
            assert ready, f"no resource line: {buffer!r}"
            chunk = os.read(proc.stdout.fileno(), 4096)
            assert chunk, proc.communicate(timeout=5)[1]
            buffer += chunk
        yield buffer.decode().strip(), proc
    finally:
        if proc.poll() is None:
            proc.send_signal(signal.SIGTERM)
            with contextlib.suppress(subprocess.TimeoutExpired):
                proc.communicate(timeout=10)
        if proc.poll() is None:
            proc.kill()
            proc.communicate(timeout=5)
        for pipe in (proc.stdout, proc.stderr):
            if pipe is not None:
                pipe.close()


@pytest.mark.parametrize(
    ("model", "question", "answer"),
    [
        ("35670A", "*IDN?", "HEWLETT-PACKARD,35670A,0000A00000,A.00.00"),
        ("3562A", "ID?", "HP3562A"),
        ("35660A", "ID?", "HP35660A"),
    ],
)
def test_serve_each_model_over_tcp(model, question, answer):
    with serving("--model", model, "--tcp", "0", "--time-scale", "0", "--no-noise") as (resource, proc):
        rm = pyvisa.ResourceManager("@py")
        try:
            termination = "\n" if model == "35670A" else "\r\n"
            inst = rm.open_resource(
                resource, read_termination=termination, write_termination="\n", timeout=5000
            )
            try:
                assert inst.query(question) == answer
            finally:
                inst.close()
        finally:
            rm.close()
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=10)
        assert f"Simulated HP {model} (".encode() in err
        assert proc.returncode == 0


def test_the_default_model_is_the_35660a():
    with serving("--tcp", "0", "--time-scale", "0") as (_, proc):
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=10)
        assert b"Simulated HP 35660A (" in err


@pytest.mark.parametrize("command", ["serve", "commands"])
def test_a_bad_model_is_one_line_and_exit_2(command):
    result = invoke_daq("sim", command, "--model", "35661A")
    assert_one_line_error(result, "--model", "35661A", "35670A")
    assert result.returncode == 2
    assert result.stdout == ""


def test_commands_lists_the_models_table():
    scpi = invoke_daq("sim", "commands", "--model", "35670A")
    assert scpi.returncode == 0, scpi.stderr
    for fragment in ("HP 35670A command set (SCPI subset)", "SENS:FREQ:SPAN", "CALC1:DATA?", "peer", "std"):
        assert fragment in scpi.stdout
    mnemonic = invoke_daq("sim", "commands", "--model", "3562a")
    assert mnemonic.returncode == 0, mnemonic.stderr
    assert "HP 3562A command set" in mnemonic.stdout
    assert "replies HP3562A" in mnemonic.stdout
    assert "100 kHz / 2^n" in mnemonic.stdout
    assert "replies HP35660A" in invoke_daq("sim", "commands").stdout


def _minimal_run(path: Path, n_samples: int, rate_hz: float) -> Path:
    """A hand-made run as docs/simulator.md (replay) describes it."""
    rng = np.random.default_rng(1)
    with h5py.File(path, "w") as f:
        hits = f.create_group("entry").create_group("hits")
        hits.create_dataset("force", data=rng.normal(size=(2, n_samples)))
        hits.create_dataset("response", data=rng.normal(size=(2, n_samples)))
        hits.create_dataset("time", data=np.arange(n_samples) / rate_hz)
    return path


def test_a_replay_of_another_record_length_is_refused_in_one_line(tmp_path):
    run = _minimal_run(tmp_path / "run.h5", 1024, 512.0)
    result = invoke_daq("sim", "serve", "--model", "3562A", "--replay", str(run), "--tcp", "0")
    assert_one_line_error(result, "--replay", "2048")
    assert result.returncode == 2
    assert result.stdout == ""


def test_a_35670a_serves_a_35660a_recording_at_400_lines(tmp_path):
    run = _minimal_run(tmp_path / "run.h5", 1024, 512.0)
    args = ("--model", "35670A", "--replay", str(run), "--tcp", "0", "--time-scale", "0")
    with serving(*args) as (resource, proc):
        rm = pyvisa.ResourceManager("@py")
        try:
            inst = rm.open_resource(resource, read_termination="\n", write_termination="\n", timeout=5000)
            try:
                inst.write("SENS:FREQ:SPAN 200 HZ")
                inst.write("INIT:IMM")
                assert inst.query("*OPC?") == "1"
                assert inst.query("SENS:AVER:COUN:INT?") == "1"
                assert inst.query("SYST:ERR?") == '+0,"No error"'
            finally:
                inst.close()
        finally:
            rm.close()
        proc.send_signal(signal.SIGTERM)
        proc.communicate(timeout=10)
