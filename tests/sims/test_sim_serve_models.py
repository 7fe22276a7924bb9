"""`daq sim serve --model` and `daq sim commands --model` as a user runs them."""

from __future__ import annotations

import contextlib
import os
import select
import signal
import socket
import subprocess
import time
from pathlib import Path

import h5py
import numpy as np
import pytest
import pyvisa

from sims.tcp_server import CLOSE_WAIT_S
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


# ------------------------------------------------------------ stopping with SIGTERM
#: SIGTERM to exit, at most: the stop itself takes a fraction of a second, the rest
#: is room for a loaded machine (pytest -n on two cores).
STOP_S = 5.0
SERVE_3562A = ("--analyzer", "3562A", "--tcp", "0", "--time-scale", "0", "--no-noise", "--seed", "1")


def _connect(resource: str) -> socket.socket:
    """A raw socket to the TCPIP::host::port::SOCKET resource, having asked ID? once."""
    _, host, port, _ = resource.split("::")
    sock = socket.create_connection((host, int(port)), timeout=10)
    sock.sendall(b"ID?\n")
    reply = b""
    while not reply.endswith(b"\r\n"):
        chunk = sock.recv(100)
        assert chunk, reply
        reply += chunk
    assert reply == b"HP3562A\r\n"
    return sock


def _terminate(proc: subprocess.Popen, within_s: float = STOP_S) -> bytes:
    """SIGTERM; the process's stderr once it has exited, failing if it takes over ``within_s``."""
    proc.send_signal(signal.SIGTERM)
    try:
        _, err = proc.communicate(timeout=within_s)
    except subprocess.TimeoutExpired:
        pytest.fail(f"daq sim serve still running {within_s:g} s after SIGTERM")
    return err


def test_sigterm_stops_the_server_at_once_with_an_idle_client_connected():
    with serving(*SERVE_3562A) as (resource, proc), _connect(resource) as sock:
        err = _terminate(proc)
        assert proc.returncode == 0, err
        assert err.rstrip().endswith(b"Stopped."), err
        sock.settimeout(5)
        with contextlib.suppress(ConnectionResetError):
            assert sock.recv(1) == b""  # the client sees its connection end


def test_sigterm_does_not_wait_for_a_client_thread_busy_measuring():
    """9999 averages at time scale 0 are computed in the client's thread, under the
    instrument's lock, on its next command: minutes of work that nothing interrupts.
    The stop waits CLOSE_WAIT_S for that thread (a daemon), not for the measurement."""
    with serving(*SERVE_3562A) as (resource, proc), _connect(resource) as sock:
        sock.sendall(b"PRVW 0;STBL;NAVG 9999;STRT;AVG?\n")
        time.sleep(0.5)  # the hits are being drawn and averaged
        err = _terminate(proc, CLOSE_WAIT_S + STOP_S)
        assert proc.returncode == 0, err
        assert err.rstrip().endswith(b"Stopped."), err


def _cpu_s(pid: int) -> float:
    """User and system CPU time of process ``pid`` so far, s (Linux /proc, a zombie too)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rpartition(")")[2].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads /proc")
def test_after_stopped_the_process_only_exits():
    """Once 'Stopped.' is printed, exiting costs a few hundredths of a second of CPU.

    The interpreter's teardown used to walk every object of the ~900 modules the
    simulator imports (scipy's, mostly) in its garbage collections: 0.35-0.45 s of
    CPU, which a loaded machine stretched to 5-10 s between SIGTERM and the exit (a
    flaky test_serve_each_model_over_tcp). CPU time, unlike wall time, does not
    depend on the load; reading it late only makes the test more lenient.
    """
    with serving(*SERVE_3562A) as (resource, proc), _connect(resource):
        proc.send_signal(signal.SIGTERM)
        err, deadline = b"", time.monotonic() + STOP_S
        while b"Stopped." not in err:
            ready, _, _ = select.select([proc.stderr], [], [], max(0.0, deadline - time.monotonic()))
            assert ready, f"no 'Stopped.' {STOP_S:g} s after SIGTERM: {err!r}"
            chunk = os.read(proc.stderr.fileno(), 4096)
            assert chunk, err
            err += chunk
        at_stopped = _cpu_s(proc.pid)
        # Wait for the exit without reaping: the zombie still holds its CPU times.
        while os.waitid(os.P_PID, proc.pid, os.WEXITED | os.WNOWAIT | os.WNOHANG) is None:
            assert time.monotonic() < deadline, f"still running {STOP_S:g} s after SIGTERM"
            time.sleep(0.01)
        after = _cpu_s(proc.pid) - at_stopped
        proc.communicate(timeout=STOP_S)
        assert proc.returncode == 0
        assert after < 0.15, f"{after:.2f} s of CPU between 'Stopped.' and the exit"
