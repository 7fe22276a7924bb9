"""Golden request -> reply transcripts of the simulated HP 35670A (and 35665A), SCPI,
byte for byte.

Every expected reply is written by hand from docs/instrument-scpi.md, never read
back from the simulator:

* replies end with LF; the answers of several queries in one message are joined
  by ``;``; a query that fails sends nothing;
* NR3 numbers ``{:+.9E}`` (``+2.000000000E+02``), counts and booleans NR1, choices
  their short form, feeds in double quotes, ``FORM:DATA?`` -> ``REAL,64`` / ``ASC,0``;
* ``SYST:ERR?`` -> ``<code with sign>,"<SCPI message>; <detail>"``;
* the SCPI path rule: after ``;`` a header is relative to the previous one's path
  unless it starts with ``:`` or ``*``;
* ``CALC<n>:DATA?`` with ``FORM:DATA REAL,64``: ``#<d><len>`` + big-endian float64 + LF.

Traces whose values must be known come from the replay source (the hits of
tests/sims/goldens/common.py; 200 Hz span, 400 lines: 1024 samples at 512 Hz).
tests/sims/test_golden_transcripts.py plays these goldens, and fails when a command is
added to the simulator's SCPI table without a golden here.
"""

from __future__ import annotations

import struct
from collections.abc import Callable

import numpy as np

from sims.instrument import Analyzer
from sims.scpi_status import MESSAGES
from sims.scpi_table import COMMANDS
from sims.sources import PhysicsSource, ReplaySource
from tests.sims.goldens.common import TIME_START_S, Book, Dialect, ErrorGolden, FakeClock, Golden, Hits

IDN = b"HEWLETT-PACKARD,35670A,0000A00000,A.00.00\n"
NO_ERROR = b'+0,"No error"\n'


def reply(*answers: str) -> bytes:
    return ";".join(answers).encode("ascii") + b"\n"


def err(code: str, message: str) -> bytes:
    return f'{code},"{message}"\n'.encode("ascii")


HITS = Hits.make(35670, 1024, 512.0)  # 2.56 x 200 Hz, 2.56 x 400 lines
RATE_HZ, N = HITS.rate_hz, HITS.n
TIME_FORCE, TIME_ACCEL = HITS.time_force, HITS.time_accel
# With a uniform window the FRF of the delta hit (force 2 N at sample 1, acceleration
# 3 m/s^2 at sample 5) is 1.5 exp(-2 pi j k 4 / 1024) on line k.
K = np.arange(401)
DELTA_FRF = 1.5 * np.exp(-2j * np.pi * K * 4 / N)


def make_bench(kind: str, clock: FakeClock) -> Analyzer:
    if kind == "physics":
        source = PhysicsSource("seed", seed=0)
        source.set_noise(False)
        return Analyzer(source, model="35670A")
    if kind == "35665A":
        return Analyzer(PhysicsSource("seed", seed=0), model="35665A")
    if kind == "time":
        return Analyzer(ReplaySource([HITS.time_hit], loop=True, model="35670A"), model="35670A")
    if kind == "delta":
        return Analyzer(ReplaySource([HITS.delta_hit], loop=True, model="35670A"), model="35670A")
    if kind == "clock":
        replay = ReplaySource([HITS.delta_hit], loop=True, model="35670A")
        return Analyzer(replay, time_scale=1.0, clock=clock, model="35670A")
    raise ValueError(kind)


def block64(values) -> bytes:
    payload = struct.pack(f">{len(values)}d", *values)
    return b"#" + str(len(str(len(payload)))).encode() + str(len(payload)).encode() + payload + b"\n"


def block32(values) -> bytes:
    payload = struct.pack(f">{len(values)}f", *values)
    return b"#" + str(len(str(len(payload)))).encode() + str(len(payload)).encode() + payload + b"\n"


def float64_block(n_values: int, check: Callable[[np.ndarray], bool]) -> Callable[[bytes], bool]:
    """A reply that is a REAL,64 block of ``n_values`` values passing ``check``."""

    def ok(data: bytes) -> bool:
        length = str(8 * n_values).encode()
        head = b"#" + str(len(length)).encode() + length
        if not (data.startswith(head) and data.endswith(b"\n") and len(data) == len(head) + 8 * n_values + 1):
            return False
        return bool(check(np.frombuffer(data[len(head) : -1], dtype=">f8")))

    return ok


SPAN200 = "SENS:FREQ:SPAN 200 HZ"
UNIF = ":SENS:WIND1:TYPE UNIF;:SENS:WIND2:TYPE UNIF"
REAL64 = ":FORM:DATA REAL,64"


# --------------------------------------------------------------------------- goldens
_BOOK = Book()
g, g_timed = _BOOK.g, _BOOK.g_timed

# -- identification, across the family
g("*IDN?", ("*IDN?", IDN))
g("*IDN?", ("*idn?", IDN))
g("*IDN?", ("*IDN?", b"HEWLETT-PACKARD,35665A,0000A00000,A.00.00\n"), bench="35665A")
# The mnemonic family's identify is not SCPI: -113, nothing sent.
g("SYST:ERR?", ("ID?", b""), ("SYST:ERR?", err("-113", "Undefined header; ID?")), ("SYST:ERR?", NO_ERROR))

# -- preset: every setting's query form after *RST from a state where all differ
MESS = (
    "SENS:FREQ:SPAN 200 HZ;CENT 150 HZ;RES 800;:SENS:AVER:STAT ON;COUN 7;PREV MAN;TYPE RMS;TCON FREE;"
    ":SENS:WIND1:TYPE FORC;FORC 10 MS;EXP 0.5 S;:SENS:WIND2:TYPE EXP;:INP1:COUP AC;:INP2:COUP AC;"
    ":SENS:VOLT1:RANG 5 V;:SENS:VOLT2:RANG:AUTO ON;:SENS:VOLT1:RANG:AUTO ON;"
    ":SENS:VOLT1:RANG:UNIT:XDCR:SFAC 10 MV;STAT OFF;:SENS:VOLT2:RANG:UNIT:XDCR:SFAC 0.1;"
    ":TRIG:SOUR INT2;LEV -0.2 V;SLOP NEG;STAR1 -1 S;:CALC1:FEED 'XTIM:VOLT 2';FORM REAL;"
    ":CALC2:FEED 'XFR:POW 1';:CALC3:FORM NYQ;:CALC4:FEED 'XFR:POW:LIN 2';:FORM:DATA REAL,32;:INST:SEL FFT;"
    "*ESE 36;*SRE 16;:STAT:OPER:ENAB 256;:STAT:QUES:ENAB 1"
)
PRESET_REPLIES = {
    "SENS:FREQ:SPAN?": "+5.120000000E+04",
    "SENS:FREQ:CENT?": "+2.560000000E+04",
    "SENS:FREQ:RES?": "400",
    "SENS:AVER:STAT?": "0",
    "SENS:AVER:COUN?": "1",
    "SENS:AVER:TYPE?": "RMS",
    "SENS:AVER:TCON?": "FRE",
    "SENS:AVER:PREV?": "OFF",
    "SENS:WIND1:TYPE?": "HANN",
    "SENS:WIND2:TYPE?": "HANN",
    "SENS:WIND1:FORC?": "+5.000000000E-02",
    "SENS:WIND1:EXP?": "+1.000000000E+00",
    "INP1:COUP?": "DC",
    "INP2:COUP?": "DC",
    "SENS:VOLT1:RANG?": "+1.001186530E+00",  # -3 dBVrms
    "SENS:VOLT1:RANG:AUTO?": "0",
    "SENS:VOLT2:RANG:AUTO?": "0",
    "SENS:VOLT1:RANG:UNIT:XDCR:SFAC?": "+2.250000000E-03",
    "SENS:VOLT2:RANG:UNIT:XDCR:SFAC?": "+1.020000000E-03",
    "SENS:VOLT1:RANG:UNIT:XDCR:LAB?": "N",
    "SENS:VOLT2:RANG:UNIT:XDCR:LAB?": "M/S2",
    "SENS:VOLT1:RANG:UNIT:XDCR?": "1",
    "TRIG:SOUR?": "IMM",
    "TRIG:LEV?": "+0.000000000E+00",
    "TRIG:SLOP?": "POS",
    "TRIG:STAR1?": "+0.000000000E+00",
    "TRIG:STAR2?": "+0.000000000E+00",
    "CALC1:FEED?": '"XFR:POW:RAT 2,1"',
    "CALC2:FEED?": '"XFR:POW:COH 1,2"',
    "CALC3:FEED?": '"XTIM:VOLT 1"',
    "CALC4:FEED?": '"XTIM:VOLT 2"',
    "CALC1:FORM?": "MLOG",
    "CALC2:FORM?": "MLIN",
    "CALC3:FORM?": "REAL",
    "FORM:DATA?": "ASC,0",
    "INST:SEL?": "FFT",
    # IEEE 488.2: *RST leaves the status registers alone.
    "*ESE?": "36",
    "*SRE?": "16",
    "STAT:OPER:ENAB?": "256",
    "STAT:QUES:ENAB?": "1",
}
for _query, _answer in PRESET_REPLIES.items():
    g(_query, (MESS, b""), ("SYST:ERR?", NO_ERROR), ("*RST", b""), (_query, reply(_answer)))

# -- frequency
g("SENS:FREQ:SPAN", ("SENS:FREQ:SPAN 2 KHZ;SPAN?", reply("+3.200000000E+03")))  # 51.2 kHz / 2^4, up
g(
    "SENS:FREQ:SPAN",
    ("SENSE:FREQUENCY:SPAN 1600 HZ;SPAN?;CENT?", reply("+1.600000000E+03", "+8.000000000E+02")),
)
g("SENS:FREQ:SPAN", ("FREQ:SPAN 0.2KHZ;:SENS:FREQ:SPAN?", reply("+2.000000000E+02")))
g(
    "SENS:FREQ:SPAN",
    ("SENS:FREQ:SPAN 100 KHZ", b""),
    (
        "SYST:ERR?;:SENS:FREQ:SPAN?",
        b'-222,"Data out of range; SENS:FREQ:SPAN 100 KHZ: span must be 0.09765625 Hz to 51200 Hz";'
        b"+5.120000000E+04\n",
    ),
)
g(
    "SENS:FREQ:CENT",
    ("SENS:FREQ:SPAN 200 HZ;CENT 150 HZ;CENT?;SPAN?", reply("+1.500000000E+02", "+2.000000000E+02")),
)
g("SENS:FREQ:CENT?", ("SENS:FREQ:SPAN 12.5 HZ;CENT?", reply("+6.250000000E+00")))
g("SENS:FREQ:RES", ("SENS:FREQ:RES 1600;RES?", reply("1600")))
g(
    "SENS:FREQ:RES",
    ("SENS:FREQ:RES 300", b""),
    (
        "SYST:ERR?",
        err(
            "-224",
            "Illegal parameter value; SENS:FREQ:RES 300: lines must be one of 100, 200, 400, 800, 1600",
        ),
    ),
)
g(
    "SENS:FREQ:RES",
    ("SENS:FREQ:RES 1600", b""),
    (
        "SYST:ERR?;:SENS:FREQ:RES?",
        b'-224,"Illegal parameter value; SENS:FREQ:RES 1600: lines must be one of 100, 200, 400, 800";400\n',
    ),
    bench="35665A",
)

# -- averaging and preview
g("SENS:AVER:STAT", ("SENS:AVER:STAT ON;STAT?", reply("1")), ("SENS:AVER OFF;:SENS:AVER?", reply("0")))
g("SENS:AVER:COUN", ("SENS:AVER:COUN 16;COUN?", reply("16")))
g(
    "SENS:AVER:COUN",
    ("SENS:AVER:COUN 0", b""),
    ("SYST:ERR?", err("-222", "Data out of range; SENS:AVER:COUN 0: must be 1 to 9999999")),
)
g("SENS:AVER:TYPE", ("SENS:AVER:TYPE RMS;TYPE?", reply("RMS")))
g(
    "SENS:AVER:TYPE",
    ("SENS:AVER:TYPE VECT", b""),
    ("SYST:ERR?", err("-224", "Illegal parameter value; SENS:AVER:TYPE VECT: VECT is not simulated")),
)
g(
    "SENS:AVER:TCON",
    ("SENS:AVER:TCON FREE;TCON?", reply("FRE")),
    ("SENS:AVER:TCON FREEZE;TCON?", reply("FRE")),
)
g("SENS:AVER:PREV", ("SENS:AVER:PREV MAN;PREV?", reply("MAN")), ("SENS:AVER:PREV OFF;PREV?", reply("OFF")))
g(
    "SENS:AVER:COUN:INT?",
    ("SENS:AVER:COUN:INT?", reply("0")),
    (f"{SPAN200};:SENS:AVER:STAT ON;COUN 3;:INIT:IMM;:SENS:AVER:COUN:INT?", reply("3")),
    bench="delta",
)
# A hit waits in preview (528 = measuring + pending); accepted it is in, the measurement done (256).
g(
    "SENS:AVER:PREV:ACC",
    (f"{SPAN200};:SENS:AVER:PREV MAN;:INIT:IMM;:STAT:OPER:COND?;:SENS:AVER:COUN:INT?", reply("528", "0")),
    ("SENS:AVER:PREV:ACC;:SENS:AVER:COUN:INT?;:STAT:OPER:COND?", reply("1", "256")),
    bench="delta",
)
g(
    "SENS:AVER:PREV:REJ",
    (f"{SPAN200};:SENS:AVER:PREV MAN;:INIT:IMM", b""),
    ("SENS:AVER:PREV:REJ;:SENS:AVER:COUN:INT?;:STAT:OPER:COND?", reply("0", "528")),
    bench="delta",
)
g(
    "SENS:AVER:PREV:ACC",
    ("SENS:AVER:PREV:ACC", b""),
    ("SYST:ERR?", err("-221", "Settings conflict; SENS:AVER:PREV:ACC: no hit pending")),
)

# -- windows
g("SENS:WIND1:TYPE", ("SENS:WIND1:TYPE FORC;TYPE?;:SENS:WIND2:TYPE?", reply("FORC", "HANN")))
g("SENS:WIND1:TYPE", ("SENSE:WINDOW2:TYPE EXPONENTIAL;:SENS:WIND2?;:SENS:WIND1?", reply("EXP", "HANN")))
g(
    "SENS:WIND1:TYPE",
    ("sens:wind1:type flattop;type?", reply("FLAT")),
    ("SENS:WIND1 UNIF;:SENS:WIND1?", reply("UNIF")),
)
g("SENS:WIND1:TYPE?", ("SENS:WIND1:TYPE?", reply("HANN")))
g(
    "SENS:WIND1:TYPE",
    ("SENS:WIND1:TYPE BOX", b""),
    (
        "SYST:ERR?",
        err("-224", "Illegal parameter value; SENS:WIND1:TYPE BOX: not one of HANN, FLAT, UNIF, FORC, EXP"),
    ),
)
g("SENS:WIND1:FORC", ("SENS:WIND1:FORC 0.125 S;FORC?", reply("+1.250000000E-01")))
g(
    "SENS:WIND1:FORC",
    ("SENS:WIND2:FORC 10 MS;FORC?;:SENS:WIND1:FORC?", reply("+1.000000000E-02", "+5.000000000E-02")),
)
g("SENS:WIND1:FORC?", ("SENS:WIND1:FORC?", reply("+5.000000000E-02")))
g("SENS:WIND1:EXP", ("SENS:WIND2:EXP 0.333333 S;EXP?", reply("+3.333330000E-01")))
g("SENS:WIND1:EXP", ("SENS:WIND1:EXP 250 MS;EXP?", reply("+2.500000000E-01")))
g("SENS:WIND1:EXP?", ("SENS:WIND1:EXP?", reply("+1.000000000E+00")))

# -- inputs
g("INP1:COUP", ("INP1:COUP AC;COUP?;:INP2:COUP?", reply("AC", "DC")))
g("INP1:COUP", ("INPUT2:COUPLING AC;:INP2:COUP?", reply("AC")))
g("INP1:COUP", ("INP3:COUP AC", b""), ("SYST:ERR?", err("-114", "Header suffix out of range; INP3:COUP")))
g("SENS:VOLT1:RANG", ("SENS:VOLT1:RANG 0.02 V;RANG?", reply("+2.514866859E-02")))  # up to -35 dBVrms
g("SENS:VOLT1:RANG", ("SENS:VOLT2:RANG -20;RANG?", reply("+1.586773715E-01")))  # -20 dBVrms up to -19
g("SENS:VOLT1:RANG", ("SENS:VOLT1:RANG 20 MV;RANG?", reply("+2.514866859E-02")))
g("SENS:VOLT1:RANG", ("SENS:VOLT1:RANG -33 DBVRMS;RANG?", reply("+3.166029797E-02")))
g(
    "SENS:VOLT1:RANG",
    ("SENS:VOLT1:RANG 40 V", b""),
    ("SYST:ERR?", err("-222", "Data out of range; SENS:VOLT1:RANG 40 V: range must be up to 31.66 V")),
)
g(
    "SENS:VOLT1:RANG:AUTO",
    ("SENS:VOLT1:RANG:AUTO ON;AUTO?;:SENS:VOLT2:RANG:AUTO?", reply("1", "0")),
    ("SENS:VOLT1:RANG 1 V;:SENS:VOLT1:RANG:AUTO?", reply("0")),  # a range turns autorange off
)
g("SENS:VOLT1:RANG:UNIT:XDCR:SFAC", ("SENS:VOLT1:RANG:UNIT:XDCR:SFAC 10 MV;SFAC?", reply("+1.000000000E-02")))
g(
    "SENS:VOLT1:RANG:UNIT:XDCR:SFAC",
    ("SENS:VOLT2:RANG:UNIT:XDCR:SFAC 0.0001;SFAC?", reply("+1.000000000E-04")),
)
g("SENS:VOLT1:RANG:UNIT:XDCR:LAB", ("SENS:VOLT1:RANG:UNIT:XDCR:LAB N;LAB?", reply("N")))
g("SENS:VOLT1:RANG:UNIT:XDCR:LAB", ("SENS:VOLT2:RANG:UNIT:XDCR:LAB 'M/S2';LAB?", reply("M/S2")))
g(
    "SENS:VOLT1:RANG:UNIT:XDCR:LAB",
    ("SENS:VOLT2:RANG:UNIT:XDCR:LAB G", b""),
    (
        "SYST:ERR?",
        err("-224", "Illegal parameter value; SENS:VOLT2:RANG:UNIT:XDCR:LAB G: channel 2 measures in M/S2"),
    ),
)
g(
    "SENS:VOLT1:RANG:UNIT:XDCR",
    ("SENS:VOLT1:RANG:UNIT:XDCR OFF;XDCR?;:SENS:VOLT2:RANG:UNIT:XDCR:STAT?", reply("0", "1")),
)
# EU off: the channel's data come back in volts at the input (value x V per EU).
g(
    "SENS:VOLT1:RANG:UNIT:XDCR",
    (f"{SPAN200};:SENS:VOLT1:RANG:UNIT:XDCR OFF;:FORM:DATA REAL,64;:INIT:IMM", b""),
    ("CALC3:DATA?", block64(TIME_FORCE * 2.25e-3)),
    ("CALC4:DATA?", block64(TIME_ACCEL)),
    bench="time",
)

# -- trigger
g(
    "TRIG:SOUR",
    ("TRIG:SOUR INT1;SOUR?", reply("INT1")),
    ("TRIGGER:SEQUENCE:SOURCE INTERNAL2;SOUR?", reply("INT2")),
)
g(
    "TRIG:SOUR",
    ("TRIG:SOUR EXT", b""),
    ("SYST:ERR?;:TRIG:SOUR?", b'-224,"Illegal parameter value; TRIG:SOUR EXT: EXT is not simulated";IMM\n'),
)
g(
    "TRIG:LEV",
    ("TRIG:LEV -50 MV;LEV?", reply("-5.000000000E-02")),
    ("TRIG:LEV 0.00225 V;LEV?", reply("+2.250000000E-03")),
)
g("TRIG:SLOP", ("TRIG:SLOP NEG;SLOP?", reply("NEG")), ("TRIG:SLOP POSITIVE;SLOP?", reply("POS")))
g("TRIG:STAR1", ("TRIG:STAR1 -2 MS;STAR1?;STAR2?", reply("-2.000000000E-03", "-2.000000000E-03")))
g(
    "TRIG:STAR1",
    ("TRIG:STAR2 -0.0625 S", b""),
    (
        "SYST:ERR?",
        err(
            "-222", "Data out of range; TRIG:STAR2 -0.0625 S: pre-trigger is at most one record (0.0078125 s)"
        ),
    ),
)
g("TRIG:STAR1", ("SENS:FREQ:SPAN 200 HZ;:TRIG:STAR2 -0.0625 S;STAR1?", reply("-6.250000000E-02")))
g("TRIG:STAR1", ("TRIG:STAR3 0", b""), ("SYST:ERR?", err("-114", "Header suffix out of range; TRIG:STAR3")))

# -- traces: feeds, formats, data
g("CALC1:FEED", ("CALC2:FEED 'XFR:POW:LIN 1';FEED?", reply('"XFR:POW:LIN 1"')))
g("CALC1:FEED", ('CALC1:FEED "xfr:pow:rat 2, 1";FEED?', reply('"XFR:POW:RAT 2,1"')))
g(
    "CALC1:FEED",
    ("CALC1:FEED 'XFR:POW:CROS 1,2'", b""),
    (
        "SYST:ERR?",
        err("-224", "Illegal parameter value; CALC1:FEED 'XFR:POW:CROS 1,2': not a simulated feed"),
    ),
)
g(
    "CALC1:FEED",
    ("CALC5:FEED 'XTIM:VOLT 1'", b""),
    ("SYST:ERR?", err("-114", "Header suffix out of range; CALC5:FEED")),
)
g("CALC1:FORM", ("CALC1:FORM NYQ;FORM?", reply("NYQ")), ("CALCULATE4:FORMAT UPHASE;FORM?", reply("UPH")))
g(
    "CALC1:FORM",
    ("CALC1:FORM GDEL", b""),
    (
        "SYST:ERR?;:CALC1:FORM?",
        b'-224,"Illegal parameter value; CALC1:FORM GDEL: GDEL is not simulated";MLOG\n',
    ),
)
g(
    "CALC1:DATA:HEAD:POIN?",
    ("CALC1:DATA:HEAD:POIN?;:CALC3:DATA:HEAD:POIN?", reply("401", "1024")),
    ("SENS:FREQ:RES 1600;:CALC1:DATA:HEAD:POIN?;:CALC4:DATA:HEAD:POIN?", reply("1601", "4096")),
    ("SENS:FREQ:SPAN 200 HZ;CENT 1 KHZ;:CALC3:DATA:HEAD:POIN?", reply("2048")),  # zoom: 1.28 x lines complex
)
TIME_X = TIME_START_S + np.arange(N) / RATE_HZ  # exact binary fractions
g(
    "CALC1:DATA?",
    (f"{SPAN200};{REAL64};:INIT:IMM;:CALC3:DATA?", block64(TIME_FORCE)),
    ("CALC4:DATA?", block64(TIME_ACCEL)),
    ("CALC4:FORM NYQ;DATA?", block64(np.column_stack([TIME_ACCEL, np.zeros(N)]).ravel())),
    bench="time",
)
g(
    "CALC1:DATA?",
    # The preset trace 1: the FRF in MLOG, dB of its magnitude.
    (f"{SPAN200};{REAL64};:INIT:IMM;:CALC1:DATA?", float64_block(401, lambda v: np.all(np.isfinite(v)))),
    ("CALC1:DATA:HEAD:POIN?", reply("401")),
    bench="time",
)
g(
    "CALC1:DATA?",
    ("FORM:DATA REAL,64;:CALC1:DATA?", b""),
    ("SYST:ERR?", err("-230", "Data corrupt or stale; XFR:POW:RAT 2,1: nothing averaged yet")),
)
g(
    "CALC1:DATA?",
    ("CALC3:DATA?", b""),
    ("SYST:ERR?", err("-230", "Data corrupt or stale; XTIM:VOLT 1: no time record yet")),
)
g(
    "CALC1:DATA?",
    (
        f"{SPAN200};{UNIF};{REAL64};:CALC1:FORM NYQ;:INIT:IMM;:CALC1:DATA?",
        float64_block(802, lambda v: np.allclose(v[0::2] + 1j * v[1::2], DELTA_FRF, rtol=0, atol=1e-12)),
    ),
    (
        "CALC1:FORM REAL;DATA?",
        float64_block(401, lambda v: np.allclose(v, DELTA_FRF.real, rtol=0, atol=1e-12)),
    ),
    (
        "CALC1:FORM IMAG;DATA?",
        float64_block(401, lambda v: np.allclose(v, DELTA_FRF.imag, rtol=0, atol=1e-12)),
    ),
    ("CALC1:FORM MLIN;DATA?", float64_block(401, lambda v: np.allclose(v, 1.5, rtol=0, atol=1e-12))),
    ("CALC1:FORM MLOG;DATA?", float64_block(401, lambda v: np.allclose(v, 20 * np.log10(1.5), atol=1e-9))),
    (
        "CALC1:FORM PHAS;DATA?",
        float64_block(
            401,
            lambda v: (
                np.allclose(np.exp(1j * np.radians(v)), np.exp(-2j * np.pi * K * 4 / N), atol=1e-9)
                and np.all((v > -180) & (v <= 180))
            ),
        ),
    ),
    ("CALC1:FORM UPH;DATA?", float64_block(401, lambda v: np.allclose(v, -360.0 * K * 4 / N, atol=1e-9))),
    ("CALC1:FORM POL;DATA?", float64_block(802, lambda v: np.allclose(v[0::2], DELTA_FRF.real, atol=1e-12))),
    ("CALC2:FORM REAL;DATA?", float64_block(401, lambda v: np.allclose(v, 1.0, atol=1e-12))),  # coherence
    ("CALC2:FORM MLOG;DATA?", float64_block(401, lambda v: np.allclose(v, 0.0, atol=1e-9))),  # 10 log10
    # Peak-scaled linear spectrum of 2 N at sample 1: 2 x 2 / 1024 on every line but DC (half).
    (
        "CALC2:FEED 'XFR:POW:LIN 1';FORM MLIN;DATA?",
        float64_block(401, lambda v: np.allclose(v, np.r_[2 / N, np.full(400, 4 / N)], rtol=1e-12, atol=0)),
    ),
    (
        "CALC2:FEED 'XFR:POW 2';FORM REAL;DATA?",
        float64_block(
            401, lambda v: np.allclose(v, np.r_[(3 / N) ** 2, np.full(400, (6 / N) ** 2)], rtol=1e-12, atol=0)
        ),
    ),
    bench="delta",
)
g(
    "CALC1:X:DATA?",
    (f"{SPAN200};{REAL64};:INIT:IMM;:CALC1:X:DATA?", block64(K * 0.5)),  # 0 .. 200 Hz by 0.5 Hz
    ("CALC3:X:DATA?", block64(TIME_X)),
    ("FORM:DATA REAL,32;:CALC3:X:DATA?", block32(TIME_X)),
    bench="time",
)

# -- data formats
g("FORM:DATA", ("FORM:DATA REAL,64;DATA?", reply("REAL,64")), ("FORMAT REAL;:FORM?", reply("REAL,64")))
g("FORM:DATA", ("FORM:DATA REAL,32;DATA?", reply("REAL,32")))
g(
    "FORM:DATA",
    ("FORM:DATA ASC;DATA?", reply("ASC,0")),
    ("FORM:DATA BIN", b""),
    ("SYST:ERR?", err("-224", "Illegal parameter value; FORM:DATA BIN: not REAL,64, REAL,32 or ASC")),
)
g(
    "FORM:DATA",
    (f"{SPAN200};:FORM:DATA ASC;:INIT:IMM;:CALC3:DATA?", reply(",".join(f"{v:+.16E}" for v in TIME_FORCE))),
    ("FORM:DATA REAL,32;:CALC4:DATA?", block32(TIME_ACCEL)),
    bench="time",
)

# -- instrument mode, measurement control, status
g(
    "INST:SEL",
    ("INST:SEL FFT;SEL?", reply("FFT")),
    ("INSTRUMENT OCT", b""),
    ("SYST:ERR?", err("-224", "Illegal parameter value; INSTRUMENT OCT: OCT is not simulated")),
)
g(
    "INIT:IMM",
    (f"{SPAN200};:INIT:IMM;:STAT:OPER:COND?;:SENS:AVER:COUN:INT?", reply("256", "1")),
    bench="delta",
)
g("INIT:IMM", (f"{SPAN200};:INIT;:STAT:OPER:COND?;:INITIATE:IMMEDIATE", reply("256")), bench="delta")
g_timed(
    "ABOR",
    (0.0, f"{SPAN200};:INIT:IMM;:STAT:OPER:COND?", reply("48")),
    (0.2, "ABOR;:STAT:OPER:COND?;*OPC?", reply("0", "1")),
    (9.0, "STAT:OPER:COND?;:SENS:AVER:COUN:INT?", reply("0", "0")),
)
g("ABOR", (f"{SPAN200};:INIT:IMM;:ABOR;INIT:IMM;:STAT:OPER:COND?", reply("256")), bench="delta")
# The replay triggers 0.5 s after arming; a 200 Hz span records 2 s.
g_timed(
    "STAT:OPER:COND?",
    (0.0, f"{SPAN200};:INIT:IMM;:STAT:OPER:COND?", reply("48")),
    (0.6, "STAT:OPER:COND?", reply("16")),
    (2.6, "STAT:OPER:COND?;:SENS:AVER:COUN:INT?", reply("256", "1")),
)
g_timed(
    "*OPC?",
    (0.0, f"{SPAN200};:INIT:IMM;*OPC?", b""),  # held back until the measurement is done
    (1.0, "*IDN?", b""),  # queued behind it
    (2.6, "STAT:OPER:COND?", b"1\n" + IDN + reply("256")),
)
g("*OPC?", ("*OPC?", reply("1")))
g("STAT:OPER?", (f"{SPAN200};:INIT:IMM;:STAT:OPER?;:STAT:OPER:EVEN?", reply("304", "0")), bench="delta")
g(
    "STAT:OPER:ENAB",
    ("STAT:OPER:ENAB 256;ENAB?", reply("256")),
    (f"{SPAN200};:INIT:IMM;*STB?", reply("128")),
    bench="delta",
)
g("STAT:QUES:COND?", (f"{SPAN200};:INIT:IMM;:STAT:QUES:COND?;VOLT:COND?", reply("1", "1")), bench="time")
g("STAT:QUES:COND?", (f"{SPAN200};:INIT:IMM;:STAT:QUES:COND?", reply("0")), bench="delta")
g("STAT:QUES?", (f"{SPAN200};:INIT:IMM;:STAT:QUES?;QUES?", reply("1", "0")), bench="time")
g(
    "STAT:QUES:ENAB",
    ("STAT:QUES:ENAB 1;ENAB?", reply("1")),
    (f"{SPAN200};:INIT:IMM;*STB?", reply("8")),
    bench="time",
)
g(
    "STAT:QUES:VOLT:COND?",
    ("STAT:QUES:VOLT:COND?", reply("0")),
    (f"{SPAN200};:INIT:IMM;:STAT:QUES:VOLT:COND?", reply("1")),
    bench="time",
)
g("STAT:QUES:VOLT?", (f"{SPAN200};:INIT:IMM;:STAT:QUES:VOLT?;VOLT?", reply("1", "0")), bench="time")
g(
    "STAT:PRES",
    ("STAT:OPER:ENAB 256;:STAT:QUES:ENAB 1;:STAT:PRES;:STAT:OPER:ENAB?;:STAT:QUES:ENAB?", reply("0", "0")),
)
g(
    "*STB?",
    ("*STB?", reply("0")),
    ("FOO", b""),
    ("*STB?", reply("4")),
    ("SYST:ERR?;*STB?", err("-113", "Undefined header; FOO")[:-1] + b";0\n"),
)
g("*ESR?", ("FOO;*ESR?;*ESR?", reply("32", "0")), ("SENS:FREQ:SPAN 1 MHZ;*ESR?", reply("16")))
g("*ESE", ("*ESE 32;*ESE?", reply("32")), ("FOO;*STB?", reply("36")))  # 4 error queued + 32 event summary
g("*SRE", ("*SRE 4;*SRE?", reply("4")), ("FOO;*STB?", reply("68")))  # 4 + 64 master summary
g("*OPC", ("*OPC;*ESR?", reply("1")))
g("*TST?", ("*TST?", reply("0")))
g("*CLS", ("FOO;BAR;*CLS;SYST:ERR?;*ESR?;*STB?", reply('+0,"No error"', "0", "0")))
g(
    "*RST",
    ("FOO", b""),
    (
        "SENS:FREQ:SPAN 200 HZ;*RST;:SYST:ERR?;:SENS:FREQ:SPAN?",
        b'-113,"Undefined header; FOO";+5.120000000E+04\n',
    ),
)
g("SYST:ERR?", ("SYST:ERR?", NO_ERROR), ("SYSTEM:ERROR:NEXT?", NO_ERROR))

# -- SCPI's path rule
g(
    "SYST:ERR?",
    ("SENS:FREQ:SPAN 200 HZ;SENS:AVER:COUN 5", b""),
    ("SYST:ERR?", err("-113", "Undefined header; SENS:FREQ:SENS:AVER:COUN")),
)
g("SENS:AVER:COUN", ("SENS:FREQ:SPAN 200 HZ;:SENS:AVER:COUN 5;COUN?;:SYST:ERR?", reply("5", '+0,"No error"')))

# -- errors, each code (read back through SYST:ERR?)
ERROR_GOLDENS: list[tuple[int, str, bytes]] = [
    (-102, "SENS::FREQ:SPAN 1", err("-102", "Syntax error; SENS::FREQ:SPAN 1")),
    (-104, "SENS:FREQ:SPAN ABC", err("-104", "Data type error; SENS:FREQ:SPAN ABC: not a number")),
    (
        -104,
        "SENS:WIND1:TYPE 3",
        err("-104", "Data type error; SENS:WIND1:TYPE 3: a number where a choice goes"),
    ),
    (-108, "*RST 1", err("-108", "Parameter not allowed; *RST 1")),
    (-108, "*IDN? 1", err("-108", "Parameter not allowed; *IDN? 1")),
    (-109, "SENS:FREQ:SPAN", err("-109", "Missing parameter; SENS:FREQ:SPAN")),
    (-113, "STRT", err("-113", "Undefined header; STRT")),
    (-113, "ABOR?", err("-113", "Undefined header; ABOR?")),
    (-114, "SENS:WIND3:TYPE HANN", err("-114", "Header suffix out of range; SENS:WIND3:TYPE")),
    (-131, "SENS:FREQ:SPAN 2 S", err("-131", "Invalid suffix; SENS:FREQ:SPAN 2 S: unit S does not fit")),
    (-221, "SENS:AVER:PREV:REJ", err("-221", "Settings conflict; SENS:AVER:PREV:REJ: no hit pending")),
    (
        -222,
        "SENS:WIND1:FORC 0",
        err("-222", "Data out of range; SENS:WIND1:FORC 0: must be 3.8147e-06 to 9999900"),
    ),
    (
        -224,
        "SENS:AVER:STAT MAYBE",
        err("-224", "Illegal parameter value; SENS:AVER:STAT MAYBE: not ON, OFF, 1 or 0"),
    ),
    (-224, "SIM:NOISE 5", err("-224", "Illegal parameter value; SIM:NOISE takes 0 or 1")),
    (-230, "CALC2:DATA?", err("-230", "Data corrupt or stale; XFR:POW:COH 1,2: nothing averaged yet")),
    (-240, "SIM:FAULT error", err("-240", "Hardware error; input A/D converter does not respond")),
    (-350, "FOO;" * 33, err("-113", "Undefined header; FOO")),
    (-363, "A" * 5000, err("-363", "Input buffer overrun; command of 5000 characters")),
]


# ------------------------------------------------------------------------- the dialect
def _error_golden(code: int, message: str, first: bytes) -> ErrorGolden:
    """The error made (nothing sent back), read through SYST:ERR?, then the queue empty:
    every error read exactly once."""
    exchanges = [(None, message, b""), (None, "SYST:ERR?", first)]
    if code == -350:  # 33 errors: the 32nd place holds the overflow
        exchanges += [(None, "SYST:ERR?", first)] * 30
        exchanges += [(None, "SYST:ERR?", err("-350", "Queue overflow"))]
    exchanges.append((None, "SYST:ERR?", NO_ERROR))
    return ErrorGolden(code, tuple(exchanges))


def _sends_what_it_covers(gold: Golden) -> bool:
    sent = " ".join(req.upper() for _, req, _ in gold.exchanges)
    head = gold.covers.rstrip("?").split(":")[-1].rstrip("0123456789")
    return head in sent


HP35670A = Dialect(
    model="35670A",
    goldens=tuple(_BOOK.goldens),
    error_goldens=tuple(_error_golden(*e) for e in ERROR_GOLDENS),
    make_bench=make_bench,
    # A setting's query form is covered by its preset golden or its own.
    required=frozenset({c.sent for c in COMMANDS} | {c.sent + "?" for c in COMMANDS if c.kind == "setting"}),
    sends_what_it_covers=_sends_what_it_covers,
    error_codes=frozenset(MESSAGES),
)
