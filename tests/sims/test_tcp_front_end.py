"""The simulator's TCP front end through real sockets: pyvisa-py's TCPIP SOCKET
resource and raw loopback sockets (docs/instrument.md).

Expectations come from an independent view of the same data: the time record
the analyzer holds (bit-exact), the DDAS ASCII dump against the DDAN binary
block, pyvisa's own HP block decoder, and header words documented in docs/instrument.md.
"""

from __future__ import annotations

import contextlib
import os
import socket
import struct
import threading
import time

import numpy as np
import pytest
import pyvisa

from sims.instrument import Analyzer
from sims.sources import PhysicsSource
from sims.tcp_server import TcpServer
from tests.sims.wire import HEADER_LENGTH, decode_ascii_trace, decode_trace, split_block

pytestmark = pytest.mark.timeout(30)

SPAN_HZ = 200.0
SETUP = "FRS 200 HZ;TSRC CH1;TLVL 2 MV;TDLY -10 MS;STRT"
RECORD_SAMPLES = 1024  # docs/instrument.md: 1024-sample time record per channel
LINES = 400  # docs/instrument.md: 400 lines
BIG_REQUEST = b"TIM1;" + b"DDAN;" * 200 + b"\n"  # about 1.7 MB of reply


# ---------------------------------------------------------------- helpers
def make_analyzer() -> Analyzer:
    source = PhysicsSource("seed", seed=0)
    source.set_noise(False)
    return Analyzer(source, time_scale=0.0)


def open_inst(rm: pyvisa.ResourceManager, resource: str):
    return rm.open_resource(resource, read_termination="\r\n", write_termination="\n", timeout=5000)


def connect(port: int, timeout: float = 5.0) -> socket.socket:
    sock = socket.create_connection(("127.0.0.1", port), timeout=timeout)
    sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    return sock


def recv_exact(sock: socket.socket, size: int) -> bytes:
    data = bytearray()
    while len(data) < size:
        chunk = sock.recv(size - len(data))
        if not chunk:
            raise ConnectionError(f"connection closed after {len(data)} of {size} bytes")
        data += chunk
    return bytes(data)


def recv_line(sock: socket.socket) -> bytes:
    data = bytearray()
    while not data.endswith(b"\r\n"):
        chunk = sock.recv(1)
        if not chunk:
            raise ConnectionError(f"connection closed after {bytes(data)!r}")
        data += chunk
    return bytes(data)


def recv_block(sock: socket.socket) -> bytes:
    head = recv_exact(sock, 4)
    assert head[:2] == b"#A", head
    return head + recv_exact(sock, struct.unpack(">H", head[2:])[0])


def ask(sock: socket.socket, text: str) -> bytes:
    sock.sendall(text.encode("ascii") + b"\n")
    return recv_line(sock)


def measure(sock: socket.socket) -> None:
    sock.sendall(SETUP.encode("ascii") + b"\n")
    assert ask(sock, "SMSD") == b"1\r\n"


def fd_count() -> int:
    return len(os.listdir("/proc/self/fd"))


def wait_for(condition, timeout: float = 5.0) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if condition():
            return True
        time.sleep(0.01)
    return condition()


def new_threads(baseline: set[threading.Thread]) -> list[threading.Thread]:
    return [t for t in threading.enumerate() if t not in baseline and t.is_alive()]


def no_error(sock: socket.socket) -> None:
    assert ask(sock, "ERR?") == b'0,"No error"\r\n'


# --------------------------------------------------------------- fixtures
@pytest.fixture
def analyzer() -> Analyzer:
    return make_analyzer()


@pytest.fixture
def server(analyzer):
    with TcpServer(analyzer, port=0) as srv:
        yield srv


@pytest.fixture
def rm():
    manager = pyvisa.ResourceManager("@py")
    try:
        yield manager
    finally:
        manager.close()


@pytest.fixture
def inst(rm, server):
    resource = open_inst(rm, server.resource)
    try:
        yield resource
    finally:
        resource.close()


@pytest.fixture
def sock(server):
    s = connect(server.port)
    try:
        yield s
    finally:
        s.close()


# ------------------------------------------------------------------ tests
def test_pyvisa_py_opens_the_socket_resource_and_identifies(server, inst):
    assert server.resource == f"TCPIP::127.0.0.1::{server.port}::SOCKET"
    assert inst.query("ID?") == "HP35660A"
    assert inst.query("ID?") == "HP35660A"  # and again: nothing stray left behind


def test_tim1_block_is_the_time_record_bit_exact(inst, analyzer):
    inst.write(SETUP)
    assert inst.query("SMSD") == "1"
    inst.write("TIM1;DDAN")
    head = inst.read_bytes(4)
    assert head[:2] == b"#A"
    (length,) = struct.unpack(">H", head[2:])
    assert length == (HEADER_LENGTH + RECORD_SAMPLES) * 8
    block = head + inst.read_bytes(length)

    header, values = decode_trace(block)
    force = analyzer.last_record.force_n
    assert values.dtype == np.float64
    assert values.tobytes() == np.asarray(force, dtype=np.float64).tobytes()
    assert np.any(values != 0.0)  # the hit is in the record

    # Header words as documented (docs/instrument.md, "Trace format").
    assert header[0] == 6  # input time 1
    assert header[1] == header[2] == RECORD_SAMPLES
    assert header[4] == 1  # channel 1
    assert header[7] == 0  # time domain
    assert header[10] == 4  # x in seconds
    assert header[35] == 0  # float
    assert header[36] == 1  # real
    assert header[40] == 1  # linear
    sample_rate = 2.56 * SPAN_HZ
    assert header[52] == header[53] == sample_rate / 2
    assert header[55] == 1 / sample_rate
    assert header[64] == pytest.approx(-10e-3)  # TDLY -10 MS: the record starts before the trigger

    # A binary block ends with EOI and no terminator: the next reply follows at once.
    assert inst.query("ID?") == "HP35660A"


def test_tim1_binary_equals_ascii_dump(inst):
    inst.write(SETUP)
    assert inst.query("SMSD") == "1"
    inst.write("TIM1;DDAN")
    head = inst.read_bytes(4)
    block = head + inst.read_bytes(struct.unpack(">H", head[2:])[0])
    payload, _ = split_block(block)
    binary = np.frombuffer(payload, dtype=">f8")
    inst.write("DDAS")
    assert inst.read() == "#I"
    assert int(inst.read()) == binary.size
    ascii_values = np.array([float(inst.read()) for _ in range(binary.size)])
    assert np.array_equal(binary, ascii_values)
    assert inst.query("ID?") == "HP35660A"  # the ASCII dump had exactly that many lines


def test_frsp_binary_decodes_to_the_ascii_dump(inst):
    inst.write(SETUP)
    assert inst.query("SMSD") == "1"
    inst.write("FRSP;DDAN")
    # pyvisa's own HP-block decoder, independent of the simulator and of tests/sims/wire.py.
    values = np.array(
        inst.read_binary_values(
            datatype="d", is_big_endian=True, header_fmt="hp", expect_termination=False, container=list
        )
    )
    inst.write("DDAS")
    assert inst.read() == "#I"
    assert int(inst.read()) == values.size
    first = float(inst.read())
    assert first == values[0]
    rest = [float(inst.read()) for _ in range(values.size - 1)]
    ascii_values = np.array([first, *rest])
    assert np.array_equal(values, ascii_values)
    assert inst.query("ID?") == "HP35660A"  # nothing left over from either dump

    header, body = values[:HEADER_LENGTH], values[HEADER_LENGTH:]
    n = int(header[1])
    assert header[36] == 0  # complex: interleaved re, im
    assert body.size == 2 * n
    assert header[0] == 1  # frequency response
    assert header[7] == 1  # frequency domain
    assert header[10] == 1  # x in Hz
    assert header[4] == 3  # ch2 over ch1
    assert header[55] == SPAN_HZ / LINES
    assert header[64] == 0.0  # baseband starts at 0 Hz
    assert header[64] + (n - 1) * header[55] == SPAN_HZ  # 400 lines cover the span
    response = body[0::2] + 1j * body[1::2]
    assert np.all(np.isfinite(response))
    assert np.max(np.abs(response)) > 0


def test_binary_block_followed_directly_by_the_next_reply(sock, analyzer):
    measure(sock)
    sock.sendall(b"TIM1;DDAN;ID?\n")
    block = recv_block(sock)
    assert recv_line(sock) == b"HP35660A\r\n"
    _, values = decode_trace(block)
    assert values.tobytes() == np.asarray(analyzer.last_record.force_n, dtype=np.float64).tobytes()
    sock.sendall(b"DDAS\n")
    text = bytearray()
    while text.count(b"\r\n") < 2 + HEADER_LENGTH + RECORD_SAMPLES:  # #I, count, values
        chunk = sock.recv(65536)
        assert chunk
        text += chunk
    ascii_values = decode_ascii_trace(bytes(text))
    assert np.array_equal(np.frombuffer(split_block(block)[0], dtype=">f8"), ascii_values)


def test_binds_to_loopback_by_default(analyzer):
    with TcpServer(analyzer) as srv:
        assert srv.host == "127.0.0.1"
        assert srv.port > 0
        assert srv.resource == f"TCPIP::127.0.0.1::{srv.port}::SOCKET"
        with pytest.raises(ConnectionRefusedError):
            socket.create_connection(("127.0.0.2", srv.port), timeout=2).close()
        s = connect(srv.port)
        try:
            assert ask(s, "ID?") == b"HP35660A\r\n"
        finally:
            s.close()


def test_split_packets_and_several_commands_per_packet(sock):
    for piece in (b"I", b"D", b"?"):
        sock.sendall(piece)
        time.sleep(0.03)
    sock.settimeout(0.3)
    with pytest.raises(TimeoutError):
        sock.recv(1)  # no line end yet: no complete message, no reply
    sock.settimeout(5)
    sock.sendall(b"\n")
    assert recv_line(sock) == b"HP35660A\r\n"

    # A setting, its value and the CR LF terminator split across packets.
    for piece in (b"FRS 1", b"00 H", b"Z\r", b"\nFR", b"S?\r\n"):
        sock.sendall(piece)
        time.sleep(0.03)
    assert float(recv_line(sock)) == 100.0

    # Several messages and several commands in one packet, replies in order.
    sock.sendall(b"ID?\nTRC?\n\r\nFRS 200 HZ;FRS?;DISP?\nERR?\n")
    assert recv_line(sock) == b"HP35660A\r\n"
    assert recv_line(sock) == b"A\r\n"
    assert float(recv_line(sock)) == 200.0
    assert recv_line(sock) == b"FRSP\r\n"
    assert recv_line(sock) == b'0,"No error"\r\n'
    sock.settimeout(0.2)
    with pytest.raises(TimeoutError):
        sock.recv(1)  # and nothing else


@pytest.mark.timeout(40)
def test_hundreds_of_sequential_sessions_leak_no_thread_and_no_fd(analyzer):
    warm = pyvisa.ResourceManager("@py")  # pyvisa's first use loads modules; not a leak
    warm.close()
    threads0, fds0 = set(threading.enumerate()), fd_count()
    raw_sessions, visa_sessions = 300, 20
    with TcpServer(analyzer, port=0) as srv:
        for i in range(raw_sessions):
            s = connect(srv.port)
            try:
                if i % 3 == 0:  # some close without reading, some with an unread reply
                    s.sendall(b"ID?\n")
                else:
                    assert ask(s, "ID?") == b"HP35660A\r\n"
            finally:
                s.close()
        rm = pyvisa.ResourceManager("@py")
        try:
            for _ in range(visa_sessions):
                inst = open_inst(rm, srv.resource)
                try:
                    assert inst.query("ID?") == "HP35660A"
                finally:
                    inst.close()
        finally:
            rm.close()
        # While the server runs, a session that ended leaves only the accept thread behind.
        assert wait_for(lambda: srv.active_connections == 0), srv.active_connections
        assert wait_for(lambda: len(new_threads(threads0)) == 1), new_threads(threads0)
        assert srv.connections_served == raw_sessions + visa_sessions
    assert wait_for(lambda: not new_threads(threads0)), new_threads(threads0)
    assert wait_for(lambda: fd_count() <= fds0), (fd_count(), fds0)


def test_concurrent_pyvisa_sessions_with_interleaved_queries(analyzer):
    n_clients, rounds = 8, 15
    threads0, fds0 = set(threading.enumerate()), fd_count()
    with TcpServer(analyzer, port=0) as srv:
        rm = pyvisa.ResourceManager("@py")
        insts = []
        try:
            for _ in range(n_clients):
                insts.append(open_inst(rm, srv.resource))
            insts[0].write(SETUP)
            assert insts[0].query("SMSD") == "1"
            assert insts[0].query("TIM1;DISP?") == "TIM1"  # done before any other client asks
            force = np.asarray(analyzer.last_record.force_n, dtype=np.float64).tobytes()
            # A per-connection marker: faults are armed per session, so each client
            # must read back its own (a reply routed to the wrong client shows here).
            for k, inst in enumerate(insts):
                inst.write(f"SIM:FAULT slow,delay=0,after={k + 1}")
            barrier = threading.Barrier(n_clients, timeout=10)
            failures: list[str] = []

            def client(k: int) -> None:
                inst = insts[k]
                try:
                    for r in range(rounds):
                        barrier.wait()
                        assert inst.query("ID?") == "HP35660A"
                        assert inst.query("SIM:FAULT?") == f"slow,count=always,after={k + 1},delay=0"
                        if (r + k) % 3 == 0:
                            inst.write("DDAN")
                            head = inst.read_bytes(4)
                            body = inst.read_bytes(struct.unpack(">H", head[2:])[0])
                            _, values = decode_trace(head + body)
                            assert values.tobytes() == force
                        assert inst.query("TRC?") == "A"
                except Exception as exc:
                    failures.append(f"client {k}: {exc!r}")
                    barrier.abort()

            workers = [threading.Thread(target=client, args=(k,)) for k in range(n_clients)]
            for w in workers:
                w.start()
            for w in workers:
                w.join(20)
            assert not any(w.is_alive() for w in workers)
            assert failures == []
            assert srv.active_connections == n_clients
        finally:
            for inst in insts:
                inst.close()
            rm.close()
        assert wait_for(lambda: srv.active_connections == 0), srv.active_connections
    assert wait_for(lambda: not new_threads(threads0)), new_threads(threads0)
    assert wait_for(lambda: fd_count() <= fds0), (fd_count(), fds0)


def test_server_survives_clients_that_vanish_mid_transfer(server, analyzer):
    setup = connect(server.port)
    try:
        measure(setup)
    finally:
        setup.close()

    # 1: closes with ~1.7 MB of reply unread (the kernel answers with a reset).
    s = connect(server.port)
    s.sendall(BIG_REQUEST)
    assert recv_exact(s, 4)[:2] == b"#A"  # the transfer has begun
    s.close()
    # 2: a forced reset (SO_LINGER 0) in the middle of the transfer.
    s = connect(server.port)
    s.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
    s.sendall(BIG_REQUEST)
    recv_exact(s, 20000)
    s.close()
    # 3: a reset before the server has read the request.
    s = connect(server.port)
    s.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
    s.sendall(BIG_REQUEST)
    s.close()

    # The server dropped those clients promptly, not after its give-up time.
    assert wait_for(lambda: server.active_connections == 0, timeout=5), server.active_connections
    s = connect(server.port)
    try:
        assert ask(s, "ID?") == b"HP35660A\r\n"
        s.sendall(b"TIM1;DDAN\n")
        _, values = decode_trace(recv_block(s))
        assert values.tobytes() == np.asarray(analyzer.last_record.force_n, dtype=np.float64).tobytes()
        no_error(s)
    finally:
        s.close()


def test_half_closed_client_still_gets_every_reply(server, analyzer):
    s = connect(server.port)
    try:
        measure(s)
        s.sendall(BIG_REQUEST)
        s.shutdown(socket.SHUT_WR)  # done talking, still listening
        force = np.asarray(analyzer.last_record.force_n, dtype=np.float64).tobytes()
        for _ in range(BIG_REQUEST.count(b"DDAN")):
            _, values = decode_trace(recv_block(s))
            assert values.tobytes() == force
        assert s.recv(1) == b""  # then the server closes its side
    finally:
        s.close()


def test_close_joins_every_thread_and_releases_the_port(analyzer, rm):
    threads0 = set(threading.enumerate())
    srv = TcpServer(analyzer, port=0).start()
    port = srv.port
    clients: list[socket.socket] = []
    inst = None
    try:
        for _ in range(3):  # idle clients
            clients.append(connect(port))
        inst = open_inst(rm, srv.resource)
        assert inst.query("ID?") == "HP35660A"
        stuck = connect(port)  # asks for a lot and never reads
        clients.append(stuck)
        measure(stuck)
        stuck.sendall(BIG_REQUEST)
        assert wait_for(lambda: srv.active_connections == 5)
        time.sleep(0.3)  # let the server fill the socket buffers and block in send

        srv.close()  # a close that waited on the stuck send forever is the timeout mark's
        assert not new_threads(threads0), new_threads(threads0)
        assert srv.active_connections == 0

        for c in clients[:3]:  # the idle clients see the connection end
            c.settimeout(2)
            with contextlib.suppress(ConnectionResetError):
                assert c.recv(1) == b""
        with pytest.raises(ConnectionRefusedError):
            socket.create_connection(("127.0.0.1", port), timeout=2).close()
        again = socket.create_server(("127.0.0.1", port))  # the port is free again
        again.close()
        srv.close()  # a second close (e.g. an explicit one then __exit__) is harmless
    finally:
        srv.close()
        if inst is not None:
            with contextlib.suppress(Exception):
                inst.close()
        for c in clients:
            c.close()
