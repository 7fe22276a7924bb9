"""The transports against real parts: the simulator's TCP server through pyvisa-py,
its Prologix controller on a real pseudo-terminal through pyserial, and its
in-process link; real lock files, real subprocesses, real signals.

Every address is 127.0.0.1 or a local pty. Lock files go to a per-test directory
($DAQ_LOCK_DIR).
"""

from __future__ import annotations

import contextlib
import logging
import os
import select
import signal
import socket
import struct
import subprocess
import sys
import threading
import time
import tty
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from drivers.errors import ConnectionFailed, ConnectionLost, DriverError, InstrumentTimeout, ResourceBusy
from drivers.hp_mnemonic import HPMnemonicAnalyzer as HP35660A
from drivers.locking import ResourceLock
from drivers.loopback import LoopbackTransport
from drivers.prologix_transport import PrologixTransport, escape, parse_resource
from drivers.resources import list_resources, open_transport
from drivers.transport import Transport
from drivers.visa_transport import VisaTransport
from sims.inprocess import InProcessConnection
from sims.instrument import Analyzer
from sims.prologix import PrologixPty
from sims.sources import PhysicsSource
from sims.tcp_server import TcpServer

pytestmark = pytest.mark.timeout(20)

ROOT = Path(__file__).resolve().parents[2]
KINDS = ("visa", "prologix", "loopback")
LOCKED_KINDS = ("visa", "prologix")
#: A measurement that completes at once at time scale 0 (then TIM1 holds a record).
SETUP = b"FRS 200 HZ;TSRC CH1;TLVL 2 MV;TDLY -10 MS;STRT"
#: TIM1 dump: #A, 2-byte count of (66 header + 1024 points) x 8 bytes = 8720.
TIM1_HEAD = b"#A\x22\x10"
TIM1_BYTES = 8720
#: A read that times out ends no earlier than timeout_s less this (the clock's grain);
#: how late it may end is not timed: the timeout mark ends a read that hangs.
EARLY_S = 0.05


# ---------------------------------------------------------------- fixtures
def make_analyzer() -> Analyzer:
    source = PhysicsSource("seed", seed=0)
    source.set_noise(False)
    return Analyzer(source, time_scale=0.0)


@dataclass
class Endpoint:
    kind: str
    resource: str
    make: Callable[..., Transport]  # make(timeout_s=...) -> a closed transport


@pytest.fixture
def lock_dir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    path = tmp_path / "locks"
    monkeypatch.setenv("DAQ_LOCK_DIR", str(path))
    return path


@contextlib.contextmanager
def serve(kind: str) -> Iterator[Endpoint]:
    analyzer = make_analyzer()
    if kind == "visa":
        with TcpServer(analyzer) as server:
            assert server.host == "127.0.0.1"
            resource = server.resource
            yield Endpoint(kind, resource, lambda timeout_s=2.0: VisaTransport(resource, timeout_s))
    elif kind == "prologix":
        with PrologixPty(analyzer) as pty:
            resource = f"PROLOGIX::{pty.port}::11"
            yield Endpoint(kind, resource, lambda timeout_s=2.0: PrologixTransport(resource, timeout_s))
    else:
        yield Endpoint(
            kind,
            "LOOPBACK",
            lambda timeout_s=2.0: LoopbackTransport(
                lambda: InProcessConnection(analyzer), timeout_s=timeout_s
            ),
        )


@pytest.fixture(params=KINDS)
def endpoint(request: pytest.FixtureRequest, lock_dir: Path) -> Iterator[Endpoint]:
    with serve(request.param) as ep:
        yield ep


@pytest.fixture(params=LOCKED_KINDS)
def locked_endpoint(request: pytest.FixtureRequest, lock_dir: Path) -> Iterator[Endpoint]:
    with serve(request.param) as ep:
        yield ep


@contextlib.contextmanager
def opened(ep: Endpoint, timeout_s: float = 2.0) -> Iterator[Transport]:
    transport = ep.make(timeout_s=timeout_s)
    transport.open()
    try:
        yield transport
    finally:
        transport.close()


def assert_lock_free(resource: str) -> None:
    """Nobody, in this process or another, holds the lock file of ``resource``."""
    kind = PrologixTransport if resource.upper().startswith("PROLOGIX::") else VisaTransport
    lock = ResourceLock(kind(resource).lock_key)  # constructing does not open
    lock.acquire()
    lock.release()


def ask(transport: Transport, message: bytes) -> bytes:
    transport.write(message)
    return transport.read_line()


def timed(action: Callable[[], object]) -> tuple[Exception | None, float]:
    """(the exception ``action`` raised or None, seconds it took)."""
    start = time.monotonic()
    try:
        action()
    except Exception as exc:
        return exc, time.monotonic() - start
    return None, time.monotonic() - start


# ---------------------------------------------------------------- bytes both ways
def test_write_and_read_line(endpoint: Endpoint):
    with opened(endpoint) as t:
        assert t.is_open
        assert ask(t, b"ID?") == b"HP35660A"  # CR LF stripped
        t.write(b"FRS 400 HZ")
        reply = ask(t, b"FRS?")
        assert b"\r" not in reply
        assert b"\n" not in reply
        assert float(reply) == 400.0
        # two replies to one message come as two lines
        t.write(b"ID?;TRC?")
        assert t.read_line() == b"HP35660A"
        assert t.read_line() == b"A"


def test_read_exact_a_binary_block(endpoint: Endpoint):
    with opened(endpoint) as t:
        t.write(SETUP)
        t.write(b"TRCA;TIM1;DDAN")
        head = t.read_exact(4)
        assert head == TIM1_HEAD
        payload = t.read_exact(TIM1_BYTES)
        assert len(payload) == TIM1_BYTES
        values = np.frombuffer(payload, dtype=">f8")
        # Header words as documented (docs/instrument.md): 0 display function (6 input
        # time ch1), 1 elements, 7 domain (0 time), 10 x units (4 s).
        assert values[0] == 6.0
        assert values[1] == 1024.0
        assert values[7] == 0.0
        assert values[10] == 4.0
        assert np.all(np.isfinite(values))
        # nothing stray after the block: the next reply is the next reply
        assert ask(t, b"ID?") == b"HP35660A"


def test_read_exact_in_small_pieces(endpoint: Endpoint):
    with opened(endpoint) as t:
        t.write(b"ID?")
        pieces = [t.read_exact(1), t.read_exact(3), t.read_exact(6)]
        assert pieces == [b"H", b"P35", b"660A\r\n"]
        t.write(b"DSAN")
        assert t.read_exact(2) == b"#A"
        (length,) = struct.unpack(">H", t.read_exact(2))
        assert length == 96 * 8  # the 96-value state dump
        state = [struct.unpack(">d", t.read_exact(8))[0] for _ in range(96)]
        assert state[0] == 102400.0  # word 0: the span, preset to the widest
        assert ask(t, b"TRC?") == b"A"


@pytest.mark.parametrize("read", ["line", "exact"])
def test_read_with_nothing_pending_times_out_in_seconds(endpoint: Endpoint, read: str):
    with opened(endpoint, timeout_s=0.4) as t:
        assert ask(t, b"ID?") == b"HP35660A"
        exc, elapsed = timed(t.read_line if read == "line" else lambda: t.read_exact(4))
        assert isinstance(exc, InstrumentTimeout), exc
        assert "\n" not in str(exc)
        assert elapsed >= 0.4 - EARLY_S  # it waited out its timeout
        # a timeout leaves the link usable
        assert ask(t, b"ID?") == b"HP35660A"


def test_timeout_changed_on_an_open_transport(endpoint: Endpoint):
    # Opened with an hour: were the new timeout ignored, the read would hang until the
    # timeout mark ends the test.
    with opened(endpoint, timeout_s=3600.0) as t:
        t.timeout_s = 0.25
        exc, elapsed = timed(t.read_line)
        assert isinstance(exc, InstrumentTimeout), exc
        assert elapsed >= 0.25 - EARLY_S
        with pytest.raises(ValueError, match="positive"):
            t.timeout_s = 0


def test_short_reply_to_read_exact_times_out(endpoint: Endpoint):
    with opened(endpoint, timeout_s=0.4) as t:
        t.write(b"ID?")  # 10 bytes come, 20 are asked for
        exc, elapsed = timed(lambda: t.read_exact(20))
        assert isinstance(exc, InstrumentTimeout), exc
        assert elapsed >= 0.4 - EARLY_S  # it waited out its timeout


def test_a_reply_slower_than_a_second_still_arrives_within_the_timeout(endpoint: Endpoint):
    """timeout_s is the transport's promise: a reply that comes after 1 s is read
    when timeout_s is 2.5 s (the Prologix controller's own ++read_tmo_ms is 0.5 s)."""
    with opened(endpoint, timeout_s=2.5) as t:
        t.write(b"SIM:FAULT slow,delay=1.0,count=1")
        t.write(b"ID?")
        start = time.monotonic()
        assert t.read_line() == b"HP35660A"  # no InstrumentTimeout: the wait went on past 1 s
        assert time.monotonic() - start >= 0.9  # the reply really was that slow


def test_a_reply_slower_than_the_timeout_times_out_on_time(endpoint: Endpoint):
    with opened(endpoint, timeout_s=0.4) as t:
        t.write(b"SIM:FAULT slow,delay=5,count=1")
        t.write(b"ID?")
        exc, elapsed = timed(t.read_line)
        assert isinstance(exc, InstrumentTimeout), exc
        assert elapsed >= 0.4 - EARLY_S  # it waited out its timeout


def test_timeout_must_be_positive():
    with pytest.raises(ValueError, match="positive"):
        LoopbackTransport(lambda: None, timeout_s=0)
    with pytest.raises(ValueError, match="positive"):
        VisaTransport("TCPIP::127.0.0.1::1::SOCKET", timeout_s=-1, lock_file=False)


# ---------------------------------------------------------------- clear, reconnect
def test_clear_right_after_a_query_leaves_no_stale_reply(endpoint: Endpoint):
    with opened(endpoint, timeout_s=1.0) as t:
        t.write(b"FRS 400 HZ")
        t.write(b"ID?")
        t.clear()
        t.write(b"FRS?")
        assert float(t.read_line()) == 400.0


def test_clear_after_the_reply_arrived_leaves_no_stale_reply(endpoint: Endpoint):
    with opened(endpoint, timeout_s=1.0) as t:
        t.write(b"ID?")
        time.sleep(0.2)  # the reply is on its way or waiting in a buffer
        t.clear()
        assert ask(t, b"TRC?") == b"A"


def test_clear_after_half_the_replies_were_read(endpoint: Endpoint):
    with opened(endpoint, timeout_s=0.5) as t:
        t.write(b"ID?;FRS?;AVG?")
        assert t.read_line() == b"HP35660A"
        t.clear()
        assert ask(t, b"TRC?") == b"A"
        exc, _ = timed(t.read_line)  # and nothing else is left
        assert isinstance(exc, InstrumentTimeout), exc


def test_clear_in_the_middle_of_a_binary_block(endpoint: Endpoint):
    with opened(endpoint, timeout_s=1.0) as t:
        t.write(SETUP)
        t.write(b"TRCA;TIM1;DDAN")
        assert t.read_exact(4) == TIM1_HEAD
        t.read_exact(100)
        t.clear()
        assert ask(t, b"ID?") == b"HP35660A"


def test_reconnect(endpoint: Endpoint):
    with opened(endpoint) as t:
        t.write(b"FRS 800 HZ")
        assert ask(t, b"ID?") == b"HP35660A"
        for _ in range(2):
            t.reconnect()
            assert t.is_open
            assert float(ask(t, b"FRS?")) == 800.0  # the same instrument, a fresh link


@pytest.mark.parametrize("kind", ["visa", "loopback"])
def test_reconnect_drops_a_pending_reply(kind: str, lock_dir: Path):
    """A fresh link is a clean slate (VisaTransport's device clear of a socket relies
    on it). Not asked of Prologix: the instrument behind the adapter keeps its output."""
    with serve(kind) as ep, opened(ep, timeout_s=1.0) as t:
        t.write(b"ID?")
        time.sleep(0.1)
        t.reconnect()
        assert ask(t, b"TRC?") == b"A"


def test_write_after_close_is_connection_lost(endpoint: Endpoint):
    t = endpoint.make()
    t.open()
    t.close()
    t.close()  # twice is fine
    assert not t.is_open
    with pytest.raises(ConnectionLost):
        t.write(b"ID?")


def test_loopback_link_dropped_by_the_instrument_is_connection_lost():
    analyzer = make_analyzer()
    t = LoopbackTransport(lambda: InProcessConnection(analyzer, faults=["drop"]), timeout_s=1.0)
    with t:
        t.write(SETUP)
        t.write(b"TRCA;TIM1;DDAN")
        assert t.read_exact(4) == TIM1_HEAD
        with pytest.raises(ConnectionLost):
            t.read_exact(TIM1_BYTES)
        t.reconnect()
        assert ask(t, b"ID?") == b"HP35660A"


# ---------------------------------------------------------------- the thread lock
@pytest.mark.timeout(30)
def test_two_threads_on_one_driver_never_get_each_others_replies(endpoint: Endpoint):
    with opened(endpoint, timeout_s=2.0) as t:
        driver = HP35660A(t, retries=0)  # no retry may paper over a mix-up
        driver.send("FRS 400 HZ")
        rounds = 100
        barrier = threading.Barrier(2)
        results: dict[str, list[str]] = {"ID?": [], "FRS?": []}
        failures: list[BaseException] = []

        def worker(query: str) -> None:
            try:
                barrier.wait(timeout=5)
                for _ in range(rounds):
                    results[query].append(driver.query(query))
            except BaseException as exc:
                failures.append(exc)

        threads = [threading.Thread(target=worker, args=(q,), daemon=True) for q in results]
        switch = sys.getswitchinterval()
        sys.setswitchinterval(1e-5)  # switch threads often: a missing lock shows
        try:
            for thread in threads:
                thread.start()
            for thread in threads:
                thread.join(25)
        finally:
            sys.setswitchinterval(switch)
        assert not any(thread.is_alive() for thread in threads)
        assert failures == []
        assert results["ID?"] == ["HP35660A"] * rounds
        assert len(results["FRS?"]) == rounds
        assert all(float(reply) == 400.0 for reply in results["FRS?"])


# ---------------------------------------------------------------- lock files
HOLD_SCRIPT = """
import os, sys, time
from drivers.resources import open_transport
transport = open_transport(sys.argv[1], timeout_s=2.0)
transport.write(b"ID?")
assert transport.read_line() == b"HP35660A"
print("holding", os.getpid(), flush=True)
time.sleep(60)
"""

TRY_SCRIPT = """
import sys
from drivers.errors import ResourceBusy
from drivers.resources import open_transport
try:
    transport = open_transport(sys.argv[1], timeout_s=2.0)
except ResourceBusy as exc:
    print("busy:", exc, flush=True)
    sys.exit(3)
transport.write(b"ID?")
print("opened:", transport.read_line().decode(), flush=True)
transport.close()
"""


def run_try(resource: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-c", TRY_SCRIPT, resource],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=15,
        check=False,
    )


@contextlib.contextmanager
def holder(resource: str) -> Iterator[subprocess.Popen[str]]:
    """A subprocess that opens ``resource`` and holds it until killed."""
    proc = subprocess.Popen(
        [sys.executable, "-c", HOLD_SCRIPT, resource],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        ready, _, _ = select.select([proc.stdout], [], [], 10)
        assert ready, "the holding process did not report in"
        line = proc.stdout.readline()
        assert line == f"holding {proc.pid}\n", (line, proc.stderr.read() if proc.poll() is not None else "")
        yield proc
    finally:
        if proc.poll() is None:
            proc.send_signal(signal.SIGKILL)
        proc.wait(5)
        proc.stdout.close()
        proc.stderr.close()


def test_second_transport_in_the_same_process_is_busy(locked_endpoint: Endpoint, lock_dir: Path):
    with opened(locked_endpoint) as first:
        second = locked_endpoint.make()
        with pytest.raises(ResourceBusy) as info:
            second.open()
        assert "in use by this process" in str(info.value)
        assert locked_endpoint.resource in str(info.value)
        assert not second.is_open
        # the refused one disturbed nothing
        assert ask(first, b"ID?") == b"HP35660A"
        assert len(list(lock_dir.iterdir())) == 1
    with opened(locked_endpoint) as again:  # closed: free again
        assert ask(again, b"ID?") == b"HP35660A"


@pytest.mark.timeout(40)
def test_second_process_is_busy_while_we_hold_it(locked_endpoint: Endpoint):
    with opened(locked_endpoint) as first:
        proc = run_try(locked_endpoint.resource)
        assert proc.returncode == 3, proc.stderr
        assert proc.stdout.startswith("busy: ")
        assert f"pid {os.getpid()}" in proc.stdout
        assert ask(first, b"ID?") == b"HP35660A"
    proc = run_try(locked_endpoint.resource)  # after close, the other process gets in
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout == "opened: HP35660A\n"


@pytest.mark.timeout(40)
def test_lock_of_a_killed_process_is_free_again(locked_endpoint: Endpoint):
    with holder(locked_endpoint.resource) as proc:
        with pytest.raises(ResourceBusy) as info:
            locked_endpoint.make().open()
        assert f"pid {proc.pid}" in str(info.value)
        proc.send_signal(signal.SIGKILL)
        assert proc.wait(5) == -signal.SIGKILL
    # no clean-up ran in the killed process; the kernel dropped its lock
    with opened(locked_endpoint) as t:
        assert ask(t, b"ID?") == b"HP35660A"


@pytest.mark.parametrize("other_name", ["prologix::{port}::11", "PROLOGIX::{port}::12"])
def test_one_serial_port_is_one_lock_whatever_the_name(other_name: str, lock_dir: Path):
    """parse_resource takes the prefix in any case, and one adapter is one byte
    stream whatever GPIB address is asked for: a second name for the same serial
    port must not let a second user onto it."""
    with PrologixPty(make_analyzer()) as pty, PrologixTransport(f"PROLOGIX::{pty.port}::11", 1.0) as first:
        second = PrologixTransport(other_name.format(port=pty.port), 1.0)
        try:
            with pytest.raises(ResourceBusy):
                second.open()
        finally:
            second.close()
        assert ask(first, b"ID?") == b"HP35660A"


def test_reconnect_keeps_the_lock(locked_endpoint: Endpoint):
    with opened(locked_endpoint) as t:
        t.reconnect()
        with pytest.raises(ResourceBusy):
            ResourceLock(t.lock_key).acquire()
        assert ask(t, b"ID?") == b"HP35660A"


def test_lock_is_released_when_a_reconnect_fails(lock_dir: Path):
    """The server goes away, the reconnect fails, the application closes the
    transport: the lock file must be free again (not held until the process exits)."""
    server = TcpServer(make_analyzer()).start()
    t = VisaTransport(server.resource, timeout_s=1.0)
    try:
        t.open()
        server.close()
        with pytest.raises(ConnectionFailed):
            t.reconnect()
        t.close()
        assert_lock_free(server.resource)  # ResourceBusy here: the failed reconnect leaked it
    finally:
        t.close()
        server.close()


# ---------------------------------------------------------------- the wire log
def wire_messages(caplog: pytest.LogCaptureFixture) -> list[str]:
    return [r.getMessage() for r in caplog.records if r.name == "drivers.wire"]


def test_every_message_is_logged_at_debug(endpoint: Endpoint, caplog: pytest.LogCaptureFixture):
    caplog.set_level(logging.DEBUG, logger="drivers.wire")
    with opened(endpoint) as t:
        assert ask(t, b"ID?") == b"HP35660A"
        t.write(b"DSAN")
        t.read_exact(4)
    messages = wire_messages(caplog)
    assert all(r.levelno == logging.DEBUG for r in caplog.records if r.name == "drivers.wire")
    res = endpoint.resource
    assert f"{res} -> b'ID?'" in messages
    assert f"{res} <- b'HP35660A'" in messages
    assert f"{res} -> b'DSAN'" in messages
    assert f"{res}: opened" in messages
    assert f"{res}: closed" in messages


def test_binary_blocks_are_summarised_in_the_log(endpoint: Endpoint, caplog: pytest.LogCaptureFixture):
    caplog.set_level(logging.DEBUG, logger="drivers.wire")
    with opened(endpoint) as t:
        t.write(SETUP)
        t.write(b"TRCA;TIM1;DDAN")
        whole = t.read_exact(4 + TIM1_BYTES)  # head and payload in one read
        assert whole.startswith(TIM1_HEAD)
        t.write(b"TRCA;TIM1;DDAN")
        t.read_exact(4)
        t.read_exact(TIM1_BYTES)  # the payload alone does not start with '#'
    messages = wire_messages(caplog)
    assert max(len(m) for m in messages) < 700
    assert sum(f"{4 + TIM1_BYTES} bytes" in m for m in messages) == 1
    assert sum(f"{TIM1_BYTES} bytes" in m for m in messages) == 1


# ---------------------------------------------------------------- unreachable resources
def assert_one_line_failure(exc: BaseException, *words: str) -> None:
    assert isinstance(exc, ConnectionFailed), repr(exc)
    text = str(exc)
    assert text
    assert "\n" not in text
    assert len(text) < 200 + 2 * sum(len(w) for w in words)
    for word in words:
        assert word in text


@pytest.fixture
def dead_tcp_port() -> Iterator[int]:
    """A loopback port that is bound (so nobody else takes it) but not listening."""
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        yield sock.getsockname()[1]


def test_tcp_port_with_nothing_listening(dead_tcp_port: int, lock_dir: Path):
    resource = f"TCPIP::127.0.0.1::{dead_tcp_port}::SOCKET"
    exc, _ = timed(lambda: open_transport(resource, timeout_s=2.0))
    assert_one_line_failure(exc, resource)  # refused: ConnectionFailed, not a wait for a reply
    assert_lock_free(resource)  # the failed open left the lock file free


def test_nonexistent_serial_port(lock_dir: Path, tmp_path: Path):
    port = str(tmp_path / "no-such-tty")
    exc, _ = timed(lambda: open_transport(f"PROLOGIX::{port}::11", timeout_s=1.0))
    assert_one_line_failure(exc, port)
    exc, _ = timed(lambda: open_transport(f"ASRL{port}::INSTR", timeout_s=1.0))
    assert_one_line_failure(exc, port)
    assert_lock_free(f"PROLOGIX::{port}::11")


@pytest.mark.parametrize("resource", ["BOGUS::1::INSTR", "TCPIP::127.0.0.1::SOCKET"])
def test_malformed_visa_resource(resource: str, lock_dir: Path):
    exc, _ = timed(lambda: open_transport(resource, timeout_s=1.0))
    assert_one_line_failure(exc, resource)


def test_empty_resource_name():
    with pytest.raises(ValueError, match="empty"):
        open_transport("   ")


@contextlib.contextmanager
def fake_serial_peer(answer: bytes | None) -> Iterator[tuple[str, bytearray]]:
    """A pty pair of our own: the port, and everything written to it. With an
    ``answer``, each ``++ver`` is answered with it; without, nobody answers."""
    master, slave = os.openpty()
    tty.setraw(slave)
    port = os.ttyname(slave)
    received = bytearray()
    answered = [0]
    stop = threading.Event()

    def run() -> None:
        while not stop.is_set():
            ready, _, _ = select.select([master], [], [], 0.02)
            if not ready:
                continue
            try:
                received.extend(os.read(master, 4096))
            except OSError:
                continue
            while answer is not None and received.count(b"++ver\n") > answered[0]:
                answered[0] += 1
                os.write(master, answer)

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    try:
        yield port, received
    finally:
        stop.set()
        thread.join(2)
        os.close(master)
        os.close(slave)


def test_serial_port_where_no_prologix_answers(lock_dir: Path):
    with fake_serial_peer(None) as (port, received):
        exc, _ = timed(lambda: open_transport(f"PROLOGIX::{port}::11", timeout_s=0.5))
        assert b"++ver\n" in received  # it asked
        assert_one_line_failure(exc, port)  # and gave up: the timeout mark catches a hang


def fds_on(port: str) -> set[str]:
    """Our file descriptors open on ``port``."""
    found = set()
    for fd in os.listdir("/proc/self/fd"):
        with contextlib.suppress(OSError):
            if os.path.realpath(f"/proc/self/fd/{fd}") == port:
                found.add(fd)
    return found


@pytest.mark.parametrize("answer", [None, b"hello, I am a modem\r\n"])
def test_failed_prologix_open_closes_the_serial_port(answer: bytes | None, lock_dir: Path):
    """A transport whose open failed holds nothing: not the lock file, not the port
    (the application may keep the object to try again later)."""
    with fake_serial_peer(answer) as (port, _):
        resource = f"PROLOGIX::{port}::11"
        ours = fds_on(port)  # the pty's own slave end
        transport = PrologixTransport(resource, timeout_s=0.3)
        failed = False
        try:
            transport.open()
        except DriverError:
            failed = True
        assert failed
        assert not transport.is_open
        assert fds_on(port) == ours
        assert_lock_free(resource)


def test_serial_port_where_something_else_answers(lock_dir: Path):
    with fake_serial_peer(b"hello, I am a modem\r\n") as (port, _):
        exc, _ = timed(lambda: open_transport(f"PROLOGIX::{port}::11", timeout_s=1.0))
        assert_one_line_failure(exc, port, "Prologix")


# ---------------------------------------------------------------- Prologix specifics
SPECIAL = {0x0D, 0x0A, 0x1B, 0x2B}  # CR, LF, ESC, '+'


def test_escape_exactly_cr_lf_esc_and_plus():
    everything = bytes(range(256))
    expected = b"".join((b"\x1b" if b in SPECIAL else b"") + bytes([b]) for b in everything)
    assert escape(everything) == expected
    assert len(escape(everything)) == 256 + 4
    assert escape(b"FRS 200 HZ;TLVL -2 MV") == b"FRS 200 HZ;TLVL -2 MV"
    assert escape(b"a+b\r\n\x1b") == b"a\x1b+b\x1b\r\x1b\n\x1b\x1b"
    assert escape(b"++ver") == b"\x1b+\x1b+ver"
    assert escape(b"") == b""


def test_escaped_data_goes_on_the_wire(lock_dir: Path):
    version = b"Prologix GPIB-USB Controller version 6.101\r\n"
    with (
        fake_serial_peer(version) as (port, received),
        PrologixTransport(f"PROLOGIX::{port}::11", timeout_s=1.0) as t,
    ):
        # Opening ends with a device clear; wait until the peer has seen it.
        deadline = time.monotonic() + 2
        while not bytes(received).endswith(b"++clr\n") and time.monotonic() < deadline:
            time.sleep(0.01)
        start = len(received)
        t.write(b"SNS1 2+3\r\x1bX")
        want = b"SNS1 2\x1b+3\x1b\r\x1b\x1bX\n"  # escaped, then the one LF that ends it
        deadline = time.monotonic() + 2
        while len(received) - start < len(want) and time.monotonic() < deadline:
            time.sleep(0.01)
        assert bytes(received[start:]) == want


@pytest.mark.parametrize(
    ("resource", "expected"),
    [
        ("PROLOGIX::/dev/ttyUSB0::11", ("/dev/ttyUSB0", 11)),
        ("prologix::COM3::0", ("COM3", 0)),
        (
            "Prologix::/dev/serial/by-id/usb-Prologix_GPIB-USB::30",
            ("/dev/serial/by-id/usb-Prologix_GPIB-USB", 30),
        ),
    ],
)
def test_parse_resource_accepts(resource: str, expected: tuple[str, int]):
    assert parse_resource(resource) == expected


@pytest.mark.parametrize(
    "resource",
    [
        "PROLOGIX::/dev/ttyUSB0",
        "PROLOGIX::::11",
        "PROLOGIX::/dev/ttyUSB0::31",
        "PROLOGIX::/dev/ttyUSB0::-1",
        "PROLOGIX::/dev/ttyUSB0::eleven",
        "PROLOGIX::/dev/ttyUSB0::",
        "PROLOGIX::/dev/ttyUSB0::1 1",
        "PROLOGIX::/dev/ttyUSB0::11::INSTR",
        "PROLOGIX:/dev/ttyUSB0:11",
        "GPIB0::11::INSTR",
        "PRLGX-ASRL::/dev/ttyUSB0::INTFC",
        "",
    ],
)
def test_parse_resource_rejects(resource: str):
    with pytest.raises(ValueError, match=r"Prologix resource|GPIB address") as info:
        parse_resource(resource)
    assert repr(resource) in str(info.value)
    with pytest.raises(ValueError, match=r"Prologix resource|GPIB address"):
        PrologixTransport(resource)


def test_bad_prologix_name_through_open_transport(lock_dir: Path):
    with pytest.raises(ValueError, match="GPIB address"):
        open_transport("PROLOGIX::/dev/ttyUSB0::99")
    assert not lock_dir.exists() or not any(lock_dir.iterdir())


# ---------------------------------------------------------------- finding resources
@pytest.mark.timeout(10)
def test_list_resources_sends_nothing_onto_the_network(monkeypatch: pytest.MonkeyPatch):
    attempts: list[tuple[str, tuple]] = []

    def refuse(name: str):
        def call(self, *args, **kwargs):
            attempts.append((name, args))
            raise OSError(f"test: no network traffic from list_resources ({name})")

        return call

    for name in ("sendto", "sendmsg", "connect", "connect_ex"):
        monkeypatch.setattr(socket.socket, name, refuse(name))
    found = list_resources()
    assert attempts == []  # no discovery packet, so none of its 1 s waits either
    assert set(found) == {"visa", "serial", "notes"}
    assert all(isinstance(v, list) for v in found.values())
    assert all(isinstance(n, str) for v in found.values() for n in v)
    assert not any(name.upper().startswith(("TCPIP", "PRLGX")) for name in found["visa"])
    assert any("network instruments are not searched" in note for note in found["notes"])
