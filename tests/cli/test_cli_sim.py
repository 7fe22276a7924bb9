"""`daq sim serve` and `daq sim commands` as a user runs them. A server that
serves is the real console script in a subprocess (it must outlive the call and
take signals), reached through pyvisa-py and pyserial on loopback; what fails
before serving, and `daq sim commands`, run in-process (daq.cli.app.main)."""

from __future__ import annotations

import contextlib
import os
import re
import select
import signal
import socket
import struct
import subprocess
import time

import pytest
import pyvisa
import serial

from sims.command_table import COMMANDS
from sims.instrument import Analyzer
from sims.sources import PhysicsSource
from tests.cli_helpers import DAQ, ENV, assert_one_line_error, invoke_daq

pytestmark = pytest.mark.timeout(30)

TCP_RESOURCE = re.compile(r"^TCPIP::127\.0\.0\.1::(\d+)::SOCKET$")
#: pyvisa-py's name for the pty, or the project's PROLOGIX::<port>::<GPIB address> (drivers/).
PTY_RESOURCE = re.compile(
    r"^(?:ASRL(?P<asrl>/dev/pts/\d+)::INSTR|PROLOGIX::(?P<port>/dev/pts/\d+)::(?P<addr>\d+))$"
)
SETUP = "FRS 200 HZ;TSRC CH1;TLVL 2 MV;TDLY -10 MS;STRT"
#: The ordinary stop tests give the server this long after its resource line; the
#: window right after it has a test of its own (test_signal_right_after_the_resource_line).
SETTLE_S = 0.3


def _default_sigint() -> None:
    # A child started from a shell that ignores SIGINT would inherit that; Ctrl-C
    # in a terminal reaches a server with the default disposition.
    signal.signal(signal.SIGINT, signal.SIG_DFL)


#: Injected into the child (as sitecustomize): after each flush of stdout its main
#: thread stalls, as a busy machine may stall it right after the resource line.
STALL_AFTER_STDOUT_FLUSH = """
import sys, time

class _StallAfterFlush:
    def __init__(self, stream):
        self._stream = stream

    def flush(self):
        self._stream.flush()
        time.sleep(0.5)

    def __getattr__(self, name):
        return getattr(self._stream, name)

sys.stdout = _StallAfterFlush(sys.stdout)
"""


class Server:
    """A `daq sim serve` subprocess and the resource line it printed."""

    def __init__(self, *args: str, pythonpath: str | None = None) -> None:
        env = {**os.environ, **ENV}
        env.pop("DAQ_DEBUG", None)
        if pythonpath is not None:
            env["PYTHONPATH"] = os.pathsep.join(filter(None, [pythonpath, env.get("PYTHONPATH")]))
        self.proc = subprocess.Popen(
            [str(DAQ), "sim", "serve", *args],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            env=env,
            preexec_fn=_default_sigint,
        )
        self.stdout = b""
        self.stderr = b""
        self.resource = self._read_resource_line(timeout=20)

    def _read_resource_line(self, timeout: float) -> str:
        fd = self.proc.stdout.fileno()
        deadline = time.monotonic() + timeout
        buffer = b""
        while b"\n" not in buffer:
            left = deadline - time.monotonic()
            if left <= 0:
                raise AssertionError(f"no resource line within {timeout} s: {buffer!r}")
            ready, _, _ = select.select([fd], [], [], left)
            if ready:
                chunk = os.read(fd, 4096)
                if not chunk:
                    _, err = self.proc.communicate(timeout=5)
                    raise AssertionError(f"daq sim serve ended early: {err.decode(errors='replace')}")
                buffer += chunk
        self.stdout = buffer
        line, _, rest = buffer.partition(b"\n")
        assert rest == b"", buffer
        return line.decode()

    def stop(self, signum: int, timeout: float = 10.0) -> int:
        """Send ``signum``; the exit status (a server still running after ``timeout``
        fails the test: TimeoutExpired). Output is collected."""
        self.proc.send_signal(signum)
        out, err = self.proc.communicate(timeout=timeout)
        self.stdout += out
        self.stderr += err
        return self.proc.returncode

    def close(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            with contextlib.suppress(subprocess.TimeoutExpired):
                self.proc.communicate(timeout=5)
        for pipe in (self.proc.stdout, self.proc.stderr):
            if pipe is not None:
                pipe.close()


@contextlib.contextmanager
def serving(*args: str, pythonpath: str | None = None):
    server = Server(*args, pythonpath=pythonpath)
    try:
        yield server
    finally:
        server.close()


@contextlib.contextmanager
def visa(resource: str):
    rm = pyvisa.ResourceManager("@py")
    try:
        inst = rm.open_resource(resource, read_termination="\r\n", write_termination="\n", timeout=5000)
        try:
            yield inst
        finally:
            inst.close()
    finally:
        rm.close()


def assert_stopped_cleanly(server: Server, status: int) -> None:
    """Exit 0 with "Stopped." (a hang is stop()'s timeout, not a time checked here)."""
    stderr = server.stderr.decode(errors="replace")
    assert status == 0, stderr
    assert "Stopped." in stderr.splitlines()
    assert "Traceback" not in stderr
    # The resource is the only line on stdout.
    assert server.stdout.decode().splitlines() == [server.resource]


# ------------------------------------------------------------------ serve
def test_serve_tcp_prints_its_resource_and_stops_on_sigint():
    with serving("--tcp", "0", "--time-scale", "0") as server:
        match = TCP_RESOURCE.match(server.resource)
        assert match, server.resource
        assert int(match.group(1)) > 0
        with visa(server.resource) as inst:
            assert inst.query("ID?") == "HP35660A"
            assert float(inst.query("SIM:TIME?")) == 0.0
        time.sleep(SETTLE_S)
        status = server.stop(signal.SIGINT)
        assert_stopped_cleanly(server, status)
        # The port is released.
        with pytest.raises(ConnectionRefusedError):
            socket.create_connection(("127.0.0.1", int(match.group(1))), timeout=2).close()


def test_serve_stops_on_sigterm_with_a_client_connected():
    with serving("--tcp", "0", "--time-scale", "0") as server:
        with visa(server.resource) as inst:
            assert inst.query("ID?") == "HP35660A"
            time.sleep(SETTLE_S)
            status = server.stop(signal.SIGTERM)
        assert_stopped_cleanly(server, status)


def test_serve_pty_prints_a_resource_whose_port_speaks_prologix():
    with serving("--pty", "--time-scale", "0", "--gpib-address", "7") as server:
        match = PTY_RESOURCE.match(server.resource)
        assert match, server.resource
        if match["port"]:
            assert match["addr"] == "7"
        port = serial.Serial(match["asrl"] or match["port"], baudrate=115200, timeout=3)
        try:
            port.write(b"++ver\n")
            assert port.read_until(b"\r\n") == b"Prologix GPIB-USB Controller version 6.101\r\n"
            port.write(b"++auto 0\n++read_tmo_ms 50\n++addr 11\nID?\n++read eoi\n")
            port.timeout = 0.4
            assert port.read(100) == b""  # nobody at 11: --gpib-address 7 took
            port.timeout = 3
            port.write(b"++addr 7\nID?\n++read eoi\n")
            assert port.read_until(b"\r\n") == b"HP35660A\r\n"
        finally:
            port.close()
        time.sleep(SETTLE_S)
        status = server.stop(signal.SIGINT)
        assert_stopped_cleanly(server, status)


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_signal_right_after_the_resource_line(tmp_path, signum):
    """The resource line tells a script the server is up; stopping it at once must
    still end in a clean exit 0 with "Stopped.". The child's main thread is made to
    stall just after printing (as a loaded machine may), which only widens the window."""
    (tmp_path / "sitecustomize.py").write_text(STALL_AFTER_STDOUT_FLUSH)
    with serving("--tcp", "0", "--time-scale", "0", pythonpath=str(tmp_path)) as server:
        assert TCP_RESOURCE.match(server.resource), server.resource
        status = server.stop(signum)
        assert_stopped_cleanly(server, status)


def _tim1_block(inst) -> bytes:
    inst.write(SETUP)
    assert inst.query("SMSD") == "1"
    inst.write("TIM1;DDAN")
    head = inst.read_bytes(4)
    assert head[:2] == b"#A"
    return head + inst.read_bytes(struct.unpack(">H", head[2:])[0])


def _in_process_tim1(scenario: str, seed: int) -> bytes:
    source = PhysicsSource(scenario, seed=seed)
    source.set_noise(False)
    analyzer = Analyzer(source, time_scale=0.0)
    analyzer.execute(SETUP)
    assert analyzer.execute("SMSD")[0].data == b"1\r\n"
    return analyzer.execute("TIM1;DDAN")[0].data


def test_serve_with_scenario_seed_and_no_noise():
    with serving(
        "--tcp", "0", "--time-scale", "0", "--scenario", "realistic", "--seed", "3", "--no-noise"
    ) as server:
        assert TCP_RESOURCE.match(server.resource), server.resource
        with visa(server.resource) as inst:
            assert inst.query("SIM:SCEN?") == "realistic"
            assert inst.query("SIM:NOISE?") == "0"
            served = _tim1_block(inst)
        time.sleep(SETTLE_S)
        status = server.stop(signal.SIGTERM)
        assert_stopped_cleanly(server, status)
    # Same scenario, seed and commands give the same data; the seed matters.
    assert served == _in_process_tim1("realistic", 3)
    assert served != _in_process_tim1("realistic", 0)
    banner = server.stderr.decode()
    assert "realistic" in banner
    assert "seed 3" in banner


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (("--tcp", "0", "--pty"), "--pty"),
        (("--tcp", "0", "--fault", "bogus"), "bogus"),
        (("--pty", "--gpib-address", "99"), "--gpib-address"),
        (("--tcp", "70000"), "--tcp"),
        (("--tcp", "0", "--time-scale", "-1"), "--time-scale"),
        (("--tcp", "0", "--replay", "/nonexistent.h5"), "/nonexistent.h5"),
        (("--tcp", "0", "--host", "not-an-ip"), "not-an-ip"),
    ],
)
def test_serve_rejects_bad_options_in_one_line(args, fragment):
    result = invoke_daq("sim", "serve", *args)
    assert_one_line_error(result, fragment)
    assert result.stdout == ""  # no resource was printed: nothing is served


def test_serve_on_a_port_in_use_fails_in_one_line():
    busy = socket.create_server(("127.0.0.1", 0))
    try:
        port = busy.getsockname()[1]
        result = invoke_daq("sim", "serve", "--tcp", str(port), "--time-scale", "0")
    finally:
        busy.close()
    assert_one_line_error(result, str(port))
    assert result.stdout == ""


# --------------------------------------------------------------- commands
def test_sim_commands_lists_every_mnemonic():
    result = invoke_daq("sim", "commands")
    assert result.returncode == 0, result.stderr
    listed = set()
    for line in result.stdout.splitlines():
        cells = line.split("│")
        if len(cells) > 2:
            listed.update(part.strip() for part in cells[1].split(" / ") if part.strip())
    expected = {c.mnemonic for c in COMMANDS}
    expected |= {c.mnemonic + "?" for c in COMMANDS if c.kind == "setting"}
    assert listed == expected


def test_serve_hammer_option_is_validated():
    assert_one_line_error(invoke_daq("sim", "serve", "--tcp", "0", "--hammer", "peak=3"), "--hammer")
    assert_one_line_error(invoke_daq("sim", "serve", "--tcp", "0", "--hammer", "peak_force_n=-1"), "positive")


# ------------------------------------------------------- hammer and sensor positions
def _in_process_tim2(scenario: str, seed: int, **kwargs) -> bytes:
    source = PhysicsSource(scenario, seed=seed, **kwargs)
    source.set_noise(False)
    analyzer = Analyzer(source, time_scale=0.0)
    analyzer.execute(SETUP)
    assert analyzer.execute("SMSD")[0].data == b"1\r\n"
    return analyzer.execute("TIM2;DDAN")[0].data


def _tim2_block(inst) -> bytes:
    inst.write(SETUP)
    assert inst.query("SMSD") == "1"
    inst.write("TIM2;DDAN")
    head = inst.read_bytes(4)
    assert head[:2] == b"#A"
    return head + inst.read_bytes(struct.unpack(">H", head[2:])[0])


def test_serve_with_positions_moves_the_hammer_and_sensor_and_sim_controls_move_them_again():
    with serving(
        "--tcp",
        "0",
        "--time-scale",
        "0",
        "--scenario",
        "realistic",
        "--seed",
        "4",
        "--no-noise",
        "--force-at",
        "0.3",
        "--sensor-at",
        "0.55",
    ) as server:
        with visa(server.resource) as inst:
            assert inst.query("SIM:FORCE?") == "0.3"
            assert inst.query("SIM:SENSOR?") == "0.55"
            served = _tim2_block(inst)
            # Between hits the capture moves on, point by point.
            inst.write("SIM:FORCE 0.1")
            assert inst.query("SIM:FORCE?") == "0.1"
            inst.write("SIM:SENSOR 0.9")  # off the 0.7 m beam: refused, one error, nothing moves
            assert inst.query("ERR?").startswith("3,")
            assert inst.query("ERR?") == '0,"No error"'
            assert inst.query("SIM:SENSOR?") == "0.55"
            moved = _tim2_block(inst)
        time.sleep(SETTLE_S)
        status = server.stop(signal.SIGTERM)
        assert_stopped_cleanly(server, status)
    assert served == _in_process_tim2("realistic", 4, force_at_m=0.3, sensor_at_m=0.55)
    assert served != _in_process_tim2("realistic", 4)
    assert moved != served
    assert "hammer at 0.3 m, accelerometer at 0.55 m" in server.stderr.decode()


def test_serve_with_a_damping_matrix_of_your_own(tmp_path):
    matrix = tmp_path / "r.txt"
    matrix.write_text("# N s/m\n3, 1, -0.5\n1, 2, 0.4\n-0.5, 0.4, 1.5\n")
    with serving("--tcp", "0", "--time-scale", "0", "--damping-matrix", str(matrix)) as server:
        with visa(server.resource) as inst:
            assert inst.query("SIM:SCEN?") == "custom"
            assert inst.query("SIM:DAMP?") == "3.0,1.0,-0.5,1.0,2.0,0.4,-0.5,0.4,1.5"
        time.sleep(SETTLE_S)
        status = server.stop(signal.SIGTERM)
        assert_stopped_cleanly(server, status)
    assert "scenario custom" in server.stderr.decode()


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (("--force-at", "0"), "--force-at"),
        (("--force-at", "-0.2"), "--force-at"),
        (("--sensor-at", "0.71"), "--sensor-at"),
        (("--sensor-at", "nan"), "--sensor-at"),
        (("--force-at", "tip"), "--force-at"),
        (("--damping-matrix", "1,2,3"), "9 numbers"),
        (("--damping-matrix", "1,2,0,0,1,0,0,0,1"), "symmetric"),
        (("--damping-matrix", "1,0,0,0,-2,0,0,0,1"), "positive semi-definite"),
        (("--scenario", "realistic", "--damping-matrix", "1,0,0,0,1,0,0,0,1"), "--damping-matrix"),
        (("--replay", "/nonexistent.h5", "--sensor-at", "0.3"), "--sensor-at"),
    ],
)
def test_serve_refuses_bad_positions_and_matrices_in_one_line(args, fragment):
    result = invoke_daq("sim", "serve", "--tcp", "0", "--time-scale", "0", *args)
    assert_one_line_error(result, fragment)
    assert result.returncode == 2
    assert result.stdout == ""
