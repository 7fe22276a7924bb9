"""Golden request -> reply transcripts of the simulated HP 35660A and HP 3562A, byte for byte.

Every expected reply is written by hand from the documented formats (docs/instrument.md:
the 3562A family's dumps and header codes, and the project's choices for the rest;
docs/instrument-scpi.md, "The HP 3562A dialect", for what the 3562A does otherwise),
never read back from the simulator:

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

The two models differ in what docs/instrument-scpi.md says: ``ID?`` answers
``HP3562A``; 800 lines (801 points), 2048-sample records; spans 100 kHz / 2^n
(the 35660A: 102.4 kHz / 2^n, 400 lines, 1024-sample records).

Traces whose values must be known in advance come from the replay source (hits of
tests/sims/goldens/common.py; sample rate 2.56 x span): the 35660A at its 200 Hz
span, 1024 samples at 512 Hz; the 3562A at its 195.3125 Hz span (100 kHz / 2^9),
2048 samples at 500 Hz.
"""

from __future__ import annotations

from sims.command_table import ERRORS, commands_for
from sims.instrument import Analyzer
from sims.sources import PhysicsSource, ReplaySource
from tests.sims.goldens.common import (
    Book,
    Dialect,
    ErrorGolden,
    FakeClock,
    Golden,
    Hits,
    ascii_dump,
    block,
    lines,
    mnemonics_in,
    state_with,
    time_trace,
)

NO_ERROR = lines('0,"No error"')


def _bench(model: str, hits: Hits):
    def make_bench(kind: str, clock: FakeClock) -> Analyzer:
        if kind == "physics":
            source = PhysicsSource("seed", seed=0)
            source.set_noise(False)
            return Analyzer(source, model=model)
        if kind == "time":
            return Analyzer(ReplaySource([hits.time_hit], loop=True, model=model), model=model)
        if kind == "delta":
            return Analyzer(ReplaySource([hits.delta_hit], loop=True, model=model), model=model)
        if kind == "clock":
            replay = ReplaySource([hits.delta_hit], loop=True, model=model)
            return Analyzer(replay, time_scale=1.0, clock=clock, model=model)
        raise ValueError(kind)

    return make_bench


def _state(span_hz: float, center_hz: float, *rest: float) -> list[float]:
    return [span_hz, center_hz, *rest, *([0.0] * 70)]


# The state dump, word by word (docs/instrument.md, "State dump"): 0 span Hz, 1 center
# Hz, 2 averages, 3 averaging (1 STBL, 0 AVOF), 4 preview, 5/6 windows (UNIF 0, HANN 1,
# FLAT 2, FORC 3, EXPO 4), 7/8 force widths s, 9/10 exponential decays s, 11/12 ranges
# V, 13/14 autorange, 15/16 AC coupling, 17/18 sensitivities V/EU, 19 trigger source
# (0 FREE, 1 CH1, 2 CH2), 20 level V, 21 slope (1 POS, -1 NEG), 22 delay s, 23 active
# trace (0 A, 1 B), 24/25 display-function codes of traces A and B; 26-95 zero.
_PRESET_REST = (
    *(1.0, 0.0, 0.0),
    *(1.0, 1.0, 0.05, 0.05, 1.0, 1.0),
    *(1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.00225, 0.00102),
    *(0.0, 0.0, 1.0, 0.0),
    *(0.0, 1.0, 4.0),
)
# Every setting away from its preset (and an error in the queue), after the span and center.
_MESS_REST = (
    "NAVG 7;STBL;PRVW 1;WIN1 FORC;WIN2 EXPO;FWD1 10 MS;FWD2 20 MS;"
    "EXD1 0.5 S;EXD2 2 S;RNG1 5 V;RNG2 50 MV;AU1;AU2;C1AC 1;C2AC 1;SNS1 10 MV;SNS2 100 MV;"
    "TSRC CH2;TLVL -0.2 V;TSLP NEG;TDLY -1 S;TRCB;TIM2;TRCA;LSP1"
)
_MESS_STATE_REST = (
    *(7.0, 1.0, 1.0),
    *(3.0, 4.0, 0.01, 0.02, 0.5, 2.0),
    *(5.011872336272722, 0.05011872336272722, 1.0, 1.0, 1.0, 1.0, 0.01, 0.1),  # ranges up 1 dB steps
    *(2.0, -0.2, -1.0, -1.0),
    *(0.0, 8.0, 7.0),  # trace A active: LSP1 on A, TIM2 on B
)

# Every setting's query form after RST from a state where all differ (FRS? and CF?
# are the model's own).
_PRESET_REPLIES = {
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


def _shared(
    book: Book,
    *,
    model: str,
    span: str,
    preset_frs_cf: tuple[str, str],
    preset_state: list[float],
    mess: str,
    mess_state: list[float],
    hits: Hits,
    done_s: float,
    cont_done_s: tuple[float, float],
) -> None:
    """The goldens the two models share, given what differs: the span that records the
    replay's hits (``span``), the preset, and when a record started at 0 s (``done_s``)
    or, after a pause, at 10 s (``cont_done_s``: just before and just after) is done."""
    g = book.g
    frs, cf = preset_frs_cf
    for query, answer in {"FRS?": frs, "CF?": cf, **_PRESET_REPLIES}.items():
        g(query, (f"{mess};FOO;RST;{query}", lines(answer)))

    # -- settings: set, then query (the query forms again where it matters)
    g("NAVG", ("NAVG 16;NAVG?", lines("16")))
    g("NAVG", ("NAVG5;NAVG?", lines("5")))
    g("PRVW", ("PRVW 1;PRVW?;PRVW OFF;PRVW?", lines("1", "0")))
    g("WIN1", ("WIN1 FORC;WIN1?;WIN2?", lines("FORC", "HANN")))
    g("WIN2", ("WIN2 EXPO;WIN1?;WIN2?", lines("HANN", "EXPO")))
    g("FWD1", ("FWD1 10 MS;FWD1?;FWD2?", lines("+1.000000000E-02", "+5.000000000E-02")))
    g("FWD2", ("FWD2 2.5 MS;FWD2?", lines("+2.500000000E-03")))
    g("EXD1", ("EXD1 250 MS;EXD1?", lines("+2.500000000E-01")))
    g("EXD2", ("EXD2 3 S;EXD2?;EXD1?", lines("+3.000000000E+00", "+1.000000000E+00")))
    g("RNG1", ("RNG1 2 V;RNG1?", lines("+2.238721139E+00")))  # up to +7 dBV
    g("RNG2", ("RNG2 20 MV;RNG2?;RNG1?", lines("+2.238721139E-02", "+1.000000000E+00")))  # -33 dBV
    g("C2AC", ("C2AC ON;C2AC?;C1AC?", lines("1", "0")))
    g("SNS1", ("SNS1 10 MV;SNS1?", lines("+1.000000000E-02")))
    g("SNS2", ("SNS2 100 UV;SNS2?", lines("+1.000000000E-04")))
    g("TSRC", ("TSRC CH2;TSRC?", lines("CH2")))
    g("TLVL", ("TLVL -50 MV;TLVL?", lines("-5.000000000E-02")))
    g("TSLP", ("TSLP NEG;TSLP?", lines("NEG")))
    g("TDLY", ("TDLY -2 MS;TDLY?", lines("-2.000000000E-03")))

    # -- identification, reset, local
    g("ID?", ("ID?", lines(f"HP{model}")))
    g("RST", (f"{mess};RST;DSAS", ascii_dump(preset_state)))
    g("LCL", ("NAVG 4;LCL;NAVG?;ERR?", lines("4", '0,"No error"')))

    # -- windows, averaging, measurement, mode
    g("UNIF", ("UNIF;WIN1?;WIN2?", lines("UNIF", "UNIF")))
    g("HANN", ("UNIF;HANN;WIN1?;WIN2?", lines("HANN", "HANN")))
    g("FLAT", ("FLAT;WIN1?;WIN2?", lines("FLAT", "FLAT")))
    g("FRQR", ("FRQR;ERR?", lines('0,"No error"')))
    g("LNRS", ("LNRS;ERR?", lines('0,"No error"')))
    g("STBL", (f"{span};STBL;NAVG 3;STRT;AVG?;SMSD", lines("3", "1")), bench="delta")
    g("AVOF", (f"{span};STBL;AVOF;NAVG 3;STRT;AVG?;SMSD", lines("1", "1")), bench="delta")
    g("AVMD?", ("STBL;AVMD?;AVOF;AVMD?", lines("STBL", "AVOF")))

    # -- autorange; a range setting turns it off (only DSAS shows it otherwise)
    g("AU1?", ("AU1;AU1?;AU2?;RNG1 1 V;AU1?", lines("1", "0", "0")))
    g("AU2?", ("AU2;AU2?;AU1?;RNG2 1 V;AU2?", lines("1", "0", "0")))
    g("AU1", ("RST;AU1;DSAS", ascii_dump(state_with(preset_state, w13=1.0))))
    g("AU2", ("RST;AU2;DSAS", ascii_dump(state_with(preset_state, w14=1.0))))

    # -- traces and display functions (each trace keeps its own)
    g("TRC?", ("TRC?", lines("A")))
    g("DISP?", ("DISP?;TRCB;DISP?", lines("FRSP", "COHR")))
    g("TRCA", ("TRCB;TRCA;TRC?;DISP?", lines("A", "FRSP")))
    g("TRCB", ("TRCB;TRC?;DISP?", lines("B", "COHR")))
    for fn in ("TIM1", "TIM2", "LSP1", "LSP2", "PSP1", "PSP2", "COHR"):
        g(fn, (f"TRCB;{fn};DISP?;TRC?;TRCA;DISP?", lines(fn, "B", "FRSP")))
    g("FRSP", ("TIM1;FRSP;DISP?;TRCB;DISP?", lines("FRSP", "COHR")))

    # -- measurement control and status
    g("SMSD", ("SMSD", lines("0")))
    g("STRT", (f"{span};STRT;SMSD;AVG?;STA?", lines("1", "1", "1")), bench="delta")
    g(
        "ACPT",
        (f"{span};PRVW 1;STRT;STA?;AVG?;ACPT;AVG?;STA?;SMSD", lines("32", "0", "1", "1", "1")),
        bench="delta",
    )
    g("RJCT", (f"{span};PRVW 1;STRT;RJCT;STA?;AVG?;SMSD", lines("32", "0", "0")), bench="delta")
    g("STA?", ("STA?;FOO;STA?;ERR?;STA?", lines("0", "16", '1,"Undefined command: FOO"', "0")))
    g("ERR?", ("ERR?", lines('0,"No error"')))
    g("CLER", ("FOO;BAR;CLER;ERR?;STA?", lines('0,"No error"', "0")))
    # 5 = done + ch1 overload
    g("OVLD?", (f"OVLD?;{span};STRT;OVLD?;STA?", lines("0,0", "1,0", "5")), bench="time")
    g("AVG?", ("AVG?", lines("0")))

    # Timing with a fake clock: the replay triggers 0.5 s after arming.
    book.g_timed(
        "SMSD",
        (0.0, f"{span};STRT;STA?;SMSD", lines("2", "0")),
        (0.6, "STA?;SMSD", lines("64", "0")),
        (done_s, "STA?;SMSD;AVG?", lines("1", "1", "1")),
    )
    book.g_timed(
        "PAUS",
        (0.0, f"{span};STRT;STA?", lines("2")),
        (0.2, "PAUS;STA?", lines("130")),  # waiting + paused
        (50.0, "STA?;SMSD;AVG?", lines("130", "0", "0")),
    )
    before, after = cont_done_s
    book.g_timed(
        "CONT",
        (0.0, f"{span};STRT", b""),
        (0.2, "PAUS", b""),
        (10.0, "CONT;STA?", lines("2")),  # 9.8 s later: trigger at 10.3 s
        (10.29, "STA?", lines("2")),
        (10.31, "STA?", lines("64")),
        (before, "STA?;SMSD", lines("64", "0")),
        (after, "STA?;SMSD;AVG?", lines("1", "1", "1")),
    )

    # -- transfers. Display codes: input time 1 = 6, input time 2 = 7; y units (ours)
    # N = 1, m/s^2 = 2.
    tim1 = time_trace(hits, 6, 1, 1, 1, hits.time_force)
    tim2 = time_trace(hits, 7, 2, 0, 2, hits.time_accel)
    g("DDAN", (f"{span};STRT;TIM1;DDAN", block(tim1)), bench="time")
    g("DDAN", (f"{span};STRT;TRCB;TIM2;DDAN", block(tim2)), bench="time")
    g("DDAS", (f"{span};STRT;TIM2;DDAS", ascii_dump(tim2)), bench="time")
    g("DDAS", (f"{span};STRT;TRCB;TIM1;DDAS", ascii_dump(tim1)), bench="time")
    g("DSAS", ("RST;DSAS", ascii_dump(preset_state)))
    g("DSAS", (f"{mess};DSAS", ascii_dump(mess_state)))
    g("DSAN", ("RST;DSAN", block(preset_state)))
    g("DSAN", (f"{mess};DSAN", block(mess_state)))
    # The codes the mess leaves out: UNIF 0 and FLAT 2, trigger on CH1 1, trace B active
    # 1, and the display codes of PSP1 2, PSP2 3, TIM1 6 and LSP2 9.
    state = state_with(preset_state, w5=0, w6=0, w19=1, w23=1, w24=2, w25=3)
    g("DSAN", ("RST;UNIF;TSRC CH1;PSP1;TRCB;PSP2;DSAN", block(state)))
    state = state_with(preset_state, w5=2, w6=2, w23=1, w24=6, w25=9)
    g("DSAS", ("RST;FLAT;TIM1;TRCB;LSP2;DSAS", ascii_dump(state)))


# ------------------------------------------------------------------------- HP 35660A
HITS_35660A = Hits.make(35660, 1024, 512.0)  # 2.56 x 200 Hz
_B = Book()
_shared(
    _B,
    model="35660A",
    span="FRS 200 HZ",
    preset_frs_cf=("+1.024000000E+05", "+5.120000000E+04"),
    preset_state=_state(102400.0, 51200.0, *_PRESET_REST),
    mess=f"FRS 12.5 HZ;CF 36 HZ;{_MESS_REST}",
    mess_state=_state(12.5, 36.0, *_MESS_STATE_REST),
    hits=HITS_35660A,
    done_s=2.6,  # a 200 Hz span records 1024 / 512 Hz = 2 s
    cont_done_s=(12.29, 12.31),
)
_B.g("FRS", ("FRS 2 KHZ;FRS?", lines("+3.200000000E+03")))  # 102.4 kHz / 2^5, rounded up
_B.g("FRS", ("FRS 1600 HZ;FRS?;CF?", lines("+1.600000000E+03", "+8.000000000E+02")))
_B.g("CF", ("FRS 12.5 HZ;CF?;CF 36 HZ;CF?", lines("+6.250000000E+00", "+3.600000000E+01")))
_B.g("RNG1", ("RNG1 -3.5 DBV;RNG1?", lines("+7.079457844E-01")))  # up to -3 dBV
_B.g("C1AC", ("C1AC 1;C1AC?;C2AC?", lines("1", "0")))
# -- fused forms, case, several commands in one message, line ends inside a message
_B.g("C1AC", ("C1AC1;C1AC?", lines("1")))
_B.g("FRS", ("FRS2KHZ;FRS?", lines("+3.200000000E+03")))
_B.g("RNG2", ("RNG2-20DBV;RNG2?", lines("+1.000000000E-01")))
_B.g("ID?", ("id?", lines("HP35660A")))
_B.g("FRS", ("frs 2 khz;FrS?", lines("+3.200000000E+03")))
_B.g("WIN1", ("win1 forc;win1?", lines("FORC")))
_B.g("C1AC", ("c1ac1;c1ac?", lines("1")))
_B.g("TRC?", ("ID?;NAVG 3;NAVG?;TRC?", lines("HP35660A", "3", "A")))
_B.g("NAVG", ("ID?\nNAVG 2\nNAVG?", lines("HP35660A", "2")))
GOLDENS_35660A = tuple(_B.goldens)

# -- errors, read back through ERR? (code -> transcripts)
ERRORS_35660A: list[tuple[int, str, bytes]] = [
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

# --------------------------------------------------------------------------- HP 3562A
HITS_3562A = Hits.make(3562, 2048, 500.0)  # 2.56 x 195.3125 Hz
SPAN_3562A = "FRS 195.3125 HZ"
_B = Book()
_shared(
    _B,
    model="3562A",
    span=SPAN_3562A,
    preset_frs_cf=("+1.000000000E+05", "+5.000000000E+04"),
    preset_state=_state(100000.0, 50000.0, *_PRESET_REST),  # 100 kHz at baseband
    mess=f"FRS 195.3125 HZ;CF 300 HZ;{_MESS_REST}",
    mess_state=_state(195.3125, 300.0, *_MESS_STATE_REST),
    hits=HITS_3562A,
    done_s=4.7,  # 2048 samples at 500 Hz take 4.096 s
    cont_done_s=(14.39, 14.40),  # trigger at 10.3 s, done at 14.396 s
)
_B.g("ID?", ("id?;*IDN?;ERR?", lines("HP3562A", '1,"Undefined command: *IDN?"')))
_B.g("FRS", ("FRS 2 KHZ;FRS?", lines("+3.125000000E+03")))  # 100 kHz / 2^5, rounded up
_B.g("FRS", ("FRS 1600 HZ;FRS?;CF?", lines("+3.125000000E+03", "+1.562500000E+03")))
_B.g("FRS", ("FRS 195.3125 HZ;FRS?", lines("+1.953125000E+02")))
_B.g("FRS", ("FRS2KHZ;FRS?", lines("+3.125000000E+03")))
_B.g(
    "FRS",
    (
        "FRS 102.4 KHZ;ERR?;FRS?",
        lines(
            '2,"Parameter out of range: FRS 102.4 KHZ: span must be 0.19073486 Hz to 100000 Hz"',
            "+1.000000000E+05",
        ),
    ),
)
_B.g("CF", (f"{SPAN_3562A};CF?;CF 1000 HZ;CF?", lines("+9.765625000E+01", "+1.000000000E+03")))
_B.g(
    "CF",
    (
        f"{SPAN_3562A};CF 99950 HZ;ERR?",
        lines(
            '2,"Parameter out of range: CF 99950 HZ: '
            'with a 195.312 Hz span the center must be 97.6562 Hz to 99902.3 Hz"'
        ),
    ),
)
_B.g("C1AC", ("C1AC1;C1AC?;C2AC?", lines("1", "0")))
# A preset record lasts 800 / 100 kHz = 8 ms: that is the most pre-trigger.
_B.g(
    "TDLY",
    (
        "TDLY -9 MS;ERR?",
        lines('2,"Parameter out of range: TDLY -9 MS: pre-trigger is at most one record (0.008 s)"'),
    ),
)
GOLDENS_3562A = tuple(_B.goldens)

ERRORS_3562A: list[tuple[int, str, bytes]] = [
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


# ------------------------------------------------------------------------- the dialect
def _sends_what_it_covers(gold: Golden) -> bool:
    """The golden sends its mnemonic, plain or fused with its value (``C1AC1``)."""
    sent = mnemonics_in(req for _, req, _ in gold.exchanges)
    return any(
        tok == gold.covers or (tok.startswith(gold.covers) and tok[len(gold.covers)] in "0123456789+-.")
        for tok in sent
    )


def _errors(table: list[tuple[int, str, bytes]]) -> tuple[ErrorGolden, ...]:
    """The error made and read back in one message, then the queue empty: each error read once."""
    return tuple(
        ErrorGolden(code, ((None, msg, answer), (None, "ERR?", NO_ERROR))) for code, msg, answer in table
    )


def _message_in_reply(gold: ErrorGolden) -> bool:
    return f'{gold.code},"{ERRORS[gold.code]}: '.encode("ascii") in gold.exchanges[0][2]


def dialect(model: str, goldens: tuple[Golden, ...], errors, hits: Hits) -> Dialect:
    table = commands_for(model)
    return Dialect(
        model=model,
        goldens=goldens,
        error_goldens=_errors(errors),
        make_bench=_bench(model, hits),
        required=frozenset(
            {c.mnemonic for c in table} | {c.mnemonic + "?" for c in table if c.kind == "setting"}
        ),
        sends_what_it_covers=_sends_what_it_covers,
        error_codes=frozenset(ERRORS),
        error_message_in_reply=_message_in_reply,
    )


HP35660A = dialect("35660A", GOLDENS_35660A, ERRORS_35660A, HITS_35660A)
HP3562A = dialect("3562A", GOLDENS_3562A, ERRORS_3562A, HITS_3562A)
