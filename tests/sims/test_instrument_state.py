"""The simulated analyzer's state over time: settings, coercion, errors, the
measurement state machine (fake clock), preview, averaging, autorange, traces,
state dumps, zoom and determinism, all through the bytes of a connection.

Expectations come from docs/instrument.md and the documented command table
(sims/command_table.py), never from the simulator's own replies: numeric replies
``{:+.9E}``, spans 102.4 kHz / 2^n rounded up, ranges in 1 dB steps rounded up,
status bits 1 done, 2 waiting, 4/8 overload, 16 error, 32 hit pending,
64 measuring, 128 paused. Traces with known values come from the replay source
(sample rate 2.56 x span: 512 Hz at a 200 Hz span, a 2 s record; the replay
triggers 0.5 s after arming).
"""

from __future__ import annotations

import struct

import numpy as np
import pytest

from sims.instrument import Analyzer
from sims.sources import RecordedHit, ReplaySource
from tests.sims.wire import ask

pytestmark = pytest.mark.timeout(10)

CRLF = b"\r\n"
N = 1024
RATE_HZ = 512.0  # 2.56 x 200 Hz
DONE, WAITING, OVL1, OVL2, ERROR, PENDING, MEASURING, PAUSED = 1, 2, 4, 8, 16, 32, 64, 128


class FakeClock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def lines(*texts: str) -> bytes:
    return b"".join(t.encode("ascii") + CRLF for t in texts)


def num(value: float) -> bytes:
    return f"{value:+.9E}".encode("ascii") + CRLF


def dbv(db: int) -> float:
    return 10.0 ** (db / 20.0)


def status(conn) -> int:
    reply = ask(conn, "STA?")
    assert reply.endswith(CRLF)
    return int(reply)


def state_words(conn) -> list[float]:
    """The DSAS state dump: #I, the count line 96, then one value per line."""
    rows = ask(conn, "DSAS").split(CRLF)
    assert rows[:2] == [b"#I", b"96"]
    assert rows[-1] == b""
    return [float(r) for r in rows[2:-1]]


def dump(conn, request: str = "DDAN") -> tuple[np.ndarray, np.ndarray]:
    """(header, data) of a #A trace block, decoded from docs/instrument.md."""
    reply = ask(conn, request)
    assert reply[:2] == b"#A", reply[:40]
    (length,) = struct.unpack(">H", reply[2:4])
    assert len(reply) == 4 + length
    values = np.array(struct.unpack(f">{length // 8}d", reply[4:]))
    header, body = values[:66], values[66:]
    if header[36] == 0:  # complex, interleaved
        body = body[0::2] + 1j * body[1::2]
    assert body.size == header[1]
    return header, body


def impulse_hit(force_amplitude: float, accel_amplitude: float = 1.0, overload=(False, False)) -> RecordedHit:
    """Impulses at sample 0 of both channels: with a uniform window every line of the
    ch1 linear spectrum reads 2 x amplitude / 1024 (the DC line half that)."""
    force, accel = np.zeros(N), np.zeros(N)
    force[0], accel[0] = force_amplitude, accel_amplitude
    return RecordedHit(force, accel, RATE_HZ, overload=overload)


def replay(hits, loop=False, clock=None) -> Analyzer:
    if clock is None:
        return Analyzer(ReplaySource(list(hits), loop=loop))
    return Analyzer(ReplaySource(list(hits), loop=loop), time_scale=1.0, clock=clock)


def lsp1_line1(conn) -> float:
    header, body = dump(conn, "LSP1;DDAN")
    assert header[0] == 8  # linear spectrum 1
    return float(body[1].real)


# --------------------------------------------------------------------------- persistence, preset
def test_settings_data_and_errors_persist_across_connections(make_analyzer, connect):
    analyzer = replay([impulse_hit(2.0)], loop=True)
    first = connect(analyzer)
    assert ask(first, "FRS 200 HZ;NAVG 4;STBL;WIN1 FORC;TSRC CH1;TLVL 20 MV;TRCB;PSP2;STRT;FOO") == b""
    first.close()
    second = connect(analyzer)
    assert ask(second, "FRS?;NAVG?;WIN1?;TSRC?;TLVL?;TRC?;DISP?") == b"".join(
        [num(200.0), lines("4", "FORC", "CH1"), num(0.02), lines("B", "PSP2")]
    )
    assert ask(second, "AVG?;SMSD") == lines("4", "1")  # the measurement made on the first
    assert ask(second, "ERR?;ERR?") == lines('1,"Undefined command: FOO"', '0,"No error"')
    # A third client sees what the second changed.
    assert ask(second, "NAVG 9") == b""
    assert ask(connect(analyzer), "NAVG?") == lines("9")


def test_rst_restores_preset_and_clears_data_and_errors(connect):
    conn = connect(replay([impulse_hit(2.0)], loop=True))
    ask(conn, "FRS 200 HZ;STRT;NAVG 3;UNIF;TSRC CH2;RNG1 5 V;AU2;TRCB;LSP2;FOO")
    assert ask(conn, "AVG?;STA?") == lines("1", str(DONE | ERROR))
    assert ask(conn, "RST;STA?;AVG?;SMSD;ERR?;OVLD?") == lines("0", "0", "0", '0,"No error"', "0,0")
    assert ask(conn, "FRS?;CF?;NAVG?;WIN1?;WIN2?;TSRC?;RNG1?;TRC?;DISP?") == b"".join(
        [num(102400.0), num(51200.0), lines("1", "HANN", "HANN", "FREE"), num(1.0), lines("A", "FRSP")]
    )
    assert ask(conn, "DDAN") == b""  # the data went with the reset
    assert ask(conn, "ERR?") == lines('5,"No data available: FRSP: no averaged data yet"')


# --------------------------------------------------------------------------- errors
def test_errors_are_queued_in_order_and_the_session_continues(connect):
    conn = connect()
    reply = ask(conn, "FOO;FRS 400 HZ;NAVG 0;BAR 1;FRS?;ID? 2;NAVG?;ID?")
    assert reply == num(400.0) + lines("1", "HP35660A")
    assert status(conn) & ERROR
    assert ask(conn, "ERR?") == lines('1,"Undefined command: FOO"')
    assert ask(conn, "ERR?") == lines('2,"Parameter out of range: NAVG 0"')
    assert status(conn) & ERROR  # still two queued
    assert ask(conn, "ERR?") == lines('1,"Undefined command: BAR"')
    assert ask(conn, "ERR?") == lines('3,"Invalid parameter: ID? takes no value"')
    assert ask(conn, "ERR?") == lines('0,"No error"')
    assert not status(conn) & ERROR
    # A second message after the errors is served normally.
    assert ask(conn, "FRS 800 HZ;FRS?") == num(800.0)


def test_error_queue_keeps_the_oldest_and_flags_the_overflow(connect):
    conn = connect()
    assert ask(conn, ";".join(f"BAD{i}" for i in range(40))) == b""
    for i in range(31):
        assert ask(conn, "ERR?") == lines(f'1,"Undefined command: BAD{i}"')
    assert ask(conn, "ERR?").startswith(b'8,"Input buffer overflow: ')
    assert ask(conn, "ERR?") == lines('0,"No error"')


def test_malformed_signed_integer_is_error_3_not_a_crash(connect):
    """``NAVG --5`` passes a digit check but is no integer: error 3, and the session goes on."""
    conn = connect()
    assert ask(conn, "NAVG --5;ID?") == lines("HP35660A")
    assert ask(conn, "ERR?").startswith(b'3,"Invalid parameter: ')
    assert ask(conn, "NAVG?") == lines("1")


@pytest.mark.parametrize("text", ["NAVG \u00b2", "PRVW \u00b9", "NAVG \u0663"])
def test_a_non_ascii_digit_given_to_the_analyzer_itself_is_error_3(text):
    """Analyzer.execute takes str (front ends decode ASCII first): a superscript or
    Arabic-Indic digit is no integer to the analyzer, not a ValueError escaping it."""
    analyzer = Analyzer()
    assert analyzer.execute(text) == []
    (reply,) = analyzer.execute("ERR?")
    assert reply.data.startswith(b'3,"Invalid parameter: ')
    assert [r.data for r in analyzer.execute("NAVG?;PRVW?")] == [b"1\r\n", b"0\r\n"]


def test_non_ascii_byte_is_error_1_not_a_crash(connect):
    """A stray byte >= 0x80 is an undefined command whose ERR? text still encodes as ASCII."""
    conn = connect()
    conn.write(b"FO\xffO\n")
    reply = ask(conn, "ERR?")
    assert reply.startswith(b'1,"Undefined command: ')
    assert reply.endswith(b'"\r\n')
    reply.decode("ascii")
    assert ask(conn, "ID?") == lines("HP35660A")


# --------------------------------------------------------------------------- coercion
@pytest.mark.parametrize(
    ("text", "expected_hz"),
    [
        ("102.4 KHZ", 102400.0),
        ("100 KHZ", 102400.0),
        ("51201 HZ", 102400.0),
        ("51200", 51200.0),
        ("2 KHZ", 3200.0),
        ("1600 HZ", 1600.0),
        ("201 HZ", 400.0),
        ("150 HZ", 200.0),
        ("12.5 HZ", 12.5),
        ("0.2 HZ", 0.390625),
        ("0.1953125 HZ", 0.1953125),  # 102.4 kHz / 2^19, the narrowest
    ],
)
def test_span_is_rounded_up_to_102_4_khz_over_a_power_of_two(text, expected_hz, connect):
    conn = connect()
    assert ask(conn, f"FRS {text};FRS?;CF?;ERR?") == num(expected_hz) + num(expected_hz / 2) + lines(
        '0,"No error"'
    )


@pytest.mark.parametrize("text", ["102401 HZ", "0.19 HZ", "0 HZ", "-200 HZ", "1E6 HZ"])
def test_span_out_of_range_is_error_2_and_keeps_the_span(text, connect):
    conn = connect()
    ask(conn, "FRS 400 HZ")
    assert ask(conn, f"FRS {text};FRS?") == num(400.0)
    assert ask(conn, "ERR?").startswith(f'2,"Parameter out of range: FRS {text}'.encode("ascii"))


@pytest.mark.parametrize(
    ("text", "expected_v"),
    [
        ("1 V", 1.0),
        ("1.1 V", dbv(1)),
        ("0.5 V", dbv(-6)),
        ("501.1 MV", dbv(-6)),
        ("501.2 MV", dbv(-5)),
        ("2 V", dbv(7)),
        ("20 MV", dbv(-33)),
        ("1 MV", dbv(-51)),  # below the most sensitive range: that range
        ("22 V", dbv(27)),
        ("0 DBV", 1.0),
        ("-3.5 DBV", dbv(-3)),
    ],
)
def test_range_is_rounded_up_to_a_whole_dbv(text, expected_v, connect):
    conn = connect()
    assert ask(conn, f"RNG1 {text};RNG2 {text};RNG1?;RNG2?;ERR?") == num(expected_v) * 2 + lines(
        '0,"No error"'
    )


@pytest.mark.parametrize("text", ["23 V", "0 V", "-1 V", "28 DBV"])
def test_range_out_of_range_is_error_2(text, connect):
    conn = connect()
    assert ask(conn, f"RNG1 {text};RNG1?") == num(1.0)
    assert ask(conn, "ERR?").startswith(f'2,"Parameter out of range: RNG1 {text}'.encode("ascii"))


def test_pre_trigger_delay_is_at_most_one_record(connect):
    conn = connect()
    record_s = 1024 / (2.56 * 102400)  # 3.90625 ms at the full span
    assert ask(conn, "TDLY -3.90625 MS;TDLY?") == num(-record_s)
    assert ask(conn, "TDLY -3.91 MS;TDLY?") == num(-record_s)
    assert ask(conn, "ERR?").startswith(b'2,"Parameter out of range: TDLY -3.91 MS')
    # At 200 Hz the record is 2 s long.
    assert ask(conn, "FRS 200 HZ;TDLY -2 S;TDLY?;ERR?") == num(-2.0) + lines('0,"No error"')
    assert ask(conn, "TDLY -2.01 S;TDLY?") == num(-2.0)
    assert ask(conn, "ERR?").startswith(b'2,"Parameter out of range: TDLY -2.01 S')
    # A post-trigger delay is not limited by the record.
    assert ask(conn, "TDLY 100 S;TDLY?;ERR?") == num(100.0) + lines('0,"No error"')
    # A shorter record pulls a pre-trigger delay in with it.
    assert ask(conn, "TDLY -2 S;FRS 400 HZ;TDLY?") == num(-1.0)


# --------------------------------------------------------------------------- measurement timing
def test_status_goes_waiting_measuring_done_with_the_clock(connect):
    clock = FakeClock()
    conn = connect(replay([impulse_hit(2.0)], loop=True, clock=clock))
    assert ask(conn, "FRS 200 HZ;STA?;SMSD") == lines("0", "0")
    ask(conn, "STRT")
    timeline = [
        (0.0, WAITING),
        (0.49, WAITING),
        (0.51, MEASURING),
        (2.49, MEASURING),
        (2.51, DONE),
        (9.0, DONE),
    ]
    for t, expected in timeline:
        clock.now = t
        assert status(conn) == expected, t
        assert ask(conn, "SMSD") == lines("1" if expected == DONE else "0"), t
        assert ask(conn, "AVG?") == lines("1" if expected == DONE else "0"), t


def test_status_order_with_physics_and_a_trigger(make_analyzer, connect):
    clock = FakeClock()
    conn = connect(make_analyzer(time_scale=1.0, clock=clock))
    ask(conn, "FRS 200 HZ;TSRC CH1;TLVL 5 MV;STRT")
    seen = []
    for t in np.arange(0.0, 8.0, 0.05):
        clock.now = float(t)
        s = status(conn)
        if not seen or seen[-1] != s:
            seen.append(s)
    # The technician hits 0.5-2 s after arming; a 200 Hz record lasts 2 s.
    assert seen == [WAITING, MEASURING, DONE]
    assert ask(conn, "SMSD;AVG?") == lines("1", "1")


def test_trigger_delay_moves_the_end_of_the_record(connect):
    for delay, done_at in (("1 S", 3.5), ("-1 S", 1.5)):
        clock = FakeClock()
        conn = connect(replay([impulse_hit(2.0)], loop=True, clock=clock))
        ask(conn, f"FRS 200 HZ;TDLY {delay};STRT")
        clock.now = done_at - 0.01
        assert status(conn) == MEASURING, delay
        clock.now = done_at + 0.01
        assert status(conn) == DONE, delay


def test_each_average_rearms_at_the_end_of_the_previous_record(connect):
    clock = FakeClock()
    conn = connect(replay([impulse_hit(2.0)], loop=True, clock=clock))
    ask(conn, "FRS 200 HZ;STBL;NAVG 2;STRT")
    for t, expected, count in (
        (2.51, WAITING, "1"),
        (2.99, WAITING, "1"),
        (3.01, MEASURING, "1"),
        (5.01, DONE, "2"),
    ):
        clock.now = t
        assert status(conn) == expected, t
        assert ask(conn, "AVG?") == lines(count), t
    # Catching up late gives the same result: the clock only decides *when*.
    clock2 = FakeClock()
    late = connect(replay([impulse_hit(2.0)], loop=True, clock=clock2))
    ask(late, "FRS 200 HZ;STBL;NAVG 2;STRT")
    clock2.now = 100.0
    assert ask(late, "STA?;AVG?") == lines(str(DONE), "2")


def test_pause_and_continue_shift_the_timing(connect):
    clock = FakeClock()
    conn = connect(replay([impulse_hit(2.0)], loop=True, clock=clock))
    ask(conn, "FRS 200 HZ;STRT")
    clock.now = 0.2
    ask(conn, "PAUS")
    assert status(conn) == WAITING | PAUSED
    clock.now = 5.0
    assert status(conn) == WAITING | PAUSED  # the trigger at 0.5 s did not come while paused
    ask(conn, "CONT")  # 4.8 s paused: trigger at 5.3 s, end of record at 7.3 s
    assert status(conn) == WAITING
    for t, expected in ((5.29, WAITING), (5.31, MEASURING), (6.0, MEASURING)):
        clock.now = t
        assert status(conn) == expected, t
    ask(conn, "PAUS")  # paused while measuring, at 6.0 s
    clock.now = 100.0
    assert status(conn) == MEASURING | PAUSED
    assert ask(conn, "SMSD") == lines("0")
    ask(conn, "CONT")  # 94 s more: end of record at 101.3 s
    clock.now = 101.29
    assert status(conn) == MEASURING
    clock.now = 101.31
    assert ask(conn, "STA?;SMSD") == lines(str(DONE), "1")


# --------------------------------------------------------------------------- preview, averaging
def test_preview_accept_and_reject(connect):
    hits = [impulse_hit(8.0), impulse_hit(2.0), impulse_hit(4.0)]
    conn = connect(replay(hits))
    ask(conn, "FRS 200 HZ;UNIF;PRVW 1;STBL;NAVG 2;STRT")
    assert ask(conn, "STA?;AVG?;SMSD") == lines(str(PENDING), "0", "0")
    _, body = dump(conn, "TIM1;DDAN")  # the pending hit can be looked at
    assert np.array_equal(body, hits[0].force_n)
    assert ask(conn, "FRSP;RJCT;STA?;AVG?") == lines(str(PENDING), "0")  # the next hit waits
    assert ask(conn, "ACPT;STA?;AVG?") == lines(str(PENDING), "1")
    assert ask(conn, "ACPT;STA?;AVG?;SMSD") == lines(str(DONE), "2", "1")
    # The rejected 8 N hit is not in the average: (2 + 4) / 2 N.
    assert lsp1_line1(conn) == 2 * 3.0 / N
    assert ask(conn, "ACPT;RJCT;AVG?") == lines("2")
    assert ask(conn, "ERR?;ERR?;ERR?") == lines(
        '6,"Not allowed now: ACPT with no hit waiting for preview"',
        '6,"Not allowed now: RJCT with no hit waiting for preview"',
        '0,"No error"',
    )


def test_averaging_off_takes_one_record_stable_averages_n(connect):
    hits = [impulse_hit(2.0), impulse_hit(4.0), impulse_hit(6.0)]
    off = connect(replay(hits))
    assert ask(off, "FRS 200 HZ;UNIF;AVOF;NAVG 3;STRT;AVG?;SMSD") == lines("1", "1")
    assert lsp1_line1(off) == 2 * 2.0 / N
    header, _ = dump(off, "FRSP;DDAN")
    assert header[3] == 1

    stable = connect(replay(hits))
    assert ask(stable, "FRS 200 HZ;UNIF;STBL;NAVG 3;STRT;AVG?;SMSD") == lines("3", "1")
    assert lsp1_line1(stable) == 2 * 4.0 / N  # mean of the linear spectra
    header, psp = dump(stable, "PSP1;DDAN")
    assert header[3] == 3
    # Power spectra average the squared magnitudes: (4 + 16 + 36) / 3 N^2.
    assert psp[1] == pytest.approx((4 + 16 + 36) / 3 * (2 / N) ** 2, rel=1e-12)


# --------------------------------------------------------------------------- autorange
def test_autorange_up_ranges_and_drops_the_overloaded_hit(connect):
    over = impulse_hit(8.0, 50.0, overload=(False, True))
    clean = impulse_hit(2.0, 3.0)
    conn = connect(replay([over, clean]))
    ask(conn, "FRS 200 HZ;UNIF;RNG2 1 MV;AU2")
    assert ask(conn, "RNG2?") == num(dbv(-51))
    ask(conn, "STRT")
    assert ask(conn, "STA?;AVG?;OVLD?") == lines(str(DONE), "1", "0,0")
    # The range went up (a doubling of -51 dBV rounds up to -44 dBV) ...
    assert ask(conn, "RNG2?") == num(dbv(-44))
    # ... and only the clean hit is in the average.
    assert lsp1_line1(conn) == 2 * 2.0 / N
    _, tim2 = dump(conn, "TIM2;DDAN")
    assert np.array_equal(tim2, clean.acceleration_m_s2)
    assert state_words(conn)[14] == 1.0  # autorange of channel 2 stays on


def test_overload_without_autorange_is_kept_and_flagged(connect):
    conn = connect(replay([impulse_hit(8.0, overload=(True, False))]))
    assert ask(conn, "FRS 200 HZ;AU2;STRT;STA?;AVG?;OVLD?;RNG1?") == lines(
        str(DONE | OVL1), "1", "1,0"
    ) + num(1.0)
    header, _ = dump(conn, "DDAN")
    assert header[5] == 1  # FRSP overflow word


def test_autorange_with_physics(make_analyzer, connect):
    conn = connect(make_analyzer())
    ask(conn, "FRS 200 HZ;TSRC CH1;TLVL 5 MV;RNG2 1 MV;AU2;STRT")
    assert ask(conn, "SMSD;AVG?;OVLD?") == lines("1", "1", "0,0")
    assert float(ask(conn, "RNG2?")) > dbv(-51)
    assert int(ask(conn, "SIM:HITS?")) >= 2  # at least one hit was dropped
    header, _ = dump(conn, "DDAN")
    assert header[5] == 0  # no overloaded record in the average


@pytest.mark.timeout(3)
def test_autorange_at_the_top_range_does_not_hang(connect):
    """A hit that overloads even the top range ends autoranging at the top range; the
    analyzer does not loop for ever (at time scale 0) holding its lock."""
    conn = connect(replay([impulse_hit(8.0, overload=(False, True))], loop=True))
    reply = ask(conn, "FRS 200 HZ;RNG2 1 MV;AU2;STRT;RNG2?")
    assert reply == num(dbv(27))


# --------------------------------------------------------------------------- traces, state dumps
def test_each_trace_keeps_its_display_function(connect):
    conn = connect(replay([impulse_hit(2.0)], loop=True))
    ask(conn, "FRS 200 HZ;UNIF;STRT;TRCB;PSP1;TRCA;TIM2")
    assert ask(conn, "TRC?;DISP?") == lines("A", "TIM2")
    header, _ = dump(conn)
    assert (header[0], header[1], header[7]) == (7, 1024, 0)  # input time 2, 1024 points, time
    assert ask(conn, "TRCB;TRC?;DISP?") == lines("B", "PSP1")
    header, _ = dump(conn)
    assert (header[0], header[1], header[7], header[36]) == (2, 401, 1, 1)  # power spectrum 1, real
    assert ask(conn, "COHR;DISP?;TRCA;DISP?") == lines("COHR", "TIM2")
    header, _ = dump(conn, "TRCB;DDAN")
    assert header[0] == 4  # coherence


def test_state_dump_holds_the_settings_where_the_layout_says(connect):
    """DSAN and DSAS carry the same 96 values; each setting sits at its word of the
    layout in docs/instrument.md, "State dump" (ranges rounded up to 1 dB steps)."""
    conn = connect()
    settings = (
        "FRS 25 HZ;CF 40 HZ;STBL;NAVG 12;PRVW 1;WIN1 FORC;FWD1 30 MS;WIN2 EXPO;EXD2 1.5 S;"
        "RNG1 2 V;AU1;RNG2 100 MV;C1AC 1;SNS1 4 MV;SNS2 10 MV;TSRC CH1;TLVL 0.1 V;TSLP NEG;"
        "TDLY -5 S;TRCA;TIM1;TRCB;LSP2"
    )
    ask(conn, settings)
    words = state_words(conn)
    binary = ask(conn, "DSAN")
    assert binary[:4] == b"#A" + struct.pack(">H", 96 * 8)
    assert list(struct.unpack(">96d", binary[4:])) == words
    expected = {0: 25.0, 1: 40.0, 2: 12.0, 3: 1.0, 4: 1.0, 5: 3.0, 7: 0.03, 6: 4.0, 10: 1.5}
    expected |= {11: dbv(7), 12: dbv(-20), 13: 1.0, 14: 0.0, 15: 1.0, 16: 0.0, 17: 4e-3, 18: 1e-2}
    expected |= {19: 1.0, 20: 0.1, 21: -1.0, 22: -5.0, 23: 1.0, 24: 6.0, 25: 9.0}
    assert {k: words[k] for k in expected} == pytest.approx(expected, rel=1e-12)
    assert words[26:] == [0.0] * 70
    ask(conn, "RST")
    assert state_words(conn) != words
    ask(conn, settings)
    assert state_words(conn) == words


# --------------------------------------------------------------------------- zoom
def test_zoom_traces(make_analyzer, connect):
    conn = connect(make_analyzer("realistic"))
    assert ask(conn, "FRS 12.5 HZ;CF 36 HZ;STRT;SMSD") == lines("1")
    header, frsp = dump(conn, "FRSP;DDAN")
    assert header[64] == 29.75  # start frequency: 36 - 12.5 / 2
    assert header[55] == 12.5 / 400
    assert header[52] == header[53] == 8.0  # zoom records at 1.28 x span = 16 Hz
    assert header[36] == 0  # complex
    assert header[1] == frsp.size == 401
    # The realistic beam's second mode, 34.898 Hz, sits on its line of the zoom band.
    assert abs(29.75 + np.argmax(np.abs(frsp)) * 12.5 / 400 - 34.898) <= 12.5 / 400
    header, tim1 = dump(conn, "TIM1;DDAN")
    assert header[36] == 0  # complex
    assert header[1] == tim1.size == 512
    assert np.iscomplexobj(tim1)
    assert header[55] == 1 / 16.0
    assert header[7] == 0  # time domain


def test_zoom_center_must_keep_the_band_inside_0_to_102_4_khz(connect):
    conn = connect()
    assert ask(conn, "FRS 12.5 HZ;CF 6.25 HZ;CF 102393.75 HZ;CF?;ERR?") == num(102393.75) + lines(
        '0,"No error"'
    )
    for bad in ("6 HZ", "102394 HZ", "-1 HZ"):
        assert ask(conn, f"CF {bad};CF?") == num(102393.75), bad
        assert ask(conn, "ERR?").startswith(f'2,"Parameter out of range: CF {bad}'.encode("ascii")), bad
    # At the full span there is no room for a zoom.
    assert ask(conn, "FRS 102.4 KHZ;CF 36 HZ;CF?") == num(51200.0)
    assert ask(conn, "ERR?").startswith(b'2,"Parameter out of range: CF 36 HZ')


def test_replay_refuses_a_zoom(connect):
    conn = connect(replay([impulse_hit(2.0)], loop=True))
    assert ask(conn, "FRS 200 HZ;CF 1000 HZ;STRT;SMSD;AVG?") == lines("0", "0")
    assert ask(conn, "ERR?").startswith(b'6,"Not allowed now: ')


# --------------------------------------------------------------------------- determinism, no data
MEASURE = "FRS 200 HZ;TSRC CH1;TLVL 5 MV;STBL;NAVG 2;STRT"


def _dumps(conn) -> tuple[bytes, bytes]:
    assert ask(conn, "SMSD") == lines("1")
    return ask(conn, "DDAN"), ask(conn, "TIM2;DDAN")


def test_same_seed_same_bytes_other_seed_other_bytes(make_analyzer, connect):
    a = connect(make_analyzer(seed=7, noise=True))
    b = connect(make_analyzer(seed=7, noise=True))
    c = connect(make_analyzer(seed=8, noise=True))
    for conn in (a, b, c):
        ask(conn, MEASURE)
    first, second, other = _dumps(a), _dumps(b), _dumps(c)
    assert first[0][:4] == b"#A" + struct.pack(">H", 8 * (66 + 802))  # FRSP: 401 complex
    assert first == second
    assert first[0] != other[0]
    assert first[1] != other[1]


def test_timing_does_not_change_the_data(make_analyzer, connect):
    instant = connect(make_analyzer(seed=3, noise=True))
    ask(instant, MEASURE)
    clock = FakeClock()
    timed = connect(make_analyzer(seed=3, noise=True, time_scale=1.0, clock=clock))
    ask(timed, MEASURE)
    for t in (0.3, 1.7, 2.9, 4.4, 100.0):
        clock.now = t
        status(timed)
    assert _dumps(timed) == _dumps(instant)


@pytest.mark.parametrize(
    ("request_text", "error"),
    [
        ("DDAN", '5,"No data available: FRSP: no averaged data yet"'),
        ("DDAS", '5,"No data available: FRSP: no averaged data yet"'),
        ("TRCB;DDAN", '5,"No data available: COHR: no averaged data yet"'),
        ("TIM2;DDAN", '5,"No data available: TIM2: no time record yet"'),
    ],
)
def test_dump_before_any_data_sends_nothing_and_queues_error_5(request_text, error, connect):
    conn = connect()
    assert ask(conn, request_text) == b""
    assert ask(conn, "STA?;ERR?;ERR?") == lines(str(ERROR), error, '0,"No error"')


# --------------------------------------------------------------------------- span change mid-measurement
def test_span_change_while_a_hit_waits_for_preview_does_not_crash(connect):
    """FRS while a hit waits for preview discards it: ACPT then has nothing to accept."""
    conn = connect(replay([impulse_hit(2.0)], loop=True))
    assert ask(conn, "FRS 200 HZ;PRVW 1;STRT;STA?") == lines(str(PENDING))
    ask(conn, "FRS 400 HZ;ACPT")
    assert ask(conn, "ID?;AVG?") == lines("HP35660A", "0")


def test_span_change_after_a_measurement_clears_done(connect):
    """FRS discards the average (AVG? 0), and SMSD says the measurement is not done."""
    conn = connect(replay([impulse_hit(2.0)], loop=True))
    assert ask(conn, "FRS 200 HZ;STRT;SMSD") == lines("1")
    assert ask(conn, "FRS 400 HZ;AVG?;SMSD") == lines("0", "0")


def test_record_in_flight_at_a_span_change_is_not_labelled_with_the_new_span(connect):
    """A record drawn at the old span that completes after FRS is discarded, never
    averaged or shown as if taken at the new span."""
    clock = FakeClock()
    conn = connect(replay([impulse_hit(2.0)], loop=True, clock=clock))
    ask(conn, "FRS 200 HZ;STRT")
    clock.now = 1.0  # measuring
    ask(conn, "FRS 400 HZ")
    clock.now = 10.0
    assert ask(conn, "TIM1;DDAN;ERR?") == lines('5,"No data available: TIM1: no time record yet"')
    assert ask(conn, "AVG?;SMSD") == lines("0", "0")
