"""Golden request -> reply transcripts of the simulated HP 3562A, byte for byte.

The 3562A speaks the 35660A's mnemonic dialect (docs/instrument.md) with what
docs/instrument-scpi.md, "The HP 3562A dialect", says differs: ``ID?`` answers
``HP3562A``; 800 lines (801 points), 2048-sample records (1024 complex in zoom);
spans 100 kHz / 2^n. Every expected reply is written by hand from those pages,
never read back from the simulator. Replies end CR LF; ``DDAN`` is ``#A`` + a
2-byte big-endian count + big-endian float64, a 66-value header then the data.

Traces whose values must be known come from the replay source: 2048 samples at
500 Hz, i.e. the 195.3125 Hz span (100 kHz / 2^9, 2.56 x 195.3125 = 500).
"""

from __future__ import annotations

import re
import struct
from dataclasses import dataclass

import numpy as np
import pytest

from sims.command_table import ERRORS, commands_for
from sims.instrument import Analyzer
from sims.sources import PhysicsSource, RecordedHit, ReplaySource
from tests.sim.wire import ask, decode_trace

pytestmark = pytest.mark.timeout(10)

CRLF = b"\r\n"


def lines(*texts: str) -> bytes:
    return b"".join(t.encode("ascii") + CRLF for t in texts)


class FakeClock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


SPAN = "FRS 195.3125 HZ"
RATE_HZ = 500.0
N = 2048
_rng = np.random.default_rng(3562)
TIME_FORCE = np.round(_rng.normal(0.0, 3.0, N), 6)
TIME_ACCEL = np.round(_rng.normal(0.0, 40.0, N), 6)
TIME_START_S = -0.25
TIME_HIT = RecordedHit(TIME_FORCE, TIME_ACCEL, RATE_HZ, TIME_START_S, overload=(True, False))
DELTA_FORCE = np.zeros(N)
DELTA_FORCE[1] = 2.0
DELTA_ACCEL = np.zeros(N)
DELTA_ACCEL[5] = 3.0
DELTA_HIT = RecordedHit(DELTA_FORCE, DELTA_ACCEL, RATE_HZ)


def make_bench(kind: str, clock: FakeClock) -> Analyzer:
    if kind == "physics":
        source = PhysicsSource("seed", seed=0)
        source.set_noise(False)
        return Analyzer(source, model="3562A")
    hit = TIME_HIT if kind == "time" else DELTA_HIT
    replay = ReplaySource([hit], loop=True, model="3562A")
    if kind == "clock":
        return Analyzer(replay, time_scale=1.0, clock=clock, model="3562A")
    return Analyzer(replay, model="3562A")


def block(values: list[float]) -> bytes:
    payload = struct.pack(f">{len(values)}d", *values)
    return b"#A" + struct.pack(">H", len(payload)) + payload


def ascii_dump(values: list[float]) -> bytes:
    body = b"".join(f"{v:+.16E}".encode("ascii") + CRLF for v in values)
    return b"#I" + CRLF + str(len(values)).encode("ascii") + CRLF + body


def time_trace(function_code: int, channel: int, overflow: int, y_code: int, data: np.ndarray) -> list[float]:
    """A baseband TIM trace at 195.3125 Hz: 2048 points at 500 Hz (header words of docs/instrument.md)."""
    h = [0.0] * 66
    h[0] = function_code
    h[1] = h[2] = N
    h[3] = 1
    h[4] = channel
    h[5] = overflow
    h[7] = 0  # time domain
    h[9] = y_code
    h[10] = 4  # s
    h[36] = 1  # real
    h[40] = 1  # linear
    h[52] = h[53] = RATE_HZ / 2
    h[55] = 1 / RATE_HZ
    h[64] = TIME_START_S
    return h + [float(v) for v in data]


TIM1_VALUES = time_trace(6, 1, 1, 1, TIME_FORCE)
TIM2_VALUES = time_trace(7, 2, 0, 2, TIME_ACCEL)

# The state dump, laid out as docs/instrument.md, "State dump": the 3562A's preset
# span is 100 kHz at baseband.
PRESET_STATE = [
    *(100000.0, 50000.0, 1.0, 0.0, 0.0),
    *(1.0, 1.0, 0.05, 0.05, 1.0, 1.0),
    *(1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.00225, 0.00102),
    *(0.0, 0.0, 1.0, 0.0),
    *(0.0, 1.0, 4.0),
    *([0.0] * 70),
]


def state_with(**words: float) -> list[float]:
    out = list(PRESET_STATE)
    for key, value in words.items():
        out[int(key[1:])] = float(value)
    return out


MESS = (
    "FRS 195.3125 HZ;CF 300 HZ;NAVG 7;STBL;PRVW 1;WIN1 FORC;WIN2 EXPO;FWD1 10 MS;FWD2 20 MS;"
    "EXD1 0.5 S;EXD2 2 S;RNG1 5 V;RNG2 50 MV;AU1;AU2;C1AC 1;C2AC 1;SNS1 10 MV;SNS2 100 MV;"
    "TSRC CH2;TLVL -0.2 V;TSLP NEG;TDLY -1 S;TRCB;TIM2;TRCA;LSP1"
)
MESS_STATE = [
    *(195.3125, 300.0, 7.0, 1.0, 1.0),
    *(3.0, 4.0, 0.01, 0.02, 0.5, 2.0),
    *(5.011872336272722, 0.05011872336272722, 1.0, 1.0, 1.0, 1.0, 0.01, 0.1),
    *(2.0, -0.2, -1.0, -1.0),
    *(0.0, 8.0, 7.0),
    *([0.0] * 70),
]


@dataclass(frozen=True)
class Golden:
    covers: str
    exchanges: tuple[tuple[float | None, str, bytes], ...]
    bench: str = "physics"


GOLDENS: list[Golden] = []


def g(covers: str, request: str, reply: bytes, bench: str = "physics") -> None:
    GOLDENS.append(Golden(covers, ((None, request, reply),), bench))


def g_timed(covers: str, *exchanges: tuple[float, str, bytes]) -> None:
    GOLDENS.append(Golden(covers, tuple(exchanges), "clock"))


PRESET_REPLIES = {
    "FRS?": "+1.000000000E+05",
    "CF?": "+5.000000000E+04",
    "NAVG?": "1",
    "PRVW?": "0",
    "WIN1?": "HANN",
    "WIN2?": "HANN",
    "FWD1?": "+5.000000000E-02",
    "FWD2?": "+5.000000000E-02",
    "EXD1?": "+1.000000000E+00",
    "EXD2?": "+1.000000000E+00",
    "RNG1?": "+1.000000000E+00",
    "RNG2?": "+1.000000000E+00",
    "C1AC?": "0",
    "C2AC?": "0",
    "SNS1?": "+2.250000000E-03",
    "SNS2?": "+1.020000000E-03",
    "TSRC?": "FREE",
    "TLVL?": "+0.000000000E+00",
    "TSLP?": "POS",
    "TDLY?": "+0.000000000E+00",
    "DISP?": "FRSP",
    "TRC?": "A",
    "STA?": "0",
    "AVG?": "0",
    "OVLD?": "0,0",
    "SMSD": "0",
    "ERR?": '0,"No error"',
    "AVMD?": "AVOF",
    "AU1?": "0",
    "AU2?": "0",
}
for _query, _reply in PRESET_REPLIES.items():
    g(_query, f"{MESS};FOO;RST;{_query}", lines(_reply))

# -- identification and the geometry of a 3562A
g("ID?", "ID?", lines("HP3562A"))
g("ID?", "id?;*IDN?;ERR?", lines("HP3562A", '1,"Undefined command: *IDN?"'))
g("FRS", "FRS 2 KHZ;FRS?", lines("+3.125000000E+03"))  # 100 kHz / 2^5, rounded up
g("FRS", "FRS 1600 HZ;FRS?;CF?", lines("+3.125000000E+03", "+1.562500000E+03"))
g("FRS", "FRS 195.3125 HZ;FRS?", lines("+1.953125000E+02"))
g("FRS", "FRS2KHZ;FRS?", lines("+3.125000000E+03"))
g(
    "FRS",
    "FRS 102.4 KHZ;ERR?;FRS?",
    lines(
        '2,"Parameter out of range: FRS 102.4 KHZ: span must be 0.19073486 Hz to 100000 Hz"',
        "+1.000000000E+05",
    ),
)
g("CF", f"{SPAN};CF?;CF 1000 HZ;CF?", lines("+9.765625000E+01", "+1.000000000E+03"))
g(
    "CF",
    f"{SPAN};CF 99950 HZ;ERR?",
    lines(
        '2,"Parameter out of range: CF 99950 HZ: '
        'with a 195.312 Hz span the center must be 97.6562 Hz to 99902.3 Hz"'
    ),
)

# -- the settings the two models share
g("NAVG", "NAVG 16;NAVG?", lines("16"))
g("NAVG", "NAVG5;NAVG?", lines("5"))
g("PRVW", "PRVW 1;PRVW?;PRVW OFF;PRVW?", lines("1", "0"))
g("WIN1", "WIN1 FORC;WIN1?;WIN2?", lines("FORC", "HANN"))
g("WIN2", "WIN2 EXPO;WIN1?;WIN2?", lines("HANN", "EXPO"))
g("FWD1", "FWD1 10 MS;FWD1?;FWD2?", lines("+1.000000000E-02", "+5.000000000E-02"))
g("FWD2", "FWD2 2.5 MS;FWD2?", lines("+2.500000000E-03"))
g("EXD1", "EXD1 250 MS;EXD1?", lines("+2.500000000E-01"))
g("EXD2", "EXD2 3 S;EXD2?;EXD1?", lines("+3.000000000E+00", "+1.000000000E+00"))
g("RNG1", "RNG1 2 V;RNG1?", lines("+2.238721139E+00"))
g("RNG2", "RNG2 20 MV;RNG2?;RNG1?", lines("+2.238721139E-02", "+1.000000000E+00"))
g("C1AC", "C1AC1;C1AC?;C2AC?", lines("1", "0"))
g("C2AC", "C2AC ON;C2AC?;C1AC?", lines("1", "0"))
g("SNS1", "SNS1 10 MV;SNS1?", lines("+1.000000000E-02"))
g("SNS2", "SNS2 100 UV;SNS2?", lines("+1.000000000E-04"))
g("TSRC", "TSRC CH2;TSRC?", lines("CH2"))
g("TLVL", "TLVL -50 MV;TLVL?", lines("-5.000000000E-02"))
g("TSLP", "TSLP NEG;TSLP?", lines("NEG"))
g("TDLY", "TDLY -2 MS;TDLY?", lines("-2.000000000E-03"))
# A preset record lasts 800 / 100 kHz = 8 ms: that is the most pre-trigger.
g(
    "TDLY",
    "TDLY -9 MS;ERR?",
    lines('2,"Parameter out of range: TDLY -9 MS: pre-trigger is at most one record (0.008 s)"'),
)
g("RST", f"{MESS};RST;DSAS", ascii_dump(PRESET_STATE))
g("LCL", "NAVG 4;LCL;NAVG?;ERR?", lines("4", '0,"No error"'))
g("UNIF", "UNIF;WIN1?;WIN2?", lines("UNIF", "UNIF"))
g("HANN", "UNIF;HANN;WIN1?;WIN2?", lines("HANN", "HANN"))
g("FLAT", "FLAT;WIN1?;WIN2?", lines("FLAT", "FLAT"))
g("FRQR", "FRQR;ERR?", lines('0,"No error"'))
g("LNRS", "LNRS;ERR?", lines('0,"No error"'))
g("STBL", f"{SPAN};STBL;NAVG 3;STRT;AVG?;SMSD", lines("3", "1"), "delta")
g("AVOF", f"{SPAN};STBL;AVOF;NAVG 3;STRT;AVG?;SMSD", lines("1", "1"), "delta")
g("AVMD?", "STBL;AVMD?;AVOF;AVMD?", lines("STBL", "AVOF"))
g("AU1?", "AU1;AU1?;AU2?;RNG1 1 V;AU1?", lines("1", "0", "0"))
g("AU2?", "AU2;AU2?;AU1?;RNG2 1 V;AU2?", lines("1", "0", "0"))
g("AU1", "RST;AU1;DSAS", ascii_dump(state_with(w13=1.0)))
g("AU2", "RST;AU2;DSAS", ascii_dump(state_with(w14=1.0)))
g("TRC?", "TRC?", lines("A"))
g("DISP?", "DISP?;TRCB;DISP?", lines("FRSP", "COHR"))
g("TRCA", "TRCB;TRCA;TRC?;DISP?", lines("A", "FRSP"))
g("TRCB", "TRCB;TRC?;DISP?", lines("B", "COHR"))
for _fn in ("TIM1", "TIM2", "LSP1", "LSP2", "PSP1", "PSP2", "COHR"):
    g(_fn, f"TRCB;{_fn};DISP?;TRC?;TRCA;DISP?", lines(_fn, "B", "FRSP"))
g("FRSP", "TIM1;FRSP;DISP?;TRCB;DISP?", lines("FRSP", "COHR"))
g("SMSD", "SMSD", lines("0"))
g("STRT", f"{SPAN};STRT;SMSD;AVG?;STA?", lines("1", "1", "1"), "delta")
g("ACPT", f"{SPAN};PRVW 1;STRT;STA?;AVG?;ACPT;AVG?;STA?;SMSD", lines("32", "0", "1", "1", "1"), "delta")
g("RJCT", f"{SPAN};PRVW 1;STRT;RJCT;STA?;AVG?;SMSD", lines("32", "0", "0"), "delta")
g("STA?", "STA?;FOO;STA?;ERR?;STA?", lines("0", "16", '1,"Undefined command: FOO"', "0"))
g("ERR?", "ERR?", lines('0,"No error"'))
g("CLER", "FOO;BAR;CLER;ERR?;STA?", lines('0,"No error"', "0"))
g("OVLD?", f"OVLD?;{SPAN};STRT;OVLD?;STA?", lines("0,0", "1,0", "5"), "time")
g("AVG?", "AVG?", lines("0"))

# Timing: the replay triggers 0.5 s after arming; 2048 samples at 500 Hz take 4.096 s.
g_timed(
    "SMSD",
    (0.0, f"{SPAN};STRT;STA?;SMSD", lines("2", "0")),
    (0.6, "STA?;SMSD", lines("64", "0")),
    (4.7, "STA?;SMSD;AVG?", lines("1", "1", "1")),
)
g_timed(
    "PAUS",
    (0.0, f"{SPAN};STRT;STA?", lines("2")),
    (0.2, "PAUS;STA?", lines("130")),
    (50.0, "STA?;SMSD;AVG?", lines("130", "0", "0")),
)
g_timed(
    "CONT",
    (0.0, f"{SPAN};STRT", b""),
    (0.2, "PAUS", b""),
    (10.0, "CONT;STA?", lines("2")),  # trigger at 10.3 s, done at 14.396 s
    (10.29, "STA?", lines("2")),
    (10.31, "STA?", lines("64")),
    (14.39, "STA?;SMSD", lines("64", "0")),
    (14.40, "STA?;SMSD;AVG?", lines("1", "1", "1")),
)

# -- transfers: 2048-point time records, 801-line spectra, the 96-value state
g("DDAN", f"{SPAN};STRT;TIM1;DDAN", block(TIM1_VALUES), "time")
g("DDAN", f"{SPAN};STRT;TRCB;TIM2;DDAN", block(TIM2_VALUES), "time")
g("DDAS", f"{SPAN};STRT;TIM2;DDAS", ascii_dump(TIM2_VALUES), "time")
g("DDAS", f"{SPAN};STRT;TRCB;TIM1;DDAS", ascii_dump(TIM1_VALUES), "time")
g("DSAS", "RST;DSAS", ascii_dump(PRESET_STATE))
g("DSAS", f"{MESS};DSAS", ascii_dump(MESS_STATE))
g("DSAN", "RST;DSAN", block(PRESET_STATE))
g("DSAN", f"{MESS};DSAN", block(MESS_STATE))
g("DSAN", "RST;UNIF;TSRC CH1;PSP1;TRCB;PSP2;DSAN", block(state_with(w5=0, w6=0, w19=1, w23=1, w24=2, w25=3)))
g("DSAS", "RST;FLAT;TIM1;TRCB;LSP2;DSAS", ascii_dump(state_with(w5=2, w6=2, w23=1, w24=6, w25=9)))

ERROR_GOLDENS: list[tuple[int, str, bytes]] = [
    (1, "FOO;ERR?;ERR?", lines('1,"Undefined command: FOO"', '0,"No error"')),
    (1, "*IDN?;ERR?", lines('1,"Undefined command: *IDN?"')),
    (2, "NAVG 0;ERR?;NAVG?", lines('2,"Parameter out of range: NAVG 0"', "1")),
    (3, "FRS;ERR?", lines('3,"Invalid parameter: FRS needs a value"')),
    (4, "FRS 2 KV;ERR?", lines('4,"Invalid unit: FRS: unit KV does not apply here"')),
    (5, "DDAN;ERR?", lines('5,"No data available: FRSP: no averaged data yet"')),
    (6, "ACPT;ERR?", lines('6,"Not allowed now: ACPT with no hit waiting for preview"')),
    (
        7,
        "SIM:FAULT error;STA?;ERR?;RST;STA?",
        lines("16", '7,"Hardware fault: input A/D converter does not respond"', "0"),
    ),
    (8, "A" * 5000 + ";ERR?", lines('8,"Input buffer overflow: command of 5000 characters"')),
]


@pytest.mark.parametrize("golden", GOLDENS, ids=[f"{i:03d}-{gold.covers}" for i, gold in enumerate(GOLDENS)])
def test_golden_transcript(golden: Golden, connect):
    clock = FakeClock()
    conn = connect(make_bench(golden.bench, clock))
    for at, request, reply in golden.exchanges:
        if at is not None:
            clock.now = at
        assert ask(conn, request) == reply, (at, request)


@pytest.mark.parametrize(
    ("code", "message", "reply"),
    ERROR_GOLDENS,
    ids=[f"{i:02d}-code{c}" for i, (c, _, _) in enumerate(ERROR_GOLDENS)],
)
def test_error_transcript(code: int, message: str, reply: bytes, connect):
    conn = connect(make_bench("physics", FakeClock()))
    assert ask(conn, message) == reply
    assert ask(conn, "ERR?") == lines('0,"No error"')


def test_frequency_response_dump_holds_801_lines(connect):
    """Header words of an FRSP dump at 195.3125 Hz and 800 lines; the FRF of two impulses
    (2 N at sample 1, 3 m/s^2 at sample 5, uniform windows) is 1.5 exp(-2 pi j k 4 / 2048)."""
    conn = connect(make_bench("delta", FakeClock()))
    conn.write(f"{SPAN};UNIF;STRT;FRSP;DDAN\n".encode())
    raw = conn.read(timeout_s=1.0)
    assert raw[:4] == b"#A" + struct.pack(">H", (66 + 2 * 801) * 8)
    header, frf = decode_trace(raw)
    expected_words = {
        0: 1,
        1: 801,
        2: 801,
        3: 1,
        4: 3,
        5: 0,
        7: 1,
        9: 3,
        10: 1,
        36: 0,
        40: 1,
        52: 250.0,
        53: 250.0,
    }
    for word, value in expected_words.items():
        assert header[word] == value, word
    assert header[55] == 195.3125 / 800
    assert header[64] == 0.0
    k = np.arange(801)
    np.testing.assert_allclose(frf, 1.5 * np.exp(-2j * np.pi * k * 4 / N), rtol=0, atol=1e-12)


def _mnemonics_in(request: str) -> set[str]:
    return {part.strip().split(" ")[0].upper() for part in re.split(r"[;\n]", request) if part.strip()}


def test_goldens_cover_every_command():
    table = commands_for("3562A")
    required = {c.mnemonic for c in table} | {c.mnemonic + "?" for c in table if c.kind == "setting"}
    assert required - {gold.covers for gold in GOLDENS} == set(), "commands without a golden transcript"
    for gold in GOLDENS:
        sent = set().union(*(_mnemonics_in(req) for _, req, _ in gold.exchanges))
        assert any(
            tok == gold.covers or (tok.startswith(gold.covers) and tok[len(gold.covers)] in "0123456789+-.")
            for tok in sent
        ), gold


def test_error_goldens_cover_every_error_code():
    assert {code for code, _, _ in ERROR_GOLDENS} == set(ERRORS)
    assert [c.doc for c in commands_for("3562A") if c.mnemonic == "ID?"] == ["identify: replies HP3562A"]
