"""The simulator's fault menu (sims/faults.py, sims/session.py), through the in-process
link and through real TCP sockets.

Expectations come from the fault table in sims/faults.py and the status/error
conventions of docs/instrument.md, decoded on the test side (tests/sims/wire.py).
Block-level faults run against a replayed hit whose samples the test made, so
the bytes that should arrive are known before the simulator sends any.
"""

from __future__ import annotations

import contextlib
import math
import re
import socket
import struct
import time

import numpy as np
import pytest

from sims.command_table import ERRORS
from sims.faults import FAULTS, parse_fault
from sims.inprocess import InProcessConnection
from sims.instrument import Analyzer
from sims.sources import RecordedHit, ReplaySource
from sims.tcp_server import TcpServer
from tests.sims.wire import HEADER_LENGTH, decode_trace

TYPICAL = "FRS 200 HZ;TSRC CH1;TLVL 2 MV;TDLY -10 MS;STRT"
IDENT = b"HP35660A\r\n"
N_SAMPLES = 1024
#: A TIM1/TIM2 DDAN reply: "#A", 2-byte length, (66 header + 1024 samples) float64.
TIME_PAYLOAD = 8 * (HEADER_LENGTH + N_SAMPLES)
TIME_BLOCK = 4 + TIME_PAYLOAD
STATUS_DONE, STATUS_WAITING, STATUS_ERROR = 1, 2, 16


# ---------------------------------------------------------------- clients
class _Link:
    """A client's view of the analyzer: messages out, bytes in (buffered)."""

    def __init__(self) -> None:
        self._buf = bytearray()

    def _recv(self, timeout: float) -> bytes:  # pragma: no cover - overridden
        raise NotImplementedError

    def send(self, text: str) -> None:
        raise NotImplementedError

    def close(self) -> None:
        raise NotImplementedError

    def read_until(self, marker: bytes, timeout: float = 2.0) -> bytes:
        """Everything up to and including the first ``marker``."""
        deadline = time.monotonic() + timeout
        while (i := self._buf.find(marker)) < 0:
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise TimeoutError(
                    f"{marker!r} not seen; got {len(self._buf)} bytes {bytes(self._buf[:24])!r}"
                )
            self._buf += self._recv(remaining)
        end = i + len(marker)
        out = bytes(self._buf[:end])
        del self._buf[:end]
        return out

    def read_quiet(self, quiet: float = 0.15) -> bytes:
        """Everything that arrives until nothing more comes for ``quiet`` seconds."""
        while data := self._recv(quiet):
            self._buf += data
        out = bytes(self._buf)
        self._buf.clear()
        return out

    def query(self, text: str, timeout: float = 2.0) -> bytes:
        self.send(text)
        return self.read_until(b"\r\n", timeout)

    def block_then_ident(self, commands: str) -> bytes:
        """The bytes ``commands`` produce, delimited by the ID? reply sent after them."""
        self.send(f"{commands};ID?")
        data = self.read_until(IDENT)
        return data[: -len(IDENT)]


class InProcessLink(_Link):
    def __init__(self, conn: InProcessConnection) -> None:
        super().__init__()
        self.conn = conn

    def _recv(self, timeout: float) -> bytes:
        try:
            return self.conn.read(timeout_s=timeout)
        except TimeoutError:
            return b""

    def send(self, text: str) -> None:
        self.conn.write(text.encode("ascii") + b"\n")

    def close(self) -> None:
        self.conn.close()


class TcpLink(_Link):
    def __init__(self, server: TcpServer) -> None:
        super().__init__()
        self.sock = socket.create_connection((server.host, server.port), timeout=2.0)

    def _recv(self, timeout: float) -> bytes:
        self.sock.settimeout(max(timeout, 1e-3))
        try:
            data = self.sock.recv(65536)
        except TimeoutError:
            return b""
        if not data:
            raise EOFError("the server closed the connection")
        return data

    def send(self, text: str) -> None:
        self.sock.sendall(text.encode("ascii") + b"\n")

    def close(self) -> None:
        self.sock.close()


@pytest.fixture(params=["inprocess", "tcp"])
def open_link(request):
    """open_link(analyzer, faults=()) -> a link armed with ``faults``: an
    InProcessConnection, or a socket to a TcpServer(analyzer, port=0, faults=...)."""
    with contextlib.ExitStack() as stack:

        def open_(analyzer: Analyzer, faults=()) -> _Link:
            if request.param == "inprocess":
                link: _Link = InProcessLink(InProcessConnection(analyzer, faults))
            else:
                server = stack.enter_context(TcpServer(analyzer, port=0, faults=list(faults)))
                link = TcpLink(server)
            stack.callback(link.close)
            return link

        yield open_


# ---------------------------------------------------------------- helpers
def replay_analyzer(seed: int = 7) -> tuple[Analyzer, np.ndarray, np.ndarray]:
    """An analyzer that has measured one replayed hit the test made, FRS 200 HZ."""
    rng = np.random.default_rng(seed)
    force = rng.standard_normal(N_SAMPLES) * 10.0
    response = rng.standard_normal(N_SAMPLES)
    analyzer = Analyzer(ReplaySource([RecordedHit(force, response, 512.0)], loop=True), time_scale=0.0)
    # Set up before any faulty link exists, so no fault sees these replies.
    setup = InProcessConnection(analyzer)
    setup.write(b"FRS 200 HZ;STRT\n")
    setup.write(b"SMSD\n")
    assert setup.read() == b"1\r\n"
    return analyzer, force, response


def be64(values: np.ndarray) -> bytes:
    return np.asarray(values, dtype=">f8").tobytes()


def assert_truncated_time_block(data: bytes, keep: float, samples: np.ndarray) -> None:
    """``data`` is the first ``keep`` of a TIM DDAN block of ``samples``, nothing more."""
    assert abs(len(data) - keep * TIME_BLOCK) <= 1, (len(data), keep * TIME_BLOCK)
    if len(data) < 4:
        assert data == b"#A\x22\x10"[: len(data)]
        return
    assert data[:2] == b"#A"
    (claimed,) = struct.unpack(">H", data[2:4])
    assert claimed == TIME_PAYLOAD
    assert len(data) - 4 < claimed
    body = data[4 + 8 * HEADER_LENGTH :]
    assert body == be64(samples)[: len(body)]


def assert_full_time_block(data: bytes, samples: np.ndarray) -> None:
    header, values = decode_trace(data)
    assert int(header[1]) == N_SAMPLES
    assert be64(values) == be64(samples)


def error(link: _Link) -> tuple[int, str]:
    reply = link.query("ERR?")
    match = re.fullmatch(rb'(\d+),"(.*)"\r\n', reply)
    assert match, reply
    return int(match.group(1)), match.group(2).decode("ascii")


def status(link: _Link) -> int:
    return int(link.query("STA?"))


def split_garbage(reply: bytes, expected: bytes) -> bytes:
    """The junk in front of ``expected``; checks it is all high-bit bytes."""
    assert reply.endswith(expected), reply
    junk = reply[: -len(expected)]
    assert all(b >= 0x80 for b in junk), junk
    return junk


# ---------------------------------------------------------------- parse_fault
def test_parse_fault_knows_the_documented_menu_and_defaults():
    assert set(FAULTS) == {"slow", "no_hit", "truncate", "garbage", "drop", "error"}
    slow = parse_fault("slow")
    assert slow.params["delay"] == 0.5
    assert math.isinf(slow.count)  # every reply
    assert slow.after == 0
    assert parse_fault("truncate").params["keep"] == 0.5
    assert parse_fault("drop").params["keep"] == 0.5
    assert parse_fault("garbage").params["nbytes"] == 8
    for name in ("no_hit", "truncate", "garbage", "drop"):
        assert parse_fault(name).count == 1


def test_parse_fault_reads_options_case_and_spaces_aside():
    fault = parse_fault("  Garbage , COUNT=2, after=3 ,nbytes=5 ")
    assert (fault.name, fault.count, fault.after, fault.params["nbytes"]) == ("garbage", 2, 3, 5)
    assert math.isinf(parse_fault("truncate,count=always").count)
    assert parse_fault("drop,keep=0").params["keep"] == 0.0
    assert parse_fault("slow,delay=0.2").params["delay"] == 0.2


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ("wobble", r"unknown fault 'wobble'.*truncate"),
        ("", r"unknown fault"),
        ("slow,speed=2", r"slow has no option 'speed'.*delay"),
        ("truncate,delay=1", r"truncate has no option 'delay'.*keep"),
        ("slow,delay", r"'delay' is not key=value"),
        ("slow,delay=fast", r"'delay=fast': not a number"),
        ("garbage,count=two", r"'count=two': not a number"),
        ("garbage,after=x", r"'after=x': not a number"),
        ("truncate,count=-1", r"must not be negative"),
        ("truncate,after=-2", r"must not be negative"),
        ("truncate,keep=1", r"keep must be at least 0 and below 1"),
        ("drop,keep=1.5", r"keep must be at least 0 and below 1"),
        ("drop,keep=-0.1", r"keep must be at least 0 and below 1"),
        ("slow,delay=-1", r"delay must not be negative"),
    ],
)
def test_parse_fault_rejects_bad_specs_with_a_clear_message(spec, message):
    with pytest.raises(ValueError, match=message):
        parse_fault(spec)


@pytest.mark.parametrize(
    ("spec", "option"),
    [("garbage,nbytes=nan", "nbytes"), ("garbage,seed=nan", "seed"), ("slow,delay=nan", "delay")],
)
def test_parse_fault_rejects_values_that_are_not_finite(spec, option):
    """A non-finite number is refused when the spec is parsed, naming the option;
    accepted, it would break the session at its first reply (garbage: a ValueError
    escaping the front end; slow: a reply that never comes)."""
    with pytest.raises(ValueError, match=option):
        parse_fault(spec)


@pytest.mark.timeout(5)
def test_a_bad_spec_given_to_the_tcp_server_fails_at_once():
    analyzer = Analyzer(time_scale=0.0)
    with pytest.raises(ValueError, match="unknown fault"):
        TcpServer(analyzer, port=0, faults=["truncate", "nonsense"])
    with pytest.raises(ValueError, match="not a number"):
        TcpServer(analyzer, port=0, faults=["slow,delay=later"])


# ---------------------------------------------------------------- slow
@pytest.mark.timeout(5)
def test_slow_holds_back_every_reply_by_default(open_link):
    analyzer, _, _ = replay_analyzer()
    link = open_link(analyzer, ["slow,delay=0.12"])
    for _ in range(3):
        t0 = time.monotonic()
        assert link.query("ID?") == IDENT
        assert time.monotonic() - t0 >= 0.12


@pytest.mark.timeout(5)
def test_slow_default_delay_is_half_a_second(open_link):
    analyzer, _, _ = replay_analyzer()
    link = open_link(analyzer, ["slow"])
    t0 = time.monotonic()
    link.send("ID?")
    assert link.read_quiet(0.3) == b""  # still held back
    assert link.read_until(b"\r\n") == IDENT
    assert time.monotonic() - t0 >= 0.5


@pytest.mark.timeout(15)
def test_slow_with_a_count_delays_only_that_many_replies(open_link):
    analyzer, _, _ = replay_analyzer()
    link = open_link(analyzer, ["slow,delay=1.5,count=1"])
    t0 = time.monotonic()
    for _ in range(3):
        link.send("ID?")
    assert link.read_until(IDENT, timeout=5.0) == IDENT
    assert time.monotonic() - t0 >= 1.5  # the first reply was held back
    # The two after it were ready as soon as it was: a quiet read gets both at once.
    # Held back too, they would come 1.5 s and 3 s later and the read would end empty.
    assert link.read_quiet(0.5) == IDENT * 2


# ---------------------------------------------------------------- no_hit
@pytest.mark.timeout(5)
def test_no_hit_leaves_the_analyzer_waiting_for_a_trigger(open_link, make_analyzer):
    link = open_link(make_analyzer(time_scale=0.0), ["no_hit"])
    link.send(TYPICAL)
    for _ in range(2):  # at time scale 0 any hit would already have landed
        sta = status(link)
        assert sta & STATUS_WAITING
        assert not sta & (STATUS_DONE | STATUS_ERROR)
        assert link.query("SMSD") == b"0\r\n"
        time.sleep(0.05)
    # count=1 (the default): the next STRT measures normally.
    link.send("STRT")
    assert link.query("SMSD") == b"1\r\n"
    assert error(link) == (0, "No error")


@pytest.mark.timeout(5)
def test_no_hit_count_and_after(open_link, make_analyzer):
    link = open_link(make_analyzer(time_scale=0.0), ["no_hit,count=2,after=1"])
    link.send("FRS 200 HZ;TSRC CH1;TLVL 2 MV;TDLY -10 MS")
    outcomes = []
    for _ in range(4):
        link.send("STRT")
        outcomes.append(link.query("SMSD"))
    assert outcomes == [b"1\r\n", b"0\r\n", b"0\r\n", b"1\r\n"]


# ---------------------------------------------------------------- truncate
@pytest.mark.timeout(5)
@pytest.mark.parametrize("keep", [None, 0.25, 0.0])
def test_truncate_sends_part_of_the_block_and_nothing_more(open_link, keep):
    analyzer, force, response = replay_analyzer()
    link = open_link(analyzer, ["truncate" if keep is None else f"truncate,keep={keep}"])
    link.send("TRCA;TIM1;DDAN")
    data = link.read_quiet()
    assert_truncated_time_block(data, 0.5 if keep is None else keep, force)
    # The connection is still in step: the next command's reply comes alone.
    assert link.query("ID?") == IDENT
    assert link.read_quiet(0.05) == b""
    # count=1: the next block is whole.
    assert_full_time_block(link.block_then_ident("TIM2;DDAN"), response)


@pytest.mark.timeout(5)
def test_truncate_count_and_after(open_link):
    analyzer, force, _ = replay_analyzer()
    link = open_link(analyzer, ["truncate,count=2,after=1"])
    blocks = [link.block_then_ident("TIM1;DDAN") for _ in range(4)]
    assert_full_time_block(blocks[0], force)
    assert_truncated_time_block(blocks[1], 0.5, force)
    assert_truncated_time_block(blocks[2], 0.5, force)
    assert_full_time_block(blocks[3], force)


@pytest.mark.timeout(5)
def test_truncate_leaves_ascii_replies_alone(open_link):
    analyzer, force, _ = replay_analyzer()
    link = open_link(analyzer, ["truncate"])
    assert link.query("ID?") == IDENT
    assert link.query("SMSD") == b"1\r\n"
    link.send("TIM1;DDAN")
    assert_truncated_time_block(link.read_quiet(), 0.5, force)


# ---------------------------------------------------------------- garbage
@pytest.mark.timeout(5)
def test_garbage_comes_before_the_reply_and_is_deterministic(open_link):
    analyzer, _, _ = replay_analyzer()
    link = open_link(analyzer, ["garbage"])
    junk = split_garbage(link.query("ID?"), IDENT)
    assert len(junk) == 8
    assert link.query("ID?") == IDENT  # count=1
    # A second run, another connection to another instrument: the same bytes.
    again = open_link(replay_analyzer()[0], ["garbage"])
    assert split_garbage(again.query("ID?"), IDENT) == junk


@pytest.mark.timeout(5)
def test_garbage_in_front_of_a_binary_block(open_link):
    analyzer, force, _ = replay_analyzer()
    link = open_link(analyzer, ["garbage,nbytes=3"])
    data = link.block_then_ident("TIM1;DDAN")
    assert len(data) == 3 + TIME_BLOCK
    assert all(b >= 0x80 for b in data[:3])
    assert_full_time_block(data[3:], force)


@pytest.mark.timeout(5)
def test_garbage_count_and_after(open_link):
    analyzer, _, _ = replay_analyzer()
    link = open_link(analyzer, ["garbage,count=2,after=1"])
    replies = [link.query("ID?") for _ in range(4)]
    assert replies[0] == IDENT
    assert len(split_garbage(replies[1], IDENT)) == 8
    assert len(split_garbage(replies[2], IDENT)) == 8
    assert replies[3] == IDENT


# ---------------------------------------------------------------- drop
def _recv_until_closed(sock: socket.socket, timeout: float = 2.0) -> bytes:
    data = bytearray()
    deadline = time.monotonic() + timeout
    while True:
        remaining = deadline - time.monotonic()
        assert remaining > 0, f"the server did not close the connection ({len(data)} bytes came)"
        sock.settimeout(remaining)
        chunk = sock.recv(65536)
        if not chunk:
            return bytes(data)
        data += chunk


@pytest.mark.timeout(5)
def test_drop_over_tcp_sends_part_of_the_block_then_closes_and_the_server_serves_on():
    analyzer, force, _ = replay_analyzer()
    with TcpServer(analyzer, port=0, faults=["drop"]) as server:
        with socket.create_connection((server.host, server.port), timeout=2.0) as first:
            first.sendall(b"ID?\n")  # not a block: passes
            first.sendall(b"TIM1;DDAN;ID?\n")
            data = _recv_until_closed(first)
        assert data.startswith(IDENT)
        assert_truncated_time_block(data[len(IDENT) :], 0.5, force)  # and no ID? reply after it
        second = TcpLink(server)
        try:
            assert second.query("ID?") == IDENT
            second.send("SIM:FAULT CLEAR")
            assert_full_time_block(second.block_then_ident("TIM1;DDAN"), force)
        finally:
            second.close()


@pytest.mark.timeout(5)
def test_drop_in_process_resets_the_connection_after_part_of_the_block():
    analyzer, force, _ = replay_analyzer()
    conn = InProcessConnection(analyzer, ["drop,keep=0.25"])
    conn.write(b"TIM1;DDAN;ID?\n")
    assert_truncated_time_block(conn.read(timeout_s=1.0), 0.25, force)
    with pytest.raises(ConnectionResetError):
        conn.read(timeout_s=1.0)
    with pytest.raises(ConnectionResetError):
        conn.write(b"ID?\n")
    # The instrument itself is fine: a new connection is served.
    other = InProcessConnection(analyzer)
    other.write(b"ID?\n")
    assert other.read() == IDENT


# ---------------------------------------------------------------- error
@pytest.mark.timeout(5)
def test_error_puts_the_instrument_in_a_hardware_fault_until_rst(open_link, make_analyzer):
    link = open_link(make_analyzer(time_scale=0.0), ["error"])
    code, message = error(link)
    assert code == 7
    assert message.startswith(ERRORS[7] + ": ")
    link.send(TYPICAL)  # STRT fails
    assert error(link)[0] == 7
    assert error(link) == (0, "No error")
    sta = status(link)
    assert sta & STATUS_ERROR  # the fault persists with the queue empty
    assert not sta & (STATUS_DONE | STATUS_WAITING)
    assert link.query("SMSD") == b"0\r\n"
    assert link.query("ID?") == IDENT
    link.send("RST")
    assert not status(link) & STATUS_ERROR
    assert error(link) == (0, "No error")
    link.send(TYPICAL)
    assert link.query("SMSD") == b"1\r\n"
    assert error(link) == (0, "No error")


@pytest.mark.timeout(5)
def test_strt_with_no_hit_armed_still_fails_cleanly_in_a_hardware_fault(make_analyzer):
    """With no_hit armed the session starts the analyzer itself; in a hardware fault
    that STRT still ends as error 7 in the queue, and the session keeps answering
    (no CommandError escapes the front end)."""
    analyzer = make_analyzer(time_scale=0.0)
    link = InProcessLink(InProcessConnection(analyzer, ["no_hit"]))
    link.send("SIM:FAULT error")
    assert error(link)[0] == 7
    link.send(TYPICAL)
    assert error(link)[0] == 7
    assert link.query("ID?") == IDENT


# ---------------------------------------------------------------- in-band control
@pytest.mark.timeout(5)
def test_sim_fault_query_lists_armed_faults_and_clear_disarms_them(open_link):
    analyzer, force, _ = replay_analyzer()
    link = open_link(analyzer)
    assert link.query("SIM:FAULT?") == b"NONE\r\n"
    link.send("SIM:FAULT truncate,keep=0.25")
    link.send("SIM:FAULT garbage,after=5,nbytes=2")
    listed = link.query("SIM:FAULT?").decode("ascii").removesuffix("\r\n").split(";")
    assert len(listed) == 2
    parsed = [parse_fault(spec) for spec in listed]  # the listing is in spec form
    assert [(f.name, f.count, f.after) for f in parsed] == [("truncate", 1, 0), ("garbage", 1, 5)]
    assert parsed[0].params["keep"] == 0.25
    assert parsed[1].params["nbytes"] == 2
    # Once truncate has fired it is spent and no longer listed.
    assert_truncated_time_block(link.block_then_ident("TIM1;DDAN"), 0.25, force)
    listed = link.query("SIM:FAULT?").decode("ascii")
    assert listed.startswith("garbage,")
    assert "truncate" not in listed
    link.send("SIM:FAULT CLEAR")
    assert link.query("SIM:FAULT?") == b"NONE\r\n"
    for _ in range(6):  # garbage would have fired by now
        assert link.query("ID?") == IDENT
    # A bad in-band spec is an instrument error, not a dead connection.
    link.send("SIM:FAULT wobble")
    code, message = error(link)
    assert code == 3
    assert "unknown fault 'wobble'" in message
    assert link.query("SIM:FAULT?") == b"NONE\r\n"


@pytest.mark.timeout(5)
def test_sim_fault_error_in_band(open_link, make_analyzer):
    link = open_link(make_analyzer(time_scale=0.0))
    link.send("SIM:FAULT error")
    assert status(link) & STATUS_ERROR
    link.send(TYPICAL)
    assert [error(link)[0] for _ in range(3)] == [7, 7, 0]
    assert link.query("SMSD") == b"0\r\n"
    link.send("RST")
    link.send(TYPICAL)
    assert link.query("SMSD") == b"1\r\n"


@pytest.mark.timeout(5)
def test_a_fault_armed_in_band_on_one_tcp_connection_spares_another():
    analyzer, force, _ = replay_analyzer()
    with TcpServer(analyzer, port=0) as server:
        faulty, clean = TcpLink(server), TcpLink(server)
        try:
            faulty.send("SIM:FAULT truncate")
            assert faulty.query("SIM:FAULT?").startswith(b"truncate,")
            assert clean.query("SIM:FAULT?") == b"NONE\r\n"
            assert_full_time_block(clean.block_then_ident("TIM1;DDAN"), force)
            assert_truncated_time_block(faulty.block_then_ident("TIM1;DDAN"), 0.5, force)
            # A connection opened afterwards is clean too.
            late = TcpLink(server)
            try:
                assert_full_time_block(late.block_then_ident("TIM1;DDAN"), force)
            finally:
                late.close()
        finally:
            faulty.close()
            clean.close()


@pytest.mark.timeout(5)
def test_in_process_connections_keep_their_faults_apart():
    analyzer, force, _ = replay_analyzer()
    faulty = InProcessLink(InProcessConnection(analyzer))
    clean = InProcessLink(InProcessConnection(analyzer))
    faulty.send("SIM:FAULT truncate")
    assert_full_time_block(clean.block_then_ident("TIM1;DDAN"), force)
    assert_truncated_time_block(faulty.block_then_ident("TIM1;DDAN"), 0.5, force)


@pytest.mark.timeout(5)
def test_server_wide_faults_arm_on_every_new_connection():
    analyzer, _, _ = replay_analyzer()
    with TcpServer(analyzer, port=0, faults=["garbage"]) as server:
        links = [TcpLink(server)]
        try:
            junk = split_garbage(links[0].query("ID?"), IDENT)
            assert len(junk) == 8
            assert links[0].query("ID?") == IDENT  # spent on this connection
            links[0].send("SIM:FAULT CLEAR")
            for _ in range(2):  # but every new connection gets its own, the same bytes
                links.append(TcpLink(server))
                assert split_garbage(links[-1].query("ID?"), IDENT) == junk
        finally:
            for link in links:
                link.close()
