"""Golden request -> reply transcripts of the simulated HP 35660A, byte for byte.

Every expected reply below is written by hand from the documented formats
(docs/instrument.md: the 3562A family's dumps and header codes, and the project's
choices for the rest), never read back from the simulator:

* numeric query replies ``{:+.9E}`` (``+2.000000000E+02``), integers and flags
  plain, choices as their mnemonic, every reply line ending CR LF;
* ``ERR?`` replies ``code,"Message: detail"`` with the codes of ERRORS;
* ``DDAN``: ``#A`` + 2-byte big-endian byte count + big-endian float64, a
  66-value header then the data, no terminator; ``DDAS`` is ``#I``, the count of
  values, then the same values as ASCII, ``{:+.16E}`` one per CR LF line;
* header word 0 holds the documented display-function code (1 frequency response,
  2/3 power spectrum, 4 coherence, 6/7 time record, 8/9 linear spectrum), word 7
  the domain (0 time, 1 frequency), word 10 the x units (1 Hz, 4 s);
* ``DSAN``/``DSAS``: the 96-value state dump, laid out as docs/instrument.md,
  "State dump" says (the project's choice: nothing of it is documented).

Traces whose values must be known in advance come from the replay source
(RecordedHit arrays built here; sample rate 2.56 x span, 512 Hz at 200 Hz).

``test_goldens_cover_every_command`` fails when a command is added to the
table without a golden here.
"""

from __future__ import annotations

import re
import struct
from dataclasses import dataclass

import numpy as np
import pytest

from sims.command_table import COMMANDS, ERRORS
from sims.instrument import Analyzer
from sims.sources import RecordedHit, ReplaySource
from tests.sim.wire import ask

pytestmark = pytest.mark.timeout(10)

CRLF = b"\r\n"


def lines(*texts: str) -> bytes:
    return b"".join(t.encode("ascii") + CRLF for t in texts)


# --------------------------------------------------------------------------- benches
class FakeClock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


SPAN_HZ = 200.0
RATE_HZ = 512.0  # 2.56 x 200 Hz
N = 1024

# A hit with a distinct value in every sample, for the time-record dumps.
_rng = np.random.default_rng(35660)
TIME_FORCE = np.round(_rng.normal(0.0, 3.0, N), 6)
TIME_ACCEL = np.round(_rng.normal(0.0, 40.0, N), 6)
TIME_START_S = -0.25  # first sample a quarter second before the trigger
TIME_HIT = RecordedHit(TIME_FORCE, TIME_ACCEL, RATE_HZ, TIME_START_S, overload=(True, False))

# Two delayed impulses: force 2 N at sample 1, acceleration 3 m/s^2 at sample 5.
DELTA_FORCE = np.zeros(N)
DELTA_FORCE[1] = 2.0
DELTA_ACCEL = np.zeros(N)
DELTA_ACCEL[5] = 3.0
DELTA_HIT = RecordedHit(DELTA_FORCE, DELTA_ACCEL, RATE_HZ)


def make_bench(kind: str, make_analyzer, clock: FakeClock) -> Analyzer:
    if kind == "physics":
        return make_analyzer()
    if kind == "time":
        return Analyzer(ReplaySource([TIME_HIT], loop=True))
    if kind == "delta":
        return Analyzer(ReplaySource([DELTA_HIT], loop=True))
    if kind == "clock":
        return Analyzer(ReplaySource([DELTA_HIT], loop=True), time_scale=1.0, clock=clock)
    raise ValueError(kind)


# --------------------------------------------------------------------------- expected dumps
def block(values: list[float]) -> bytes:
    payload = struct.pack(f">{len(values)}d", *values)
    return b"#A" + struct.pack(">H", len(payload)) + payload


def ascii_dump(values: list[float]) -> bytes:
    return (
        b"#I"
        + CRLF
        + str(len(values)).encode("ascii")
        + CRLF
        + b"".join(f"{v:+.16E}".encode("ascii") + CRLF for v in values)
    )


def time_trace(function_code: int, channel: int, overflow: int, y_code: int, data: np.ndarray) -> list[float]:
    """A baseband TIM trace at 200 Hz span: header words from the encoding docstring."""
    h = [0.0] * 66
    h[0] = function_code
    h[1] = h[2] = N  # elements, elements displayed
    h[3] = 1  # averages (AVOF: one record)
    h[4] = channel
    h[5] = overflow
    h[6] = 0  # overlap %
    h[7] = 0  # time domain
    h[8] = 0  # peak
    h[9] = y_code
    h[10] = 4  # x in s
    h[35] = 0  # float
    h[36] = 1  # real
    h[40] = 1  # linear
    h[43] = 0  # linear resolution
    h[52] = h[53] = RATE_HZ / 2
    h[55] = 1 / RATE_HZ
    h[64] = TIME_START_S
    return h + [float(v) for v in data]


# Display codes: input time 1 = 6, input time 2 = 7; y units (ours) N = 1, m/s^2 = 2.
TIM1_VALUES = time_trace(6, 1, 1, 1, TIME_FORCE)
TIM2_VALUES = time_trace(7, 2, 0, 2, TIME_ACCEL)

# The state dump, word by word (docs/instrument.md, "State dump"): 0 span Hz, 1 center
# Hz, 2 averages, 3 averaging (1 STBL, 0 AVOF), 4 preview, 5/6 windows (UNIF 0, HANN 1,
# FLAT 2, FORC 3, EXPO 4), 7/8 force widths s, 9/10 exponential decays s, 11/12 ranges
# V, 13/14 autorange, 15/16 AC coupling, 17/18 sensitivities V/EU, 19 trigger source
# (0 FREE, 1 CH1, 2 CH2), 20 level V, 21 slope (1 POS, -1 NEG), 22 delay s, 23 active
# trace (0 A, 1 B), 24/25 display-function codes of traces A and B; 26-95 zero.
PRESET_STATE = [
    *(102400.0, 51200.0, 1.0, 0.0, 0.0),
    *(1.0, 1.0, 0.05, 0.05, 1.0, 1.0),
    *(1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.00225, 0.00102),
    *(0.0, 0.0, 1.0, 0.0),
    *(0.0, 1.0, 4.0),
    *([0.0] * 70),
]


def state_with(**words: float) -> list[float]:
    """The preset state with some words changed: state_with(w13=1.0)."""
    out = list(PRESET_STATE)
    for key, value in words.items():
        out[int(key[1:])] = float(value)
    return out


# Every setting away from its preset (and an error in the queue).
MESS = (
    "FRS 12.5 HZ;CF 36 HZ;NAVG 7;STBL;PRVW 1;WIN1 FORC;WIN2 EXPO;FWD1 10 MS;FWD2 20 MS;"
    "EXD1 0.5 S;EXD2 2 S;RNG1 5 V;RNG2 50 MV;AU1;AU2;C1AC 1;C2AC 1;SNS1 10 MV;SNS2 100 MV;"
    "TSRC CH2;TLVL -0.2 V;TSLP NEG;TDLY -1 S;TRCB;TIM2;TRCA;LSP1"
)
MESS_STATE = [
    *(12.5, 36.0, 7.0, 1.0, 1.0),
    *(3.0, 4.0, 0.01, 0.02, 0.5, 2.0),
    *(5.011872336272722, 0.05011872336272722, 1.0, 1.0, 1.0, 1.0, 0.01, 0.1),  # ranges up 1 dB steps
    *(2.0, -0.2, -1.0, -1.0),
    *(0.0, 8.0, 7.0),  # trace A active: LSP1 on A, TIM2 on B
    *([0.0] * 70),
]


# --------------------------------------------------------------------------- goldens
@dataclass(frozen=True)
class Golden:
    covers: str  # the mnemonic (or setting query form) this transcript pins
    exchanges: tuple[tuple[float | None, str, bytes], ...]  # (fake clock time, request, reply)
    bench: str = "physics"


GOLDENS: list[Golden] = []


def g(covers: str, request: str, reply: bytes, bench: str = "physics") -> None:
    GOLDENS.append(Golden(covers, ((None, request, reply),), bench))


def g_timed(covers: str, *exchanges: tuple[float, str, bytes]) -> None:
    GOLDENS.append(Golden(covers, tuple(exchanges), "clock"))


# -- preset: every setting's query form after RST from a state where all differ
PRESET_REPLIES = {
    "FRS?": "+1.024000000E+05",
    "CF?": "+5.120000000E+04",
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

# -- settings: set, then query (the query forms again where it matters)
g("FRS", "FRS 2 KHZ;FRS?", lines("+3.200000000E+03"))  # 102.4 kHz / 2^5, rounded up
g("FRS", "FRS 1600 HZ;FRS?;CF?", lines("+1.600000000E+03", "+8.000000000E+02"))
g("CF", "FRS 12.5 HZ;CF?;CF 36 HZ;CF?", lines("+6.250000000E+00", "+3.600000000E+01"))
g("NAVG", "NAVG 16;NAVG?", lines("16"))
g("PRVW", "PRVW 1;PRVW?;PRVW OFF;PRVW?", lines("1", "0"))
g("WIN1", "WIN1 FORC;WIN1?;WIN2?", lines("FORC", "HANN"))
g("WIN2", "WIN2 EXPO;WIN1?;WIN2?", lines("HANN", "EXPO"))
g("FWD1", "FWD1 10 MS;FWD1?;FWD2?", lines("+1.000000000E-02", "+5.000000000E-02"))
g("FWD2", "FWD2 2.5 MS;FWD2?", lines("+2.500000000E-03"))
g("EXD1", "EXD1 250 MS;EXD1?", lines("+2.500000000E-01"))
g("EXD2", "EXD2 3 S;EXD2?;EXD1?", lines("+3.000000000E+00", "+1.000000000E+00"))
g("RNG1", "RNG1 2 V;RNG1?", lines("+2.238721139E+00"))  # up to +7 dBV
g("RNG1", "RNG1 -3.5 DBV;RNG1?", lines("+7.079457844E-01"))  # up to -3 dBV
g("RNG2", "RNG2 20 MV;RNG2?;RNG1?", lines("+2.238721139E-02", "+1.000000000E+00"))  # -33 dBV
g("C1AC", "C1AC 1;C1AC?;C2AC?", lines("1", "0"))
g("C2AC", "C2AC ON;C2AC?;C1AC?", lines("1", "0"))
g("SNS1", "SNS1 10 MV;SNS1?", lines("+1.000000000E-02"))
g("SNS2", "SNS2 100 UV;SNS2?", lines("+1.000000000E-04"))
g("TSRC", "TSRC CH2;TSRC?", lines("CH2"))
g("TLVL", "TLVL -50 MV;TLVL?", lines("-5.000000000E-02"))
g("TSLP", "TSLP NEG;TSLP?", lines("NEG"))
g("TDLY", "TDLY -2 MS;TDLY?", lines("-2.000000000E-03"))

# -- fused forms, case, several commands in one message, line ends inside a message
g("C1AC", "C1AC1;C1AC?", lines("1"))
g("NAVG", "NAVG5;NAVG?", lines("5"))
g("FRS", "FRS2KHZ;FRS?", lines("+3.200000000E+03"))
g("RNG2", "RNG2-20DBV;RNG2?", lines("+1.000000000E-01"))
g("ID?", "id?", lines("HP35660A"))
g("FRS", "frs 2 khz;FrS?", lines("+3.200000000E+03"))
g("WIN1", "win1 forc;win1?", lines("FORC"))
g("C1AC", "c1ac1;c1ac?", lines("1"))
g("TRC?", "ID?;NAVG 3;NAVG?;TRC?", lines("HP35660A", "3", "A"))
g("NAVG", "ID?\nNAVG 2\nNAVG?", lines("HP35660A", "2"))

# -- identification, reset, local
g("ID?", "ID?", lines("HP35660A"))
g("RST", f"{MESS};RST;DSAS", ascii_dump(PRESET_STATE))
g("LCL", "NAVG 4;LCL;NAVG?;ERR?", lines("4", '0,"No error"'))

# -- windows, averaging, measurement, mode
g("UNIF", "UNIF;WIN1?;WIN2?", lines("UNIF", "UNIF"))
g("HANN", "UNIF;HANN;WIN1?;WIN2?", lines("HANN", "HANN"))
g("FLAT", "FLAT;WIN1?;WIN2?", lines("FLAT", "FLAT"))
g("FRQR", "FRQR;ERR?", lines('0,"No error"'))
g("LNRS", "LNRS;ERR?", lines('0,"No error"'))
g("STBL", "FRS 200 HZ;STBL;NAVG 3;STRT;AVG?;SMSD", lines("3", "1"), "delta")
g("AVOF", "FRS 200 HZ;STBL;AVOF;NAVG 3;STRT;AVG?;SMSD", lines("1", "1"), "delta")

g("AVMD?", "STBL;AVMD?;AVOF;AVMD?", lines("STBL", "AVOF"))

# -- autorange; a range setting turns it off
g("AU1?", "AU1;AU1?;AU2?;RNG1 1 V;AU1?", lines("1", "0", "0"))
g("AU2?", "AU2;AU2?;AU1?;RNG2 1 V;AU2?", lines("1", "0", "0"))
# -- autorange (only DSAS shows it)
g("AU1", "RST;AU1;DSAS", ascii_dump(state_with(w13=1.0)))
g("AU2", "RST;AU2;DSAS", ascii_dump(state_with(w14=1.0)))

# -- traces and display functions (each trace keeps its own)
g("TRC?", "TRC?", lines("A"))
g("DISP?", "DISP?;TRCB;DISP?", lines("FRSP", "COHR"))
g("TRCA", "TRCB;TRCA;TRC?;DISP?", lines("A", "FRSP"))
g("TRCB", "TRCB;TRC?;DISP?", lines("B", "COHR"))
for _fn in ("TIM1", "TIM2", "LSP1", "LSP2", "PSP1", "PSP2", "COHR"):
    g(_fn, f"TRCB;{_fn};DISP?;TRC?;TRCA;DISP?", lines(_fn, "B", "FRSP"))
g("FRSP", "TIM1;FRSP;DISP?;TRCB;DISP?", lines("FRSP", "COHR"))

# -- measurement control and status
g("SMSD", "SMSD", lines("0"))
g("STRT", "FRS 200 HZ;STRT;SMSD;AVG?;STA?", lines("1", "1", "1"), "delta")
g("ACPT", "FRS 200 HZ;PRVW 1;STRT;STA?;AVG?;ACPT;AVG?;STA?;SMSD", lines("32", "0", "1", "1", "1"), "delta")
g("RJCT", "FRS 200 HZ;PRVW 1;STRT;RJCT;STA?;AVG?;SMSD", lines("32", "0", "0"), "delta")
g("STA?", "STA?;FOO;STA?;ERR?;STA?", lines("0", "16", '1,"Undefined command: FOO"', "0"))
g("ERR?", "ERR?", lines('0,"No error"'))
g("CLER", "FOO;BAR;CLER;ERR?;STA?", lines('0,"No error"', "0"))
g("OVLD?", "OVLD?;FRS 200 HZ;STRT;OVLD?;STA?", lines("0,0", "1,0", "5"), "time")  # 5 = done + ch1 overload
g("AVG?", "AVG?", lines("0"))

# Timing with a fake clock: the replay triggers 0.5 s after arming; a 200 Hz span
# records 1024 / 512 Hz = 2 s.
g_timed(
    "SMSD",
    (0.0, "FRS 200 HZ;STRT;STA?;SMSD", lines("2", "0")),
    (0.6, "STA?;SMSD", lines("64", "0")),
    (2.6, "STA?;SMSD;AVG?", lines("1", "1", "1")),
)
g_timed(
    "PAUS",
    (0.0, "FRS 200 HZ;STRT;STA?", lines("2")),
    (0.2, "PAUS;STA?", lines("130")),  # waiting + paused
    (50.0, "STA?;SMSD;AVG?", lines("130", "0", "0")),
)
g_timed(
    "CONT",
    (0.0, "FRS 200 HZ;STRT", b""),
    (0.2, "PAUS", b""),
    (10.0, "CONT;STA?", lines("2")),  # 9.8 s later: trigger at 10.3 s, done at 12.3 s
    (10.29, "STA?", lines("2")),
    (10.31, "STA?", lines("64")),
    (12.29, "STA?;SMSD", lines("64", "0")),
    (12.31, "STA?;SMSD;AVG?", lines("1", "1", "1")),
)

# -- transfers
g("DDAN", "FRS 200 HZ;STRT;TIM1;DDAN", block(TIM1_VALUES), "time")
g("DDAN", "FRS 200 HZ;STRT;TRCB;TIM2;DDAN", block(TIM2_VALUES), "time")
g("DDAS", "FRS 200 HZ;STRT;TIM2;DDAS", ascii_dump(TIM2_VALUES), "time")
g("DDAS", "FRS 200 HZ;STRT;TRCB;TIM1;DDAS", ascii_dump(TIM1_VALUES), "time")
g("DSAS", "RST;DSAS", ascii_dump(PRESET_STATE))
g("DSAS", f"{MESS};DSAS", ascii_dump(MESS_STATE))
g("DSAN", "RST;DSAN", block(PRESET_STATE))
g("DSAN", f"{MESS};DSAN", block(MESS_STATE))
# The codes MESS leaves out: UNIF 0 and FLAT 2, trigger on CH1 1, trace B active 1, and
# the display codes of PSP1 2, PSP2 3, TIM1 6 and LSP2 9.
g("DSAN", "RST;UNIF;TSRC CH1;PSP1;TRCB;PSP2;DSAN", block(state_with(w5=0, w6=0, w19=1, w23=1, w24=2, w25=3)))
g("DSAS", "RST;FLAT;TIM1;TRCB;LSP2;DSAS", ascii_dump(state_with(w5=2, w6=2, w23=1, w24=6, w25=9)))

# -- errors, read back through ERR? (code -> transcripts)
ERROR_GOLDENS: list[tuple[int, str, bytes]] = [
    (1, "FOO;ERR?;ERR?", lines('1,"Undefined command: FOO"', '0,"No error"')),
    (1, "foo 5 HZ;ID?;ERR?", lines("HP35660A", '1,"Undefined command: FOO"')),
    (1, "RST?;ERR?", lines('1,"Undefined command: RST?"')),
    (2, "NAVG 0;ERR?;NAVG?", lines('2,"Parameter out of range: NAVG 0"', "1")),
    (2, "PRVW 2;ERR?", lines('2,"Parameter out of range: PRVW 2"')),
    (2, "FWD1 0 S;ERR?", lines('2,"Parameter out of range: FWD1 0 S"')),
    (3, "ID? 1;ERR?", lines('3,"Invalid parameter: ID? takes no value"')),
    (3, "NAVG? 3;ERR?", lines('3,"Invalid parameter: NAVG? takes no value"')),
    (3, "RST 1;ERR?", lines('3,"Invalid parameter: RST takes no value"')),
    (3, "FRS;ERR?", lines('3,"Invalid parameter: FRS needs a value"')),
    (3, "NAVG 2.5;ERR?", lines("3,\"Invalid parameter: NAVG: not an integer: '2.5'\"")),
    (3, "FRS ABC;ERR?", lines("3,\"Invalid parameter: FRS: not a number: 'ABC'\"")),
    (
        3,
        "WIN1 BOX;ERR?;WIN1?",
        lines("3,\"Invalid parameter: WIN1: 'BOX' is not one of UNIF, HANN, FLAT, FORC, EXPO\"", "HANN"),
    ),
    (
        4,
        "FRS 2 KV;ERR?;FRS?",
        lines('4,"Invalid unit: FRS: unit KV does not apply here"', "+1.024000000E+05"),
    ),
    (4, "FRS2KV;ERR?", lines('4,"Invalid unit: FRS: unit KV does not apply here"')),
    (4, "TDLY 5 HZ;ERR?", lines('4,"Invalid unit: TDLY: unit HZ does not apply here"')),
    (5, "DDAN;ERR?", lines('5,"No data available: FRSP: no averaged data yet"')),
    (5, "TIM1;DDAS;ERR?", lines('5,"No data available: TIM1: no time record yet"')),
    (6, "ACPT;ERR?", lines('6,"Not allowed now: ACPT with no hit waiting for preview"')),
    (6, "RJCT;ERR?", lines('6,"Not allowed now: RJCT with no hit waiting for preview"')),
    (
        7,
        "SIM:FAULT error;STA?;ERR?;STRT;ERR?;STA?;RST;STA?",
        lines(
            "16",
            '7,"Hardware fault: input A/D converter does not respond"',
            '7,"Hardware fault: input A/D converter does not respond"',
            "16",
            "0",
        ),
    ),
    (8, "A" * 5000 + ";ERR?", lines('8,"Input buffer overflow: command of 5000 characters"')),
]


@pytest.mark.parametrize(
    "golden",
    GOLDENS,
    ids=[f"{i:03d}-{gold.covers}" for i, gold in enumerate(GOLDENS)],
)
def test_golden_transcript(golden: Golden, make_analyzer, connect):
    clock = FakeClock()
    conn = connect(make_bench(golden.bench, make_analyzer, clock))
    for at, request, reply in golden.exchanges:
        if at is not None:
            clock.now = at
        assert ask(conn, request) == reply, (at, request)


@pytest.mark.parametrize(
    ("code", "message", "reply"),
    ERROR_GOLDENS,
    ids=[f"{i:02d}-code{code}" for i, (code, _, _) in enumerate(ERROR_GOLDENS)],
)
def test_error_transcript(code: int, message: str, reply: bytes, connect):
    conn = connect()
    assert ask(conn, message) == reply
    assert ask(conn, "ERR?") == lines('0,"No error"')  # every error read exactly once


def _mnemonics_in(request: str) -> set[str]:
    return {part.strip().split(" ")[0].upper() for part in re.split(r"[;\n]", request) if part.strip()}


def test_goldens_cover_every_command():
    required = {c.mnemonic for c in COMMANDS} | {c.mnemonic + "?" for c in COMMANDS if c.kind == "setting"}
    covered = {gold.covers for gold in GOLDENS}
    assert required - covered == set(), "commands without a golden transcript"
    # ... and every golden really sends what it claims to cover (plain or fused).
    for gold in GOLDENS:
        sent = set().union(*(_mnemonics_in(req) for _, req, _ in gold.exchanges))
        assert any(
            tok == gold.covers or (tok.startswith(gold.covers) and tok[len(gold.covers)] in "0123456789+-.")
            for tok in sent
        ), gold


def test_error_goldens_cover_every_error_code():
    assert {code for code, _, _ in ERROR_GOLDENS} == set(ERRORS)
    for code, _, reply in ERROR_GOLDENS:
        assert f'{code},"{ERRORS[code]}: '.encode("ascii") in reply
