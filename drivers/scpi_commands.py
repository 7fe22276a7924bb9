"""The driver's command table for the SCPI analyzers, HP 35665A and 35670A
(docs/instrument-scpi.md), and the little SCPI grammar the driver needs.

Every entry names its source as the page does, so that a technician with HP's
reference can correct this table alone: ``peer`` (PyMeasure's ``Keysight35670A``:
headers, choices), ``std`` (IEEE 488.2, SCPI 1999), ``proj`` (our choice, to be
confirmed on a box). An entry's ``header`` is the short form the driver sends, ``<n>``
a channel (1, 2) or trace (1..4) suffix; the bytes of a setting (``command``) and the
parse of a read-back (``parse_reply``) come from the entry. The simulator keeps its
own table (sims/scpi_table.py): the two meet only on the wire. ``parse_message``
reads any message (long or short forms, optional nodes, the path rule after ``;``)
into canonical headers for ``replies`` and ``repeatable``.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, replace
from typing import Literal

from drivers.commands import number
from drivers.reply_values import typed_value
from drivers.setting_table import Channels, Setting, SettingsTable, Window

Kind = Literal["action", "setting", "query"]
ArgumentKind = Literal["quantity", "number", "integer", "flag", "choice", "string"]
ReplyKind = Literal["none", "text", "number", "integer", "flag", "choice", "string", "block"]

#: The unit suffix written after a quantity of each dimension (SI, as the driver holds it).
UNIT_SUFFIX = {"frequency": "HZ", "time": "S", "voltage": "V"}

#: Our windows and the 35670A's names of them (peer).
WINDOW_TYPES = {
    Window.UNIFORM: "UNIF", Window.HANNING: "HANN", Window.FLAT_TOP: "FLAT", Window.FORCE: "FORC",
    Window.EXPONENTIAL: "EXP",
}  # fmt: skip
#: Our trigger sources (drivers.setting_table) and the 35670A's (peer).
TRIGGER_SOURCES = {"CH1": "INT1", "CH2": "INT2", "FREE": "IMM"}
#: The EU label of each channel: the hammer in N, the accelerometer in m/s^2 (peer's list).
EU_LABELS = {1: "N", 2: "M/S2"}
#: CALC<n>:FORM coordinates (peer); the driver fetches in NYQ (complex) and REAL (real).
COORDINATES = ("NYQ", "POL", "REAL", "IMAG", "MLIN", "MLOG", "PHAS", "UPH")
#: Input ranges, V peak: 2 dB steps of dBVrms from -51 to +27 (peer); the top one.
MAX_RANGE_V = 10 ** (27 / 20) * math.sqrt(2)


#: Status bits (drivers/messages.py) from the SCPI registers: (register, bit, name).
#: OPER bits 4 and 5 are SCPI's (std), 8 and 9 the project's; QUES:VOLT bits proj.
# fmt: off
STATUS_MAP = (("oper", 8, "done"), ("oper", 5, "waiting_for_trigger"), ("oper", 9, "hit_pending"),
              ("oper", 4, "measuring"), ("volt", 0, "overload_ch1"), ("volt", 1, "overload_ch2"),
              ("stb", 2, "error"))
# fmt: on
#: The status in one message: one reply, the three answers joined by ``;``.
STATUS_QUERY = "STAT:OPER:COND?;:STAT:QUES:VOLT:COND?;*STB?"
#: What a fetch asks first, in one message: span, center, lines, hits in, overloads; the
#: block format is set with it, so that a fetch after *RST (preset ASC) reads blocks too.
STATE_QUERY = (
    "FORM:DATA REAL,64;:SENS:FREQ:SPAN?;:SENS:FREQ:CENT?;:SENS:FREQ:RES?;:SENS:AVER:COUN:INT?"
    ";:STAT:QUES:VOLT:COND?"
)

#: Our display functions: (feed, channel (3 = ch2/ch1), complex, y unit with EU on, in volts).
FEEDS = {
    "TIM1": ("XTIM:VOLT 1", 1, None, "N", "V"),
    "TIM2": ("XTIM:VOLT 2", 2, None, "m/s^2", "V"),
    "LSP1": ("XFR:POW:LIN 1", 1, True, "N", "V"),
    "LSP2": ("XFR:POW:LIN 2", 2, True, "m/s^2", "V"),
    "FRSP": ("XFR:POW:RAT 2,1", 3, True, "(m/s^2)/N", ""),
    "COHR": ("XFR:POW:COH 1,2", 3, False, "", ""),
}  # complex None: a time record, complex in zoom only


@dataclass(frozen=True)
class Argument:
    """What a setting takes: ``low``/``high`` bound numbers (inclusive, SI);
    ``choices`` the words of a choice. ``quantity`` is written with its unit
    suffix, ``number`` bare, ``flag`` as ON/OFF, ``string`` in single quotes."""

    kind: ArgumentKind
    dimension: str | None = None
    low: float = -math.inf
    high: float = math.inf
    choices: tuple[str, ...] = ()


@dataclass(frozen=True)
class ScpiCommand:
    """One header of the table.

    idempotent : safe to send again after a failed transfer; False for the commands
        whose repetition changes the outcome (INIT, accept, reject).
    reply : what the query (or a setting's read-back ``header?``) answers.
    reply_choices : the words a choice reply may hold (the short forms, upper case).
    suffixes : the values ``<n>`` may take (channels 1..2, traces 1..4).
    """

    header: str
    kind: Kind
    source: str
    meaning: str
    argument: Argument | None = None
    reply: ReplyKind = "none"
    reply_choices: tuple[str, ...] = ()
    idempotent: bool = True
    suffixes: tuple[int, ...] = ()

    def spelled(self, n: int | None = None) -> str:
        """The header as sent, its suffix filled in (ValueError if out of range)."""
        if "<n>" not in self.header:
            if n is not None:
                raise ValueError(f"{self.header} takes no suffix")
            return self.header
        if n not in self.suffixes:
            raise ValueError(f"{self.header} takes a suffix of {self.suffixes}, got {n!r}")
        return self.header.replace("<n>", str(n))


def _action(header: str, source: str, meaning: str, idempotent: bool = True) -> ScpiCommand:
    return ScpiCommand(header, "action", source, meaning, idempotent=idempotent)


def _query(header: str, source: str, meaning: str, reply: ReplyKind) -> ScpiCommand:
    return ScpiCommand(header, "query", source, meaning, reply=reply)


def _setting(header: str, source: str, meaning: str, argument: Argument, replies: tuple[str, ...] = ()):
    reply = {"quantity": "number"}.get(argument.kind, argument.kind)
    return ScpiCommand(header, "setting", source, meaning, argument, reply, replies or argument.choices)  # type: ignore[arg-type]


def _choice(*choices: str) -> Argument:
    return Argument("choice", choices=choices)


_CH = (1, 2)
_TRACES = (1, 2, 3, 4)
_FLAG = Argument("flag")
#: Window parameters, s (peer's range).
_WINDOW_TIME = Argument("quantity", "time", 3.8147e-6, 9.9999e6)


def _quantity(dimension: str, low: float, high: float) -> Argument:
    return Argument("quantity", dimension, low, high)


def _channel(command: ScpiCommand) -> ScpiCommand:
    return replace(command, suffixes=_TRACES if command.header.startswith("CALC") else _CH)


_V, _S, _HZ = "voltage", "time", "frequency"

# fmt: off
_TABLE: tuple[ScpiCommand, ...] = (
    _query("*IDN?", "std", "identify: maker, model, serial, firmware", "text"),
    _action("*RST", "std", "preset every setting, abort the measurement (error queue kept)"),
    _action("*CLS", "std", "clear the error queue and every event register"),
    _query("*OPC?", "std", "1 when no measurement is pending", "integer"),
    _query("*STB?", "std", "status byte: bit 2 (4) error queued", "integer"),
    _query("*ESR?", "std", "standard event register, read and cleared", "integer"),
    _query("SYST:ERR?", "std", 'pop the oldest error: code,"message"', "text"),
    _setting("FORM:DATA", "peer", "block format (REAL,64: big-endian float64)",
             _choice("REAL,64", "REAL,32", "ASC"), ("REAL,64", "REAL,32", "ASC,0")),
    _setting("INST:SEL", "peer", "instrument mode (FFT)", _choice("FFT")),
    _action("ABOR", "peer", "abort the measurement; the average is kept"),
    _action("INIT:IMM", "peer", "start: clear the average, arm the trigger", idempotent=False),
    _query("STAT:OPER:COND?", "peer", "operation condition: bits 4, 5 (std), 8, 9 (proj)", "integer"),
    _query("STAT:QUES:COND?", "peer", "questionable condition: bit 0 any overload", "integer"),
    _query("STAT:QUES:VOLT:COND?", "peer", "overloads: bit 0 ch1, bit 1 ch2 (proj)", "integer"),
    _setting("SENS:FREQ:SPAN", "peer", "span, Hz, rounded up: 51.2 kHz / 2^n", _quantity(_HZ, 1e-3, 51_200)),
    _setting("SENS:FREQ:CENT", "peer", "center, Hz: span/2 baseband, above: zoom", _quantity(_HZ, 0, 51_200)),
    _setting("SENS:FREQ:RES", "peer", "lines (proj: a line count)", Argument("integer", low=1, high=1600)),
    _setting("SENS:AVER:STAT", "peer", "averaging on", _FLAG),
    _setting("SENS:AVER:COUN", "peer", "hits to average", Argument("integer", low=1, high=9_999_999)),
    _query("SENS:AVER:COUN:INT?", "proj", "hits in the average so far", "integer"),
    _setting("SENS:AVER:TYPE", "peer", "averaging type", _choice("RMS")),
    # Sent FREE as the page's row says; the analyzer answers FRE (FREeze's short form).
    _setting("SENS:AVER:TCON", "peer", "stop when the count is reached", _choice("FREE"), ("FRE",)),
    _setting("SENS:AVER:PREV", "peer", "preview: MAN waits for accept or reject", _choice("MAN", "OFF"),
             ("MAN", "OFF", "TIM")),
    _action("SENS:AVER:PREV:ACC", "peer", "accept the pending hit", idempotent=False),
    _action("SENS:AVER:PREV:REJ", "peer", "reject the pending hit, re-arm", idempotent=False),
    _channel(_setting("SENS:WIND<n>:TYPE", "peer", "window", _choice(*WINDOW_TYPES.values()))),
    _channel(_setting("SENS:WIND<n>:FORC", "peer", "force window width, s", _WINDOW_TIME)),
    _channel(_setting("SENS:WIND<n>:EXP", "peer", "exponential window time constant, s", _WINDOW_TIME)),
    _channel(_setting("INP<n>:COUP", "peer", "coupling", _choice("AC", "DC"))),
    _channel(_setting("SENS:VOLT<n>:RANG", "peer", "range, V peak (proj: the V suffix); autorange off",
                      _quantity(_V, 1e-6, MAX_RANGE_V))),
    _channel(_setting("SENS:VOLT<n>:RANG:AUTO", "peer", "autorange", _FLAG)),
    _channel(_setting("SENS:VOLT<n>:RANG:UNIT:XDCR:SFAC", "proj", "transducer sensitivity, V per EU",
                      Argument("number", low=1e-6, high=10.0))),
    _channel(_setting("SENS:VOLT<n>:RANG:UNIT:XDCR:LAB", "peer", "EU label", _choice("N", "M/S2"))),
    _channel(_setting("SENS:VOLT<n>:RANG:UNIT:XDCR", "proj", "engineering units on", _FLAG)),
    _setting("TRIG:SOUR", "peer", "trigger source", _choice(*TRIGGER_SOURCES.values())),
    _setting("TRIG:LEV", "peer", "trigger level, V at the input (proj)", _quantity(_V, -100, 100)),
    _setting("TRIG:SLOP", "peer", "trigger slope", _choice("POS", "NEG")),
    _channel(_setting("TRIG:STAR<n>", "peer", "trigger delay, s; < 0 pre-trigger", _quantity(_S, -1e6, 1e6))),
    _channel(_setting("CALC<n>:FEED", "peer", "what the trace shows (FEEDS)", Argument("string"))),
    _channel(_setting("CALC<n>:FORM", "peer", "coordinates of CALC<n>:DATA?", _choice(*COORDINATES))),
    _channel(_query("CALC<n>:DATA?", "peer", "the trace's values: a definite block", "block")),
    _channel(_query("CALC<n>:X:DATA?", "peer", "x of each point (Hz, s from the trigger): a block", "block")),
    _channel(_query("CALC<n>:DATA:HEAD:POIN?", "peer", "points of the trace", "integer")),
)
# fmt: on


#: Each field of the settings (``ImpactSettings.wire_fields``) and its header, in the
#: order ``configure`` sends them, one setting per message; read back in the same order.
SETTINGS = SettingsTable(
    (
        Setting("instrument", "INST:SEL", fixed="FFT"),
        Setting("data_format", "FORM:DATA", fixed="REAL,64"),
        Setting("span_hz", "SENS:FREQ:SPAN"),
        Setting("center_hz", "SENS:FREQ:CENT"),
        Setting("lines", "SENS:FREQ:RES"),
        Channels(
            (
                Setting("window", "SENS:WIND<n>:TYPE", WINDOW_TYPES),
                Setting("force_width_s", "SENS:WIND<n>:FORC"),
                Setting("exp_decay_s", "SENS:WIND<n>:EXP"),
                Setting("sensitivity_v_per_eu", "SENS:VOLT<n>:RANG:UNIT:XDCR:SFAC"),
                Setting("eu_label", "SENS:VOLT<n>:RANG:UNIT:XDCR:LAB", fixed=EU_LABELS),
                # On: the data come in the channel's EU (what was read is the unit of a fetch).
                Setting("engineering_units", "SENS:VOLT<n>:RANG:UNIT:XDCR", fixed=True,
                        query="SENS:VOLT<n>:RANG:UNIT:XDCR"),
                Setting("ac_coupled", "INP<n>:COUP", {True: "AC", False: "DC"}),
                Setting("autorange", "SENS:VOLT<n>:RANG:AUTO", write=False),
                # A range turns autorange off.
                Setting("range_v", "SENS:VOLT<n>:RANG", when_none=("SENS:VOLT<n>:RANG:AUTO", True),
                        unless=("autorange", True, None)),
            ),
        ),
        Setting("trigger_source", "TRIG:SOUR", TRIGGER_SOURCES),
        Setting("trigger_level_v", "TRIG:LEV"),
        Setting("trigger_slope", "TRIG:SLOP"),
        # The simulator keeps one delay, a real box one per channel: both are sent, equal.
        Setting("trigger_delay_s", "TRIG:STAR<n>", each_channel=True),
        Setting("averaging", "SENS:AVER:STAT", fixed=True, query="SENS:AVER:STAT"),
        Setting("averages", "SENS:AVER:COUN", unless=("averaging", False, 1)),
        Setting("averaging_type", "SENS:AVER:TYPE", fixed="RMS"),
        Setting("averaging_stop", "SENS:AVER:TCON", fixed="FREE"),
        Setting("preview", "SENS:AVER:PREV", {True: "MAN", False: "OFF"}, extra_replies={"TIM": False}),
    )
)  # fmt: skip


# ------------------------------------------------------------------ the grammar
#: Long forms of the keywords the table uses, and their short forms (SCPI's rule:
#: either may be sent, in any case).
_LONG = {
    "SENSE": "SENS", "FREQUENCY": "FREQ", "CENTER": "CENT", "RESOLUTION": "RES",
    "AVERAGE": "AVER", "STATE": "STAT", "STATUS": "STAT", "COUNT": "COUN", "INTEGRAL": "INT",
    "TCONTROL": "TCON", "PREVIEW": "PREV", "ACCEPT": "ACC", "REJECT": "REJ", "WINDOW": "WIND",
    "FORCE": "FORC", "EXPONENTIAL": "EXP", "INPUT": "INP", "COUPLING": "COUP", "VOLTAGE": "VOLT",
    "RANGE": "RANG", "UPPER": "UPP", "SFACTOR": "SFAC", "LABEL": "LAB", "TRIGGER": "TRIG",
    "SEQUENCE": "SEQ", "SOURCE": "SOUR", "LEVEL": "LEV", "SLOPE": "SLOP", "START": "STAR",
    "CALCULATE": "CALC", "FORMAT": "FORM", "HEADER": "HEAD", "POINTS": "POIN",
    "INSTRUMENT": "INST", "SELECT": "SEL", "ABORT": "ABOR", "INITIATE": "INIT",
    "IMMEDIATE": "IMM", "OPERATION": "OPER", "CONDITION": "COND", "QUESTIONABLE": "QUES",
    "EVENT": "EVEN", "ENABLE": "ENAB", "PRESET": "PRES", "SYSTEM": "SYST", "ERROR": "ERR",
}  # fmt: skip
#: Keywords that take a numeric suffix (a missing one is 1).
_SUFFIXED = {"WIND", "VOLT", "INP", "CALC", "STAR"}
#: Optional nodes: (the keyword before, the optional one); a leading SENS is optional too.
_OPTIONAL_AFTER = {("INIT", "IMM"), ("TRIG", "SEQ"), ("RANG", "UPP"), ("ERR", "NEXT"),
                   ("OPER", "EVEN"), ("QUES", "EVEN"), ("VOLT", "EVEN")}  # fmt: skip
_KEYWORD = re.compile(r"([A-Z*]+?)(\d*)")
#: One command: anything up to a ``;`` that is not inside '...' or "...".
_COMMAND = re.compile(r"(?:[^;'\"]|'[^']*'|\"[^\"]*\")+")


@dataclass(frozen=True)
class Parsed:
    """One command of a message: its canonical header (short forms, optional nodes
    dropped, ``<n>`` for a suffix: ``WIND<n>:TYPE``), the suffix values, whether it
    is a query, and its argument text as sent."""

    key: str
    suffixes: tuple[int, ...]
    query: bool
    argument: str


def split_commands(text: str) -> list[str]:
    """The commands of a message: split at ``;`` outside quoted strings."""
    return [p.strip() for p in _COMMAND.findall(text) if p.strip()]


def parse_message(text: str) -> list[Parsed]:
    """Every command of ``text``, with the SCPI path rule: after ``;`` a header is
    relative to the path of the one before unless it starts with ``:`` or ``*``."""
    out: list[Parsed] = []
    path: list[str] = []
    for part in split_commands(text):
        head, _, argument = part.partition(" ")
        head = head.strip().upper()
        query = head.endswith("?")
        head = head.rstrip("?")
        if head.startswith("*"):
            out.append(Parsed(head, (), query, argument.strip()))
            continue  # a common command leaves the path as it was
        absolute = head.startswith(":")
        words = head.strip(":").split(":")
        full = words if absolute else path + words
        path = full[:-1]
        key, suffixes = _canonical(full)
        out.append(Parsed(key, suffixes, query, argument.strip()))
    return out


def _canonical(words: list[str]) -> tuple[str, tuple[int, ...]]:
    keys: list[str] = []
    suffixes: list[int] = []
    for word in words:
        match = _KEYWORD.fullmatch(word)
        name, digits = (match.group(1), match.group(2)) if match else (word, "")
        name = _LONG.get(name, name)
        if name in _SUFFIXED:
            suffixes.append(int(digits) if digits else 1)
            name += "<n>"
        elif digits:
            name += digits
        if keys and (keys[-1].replace("<n>", ""), name) in _OPTIONAL_AFTER:
            continue
        keys.append(name)
    if len(keys) > 1 and keys[0] == "SENS":
        keys = keys[1:]
    return ":".join(keys), tuple(suffixes)


def _key(header: str) -> str:
    return parse_message(header.replace("<n>", "1"))[0].key


COMMANDS: dict[str, ScpiCommand] = {_key(c.header): c for c in _TABLE}
#: The table by the header the driver sends (``SENS:WIND<n>:TYPE``).
BY_HEADER: dict[str, ScpiCommand] = {c.header.rstrip("?"): c for c in _TABLE}


def entry_of(parsed: Parsed) -> ScpiCommand | None:
    return COMMANDS.get(parsed.key)


def replies(text: str) -> list[str]:
    """What a message answers: ``["line"]`` when its queries all answer a line (IEEE
    488.2 joins their answers with ``;`` into one line), otherwise the kind of each
    query in order (``block`` for a definite block); ``[]`` for no reply. A query
    the table does not know is taken to answer a line."""
    kinds = []
    for parsed in parse_message(text):
        if parsed.query:
            entry = entry_of(parsed)
            kinds.append("block" if entry is not None and entry.reply == "block" else "line")
    return ["line"] if kinds and all(k == "line" for k in kinds) else kinds


def repeatable(text: str) -> bool:
    """False if any command of the message would change the outcome when sent twice."""
    return all(entry is None or entry.idempotent for entry in map(entry_of, parse_message(text)))


# ------------------------------------------------------------------ spelling and parsing
def _table_entry(header: str) -> ScpiCommand:
    entry = BY_HEADER.get(header.rstrip("?"))
    if entry is None:
        raise KeyError(f"{header} is not in the driver's SCPI command table")
    return entry


def command(header: str, value: object = None, n: int | None = None) -> str:
    """The message for one table entry: ``command("SENS:FREQ:SPAN", 200.0)`` ->
    ``SENS:FREQ:SPAN 200 HZ``; ``command("SENS:WIND<n>:TYPE", "FORC", 1)`` ->
    ``SENS:WIND1:TYPE FORC``. The value is checked against the entry (ValueError)."""
    entry = _table_entry(header)
    spelled = entry.spelled(n)
    arg = entry.argument
    if entry.kind == "query":
        raise ValueError(f"{header} is a query: read it")
    if arg is None:
        if value is not None:
            raise ValueError(f"{spelled} takes no argument, got {value!r}")
        return spelled
    return f"{spelled} {_format(spelled, arg, value)}"


def _format(name: str, arg: Argument, value: object) -> str:
    if arg.kind == "choice":
        if str(value) not in arg.choices:
            raise ValueError(f"{name} takes one of {', '.join(arg.choices)}, got {value!r}")
        return str(value)
    if arg.kind == "string":
        text = str(value)
        if "'" in text or not text.isascii():
            raise ValueError(f"{name} takes an ASCII string without quotes, got {value!r}")
        return f"'{text}'"
    if arg.kind == "flag":
        if value not in (0, 1, True, False):
            raise ValueError(f"{name} takes ON or OFF (a bool), got {value!r}")
        return "ON" if value else "OFF"
    try:
        x = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ValueError(f"{name} takes a number, got {value!r}") from None
    if isinstance(value, bool) or (arg.kind == "integer" and x != int(x)):
        raise ValueError(f"{name} takes an integer, got {value!r}")
    if not (math.isfinite(x) and arg.low <= x <= arg.high):
        raise ValueError(f"{name} takes {arg.low:g} to {arg.high:g}, got {value!r}")
    if arg.kind == "integer":
        return str(int(x))
    return number(x) if arg.kind == "number" else f"{number(x)} {UNIT_SUFFIX[arg.dimension or '']}"


def readback(header: str, n: int | None = None) -> str:
    """The query that reads a setting back (``SENS:WIND1:TYPE?``), or a query as sent."""
    entry = _table_entry(header)
    if entry.kind == "action":
        raise ValueError(f"{header} is an action: nothing to read")
    return entry.spelled(n) + ("?" if entry.kind == "setting" else "")


def parse_reply(header: str, reply: str) -> float | int | bool | str:
    """One answer, typed by the entry of ``header``: float (SI), int, bool, a choice's
    word or a string's contents. ValueError with the reason when it does not fit."""
    entry = _table_entry(header)
    kind, text = entry.reply, reply.strip()
    if kind == "string":
        if len(text) < 2 or text[0] != '"' or text[-1] != '"':
            raise ValueError("expected a string in double quotes")
        return text[1:-1].replace('""', '"')
    return typed_value(text, kind, entry.reply_choices, header, whole_integers=True)
