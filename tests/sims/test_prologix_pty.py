"""The simulator's Prologix GPIB-USB emulation on a real pseudo-terminal, driven
through pyserial and pyvisa-py's ASRL resource (docs/instrument.md, Prologix
manual v6.1).

Expectations come from the Prologix manual (command names, escaping, ++eos
codes), from docs/instrument.md (the wire format) and from independent views of the same
data: the analyzer's own time record, the ASCII dump and the TCP front end.
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
import serial

from sims.instrument import Analyzer
from sims.prologix import PrologixPty
from sims.sources import PhysicsSource
from sims.tcp_server import TcpServer
from tests.sims.wire import HEADER_LENGTH, decode_ascii_trace, decode_trace

pytestmark = pytest.mark.timeout(30)

VERSION_LINE = b"Prologix GPIB-USB Controller version 6.101\r\n"
#: What pyvisa-py (0.8+) sends when it opens a Prologix interface (docs/instrument.md).
PYVISA_PY_INIT = ("++mode 1", "++auto 0", "++read_tmo_ms 50", "++eos 3", "++eoi 1", "++eot_enable 0")
SETUP = "FRS 200 HZ;TSRC CH1;TLVL 2 MV;TDLY -10 MS;STRT"
RECORD_SAMPLES = 1024
ESC = b"\x1b"
QUIET_S = 0.3  # well above ++read_tmo_ms 50: after this long, nothing more is coming


# ---------------------------------------------------------------- helpers
def make_analyzer() -> Analyzer:
    source = PhysicsSource("seed", seed=0)
    source.set_noise(False)
    return Analyzer(source, time_scale=0.0)


def send(ser: serial.Serial, *lines: str | bytes) -> None:
    for item in lines:
        data = item.encode("latin-1") if isinstance(item, str) else item
        ser.write(data + b"\n")
    ser.flush()


def read_line(ser: serial.Serial, timeout: float = 3.0) -> bytes:
    ser.timeout = timeout
    data = ser.read_until(b"\r\n")
    assert data.endswith(b"\r\n"), f"no complete line within {timeout} s: {data!r}"
    return data


def read_exact(ser: serial.Serial, size: int, timeout: float = 5.0) -> bytes:
    ser.timeout = timeout
    data = ser.read(size)
    assert len(data) == size, f"{len(data)} of {size} bytes within {timeout} s"
    return data


def read_all(ser: serial.Serial, quiet: float = QUIET_S) -> bytes:
    """Everything that arrives until the line stays quiet for ``quiet`` s."""
    ser.timeout = quiet
    out = bytearray()
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:
        byte = ser.read(1)
        if not byte:
            break
        out += byte + ser.read(ser.in_waiting)
    return bytes(out)


def ask(ser: serial.Serial, text: str | bytes) -> bytes:
    """A query as pyvisa-py does it with ++auto 0: the message, then ++read eoi."""
    send(ser, text, "++read eoi")
    return read_line(ser)


def sync(ser: serial.Serial) -> None:
    """Wait until the controller has handled every line sent so far."""
    send(ser, "++ver")
    assert read_line(ser) == VERSION_LINE


def read_block(ser: serial.Serial) -> bytes:
    head = read_exact(ser, 4)
    assert head[:2] == b"#A", head
    return head + read_exact(ser, struct.unpack(">H", head[2:])[0])


# --------------------------------------------------------------- fixtures
@pytest.fixture
def analyzer() -> Analyzer:
    return make_analyzer()


@pytest.fixture
def pty(analyzer):
    with PrologixPty(analyzer, 11) as p:
        yield p


@pytest.fixture
def ser(pty):
    port = serial.Serial(pty.port, baudrate=115200, timeout=3)
    try:
        yield port
    finally:
        port.close()


@pytest.fixture
def visa_ser(ser):
    """The port after pyvisa-py's Prologix initialisation sequence."""
    send(ser, *PYVISA_PY_INIT)
    return ser


# ------------------------------------------------------------------ tests
def test_ver_with_every_line_end(ser):
    send(ser, "++ver")
    assert read_line(ser) == VERSION_LINE
    ser.write(b"++ver\r++ver\r\n++ver\n")  # CR, CR LF and LF each end one command
    assert read_all(ser) == VERSION_LINE * 3


def test_pyvisa_py_init_sequence_then_identify(visa_ser):
    assert ask(visa_ser, "ID?") == b"HP35660A\r\n"
    # The sequence took: each setting reads back (a query is the command without argument).
    for command, value in (
        ("++mode", b"1"),
        ("++auto", b"0"),
        ("++read_tmo_ms", b"50"),
        ("++eos", b"3"),
        ("++eoi", b"1"),
        ("++eot_enable", b"0"),
    ):
        send(visa_ser, command)
        assert read_line(visa_ser) == value + b"\r\n", command
    assert read_all(visa_ser) == b""


def test_auto_0_holds_the_reply_until_read(visa_ser):
    send(visa_ser, "ID?")
    assert read_all(visa_ser) == b""
    send(visa_ser, "++read eoi")
    assert read_line(visa_ser) == b"HP35660A\r\n"


def test_instrument_answers_only_at_its_address(visa_ser):
    send(visa_ser, "++addr 11")
    assert ask(visa_ser, "ID?") == b"HP35660A\r\n"
    send(visa_ser, "++addr 5", "ID?", "++read eoi")
    assert read_all(visa_ser) == b""  # nobody at 5: the read times out empty
    send(visa_ser, "++addr")
    assert read_line(visa_ser) == b"5\r\n"
    # Back at 11 there is nothing to read: the message sent to 5 never reached it.
    send(visa_ser, "++addr 11", "++read eoi")
    assert read_all(visa_ser) == b""
    send(visa_ser, "++addr 11 96")  # with a secondary address
    send(visa_ser, "++addr")
    assert read_line(visa_ser).startswith(b"11")
    assert ask(visa_ser, "ID?") == b"HP35660A\r\n"
    assert read_all(visa_ser) == b""  # exactly one reply


def test_other_gpib_address(analyzer):
    with PrologixPty(analyzer, 3) as p:
        port = serial.Serial(p.port, timeout=3)
        try:
            send(port, *PYVISA_PY_INIT)
            send(port, "++addr 11", "ID?", "++read eoi")
            assert read_all(port) == b""
            send(port, "++addr 3")
            assert ask(port, "ID?") == b"HP35660A\r\n"
        finally:
            port.close()
    with pytest.raises(ValueError, match="GPIB"):
        PrologixPty(analyzer, 31)


def test_auto_1_replies_without_read(visa_ser):
    send(visa_ser, "++auto 1", "++auto")
    assert read_line(visa_ser) == b"1\r\n"
    send(visa_ser, "ID?")
    assert read_line(visa_ser) == b"HP35660A\r\n"
    send(visa_ser, "TRCB")  # not a query: nothing to read
    assert read_all(visa_ser) == b""
    send(visa_ser, "TRC?")
    assert read_line(visa_ser) == b"B\r\n"
    send(visa_ser, "++auto 0", "ID?")
    assert read_all(visa_ser) == b""


def test_binary_ddan_through_read_eoi_matches_the_record_ascii_and_tcp(visa_ser, analyzer):
    send(visa_ser, SETUP)
    assert ask(visa_ser, "SMSD") == b"1\r\n"

    send(visa_ser, "TIM1;DDAN", "++read eoi")
    block = read_block(visa_ser)
    assert read_all(visa_ser) == b""  # no terminator after the block, no eot character
    payload = block[4:]
    # The payload holds bytes that a careless serial layer would eat or translate.
    assert any(c in payload for c in (b"\n", b"\r", b"\x1b", b"+", b"\x00", b"\x11", b"\x13"))
    header, values = decode_trace(block)
    assert header[1] == RECORD_SAMPLES
    assert values.tobytes() == np.asarray(analyzer.last_record.force_n, dtype=np.float64).tobytes()

    send(visa_ser, "DDAS", "++read eoi")
    expected_lines = 2 + HEADER_LENGTH + RECORD_SAMPLES  # #I, the count, the values
    visa_ser.timeout = 5
    text = b"".join(visa_ser.readline() for _ in range(expected_lines))
    assert text.count(b"\r\n") == expected_lines
    assert read_all(visa_ser) == b""
    assert np.array_equal(decode_ascii_trace(text), np.frombuffer(payload, dtype=">f8"))

    # The frequency response: the pty's bytes equal the TCP front end's for the same trace.
    send(visa_ser, "FRSP;DDAN", "++read eoi")
    frsp = read_block(visa_ser)
    with TcpServer(analyzer, port=0) as srv:
        sock = socket.create_connection(("127.0.0.1", srv.port), timeout=5)
        try:
            sock.sendall(b"DDAN\n")
            tcp = bytearray()
            while len(tcp) < len(frsp):
                chunk = sock.recv(65536)
                assert chunk
                tcp += chunk
        finally:
            sock.close()
    assert bytes(tcp) == frsp
    header, response = decode_trace(frsp)
    assert header[36] == 0  # complex
    assert np.iscomplexobj(response)
    assert ask(visa_ser, "ERR?") == b'0,"No error"\r\n'


def test_escaped_characters_reach_the_instrument_restored(visa_ser, analyzer):
    send(visa_ser, "TLVL -5 MV")
    sync(visa_ser)
    assert analyzer.settings.trigger_level_v == pytest.approx(-5e-3)
    # An escaped '+': the analyzer must get "TLVL +2 MV", not ESC in its argument.
    send(visa_ser, b"TLVL " + ESC + b"+2 MV")
    assert float(ask(visa_ser, "TLVL?")) == pytest.approx(2e-3)
    assert analyzer.settings.trigger_level_v == pytest.approx(2e-3)
    # An escaped CR and an escaped LF are data, not the end of the controller's line.
    send(visa_ser, b"TLVL 3 MV" + ESC + b"\r")
    sync(visa_ser)
    assert analyzer.settings.trigger_level_v == pytest.approx(3e-3)
    send(visa_ser, b"TLVL 4 MV" + ESC + b"\nTLVL?", "++read eoi")
    assert float(read_line(visa_ser)) == pytest.approx(4e-3)
    assert ask(visa_ser, "ERR?") == b'0,"No error"\r\n'
    # Escaped "++" at the start of a line is data for the instrument, not a controller command.
    send(visa_ser, ESC + b"+" + ESC + b"+ver", "++read eoi")
    assert read_all(visa_ser) == b""
    assert ask(visa_ser, "ERR?").startswith(b"1,")  # the analyzer got "++ver": undefined command
    # An escaped ESC arrives as one ESC.
    send(visa_ser, b"ID?" + ESC + ESC, "++read eoi")
    assert read_all(visa_ser) == b""
    assert ask(visa_ser, "ERR?").startswith(b"1,")


def test_eos_modes(visa_ser):
    # With EOI on, the message ends whatever ++eos appends (0 CR LF, 1 CR, 2 LF, 3 none).
    for mode in (0, 1, 2, 3):
        send(visa_ser, f"++eos {mode}", "++eos")
        assert read_line(visa_ser) == f"{mode}\r\n".encode()
        assert ask(visa_ser, "ID?") == b"HP35660A\r\n", mode
    send(visa_ser, "++eos 4", "++eos")  # out of range: ignored
    assert read_line(visa_ser) == b"3\r\n"

    # Without EOI, only an appended LF ends the analyzer's message (CR LF or LF).
    send(visa_ser, "++eoi 0", "++eoi")
    assert read_line(visa_ser) == b"0\r\n"
    for mode in (0, 2):
        send(visa_ser, f"++eos {mode}")
        assert ask(visa_ser, "ID?") == b"HP35660A\r\n", mode
    send(visa_ser, "++eos 1", "ID?", "++read eoi")  # CR alone ends nothing
    assert read_all(visa_ser) == b""
    # ++clr drops that unfinished message: the next one is read on its own.
    send(visa_ser, "++clr", "++eos 2")
    assert ask(visa_ser, "TRC?") == b"A\r\n"
    assert ask(visa_ser, "ERR?") == b'0,"No error"\r\n'


def test_clr_discards_pending_output(visa_ser):
    send(visa_ser, "ID?", "++clr", "++read eoi")
    assert read_all(visa_ser) == b""
    assert ask(visa_ser, "TRC?") == b"A\r\n"
    assert read_all(visa_ser) == b""


def test_spoll_returns_the_status_byte_in_decimal(visa_ser):
    send(visa_ser, "++spoll")
    assert read_line(visa_ser) == b"0\r\n"  # preset, idle, no error
    send(visa_ser, "NOSUCH")  # an undefined command sets the error bit (16)
    send(visa_ser, "++spoll")
    assert read_line(visa_ser) == b"16\r\n"
    assert ask(visa_ser, "STA?") == b"16\r\n"
    send(visa_ser, "CLER", SETUP)
    assert ask(visa_ser, "SMSD") == b"1\r\n"
    send(visa_ser, "++spoll")
    spoll = read_line(visa_ser)
    assert spoll == b"1\r\n"  # done (1), no overload, no error
    assert ask(visa_ser, "STA?") == spoll
    send(visa_ser, "++spoll 11")  # the address given explicitly
    assert read_line(visa_ser) == spoll


def test_queries_without_argument_report_the_settings(visa_ser):
    for command, values in (("++addr", (7, 11)), ("++auto", (1, 0)), ("++eoi", (0, 1))):
        for value in values:
            send(visa_ser, f"{command} {value}", command)
            assert read_line(visa_ser) == f"{value}\r\n".encode(), command
    send(visa_ser, "++auto 0")
    assert ask(visa_ser, "ID?") == b"HP35660A\r\n"


def test_unknown_controller_command(visa_ser):
    send(visa_ser, "++bogus")
    assert read_line(visa_ser) == b"Unrecognized command\r\n"
    send(visa_ser, "++ver")
    assert read_line(visa_ser) == VERSION_LINE
    assert ask(visa_ser, "ID?") == b"HP35660A\r\n"


def test_eot_character_after_eoi(visa_ser):
    send(visa_ser, "++eot_enable 1", "++eot_char 42")
    send(visa_ser, "ID?", "++read eoi")
    assert read_all(visa_ser) == b"HP35660A\r\n*"
    send(visa_ser, "TRC?;ID?", "++read eoi")  # one message, two replies: one EOI each
    assert read_all(visa_ser) == b"A\r\n*"
    send(visa_ser, "++read eoi")
    assert read_all(visa_ser) == b"HP35660A\r\n*"
    send(visa_ser, "++eot_enable 0", "ID?", "++read eoi")
    assert read_all(visa_ser) == b"HP35660A\r\n"


def test_pyvisa_py_asrl_resource(pty):
    assert pty.resource == f"ASRL{pty.port}::INSTR"
    rm = pyvisa.ResourceManager("@py")
    try:
        inst = rm.open_resource(pty.resource, read_termination="\r\n", write_termination="\n", timeout=3000)
        try:
            assert inst.query("++ver") == VERSION_LINE.decode().strip()
            for command in PYVISA_PY_INIT:
                inst.write(command)
            inst.write("ID?")
            inst.write("++read eoi")
            assert inst.read() == "HP35660A"
        finally:
            inst.close()
    finally:
        rm.close()


def test_host_can_close_and_reopen_the_port(pty):
    for _ in range(3):
        port = serial.Serial(pty.port, baudrate=115200, timeout=3)
        try:
            send(port, *PYVISA_PY_INIT)
            assert ask(port, "ID?") == b"HP35660A\r\n"
        finally:
            port.close()


def test_open_and_close_leave_no_thread_and_no_fd(analyzer):
    threads0 = set(threading.enumerate())
    fds0 = len(os.listdir("/proc/self/fd"))
    for _ in range(10):
        with PrologixPty(analyzer, 11) as p:
            port = serial.Serial(p.port, baudrate=115200, timeout=3)
            try:
                send(port, *PYVISA_PY_INIT)
                assert ask(port, "ID?") == b"HP35660A\r\n"
            finally:
                port.close()
    assert not [t for t in threading.enumerate() if t not in threads0]
    assert len(os.listdir("/proc/self/fd")) <= fds0


def test_close_is_prompt_while_the_host_has_stopped_reading(analyzer):
    """close() must not wait for a host that stopped reading in the middle of a
    transfer (docs/instrument.md: partial reads; sims/prologix.py gives such a
    host up after WRITE_GIVE_UP_S and stops on close)."""
    p = PrologixPty(analyzer, 11).start()
    port = serial.Serial(p.port, baudrate=115200, timeout=3)
    closer = threading.Thread(target=p.close, name="test-closer", daemon=True)
    try:
        send(port, *PYVISA_PY_INIT, SETUP, "SMSD", "TIM1" + ";DDAN" * 100, "++read")
        assert read_exact(port, 1000).startswith(b"1\r\n#A")  # the transfer has begun; now stop reading
        time.sleep(0.3)
        closer.start()
        # Prompt means well under the 10 s a writer waits before giving a host up
        # (WRITE_GIVE_UP_S); half of it leaves a loaded machine room to be slow.
        closer.join(5.0)
        hung = closer.is_alive()
    finally:
        if closer.ident is None:  # failed before closing: close now, the same way
            closer.start()
        # Unblock a controller stuck writing: read what it writes until close() is through.
        with contextlib.suppress(serial.SerialException, OSError):
            port.timeout = 0.1  # fails (EIO) once the pty is gone
        deadline = time.monotonic() + 20
        while closer.is_alive() and time.monotonic() < deadline:
            with contextlib.suppress(serial.SerialException, OSError):
                port.read(65536)
        port.close()
    assert not hung, "PrologixPty.close() blocks while the host does not read (os.write on the pty master)"
