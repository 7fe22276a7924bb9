"""The driver's command table for the HP 35660A (docs/instrument.md), in one place.

No public copy of the 35660A programming manual exists, so the driver speaks the
mnemonic dialect of its documented sibling, the HP 3562A. Every entry names its
source so that a technician with the real manual can correct this table alone:

* ``3562A``: seen in public code driving an HP 3562A;
* ``proj``: a project choice where no source was found, to be confirmed on a real
  35660A (per-channel windows, ranges, sensitivities, trigger, preview, queries).

Each entry carries its whole grammar, PyMeasure-style: the kind of argument, the
dimension and unit suffix of a quantity, the range the driver lets through, the
choices, the read-back query and what that query answers. The bytes of every
setting (``command``) and the parse of every read-back (``parse_reply``) are
generated from it, so correcting a mnemonic, a suffix or a choice is one edit
here. The simulator keeps an independent copy (sims/command_table.py);
``grammar()`` exposes ours for the test that compares the two.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

from drivers.record import MAX_SPAN_HZ
from drivers.reply_values import typed_value
from drivers.setting_table import (
    CHANNEL_ROWS,
    SLOPES,
    TRIGGER_SOURCES,
    Channels,
    Setting,
    SettingsTable,
    Window,
)

Kind = Literal["action", "setting", "query"]
ArgumentKind = Literal["quantity", "integer", "flag", "choice"]
#: What a reply line holds: free text, a number (SI), an integer, 0/1, one of the choices.
ReplyKind = Literal["none", "text", "number", "integer", "flag", "choice", "values", "block", "lines"]

#: The unit suffix the driver writes after a quantity of each dimension (SI, so the
#: number is sent as the driver holds it). Names as in sims/units.py.
UNIT_SUFFIX = {"frequency": "HZ", "time": "S", "voltage": "V"}

WINDOWS = tuple(w.value for w in Window)
AVERAGING_MODES = ("STBL", "AVOF")
TRACES = ("A", "B")
#: Our display mnemonics; their codes in a dump header are in drivers/trace.py.
DISPLAY_FUNCTIONS = ("TIM1", "TIM2", "LSP1", "LSP2", "PSP1", "PSP2", "FRSP", "COHR")


@dataclass(frozen=True)
class Argument:
    """What a setting takes. ``low``/``high`` bound the value (inclusive, SI) for
    quantities and integers; ``choices`` the words of a choice."""

    kind: ArgumentKind
    dimension: str | None = None
    low: float = -math.inf
    high: float = math.inf
    choices: tuple[str, ...] = ()

    @property
    def suffix(self) -> str | None:
        return UNIT_SUFFIX[self.dimension] if self.dimension else None


@dataclass(frozen=True)
class Mnemonic:
    text: str
    kind: Kind
    source: str
    meaning: str
    argument: Argument | None = None
    #: Safe to send again after a failed transfer (a setting, a query); False for
    #: commands whose repetition changes the outcome (ACPT, RJCT).
    idempotent: bool = True
    #: What the instrument sends back for this mnemonic itself (a query), or for its
    #: read-back query (a setting, ``readback``): see ReplyKind.
    reply: ReplyKind = "none"
    reply_choices: tuple[str, ...] = field(default=())

    @property
    def readback(self) -> str | None:
        """The query that reads a setting back: its mnemonic plus ``?``."""
        return self.text + "?" if self.kind == "setting" else None


def _action(text: str, source: str, meaning: str, idempotent: bool = True) -> Mnemonic:
    return Mnemonic(text, "action", source, meaning, idempotent=idempotent)


def _setting(text: str, source: str, meaning: str, argument: Argument) -> Mnemonic:
    reply = {"quantity": "number"}.get(argument.kind, argument.kind)
    return Mnemonic(text, "setting", source, meaning, argument, reply=reply, reply_choices=argument.choices)  # type: ignore[arg-type]


def _query(text: str, source: str, meaning: str, reply: ReplyKind, choices: tuple[str, ...] = ()) -> Mnemonic:
    return Mnemonic(text, "query", source, meaning, reply=reply, reply_choices=choices)


def _quantity(dimension: str, low: float, high: float) -> Argument:
    return Argument("quantity", dimension, low, high)


_FLAG = Argument("flag", low=0, high=1)
#: Window parameters, s: from a microsecond to beyond any record (400 / 0.195 Hz).
_WINDOW_TIME = _quantity("time", 1e-6, 1e4)
_SENSITIVITY = _quantity("voltage", 1e-6, 10.0)
_RANGE = _quantity("voltage", 1e-6, 100.0)

_TABLE: tuple[Mnemonic, ...] = (
    _query("ID?", "3562A", "identify; the 35660A replies HP35660A", "text"),
    _action("RST", "3562A", "preset"),
    _action("LCL", "3562A", "go to local"),
    _action("STRT", "3562A", "start a measurement (clears the average, arms)"),
    _action("PAUS", "3562A", "pause"),
    _action("CONT", "3562A", "continue"),
    _query("SMSD", "3562A", "measurement done? 1 or 0", "flag"),
    _action("ACPT", "proj", "preview: accept the pending hit", idempotent=False),
    _action("RJCT", "proj", "preview: reject the pending hit", idempotent=False),
    _setting(
        "FRS",
        "3562A",
        "frequency span, Hz (rounded up to 102.4 kHz / 2^n)",
        _quantity("frequency", 1e-3, MAX_SPAN_HZ),
    ),
    _setting(
        "CF", "proj", "center frequency, Hz (span/2 = baseband)", _quantity("frequency", 0.0, MAX_SPAN_HZ)
    ),
    _setting("NAVG", "3562A", "number of averages", Argument("integer", low=1, high=9999)),
    _action("STBL", "3562A", "stable (mean) averaging"),
    _action("AVOF", "3562A", "averaging off"),
    _setting("PRVW", "proj", "hit preview on (1) or off (0)", _FLAG),
    _action("FRQR", "3562A", "frequency response measurement"),
    _action("LNRS", "3562A", "linear resolution"),
    _action("UNIF", "3562A", "uniform window, both channels"),
    _action("HANN", "3562A", "Hanning window, both channels"),
    _action("FLAT", "3562A", "flat top window, both channels"),
    _setting("WIN1", "proj", "channel 1 window", Argument("choice", choices=WINDOWS)),
    _setting("WIN2", "proj", "channel 2 window", Argument("choice", choices=WINDOWS)),
    _setting("FWD1", "proj", "channel 1 force window width, s", _WINDOW_TIME),
    _setting("FWD2", "proj", "channel 2 force window width, s", _WINDOW_TIME),
    _setting("EXD1", "proj", "channel 1 exponential window time constant, s", _WINDOW_TIME),
    _setting("EXD2", "proj", "channel 2 exponential window time constant, s", _WINDOW_TIME),
    _setting("RNG1", "proj", "channel 1 input range, V peak", _RANGE),
    _setting("RNG2", "proj", "channel 2 input range, V peak", _RANGE),
    _action("AU1", "3562A", "autorange channel 1"),
    _action("AU2", "proj", "autorange channel 2"),
    _setting("C1AC", "3562A", "channel 1 AC (1) or DC (0) coupling", _FLAG),
    _setting("C2AC", "proj", "channel 2 AC (1) or DC (0) coupling", _FLAG),
    _setting("SNS1", "proj", "channel 1 sensitivity, V per N", _SENSITIVITY),
    _setting("SNS2", "proj", "channel 2 sensitivity, V per m/s^2", _SENSITIVITY),
    _setting("TSRC", "proj", "trigger source", Argument("choice", choices=TRIGGER_SOURCES)),
    _setting("TLVL", "proj", "trigger level, V", _quantity("voltage", -100.0, 100.0)),
    _setting("TSLP", "proj", "trigger slope", Argument("choice", choices=SLOPES)),
    _setting("TDLY", "proj", "trigger delay, s; negative = pre-trigger", _quantity("time", -1e4, 1e4)),
    _action("TRCA", "proj", "trace A active"),
    _action("TRCB", "proj", "trace B active"),
    _action("TIM1", "proj", "display: channel 1 time record"),
    _action("TIM2", "proj", "display: channel 2 time record"),
    _action("LSP1", "proj", "display: channel 1 linear spectrum"),
    _action("LSP2", "proj", "display: channel 2 linear spectrum"),
    _action("PSP1", "3562A", "display: channel 1 power spectrum"),
    _action("PSP2", "proj", "display: channel 2 power spectrum"),
    _action("FRSP", "proj", "display: frequency response ch2/ch1"),
    _action("COHR", "proj", "display: coherence"),
    _query("DISP?", "proj", "display function of the active trace", "choice", DISPLAY_FUNCTIONS),
    _query("TRC?", "proj", "active trace", "choice", TRACES),
    _query("DDAN", "3562A", "dump the active trace: #A block, 66-value header + data", "block"),
    _query("DDAS", "3562A", "dump the active trace: #I, count line, one value per line", "lines"),
    _query("DSAN", "3562A", "dump the state: #A block of 96 float64 (drivers/state.py)", "block"),
    _query("DSAS", "3562A", "dump the state: #I, count line (96), one value per line", "lines"),
    _query("STA?", "proj", "status bits (STATUS_BITS)", "integer"),
    _query("ERR?", "proj", 'pop the oldest error: code,"message"', "text"),
    _action("CLER", "proj", "clear the error queue"),
    _query("OVLD?", "proj", "overload of the last record: ch1,ch2", "values"),
    _query("AVG?", "proj", "hits in the average", "integer"),
    _query("AVMD?", "proj", "averaging mode", "choice", AVERAGING_MODES),
    _query("AU1?", "proj", "autorange of channel 1 on (1) or off (0)", "flag"),
    _query("AU2?", "proj", "autorange of channel 2 on (1) or off (0)", "flag"),
)

COMMANDS: dict[str, Mnemonic] = {m.text: m for m in _TABLE}

#: Each field of the settings (``ImpactSettings.wire_fields``) and its mnemonic, in the
#: order ``configure`` sends them; read back in ``read_order`` (the golden transcripts').
SETTINGS = SettingsTable(
    (
        Setting("measurement", "FRQR", fixed=None),
        Setting("resolution", "LNRS", fixed=None),
        Setting("span_hz", "FRS"),
        Setting("center_hz", "CF"),
        Channels(
            (
                Setting("window", "WIN{ch}"),
                Setting("force_width_s", "FWD{ch}"),
                Setting("exp_decay_s", "EXD{ch}"),
                Setting("sensitivity_v_per_eu", "SNS{ch}"),
                Setting("ac_coupled", "C{ch}AC"),
                Setting("autorange", "AU{ch}?", write=False),
                Setting("range_v", "RNG{ch}", when_none=("AU{ch}", None), unless=("autorange", True, None)),
            ),
            read_order=(
                "window",
                "sensitivity_v_per_eu",
                "autorange",
                "range_v",
                "force_width_s",
                "exp_decay_s",
                "ac_coupled",
            ),
        ),
        Setting("trigger_source", "TSRC"),
        Setting("trigger_level_v", "TLVL"),
        Setting("trigger_slope", "TSLP"),
        Setting("trigger_delay_s", "TDLY"),
        Setting("averages", "NAVG", unless=("averaging", "AVOF", 1)),
        Setting("averaging", "STBL", fixed=None, query="AVMD?"),
        Setting("preview", "PRVW"),
    ),
    read_order=(
        "span_hz",
        "center_hz",
        CHANNEL_ROWS,
        "trigger_source",
        "trigger_level_v",
        "averaging",
        "trigger_slope",
        "trigger_delay_s",
        "averages",
        "preview",
    ),
)

#: STA? bits (proj): drivers/messages.py Status, which every dialect reports in.


def grammar() -> dict[str, dict]:
    """Every mnemonic's grammar, for the test that compares it with the simulator's
    table: settings under their mnemonic (without ``?``), queries as sent."""
    out: dict[str, dict] = {}
    for m in _TABLE:
        arg = m.argument
        out[m.text] = {
            "kind": m.kind,
            "source": m.source,
            "argument": arg.kind if arg else None,
            "dimension": arg.dimension if arg else None,
            "choices": arg.choices if arg else (),
            "readback": m.readback,
        }
    return out


def number(value: float) -> str:
    """A numeric argument: 12 significant digits, more than the analyzer resolves,
    and never ``-0`` (which an instrument may refuse)."""
    return f"{float(value) + 0.0:.12g}"


def _entry(mnemonic: str, kind: Kind | None = None) -> Mnemonic:
    entry = COMMANDS.get(mnemonic)
    if entry is None:
        raise KeyError(f"{mnemonic} is not in the driver's command table")
    if kind is not None and entry.kind != kind:
        raise ValueError(f"{mnemonic} is a {entry.kind}, not a {kind}")
    return entry


def command(mnemonic: str, value: object = None) -> bytes:
    """The message for one table entry: ``command("FRS", 200.0)`` -> b"FRS 200 HZ",
    ``command("STBL")`` -> b"STBL". The value is checked against the entry's
    grammar (ValueError naming the mnemonic); units are SI."""
    entry = _entry(mnemonic)
    arg = entry.argument
    if arg is None:
        if value is not None:
            raise ValueError(f"{mnemonic} takes no argument, got {value!r}")
        return mnemonic.encode("ascii")
    return f"{mnemonic} {_format_argument(mnemonic, arg, value)}".encode("ascii")


def _format_argument(mnemonic: str, arg: Argument, value: object) -> str:
    if arg.kind == "choice":
        text = str(value)
        if text not in arg.choices:
            raise ValueError(f"{mnemonic} takes one of {', '.join(arg.choices)}, got {value!r}")
        return text
    if isinstance(value, bool) or arg.kind == "flag":
        if value not in (0, 1, True, False):
            raise ValueError(f"{mnemonic} takes 0 or 1, got {value!r}")
        return str(int(value))  # type: ignore[call-overload]
    try:
        x = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ValueError(f"{mnemonic} takes a number, got {value!r}") from None
    if arg.kind == "integer" and x != int(x):
        raise ValueError(f"{mnemonic} takes an integer, got {value!r}")
    if not (math.isfinite(x) and arg.low <= x <= arg.high):
        unit = f" {arg.suffix}" if arg.suffix else ""
        raise ValueError(f"{mnemonic} takes {arg.low:g} to {arg.high:g}{unit}, got {value!r}")
    if arg.kind == "integer":
        return str(int(x))
    return f"{number(x)} {arg.suffix}"


def parse_reply(query: str, reply: str) -> float | int | bool | str:
    """The reply line of a one-line query, typed by the table: a setting's read-back
    (``FRS?`` -> float, SI) or a query (``AVMD?`` -> "STBL"). ValueError with the
    reason when the reply does not fit; the driver turns it into a ProtocolError."""
    entry = _reply_entry(query)
    return typed_value(reply.strip(), entry.reply, entry.reply_choices, query)


def _reply_entry(query: str) -> Mnemonic:
    """The entry that says what ``query`` answers: a query's own, or the setting
    whose read-back it is (``FRS?``)."""
    entry = COMMANDS.get(query)
    if entry is not None and entry.kind == "query":
        return entry
    if query.endswith("?"):
        setting = COMMANDS.get(query[:-1])
        if setting is not None and setting.kind == "setting":
            return setting
    raise KeyError(f"{query} is not a query of the driver's command table")


def replies(text: str) -> list[str]:
    """The reply kind of each command in a message that answers (``FRS?`` -> line).

    ``line`` for any one-line reply, ``block`` for #A blocks, ``lines`` for ASCII
    dumps. A setting's query form answers a line; a mnemonic the table does not
    know is taken to answer a line if it ends with ``?``.
    """
    kinds = []
    for part in text.split(";"):
        head = part.strip().split(" ")[0].upper()
        if not head:
            continue
        try:
            kind: str = _reply_entry(head).reply
        except KeyError:
            kind = "line" if head.endswith("?") else "none"
        if kind not in ("none", "block", "lines"):
            kind = "line"
        if kind != "none":
            kinds.append(kind)
    return kinds
