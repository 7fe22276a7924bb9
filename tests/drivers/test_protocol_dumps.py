"""The exact bytes of the dumps (docs/instrument.md), built here word by word from
the documented formats, not from what the driver or the simulator emits:
``#A`` + 2-byte big-endian byte count + big-endian float64 (66 header values, then
the data, complex interleaved re, im); ``#I`` + count line + one value per line.
"""

import struct

import numpy as np
import pytest

from drivers.errors import ProtocolError
from tests.drivers.expected_protocol import expected

# ------------------------------------------------------------------ dumps
# Header words as documented (docs/instrument.md): 0 display function (1 frequency
# response, 4 coherence, 6/7 input time ch1/ch2, 8/9 linear spectrum ch1/ch2),
# 7 domain (0 time, 1 frequency), 10 x units (1 Hz, 4 s), 36 complex/real.
FREQUENCY_RESPONSE, COHERENCE, TIME_CH1, TIME_CH2, LINEAR_CH1 = 1.0, 4.0, 6.0, 7.0, 8.0
TIME, FREQUENCY = 0.0, 1.0
HZ, SECONDS = 1.0, 4.0
# Word 9, y units: no documented codes, the project's (proj): 1 N, 2 m/s^2, 3 (m/s^2)/N, 4 none.
N, M_S2, M_S2_PER_N, RATIO = 1.0, 2.0, 3.0, 4.0


def _block(values):
    payload = struct.pack(f">{len(values)}d", *values)
    return b"#A" + struct.pack(">H", len(payload)) + payload


def _ascii_dump(values):
    """#I, the count line, then one value per line, CR LF each."""
    return b"#I\r\n" + b"".join(f"{float(v)!r}\r\n".encode() for v in [len(values), *values])


def _header(function_code, n, channel, domain, y_units, complex_data, half_fs, delta, start, averages=1):
    h = [0.0] * 66
    h[0], h[1], h[2], h[3], h[4] = function_code, n, n, averages, channel
    h[7], h[9], h[36], h[40] = domain, y_units, 0.0 if complex_data else 1.0, 1.0
    h[10] = SECONDS if domain == TIME else HZ
    h[52] = h[53] = half_fs
    h[55], h[64] = delta, start
    return h


def test_fetch_frf_sends_trace_select_and_dump_and_decodes_the_block():
    lines = np.arange(401) * 0.5
    data = []
    for k in range(401):
        data += [float(k), -float(k) / 2]
    header = _header(FREQUENCY_RESPONSE, 401, 3, FREQUENCY, M_S2_PER_N, True, 256.0, 0.5, 0.0, averages=5)
    block = _block(header + data)
    assert block[:4] == b"#A\x1b\x20"  # (66 + 802) x 8 = 6944 = 0x1b20 bytes
    with expected([(b"TRCA;FRSP;DDAN", block)]) as dsa:
        frf = dsa.fetch_frf()
    assert frf.header.display_function == "FRSP"
    assert frf.header.time_domain is False
    assert frf.header.x_units == "Hz"
    assert frf.header.n_averages == 5
    assert frf.header.y_units == "(m/s^2)/N"
    np.testing.assert_array_equal(frf.x, lines)
    np.testing.assert_array_equal(frf.data, np.arange(401) - 0.5j * np.arange(401))


def test_fetch_time_records():
    force = [float(k % 7) for k in range(1024)]
    accel = [float(-k) for k in range(1024)]
    steps = [
        (
            b"TRCA;TIM1;DDAN",
            _block(_header(TIME_CH1, 1024, 1, TIME, N, False, 256.0, 1 / 512, -0.02) + force),
        ),
        (
            b"TRCA;TIM2;DDAN",
            _block(_header(TIME_CH2, 1024, 2, TIME, M_S2, False, 256.0, 1 / 512, -0.02) + accel),
        ),
    ]
    with expected(steps) as dsa:
        f, a = dsa.fetch_time_records()
    assert f.header.sample_rate_hz == 512.0
    assert f.header.x_units == "s"
    assert f.header.y_units == "N"
    assert a.header.y_units == "m/s^2"
    assert f.x[0] == -0.02
    np.testing.assert_array_equal(f.data, force)
    np.testing.assert_array_equal(a.data, accel)


def test_an_frf_under_the_old_project_codes_is_refused():
    """Before issue 7 the driver wrote FRSP as 7, which the 3562A family documents as
    the channel 2 time record: such a dump must not pass as a frequency response."""
    h = _header(7.0, 401, 3, FREQUENCY, M_S2_PER_N, True, 256.0, 0.5, 0.0)
    with (
        expected([(b"TRCA;FRSP;DDAN", _block(h + [0.0] * 802))], retries=0) as dsa,
        pytest.raises(ProtocolError, match="asked for FRSP, the dump holds TIM2"),
    ):
        dsa.fetch_frf()


def test_fetch_coherence_in_ascii():
    h = _header(COHERENCE, 401, 3, FREQUENCY, RATIO, False, 256.0, 0.5, 0.0, averages=3)
    coherence = [k / 400 for k in range(401)]
    dump = _ascii_dump(h + coherence)
    assert dump.startswith(b"#I\r\n467.0\r\n4.0\r\n401.0\r\n")  # count 66 + 401, coherence
    with expected([(b"TRCA;COHR;DDAS", dump)]) as dsa:
        trace = dsa.fetch_trace("COHR", ascii=True)
    assert trace.header.display_function == "COHR"
    assert trace.header.n_averages == 3
    np.testing.assert_array_equal(trace.data, coherence)


def test_a_garbled_dump_is_retried_after_a_device_clear_then_reported():
    good = _block(_header(COHERENCE, 401, 3, FREQUENCY, RATIO, False, 256.0, 0.5, 0.0) + [1.0] * 401)
    with expected([(b"TRCA;COHR;DDAN", b"\xff\xfe" + good), (b"TRCA;COHR;DDAN", good)], retries=1) as dsa:
        assert dsa.fetch_coherence().data.tolist() == [1.0] * 401
    with (
        expected([(b"TRCA;COHR;DDAN", b"garbage!"), (b"TRCA;COHR;DDAN", b"garbage!")], retries=1) as dsa,
        pytest.raises(ProtocolError, match=r"DDAN of COHR: .*'#'.*\(after 2 attempts\)"),
    ):
        dsa.fetch_coherence()


@pytest.mark.parametrize(
    ("header_change", "message"),
    [
        ({1: 400.0, 2: 400.0}, "401 points"),
        ({0: LINEAR_CH1}, "holds LSP1"),
        ({9: 42.0}, "unknown code"),
        ({10: SECONDS}, "do not fit the domain"),
        ({36: 0.5}, "0 or 1"),
    ],
)
def test_inconsistent_dumps_are_protocol_errors(header_change, message):
    h = _header(COHERENCE, 401, 3, FREQUENCY, RATIO, False, 256.0, 0.5, 0.0)
    for index, value in header_change.items():
        h[index] = value
    n = int(h[1])
    with (
        expected([(b"TRCA;COHR;DDAN", _block(h + [0.5] * n))], retries=0) as dsa,
        pytest.raises(ProtocolError, match=message),
    ):
        dsa.fetch_coherence()


# The state dump: 96 float64; where our settings sit is the project's choice
# (drivers/state.py, proj); every other word is undocumented.
STATE = [0.0] * 96
STATE[0:5] = [200.0, 100.0, 5.0, 1.0, 1.0]  # span Hz, center Hz, averages, 1 = STBL, preview
STATE[5:11] = [3.0, 4.0, 0.05, 0.05, 1.0, 0.5]  # windows FORC, EXPO; force widths s; exp decays s
STATE[11:19] = [0.02, 1.0, 0.0, 1.0, 0.0, 0.0, 2.25e-3, 1.02e-3]  # ranges V, AU1 off, AU2 on, DC, sens.
STATE[19:26] = [
    1.0,
    2.25e-3,
    -1.0,
    -0.02,
    1.0,
    1.0,
    4.0,
]  # CH1, level V, NEG, delay s, B, FRSP, COHR
STATE[80] = 12345.0  # an undocumented word: kept raw, never interpreted


def _check_state(state):
    assert (state.span_hz, state.center_hz, state.n_averages) == (200.0, 100.0, 5)
    assert (state.averaging, state.preview) == ("STBL", True)
    assert (state.window1, state.window2) == ("FORC", "EXPO")
    assert (state.force_width1_s, state.exp_decay2_s) == (0.05, 0.5)
    assert (state.range1_v, state.autorange1, state.autorange2, state.ac_coupled1) == (
        0.02,
        False,
        True,
        False,
    )
    assert (state.sensitivity1_v_per_eu, state.sensitivity2_v_per_eu) == (2.25e-3, 1.02e-3)
    assert (state.trigger_source, state.trigger_level_v, state.trigger_slope) == ("CH1", 2.25e-3, "NEG")
    assert state.trigger_delay_s == -0.02
    assert (state.active_trace, state.display_a, state.display_b) == ("B", "FRSP", "COHR")
    assert state.values.tolist() == STATE


def test_read_state_binary():
    block = _block(STATE)
    assert block[:4] == b"#A\x03\x00"  # 96 x 8 = 768 bytes
    with expected([(b"DSAN", block)]) as dsa:
        _check_state(dsa.read_state())


def test_read_state_ascii():
    dump = _ascii_dump(STATE)
    assert dump.startswith(b"#I\r\n96.0\r\n200.0\r\n")
    with expected([(b"DSAS", dump)]) as dsa:
        _check_state(dsa.read_state(ascii=True))


@pytest.mark.parametrize(
    ("words", "message"),
    [
        (STATE[:95], "a state dump holds 96 values, got 95"),
        ([*STATE[:5], 5.0, *STATE[6:]], r"state word 5 \(WIN1"),  # no 6th window
        ([*STATE[:4], 0.5, *STATE[5:]], r"state word 4 \(PRVW"),  # a flag of 0.5
        ([*STATE[:24], 5.0, *STATE[25:]], r"state word 24 \(DISP\?"),  # cross spectrum: not ours
    ],
)
def test_a_state_dump_that_does_not_fit_is_a_protocol_error(words, message):
    with expected([(b"DSAN", _block(words))], retries=0) as dsa, pytest.raises(ProtocolError, match=message):
        dsa.read_state()


def test_the_old_state_dump_of_commands_is_refused():
    """Before issue 7 DSAN carried the state as ASCII commands in an #A block."""
    text = b"FRS 200.0 HZ;CF 100.0 HZ"
    with (
        expected([(b"DSAN", b"#A" + struct.pack(">H", len(text)) + text)], retries=0) as dsa,
        pytest.raises(ProtocolError),
    ):
        dsa.read_state()
