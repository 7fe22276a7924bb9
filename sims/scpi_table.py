"""The simulator's own table of the SCPI subset the 35670A and 35665A speak
(docs/instrument-scpi.md), with its header matcher and parameter parsers.

Independent of the driver's table on purpose (docs/simulator.md). Each entry is
tagged with its source: ``std`` (IEEE 488.2 / SCPI 1999), ``peer`` (seen in
PyMeasure's 35670A driver), ``proj`` (our choice). A pattern is the long form:
upper case is the short form, ``[...]`` an optional node, ``<n>`` a numeric
suffix (1 when omitted); a query-only entry ends with ``?``, a setting's query is
its header plus ``?``.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from typing import Literal

Kind = Literal["setting", "action", "query"]


class ScpiError(Exception):
    """A command that fails: its SCPI error code and a detail for the message."""

    def __init__(self, code: int, detail: str) -> None:
        super().__init__(f"{code}: {detail}")
        self.code = code
        self.detail = detail


# ------------------------------------------------------------------ parameters
#: Unit suffix -> factor to SI, per dimension (``MHZ`` is mega for a frequency, SCPI's rule).
UNITS: dict[str, dict[str, float]] = {
    "frequency": {"HZ": 1.0, "KHZ": 1e3, "MHZ": 1e6, "MAHZ": 1e6},
    "time": {"S": 1.0, "MS": 1e-3, "US": 1e-6},
    "voltage": {"V": 1.0, "MV": 1e-3, "UV": 1e-6},
    "none": {},
}
_NUMBER = re.compile(r"^([+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)\s*([A-Za-z/]*)$")


def _number(text: str) -> tuple[float, str]:
    match = _NUMBER.match(text.strip())
    if not match:
        raise ScpiError(-104, "not a number")
    return float(match.group(1)), match.group(2).upper()


@dataclass(frozen=True)
class Param:
    """What a setting takes.

    kind : "number" (a float in SI units of ``dimension``), "range" (an input range:
        V/MV/UV peak, or dBVrms bare or with DBVRMS, returned in V peak),
        "integer" (NRf rounded), "bool" (ON/OFF/1/0 -> 1/0), "choice" (``choices``
        are long forms; returns the short form in upper case), "feed" (a quoted
        string among FEEDS), "format" (FORM:DATA's REAL,64 | REAL,32 | ASC), "label".
    low, high : the accepted range of a number, integer or range (-222 outside).
    not_simulated : choices the instrument offers that the simulator refuses (-224).
    aliases : other spellings of a choice, (spelling, short form).
    """

    kind: Literal["number", "range", "integer", "bool", "choice", "feed", "format", "label"]
    dimension: str = "none"
    low: float = -math.inf
    high: float = math.inf
    choices: tuple[str, ...] = ()
    not_simulated: tuple[str, ...] = ()
    aliases: tuple[tuple[str, str], ...] = ()

    def parse(self, text: str) -> float | int | str:
        kind, text = self.kind, text.strip()
        if kind == "number":
            value, unit = _number(text)
            if unit:
                if unit not in UNITS[self.dimension]:
                    raise ScpiError(-131, f"unit {unit} does not fit")
                value *= UNITS[self.dimension][unit]
            return self._in_range(value)
        if kind == "range":
            value, unit = _number(text)
            if unit in ("", "DBVRMS"):
                value = 10.0 ** (value / 20.0) * math.sqrt(2.0) if value < 400 else math.inf
            elif unit in UNITS["voltage"]:
                value *= UNITS["voltage"][unit]
            else:
                raise ScpiError(-131, f"unit {unit} does not fit")
            return self._in_range(value)
        if kind == "integer":
            value, unit = _number(text)
            if unit:
                raise ScpiError(-131, f"unit {unit} does not fit")
            return int(self._in_range(float(round(value))))
        token = text.upper()
        if kind == "bool":
            if token in ("ON", "1"):
                return 1
            if token in ("OFF", "0"):
                return 0
            raise ScpiError(-224, "not ON, OFF, 1 or 0")
        if kind == "choice":
            if _NUMBER.match(token):
                raise ScpiError(-104, "a number where a choice goes")
            for spelling, short in self.aliases:
                if token == spelling:
                    return short
            for choice in self.choices + self.not_simulated:
                if token in (short_form(choice), choice.upper()):
                    if choice in self.not_simulated:
                        raise ScpiError(-224, f"{short_form(choice)} is not simulated")
                    return short_form(choice)
            offered = ", ".join(short_form(c) for c in self.choices)
            raise ScpiError(-224, f"not one of {offered}")
        if kind == "feed":
            return parse_feed(text)
        if kind == "format":
            return parse_data_format(text)
        if kind == "label":
            return unquote(text).upper()
        raise AssertionError(kind)  # pragma: no cover

    def _in_range(self, value: float) -> float:
        if not (math.isfinite(value) and self.low <= value <= self.high):
            raise ScpiError(-222, f"must be {self.low:.10g} to {self.high:.10g}")
        return value


def short_form(keyword: str) -> str:
    """The upper-case short form of a keyword written in long form: ``FREQuency`` -> ``FREQ``."""
    short = "".join(ch for ch in keyword if ch.isupper() or ch.isdigit() or ch in "*?/,")
    return short or keyword.upper()


def unquote(text: str) -> str:
    text = text.strip()
    if len(text) >= 2 and text[0] == text[-1] and text[0] in "'\"":
        return text[1:-1]
    return text


#: The feeds the simulator measures (docs/instrument-scpi.md, "Feeds"), canonical form.
FEEDS = (
    "XTIM:VOLT 1",
    "XTIM:VOLT 2",
    "XFR:POW:LIN 1",
    "XFR:POW:LIN 2",
    "XFR:POW 1",
    "XFR:POW 2",
    "XFR:POW:RAT 2,1",
    "XFR:POW:COH 1,2",
)


def parse_feed(text: str) -> str:
    """A quoted feed string in canonical form: upper case, one blank before the
    channels, none after the comma."""
    raw = text.strip()
    if len(raw) < 2 or raw[0] != raw[-1] or raw[0] not in "'\"":
        raise ScpiError(-104, "a feed is a quoted string")
    words = unquote(raw).upper().split()
    canonical = (words[0] + " " + "".join(words[1:])).replace(", ", ",") if words else ""
    if canonical not in FEEDS:
        raise ScpiError(-224, "not a simulated feed")
    return canonical


def parse_data_format(text: str) -> str:
    """``REAL,64``, ``REAL,32`` or ``ASC`` from FORM:DATA's argument."""
    parts = [p.strip().upper() for p in text.split(",")]
    kind = parts[0]
    length = parts[1] if len(parts) > 1 else ""
    if kind in ("REAL",) and length in ("", "64"):
        return "REAL,64"
    if kind == "REAL" and length == "32":
        return "REAL,32"
    if kind in ("ASC", "ASCII") and len(parts) <= 2:
        return "ASC"
    raise ScpiError(-224, "not REAL,64, REAL,32 or ASC")


# ------------------------------------------------------------------ the table
@dataclass(frozen=True)
class Node:
    short: str
    long: str
    optional: bool
    suffix: bool


@dataclass(frozen=True)
class ScpiCommand:
    """One header. ``key`` names it for the interpreter; ``sent`` is the short form
    the driver sends (docs/instrument-scpi.md); ``suffix_max`` bounds ``<n>``."""

    pattern: str
    kind: Kind
    key: str
    source: str
    doc: str
    sent: str
    param: Param | None = None
    suffix_max: int = 2
    nodes: tuple[Node, ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "nodes", _nodes(self.pattern.rstrip("?")))


def _nodes(pattern: str) -> tuple[Node, ...]:
    out = []
    for piece in re.findall(r"\[:?([^\]]+)\]|:?([^:\[]+)", pattern):
        optional, text = (True, piece[0]) if piece[0] else (False, piece[1])
        suffix = text.endswith("<n>")
        word = text[:-3] if suffix else text
        out.append(Node(short_form(word), word.upper(), optional, suffix))
    return tuple(out)


_F = Param("number", "frequency")
_T = Param("number", "time", 3.8147e-6, 9.9999e6)
_BOOL = Param("bool")
_MASK = Param("integer", low=0, high=32767)
_BYTE = Param("integer", low=0, high=255)


def _c(pattern: str, kind: Kind, key: str, source: str, doc: str, sent: str, param=None, n: int = 2):
    return ScpiCommand(pattern, kind, key, source, doc, sent, param, n)


COMMANDS: tuple[ScpiCommand, ...] = (
    # -- IEEE 488.2 common commands and the error queue
    _c("*IDN?", "query", "idn", "std", "identify: maker, model, serial, firmware", "*IDN?"),
    _c("*RST", "action", "rst", "std", "preset; the error queue and status registers stay", "*RST"),
    _c("*CLS", "action", "cls", "std", "clear the error queue, *ESR and the event registers", "*CLS"),
    _c("*OPC", "action", "opc", "std", "set *ESR bit 0 when no measurement is pending", "*OPC"),
    _c("*OPC?", "query", "opc?", "std", "reply 1 when no measurement is pending", "*OPC?"),
    _c("*STB?", "query", "stb", "std", "status byte: 4 error queued, 8 QUES, 32 ESB, 64 MSS, 128 OPER",
       "*STB?"),
    _c("*ESR?", "query", "esr", "std", "standard event register, read and cleared", "*ESR?"),
    _c("*ESE", "setting", "ese", "std", "standard event enable, 0..255", "*ESE", _BYTE),
    _c("*SRE", "setting", "sre", "std", "service request enable, 0..255", "*SRE", _BYTE),
    _c("*TST?", "query", "tst", "std", "self-test: 0 passes", "*TST?"),
    _c("SYSTem:ERRor[:NEXT]?", "query", "error", "std", 'pop the oldest error: code,"message"', "SYST:ERR?"),
    # -- data transfer, instrument mode, measurement control
    _c("FORMat[:DATA]", "setting", "data_format", "peer", "REAL,64 | REAL,32 | ASC", "FORM:DATA",
       Param("format")),
    _c("INSTrument[:SELect]", "setting", "instrument", "peer", "instrument mode: FFT", "INST:SEL",
       Param("choice", choices=("FFT",), not_simulated=("CORRelation", "HISTogram", "OCTave", "ORDer",
                                                        "SINE"))),
    _c("ABORt", "action", "abort", "peer", "abort the measurement", "ABOR"),
    _c("INITiate[:IMMediate]", "action", "init", "peer", "start: clear the average, arm the trigger",
       "INIT:IMM"),
    # -- status registers
    _c("STATus:OPERation:CONDition?", "query", "oper_cond", "peer",
       "16 measuring, 32 waiting for trigger, 256 done (proj), 512 hit pending (proj)", "STAT:OPER:COND?"),
    _c("STATus:OPERation[:EVENt]?", "query", "oper_event", "peer", "operation events, read and cleared",
       "STAT:OPER?"),
    _c("STATus:OPERation:ENABle", "setting", "oper_enable", "peer", "operation enable", "STAT:OPER:ENAB",
       _MASK),
    _c("STATus:QUEStionable:CONDition?", "query", "ques_cond", "peer", "1 any overload", "STAT:QUES:COND?"),
    _c("STATus:QUEStionable[:EVENt]?", "query", "ques_event", "peer", "questionable events, read and cleared",
       "STAT:QUES?"),
    _c("STATus:QUEStionable:ENABle", "setting", "ques_enable", "peer", "questionable enable",
       "STAT:QUES:ENAB", _MASK),
    _c("STATus:QUEStionable:VOLTage:CONDition?", "query", "volt_cond", "peer",
       "1 channel 1 overloaded, 2 channel 2 (proj bits)", "STAT:QUES:VOLT:COND?"),
    _c("STATus:QUEStionable:VOLTage[:EVENt]?", "query", "volt_event", "peer",
       "overload events, read and cleared", "STAT:QUES:VOLT?"),
    _c("STATus:PRESet", "action", "status_preset", "peer", "every enable register to 0", "STAT:PRES"),
    # -- frequency
    _c("[SENSe]:FREQuency:SPAN", "setting", "span", "peer", "span, Hz: top / 2^n, rounded up",
       "SENS:FREQ:SPAN", _F),
    _c("[SENSe]:FREQuency:CENTer", "setting", "center", "peer", "center, Hz: span/2 baseband, above zoom",
       "SENS:FREQ:CENT", _F),
    _c("[SENSe]:FREQuency:RESolution", "setting", "lines", "peer", "lines (proj: a line count)",
       "SENS:FREQ:RES", Param("integer", low=1, high=1e6)),
    # -- averaging and preview
    _c("[SENSe]:AVERage[:STATe]", "setting", "aver_state", "peer", "averaging on/off", "SENS:AVER:STAT",
       _BOOL),
    _c("[SENSe]:AVERage:COUNt", "setting", "aver_count", "peer", "number of averages", "SENS:AVER:COUN",
       Param("integer", low=1, high=9999999)),
    _c("[SENSe]:AVERage:COUNt:INTermediate?", "query", "aver_done", "proj", "hits in the average so far",
       "SENS:AVER:COUN:INT?"),
    _c("[SENSe]:AVERage:TYPE", "setting", "aver_type", "peer", "RMS (power) averaging", "SENS:AVER:TYPE",
       Param("choice", choices=("RMS",), not_simulated=("VECTor", "TIME", "MAXimum", "ECONfidence"))),
    _c("[SENSe]:AVERage:TCONtrol", "setting", "aver_tcon", "peer", "FREeze: stop at the count",
       "SENS:AVER:TCON", Param("choice", choices=("FREeze",), not_simulated=("REPeat", "EXPonential"),
                               aliases=(("FREE", "FRE"),))),
    _c("[SENSe]:AVERage:PREView", "setting", "preview", "peer", "OFF | MANual hit preview", "SENS:AVER:PREV",
       Param("choice", choices=("OFF", "MANual"), not_simulated=("TIMed",))),
    _c("[SENSe]:AVERage:PREView:ACCept", "action", "accept", "peer", "accept the pending hit",
       "SENS:AVER:PREV:ACC"),
    _c("[SENSe]:AVERage:PREView:REJect", "action", "reject", "peer", "reject the pending hit",
       "SENS:AVER:PREV:REJ"),
    # -- windows
    _c("[SENSe]:WINDow<n>[:TYPE]", "setting", "window", "peer", "window of channel n", "SENS:WIND1:TYPE",
       Param("choice", choices=("HANNing", "FLATtop", "UNIForm", "FORCe", "EXPonential"),
             not_simulated=("LAG", "LLAG"))),
    _c("[SENSe]:WINDow<n>:FORCe", "setting", "force_width", "peer", "force window width, s",
       "SENS:WIND1:FORC", _T),
    _c("[SENSe]:WINDow<n>:EXPonential", "setting", "exp_decay", "peer", "exponential time constant, s",
       "SENS:WIND1:EXP", _T),
    # -- inputs
    _c("INPut<n>:COUPling", "setting", "coupling", "peer", "AC | DC", "INP1:COUP",
       Param("choice", choices=("AC", "DC"))),
    _c("[SENSe]:VOLTage<n>:RANGe[:UPPer]", "setting", "range", "peer", "input range, V peak (2 dB steps, up)",
       "SENS:VOLT1:RANG", Param("range", low=0.0, high=1e9)),
    _c("[SENSe]:VOLTage<n>:RANGe:AUTO", "setting", "autorange", "peer", "autorange on/off",
       "SENS:VOLT1:RANG:AUTO", _BOOL),
    _c("[SENSe]:VOLTage<n>:RANGe:UNIT:XDCR:SFACtor", "setting", "sensitivity", "proj",
       "transducer sensitivity, V per EU", "SENS:VOLT1:RANG:UNIT:XDCR:SFAC",
       Param("number", "voltage", 1e-6, 10.0)),
    _c("[SENSe]:VOLTage<n>:RANGe:UNIT:XDCR:LABel", "setting", "label", "peer",
       "EU label: N (ch1), M/S2 (ch2)", "SENS:VOLT1:RANG:UNIT:XDCR:LAB", Param("label")),
    _c("[SENSe]:VOLTage<n>:RANGe:UNIT:XDCR[:STATe]", "setting", "eu", "proj", "engineering units on/off",
       "SENS:VOLT1:RANG:UNIT:XDCR", _BOOL),
    # -- trigger
    _c("TRIGger[:SEQuence]:SOURce", "setting", "trig_source", "peer", "IMMediate | INTernal1 | INTernal2",
       "TRIG:SOUR", Param("choice", choices=("IMMediate", "INTernal1", "INTernal2"),
                          not_simulated=("EXTernal", "BUS", "OUTPut", "INTernal3", "INTernal4"))),
    _c("TRIGger[:SEQuence]:LEVel", "setting", "trig_level", "peer", "trigger level, V at the input",
       "TRIG:LEV", Param("number", "voltage", -100.0, 100.0)),
    _c("TRIGger[:SEQuence]:SLOPe", "setting", "trig_slope", "peer", "POSitive | NEGative", "TRIG:SLOP",
       Param("choice", choices=("POSitive", "NEGative"))),
    _c("TRIGger[:SEQuence]:STARt<n>", "setting", "trig_delay", "peer", "trigger delay, s (one for both here)",
       "TRIG:STAR1", Param("number", "time", -1e4, 1e4)),
    # -- traces
    _c("CALCulate<n>:FEED", "setting", "feed", "peer", "what trace n shows", "CALC1:FEED", Param("feed"), 4),
    _c("CALCulate<n>:FORMat", "setting", "format", "peer", "coordinates of CALC:DATA?", "CALC1:FORM",
       Param("choice", choices=("NYQuist", "POLar", "REAL", "IMAGinary", "MLINear", "MLOGarithmic", "PHASe",
                                "UPHase"), not_simulated=("GDELay",)), 4),
    _c("CALCulate<n>:DATA?", "query", "data", "peer", "the trace's points (block)", "CALC1:DATA?", n=4),
    _c("CALCulate<n>:DATA:HEADer:POINts?", "query", "points", "peer", "points of the trace",
       "CALC1:DATA:HEAD:POIN?", n=4),
    _c("CALCulate<n>:X:DATA?", "query", "x_data", "peer", "x of each point (block)", "CALC1:X:DATA?", n=4),
)  # fmt: skip


def match(tokens: list[str], query: bool) -> tuple[ScpiCommand, list[int]] | None:
    """The command whose pattern ``tokens`` (keywords as sent, upper case, ``?`` off)
    spell, and the numeric suffixes they carry; None if none does."""
    for command in COMMANDS:
        if command.kind == "query" and not query:
            continue
        if command.kind == "action" and query:
            continue
        suffixes = _match_nodes(command.nodes, tokens)
        if suffixes is not None:
            return command, suffixes
    return None


def _match_nodes(nodes: tuple[Node, ...], tokens: list[str]) -> list[int] | None:
    if not nodes:
        return [] if not tokens else None
    node, rest = nodes[0], nodes[1:]
    if tokens:
        token = tokens[0]
        word, digits = token, ""
        if node.suffix:
            word = token.rstrip("0123456789")
            digits = token[len(word) :]
        if word in (node.short, node.long):
            tail = _match_nodes(rest, tokens[1:])
            if tail is not None:
                return ([int(digits) if digits else 1] if node.suffix else []) + tail
    if node.optional:
        tail = _match_nodes(rest, tokens)
        if tail is not None:
            return ([1] if node.suffix else []) + tail
    return None


def split_units(message: str) -> list[str]:
    """The commands of one message: split at ``;`` outside quotes, blanks dropped."""
    units, current, quote = [], [], ""
    for ch in message.replace("\r", "").replace("\n", " "):
        if quote:
            quote = "" if ch == quote else quote
        elif ch in "'\"":
            quote = ch
        elif ch == ";":
            units.append("".join(current))
            current = []
            continue
        current.append(ch)
    units.append("".join(current))
    return [u.strip() for u in units if u.strip()]


def grammar() -> dict[str, dict]:
    """Each command as the driver sends it (``sent``) with its kind, source and
    parameter kind, for tests and ``daq sim commands --model 35670A``."""
    return {
        c.sent: {
            "pattern": c.pattern,
            "kind": c.kind,
            "source": c.source,
            "param": c.param.kind if c.param is not None else None,
            "choices": tuple(short_form(x) for x in c.param.choices) if c.param is not None else (),
            "doc": c.doc,
        }
        for c in COMMANDS
    }
