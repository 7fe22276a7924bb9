"""Binary blocks (drivers.blocks) and trace decoding (drivers.trace).

Expected bytes are written by hand from the documented formats:

* HP ``#A`` (docs/instrument.md): ``#A``, a 2-byte big-endian byte count, the payload.
* IEEE 488.2 definite length: ``#``, one digit n, n digits of byte count, the payload.
* IEEE 488.2 indefinite length: ``#0``, the payload, LF.

Payloads are big-endian IEEE float64 or float32.
"""

from __future__ import annotations

import struct

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from drivers.blocks import parse_block, read_ascii_dump
from drivers.errors import ProtocolError
from drivers.trace import Trace

pytestmark = pytest.mark.timeout(60)

FAST = settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
CMD = "DDAN"

# 1.0, -2.5, 0.1 as big-endian IEEE float64 / float32, spelled out bit by bit.
F8_ONE = b"\x3f\xf0\x00\x00\x00\x00\x00\x00"
F8_MINUS_2_5 = b"\xc0\x04\x00\x00\x00\x00\x00\x00"
F8_TENTH = b"\x3f\xb9\x99\x99\x99\x99\x99\x9a"
F8_NAN = b"\x7f\xf8\x00\x00\x00\x00\x00\x00"
F8_INF = b"\x7f\xf0\x00\x00\x00\x00\x00\x00"
F8_MINUS_INF = b"\xff\xf0\x00\x00\x00\x00\x00\x00"
F4_ONE = b"\x3f\x80\x00\x00"
F4_MINUS_2_5 = b"\xc0\x20\x00\x00"
F4_NAN = b"\x7f\xc0\x00\x00"
F4_INF = b"\x7f\x80\x00\x00"

F8_PAYLOAD = F8_ONE + F8_MINUS_2_5 + F8_TENTH  # 24 bytes
F4_PAYLOAD = F4_ONE + F4_MINUS_2_5  # 8 bytes


def bits(values: np.ndarray) -> bytes:
    """Bit pattern of native float64 values: tells -0.0 from 0.0, compares exactly."""
    return np.ascontiguousarray(values, dtype=np.float64).tobytes()


def block(kind: str, payload: bytes) -> bytes:
    """A block built by hand from the formats above."""
    if kind == "A":
        return b"#A" + struct.pack(">H", len(payload)) + payload
    if kind == "definite":
        digits = str(len(payload)).encode()
        return b"#" + str(len(digits)).encode() + digits + payload
    assert kind == "indefinite"
    return b"#0" + payload + b"\n"


def assert_protocol_error(data: bytes, *, command: str = CMD, **kwargs) -> ProtocolError:
    """parse_block must reject ``data`` with a one-line error naming the command and the bytes."""
    with pytest.raises(ProtocolError) as info:
        parse_block(data, command, **kwargs)
    exc = info.value
    text = str(exc)
    assert exc.command == command
    assert text.startswith(f"{command}: ")
    assert "\n" not in text
    if data:
        assert exc.received == data
        assert "received " + repr(data[:12]).rstrip("'") in text
    return exc


# ------------------------------------------------------------------ good blocks, by hand
@pytest.mark.parametrize(
    ("data", "dtype", "expected"),
    [
        (b"#A\x00\x18" + F8_PAYLOAD, ">f8", [1.0, -2.5, 0.1]),
        (b"#224" + F8_PAYLOAD, ">f8", [1.0, -2.5, 0.1]),
        (b"#3024" + F8_PAYLOAD, ">f8", [1.0, -2.5, 0.1]),
        (b"#9000000024" + F8_PAYLOAD, ">f8", [1.0, -2.5, 0.1]),
        (b"#0" + F8_PAYLOAD + b"\n", ">f8", [1.0, -2.5, 0.1]),
        (b"#A\x00\x08" + F4_PAYLOAD, ">f4", [1.0, -2.5]),
        (b"#18" + F4_PAYLOAD, ">f4", [1.0, -2.5]),
        (b"#0" + F4_PAYLOAD + b"\n", ">f4", [1.0, -2.5]),
        # empty blocks are blocks too
        (b"#A\x00\x00", ">f8", []),
        (b"#10", ">f8", []),
        (b"#0\n", ">f8", []),
    ],
)
def test_hand_written_blocks_parse(data, dtype, expected):
    values = parse_block(data, CMD, dtype=dtype)
    assert values.dtype == np.float64
    assert values.shape == (len(expected),)
    assert bits(values) == bits(np.array(expected, dtype=np.float64))


def test_float32_values_are_widened_exactly():
    # 0.1 in float32 is 0x3DCCCCCD = 0.100000001490116...; it must not be re-rounded.
    values = parse_block(b"#A\x00\x04\x3d\xcc\xcc\xcd", CMD, dtype=">f4")
    assert values[0] == np.float64(np.float32(0.1))
    assert values[0] != 0.1


def test_signed_zero_and_extremes_survive():
    payload = (
        b"\x80\x00\x00\x00\x00\x00\x00\x00"  # -0.0
        + b"\x00\x00\x00\x00\x00\x00\x00\x01"  # smallest subnormal
        + b"\x7f\xef\xff\xff\xff\xff\xff\xff"  # largest finite
    )
    values = parse_block(b"#A\x00\x18" + payload, CMD)
    assert np.signbit(values[0])
    assert values[0] == 0.0
    assert values[1] == 5e-324
    assert values[2] == np.finfo(np.float64).max


@pytest.mark.parametrize("trailer", [b"\n", b"\r\n"])
@pytest.mark.parametrize("head", [b"#A\x00\x18", b"#224"])
def test_line_end_after_a_counted_block_is_tolerated(head, trailer):
    values = parse_block(head + F8_PAYLOAD + trailer, CMD)
    assert values.tolist() == [1.0, -2.5, 0.1]


def test_expected_values_matching_count_is_accepted():
    assert parse_block(b"#A\x00\x18" + F8_PAYLOAD, CMD, expected_values=3).size == 3


def test_unknown_dtype_is_a_programming_error_not_a_protocol_error():
    with pytest.raises(ValueError, match="dtype"):
        parse_block(b"#A\x00\x08" + F8_ONE, CMD, dtype="<f8")


# ------------------------------------------------------------------ bad blocks, by hand
@pytest.mark.parametrize(
    "data",
    [
        b"#A\x00\x20" + F8_PAYLOAD,  # announces 32 bytes, 24 follow
        b"#A\x00\x19" + F8_PAYLOAD,  # announces 25
        b"#232" + F8_PAYLOAD,
        b"#9000000025" + F8_PAYLOAD,
        b"#A\x00\x18" + F8_PAYLOAD[:-1],  # one byte short
        b"#A\x00\x18",  # header only
    ],
)
def test_truncated_payload(data):
    exc = assert_protocol_error(data)
    assert "truncated" in exc.reason


@pytest.mark.parametrize(
    "data",
    [
        b"#",  # no type
        b"#A",  # no length
        b"#A\x00",  # half a length
        b"#2",  # no digits
        b"#22",  # one of two digits
        b"#9" + b"12345678",  # eight of nine digits
    ],
)
def test_short_header(data):
    exc = assert_protocol_error(data)
    assert "truncated" in exc.reason


@pytest.mark.parametrize(
    "data",
    [
        b"#A\x00\x10" + F8_PAYLOAD,  # announces 16 of the 24 bytes: 8 stray ones
        b"#216" + F8_PAYLOAD,
        b"#A\x00\x18" + F8_PAYLOAD + b"\r",
        b"#A\x00\x18" + F8_PAYLOAD + b"\n\n",
        b"#A\x00\x18" + F8_PAYLOAD + b"\n\r",
        b"#A\x00\x18" + F8_PAYLOAD + b" ",
        b"#A\x00\x18" + F8_PAYLOAD + b"\r\n\r\n",
        b"#224" + F8_PAYLOAD + b"#A\x00\x00",  # a second block
        b"#A\x00\x18" + F8_PAYLOAD + b"\x00",
    ],
)
def test_stray_bytes_after_the_block(data):
    exc = assert_protocol_error(data)
    assert "after the block" in exc.reason


@pytest.mark.parametrize(
    "data",
    [b"#2x4" + F8_PAYLOAD, b"#2 4" + F8_PAYLOAD, b"#3+24" + F8_PAYLOAD, b"#3-24" + F8_PAYLOAD, b"#22\x004"],
)
def test_non_numeric_ieee_length(data):
    exc = assert_protocol_error(data)
    assert "non-numeric" in exc.reason


@pytest.mark.parametrize("data", [b"#B\x00\x08" + F8_ONE, b"#a\x00\x08" + F8_ONE, b"#\n", b"##"])
def test_unknown_block_type(data):
    exc = assert_protocol_error(data)
    assert "unknown block type" in exc.reason


@pytest.mark.parametrize(
    ("data", "dtype"),
    [
        (b"#A\x00\x0c" + F8_ONE + b"\x00\x00\x00\x00", ">f8"),
        (b"#212" + F8_ONE + b"\x00\x00\x00\x00", ">f8"),
        (b"#0" + F8_ONE + b"\x00\x00\x00\x00\n", ">f8"),
        (b"#A\x00\x06" + F4_ONE + b"\x00\x00", ">f4"),
        (b"#A\x00\x01\x00", ">f8"),
    ],
)
def test_payload_not_whole_values(data, dtype):
    exc = assert_protocol_error(data, dtype=dtype)
    assert "not whole" in exc.reason


@pytest.mark.parametrize(
    ("data", "dtype", "index"),
    [
        (b"#A\x00\x10" + F8_ONE + F8_NAN, ">f8", 1),
        (b"#A\x00\x10" + F8_INF + F8_ONE, ">f8", 0),
        (b"#216" + F8_ONE + F8_MINUS_INF, ">f8", 1),
        (b"#0" + F8_NAN + b"\n", ">f8", 0),
        (b"#A\x00\x08" + F4_ONE + F4_NAN, ">f4", 1),
        (b"#18" + F4_INF + F4_ONE, ">f4", 0),
    ],
)
def test_non_finite_values(data, dtype, index):
    exc = assert_protocol_error(data, dtype=dtype)
    assert f"non-finite value at index {index}" in exc.reason


@pytest.mark.parametrize("expected", [0, 2, 4, 401])
def test_wrong_point_count(expected):
    exc = assert_protocol_error(b"#A\x00\x18" + F8_PAYLOAD, expected_values=expected)
    assert f"expected {expected} values, got 3" in exc.reason


@pytest.mark.parametrize("data", [b"#0" + F8_PAYLOAD, b"#0", b"#0" + F8_PAYLOAD + b"\r"])
def test_indefinite_block_without_final_lf(data):
    exc = assert_protocol_error(data)
    assert "final LF" in exc.reason


@pytest.mark.parametrize(
    "data",
    [b"", b"1.0,-2.5\r\n", b" #A\x00\x08" + F8_ONE, b"\r\n#A\x00\x08" + F8_ONE, b"A\x00\x08" + F8_ONE],
)
def test_not_starting_with_hash(data):
    exc = assert_protocol_error(data)
    assert "'#'" in exc.reason


def test_error_message_summarises_a_large_block():
    # 1000 values announced, 999 sent: the message stays a short line.
    data = b"#A\x1f\x40" + F8_ONE * 999
    exc = assert_protocol_error(data, command="DDAN of TIM1")
    text = str(exc)
    assert len(text) < 300
    assert f"({len(data)} bytes)" in text
    assert text.startswith("DDAN of TIM1: truncated block: 7992 of 8000 payload bytes")


# ------------------------------------------------------------------ properties
finite64 = st.floats(allow_nan=False, allow_infinity=False)
finite32 = st.floats(allow_nan=False, allow_infinity=False, width=32)
KINDS = ("A", "definite", "indefinite")


@FAST
@given(values=st.lists(finite64, max_size=300), kind=st.sampled_from(KINDS))
def test_any_finite_float64_array_round_trips(values, kind):
    payload = struct.pack(f">{len(values)}d", *values)
    result = parse_block(block(kind, payload), CMD, dtype=">f8", expected_values=len(values))
    assert result.dtype == np.float64
    assert result.shape == (len(values),)
    assert bits(result) == bits(np.array(values, dtype=np.float64))


@FAST
@given(values=st.lists(finite32, max_size=300), kind=st.sampled_from(KINDS))
def test_any_finite_float32_array_round_trips(values, kind):
    payload = np.array(values, dtype=">f4").tobytes()
    assert len(payload) == 4 * len(values)
    result = parse_block(block(kind, payload), CMD, dtype=">f4", expected_values=len(values))
    assert result.dtype == np.float64
    assert bits(result) == bits(np.array(values, dtype=np.float32).astype(np.float64))


@FAST
@given(
    values=st.lists(finite32, max_size=40),
    kind=st.sampled_from(("A", "definite")),
    dtype=st.sampled_from((">f8", ">f4")),
    data=st.data(),
)
def test_every_strict_prefix_of_a_counted_block_is_rejected(values, kind, dtype, data):
    payload = np.array(values, dtype=np.float64).astype(dtype).tobytes()
    whole = block(kind, payload)
    parse_block(whole, CMD, dtype=dtype)  # the whole block is fine
    cut = data.draw(st.integers(min_value=0, max_value=len(whole) - 1), label="cut")
    with pytest.raises(ProtocolError):
        parse_block(whole[:cut], CMD, dtype=dtype)


@FAST
@given(
    values=st.lists(finite64, max_size=20),
    kind=st.sampled_from(("A", "definite")),
    trailer=st.binary(min_size=1, max_size=6).filter(lambda t: t not in (b"\n", b"\r\n")),
)
def test_anything_but_a_line_end_after_a_counted_block_is_rejected(values, kind, trailer):
    whole = block(kind, struct.pack(f">{len(values)}d", *values))
    with pytest.raises(ProtocolError) as info:
        parse_block(whole + trailer, CMD)
    assert info.value.received == whole + trailer


arbitrary_reply = st.one_of(
    st.binary(max_size=200),
    st.builds(
        bytes.__add__,
        st.sampled_from([b"#A", b"#0", b"#1", b"#2", b"#3", b"#9", b"#", b"#A\x00", b"#18", b"#216"]),
        st.binary(max_size=200),
    ),
)


@FAST
@given(data=arbitrary_reply, dtype=st.sampled_from((">f8", ">f4")), expected=st.none() | st.integers(0, 30))
def test_arbitrary_bytes_give_finite_values_or_protocol_error(data, dtype, expected):
    error: ProtocolError | None = None
    try:
        values = parse_block(data, CMD, dtype=dtype, expected_values=expected)
    except ProtocolError as exc:
        error = exc
    if error is not None:
        assert error.command == CMD
        assert str(error).startswith(f"{CMD}: ")
        return
    assert isinstance(values, np.ndarray)
    assert values.dtype == np.float64
    assert values.ndim == 1
    assert np.all(np.isfinite(values))
    if expected is not None:
        assert values.size == expected


# ------------------------------------------------------------------ traces
HEADER = 66
# Display-function codes of header word 0 as the 3562A family documents them
# (docs/instrument.md), under our mnemonics; 5 (cross spectrum) and 10 (impulse
# response) exist but the driver never asks for them.
DISPLAY = {1: "FRSP", 2: "PSP1", 3: "PSP2", 4: "COHR", 6: "TIM1", 7: "TIM2", 8: "LSP1", 9: "LSP2"}
# Header word 10 (documented) and word 7: 0 time, 1 frequency.
X_UNITS = {1: "Hz", 4: "s"}
# Header word 9: no documented codes, ours (proj).
Y_UNITS = {0: "V", 1: "N", 2: "m/s^2", 3: "(m/s^2)/N", 4: "", 5: "N^2", 6: "(m/s^2)^2"}


def trace_values(
    n_points: int = 4,
    display: float = 1.0,
    y_units: float = 3.0,
    time_domain: bool = False,
    complex_data: bool = True,
    body: int | None = None,
    **words: float,
) -> np.ndarray:
    """A 66-value header built word by word, followed by ``body`` data values."""
    h = np.zeros(HEADER)
    h[0] = display
    h[1] = n_points
    h[2] = n_points
    h[3] = 5  # averages
    h[4] = 3  # channel: ch2/ch1
    h[7] = 0.0 if time_domain else 1.0
    h[9] = y_units
    h[10] = 4.0 if time_domain else 1.0  # x units: s or Hz
    h[36] = 0.0 if complex_data else 1.0
    h[52] = h[53] = 256.0
    h[55] = 1 / 512 if time_domain else 0.5
    h[64] = 0.0
    for key, value in words.items():
        h[int(key.removeprefix("w"))] = value
    count = n_points * (2 if complex_data else 1) if body is None else body
    return np.concatenate([h, np.arange(count, dtype=float) + 1.0])


def test_trace_header_decodes_by_hand():
    trace = Trace.from_values(trace_values(n_points=3, w3=7, w5=1, w64=10.0), CMD)
    h = trace.header
    assert (h.display_function, h.n_points, h.n_averages, h.channel) == ("FRSP", 3, 7, 3)
    assert (h.overflow, h.time_domain, h.complex_data) == (True, False, True)
    assert (h.x_units, h.y_units) == ("Hz", "(m/s^2)/N")
    assert (h.sample_rate_hz, h.delta_x, h.start_x) == (512.0, 0.5, 10.0)
    assert trace.data.tolist() == [1 + 2j, 3 + 4j, 5 + 6j]
    assert trace.x.tolist() == [10.0, 10.5, 11.0]


def test_real_time_trace_by_hand():
    trace = Trace.from_values(
        trace_values(n_points=3, display=6, y_units=1, time_domain=True, complex_data=False), CMD
    )
    assert trace.header.display_function == "TIM1"
    assert trace.header.x_units == "s"
    assert trace.data.dtype == np.float64
    assert trace.data.tolist() == [1.0, 2.0, 3.0]


@pytest.mark.parametrize(
    "words",
    [
        {"display": 0},
        {"display": 5},  # cross spectrum: documented, but not a function the driver reads
        {"display": 11},
        {"display": 7.5},
        {"y_units": 7},
        {"y_units": -1},
        {"w10": 2},  # x units
        {"w10": 0},  # the old project code for seconds
        {"w10": 4},  # seconds on a frequency trace
        {"w5": 2},  # overflow flag
        {"w7": 0.5},  # domain flag
        {"w36": 3},  # complex/real flag
        {"w4": 0},  # channel
        {"w3": -1},  # averages
        {"w3": 1.5},
        {"w52": 0},
        {"w55": -0.5},
        {"n_points": 0, "body": 0},
        {"n_points": 2.5, "body": 5},
    ],
)
def test_trace_rejects_bad_header_words(words):
    with pytest.raises(ProtocolError) as info:
        Trace.from_values(trace_values(**words), "DDAN of FRSP")
    assert str(info.value).startswith("DDAN of FRSP: ")


@pytest.mark.parametrize(
    ("n_points", "complex_data", "body"), [(4, True, 7), (4, True, 9), (4, False, 8), (4, True, 0)]
)
def test_trace_rejects_inconsistent_counts(n_points, complex_data, body):
    with pytest.raises(ProtocolError, match=f"holds {body}"):
        Trace.from_values(trace_values(n_points=n_points, complex_data=complex_data, body=body), CMD)


def test_trace_rejects_a_short_header():
    with pytest.raises(ProtocolError, match="66-value header"):
        Trace.from_values(np.ones(65), CMD)


@FAST
@given(word=st.sampled_from([0, 9, 10]), code=finite64)
def test_trace_rejects_any_unknown_code(word, code):
    known = {0: DISPLAY, 9: Y_UNITS, 10: X_UNITS}[word]
    if code in known:
        return
    with pytest.raises(ProtocolError, match=f"header word {word} "):
        Trace.from_values(trace_values(**{f"w{word}": code}), CMD)


@FAST
@given(
    n_points=st.integers(1, 50),
    complex_data=st.booleans(),
    delta=st.integers(-20, 20).filter(lambda d: d != 0),
)
def test_trace_rejects_any_inconsistent_count(n_points, complex_data, delta):
    expected = n_points * (2 if complex_data else 1)
    body = max(0, expected + delta)
    if body == expected:
        return
    with pytest.raises(ProtocolError, match=f"announces {expected} data values"):
        Trace.from_values(trace_values(n_points=n_points, complex_data=complex_data, body=body), CMD)


@FAST
@given(
    n_points=st.integers(1, 50),
    display=st.sampled_from(sorted(DISPLAY)),
    y_units=st.sampled_from(sorted(Y_UNITS)),
    time_domain=st.booleans(),
    complex_data=st.booleans(),
)
def test_trace_accepts_any_consistent_header(n_points, display, y_units, time_domain, complex_data):
    values = trace_values(n_points, display, y_units, time_domain, complex_data)
    trace = Trace.from_values(values, CMD)
    assert trace.header.display_function == DISPLAY[display]
    assert trace.header.y_units == Y_UNITS[y_units]
    assert trace.header.x_units == ("s" if time_domain else "Hz")
    assert trace.header.time_domain is time_domain
    assert trace.data.shape == (n_points,)
    body = values[HEADER:]
    expected = body[0::2] + 1j * body[1::2] if complex_data else body
    assert np.array_equal(trace.data, expected)


@FAST
@given(values=st.lists(finite64, min_size=0, max_size=90))
def test_trace_of_arbitrary_finite_values_is_a_trace_or_a_protocol_error(values):
    try:
        trace = Trace.from_values(np.array(values, dtype=float), CMD)
    except ProtocolError:
        return
    assert trace.data.shape == (trace.header.n_points,)


# ------------------------------------------------------------------ ASCII dumps
def lines_of(data: bytes):
    """read_line over ``data``: one CR LF line per call, InstrumentTimeout at the end."""
    from drivers.errors import InstrumentTimeout

    pending = data.split(b"\r\n")

    def read_line() -> bytes:
        if len(pending) <= 1:
            raise InstrumentTimeout("no more lines")
        return pending.pop(0)

    return read_line


def test_ascii_dump_is_hash_i_then_the_count_then_the_values():
    data = b"#I\r\n+3.0000000000000000E+00\r\n+1.5E+00\r\n-2.5E-03\r\n+4.0E+02\r\n"
    assert read_ascii_dump(lines_of(data), "DDAS", 10).tolist() == [1.5, -2.5e-3, 400.0]


def test_ascii_dump_count_on_the_hash_i_line_is_taken_too():
    assert read_ascii_dump(lines_of(b"#I2\r\n1\r\n2\r\n"), "DDAS", 10).tolist() == [1.0, 2.0]


@pytest.mark.parametrize(
    ("data", "message"),
    [
        (b"+3.0E+00\r\n1\r\n2\r\n3\r\n", "starting with '#I'"),  # today's DDAS: no #I
        (b"#I\r\n2.5\r\n1\r\n2\r\n", "whole number"),
        (b"#I\r\n11\r\n", "whole number 0..10"),
        (b"#I\r\n-1\r\n", "whole number"),
        (b"#I\r\nthree\r\n", "the count of the ASCII dump is not a number"),
        (b"#I\r\n2\r\n1\r\nnan\r\n", "value 1 of the ASCII dump is not finite"),
        (b"#I\r\n2\r\n1\r\nFRS 200 HZ\r\n", "value 1 of the ASCII dump is not a number"),
    ],
)
def test_ascii_dump_refuses_what_is_not_one(data, message):
    with pytest.raises(ProtocolError, match=message) as info:
        read_ascii_dump(lines_of(data), "DDAS", 10)
    assert str(info.value).startswith("DDAS: ")


def test_ascii_dump_shorter_than_its_count_times_out():
    from drivers.errors import InstrumentTimeout

    with pytest.raises(InstrumentTimeout):
        read_ascii_dump(lines_of(b"#I\r\n3\r\n1\r\n2\r\n"), "DDAS", 10)
