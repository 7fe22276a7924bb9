"""The simulator's copy of the analyzer's command set (docs/instrument.md).

One table, each entry tagged with its source:

* ``3562A``: seen in public code driving an HP 3562A, the 35660A's documented sibling;
* ``proj``: a project choice where no source was found, to be confirmed on a real
  35660A (per-channel windows, ranges, sensitivities, trigger, preview, queries).

The driver keeps its own, independent copy (drivers/); the golden transcripts in
tests/ pin both to the same bytes. A setting's query form is its mnemonic plus
``?`` and replies in SI units.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Literal

from sims.units import ArgumentError, Dimension, parse_quantity

Kind = Literal["action", "setting", "query"]

WINDOWS = ("UNIF", "HANN", "FLAT", "FORC", "EXPO")
TRIGGER_SOURCES = ("CH1", "CH2", "FREE")
SLOPES = ("POS", "NEG")
DISPLAY_FUNCTIONS = ("TIM1", "TIM2", "LSP1", "LSP2", "PSP1", "PSP2", "FRSP", "COHR")


@dataclass(frozen=True)
class Argument:
    """What a setting accepts: a number of a dimension, an integer, a flag or a choice."""

    kind: Literal["quantity", "integer", "flag", "choice"]
    dimension: Dimension = "none"
    low: float = float("-inf")
    high: float = float("inf")
    choices: tuple[str, ...] = ()

    def parse(self, text: str) -> float | int | str:
        """The value ``text`` gives: a quantity in SI units (Hz, s, V), an integer, a
        flag as 0/1 (``ON``/``OFF`` too) or a choice's mnemonic, upper case.

        ArgumentError (code 3 malformed, 4 wrong unit) if it gives none; the range
        (``low``..``high``) is left to the caller, which reports it as error 2.
        """
        if self.kind == "quantity":
            return parse_quantity(text, self.dimension)
        token = text.strip().upper()
        if self.kind == "choice":
            if token not in self.choices:
                raise ArgumentError(f"{token!r} is not one of {', '.join(self.choices)}", 3)
            return token
        if self.kind == "flag":
            token = {"ON": "1", "OFF": "0"}.get(token, token)
        digits = token[1:] if token[:1] in "+-" else token
        # ASCII only: str.isdigit() also takes "²", which int() then refuses.
        if not (digits.isascii() and digits.isdigit()):
            raise ArgumentError(f"not an integer: {text.strip()!r}", 3)
        return int(token)


@dataclass(frozen=True)
class Command:
    mnemonic: str
    kind: Kind
    source: Literal["3562A", "proj"]
    doc: str
    attribute: str | None = None  # settings field (settings) or action argument
    argument: Argument | None = None


def _setting(mnemonic: str, attribute: str, argument: Argument, source: str, doc: str) -> Command:
    return Command(mnemonic, "setting", source, doc, attribute, argument)  # type: ignore[arg-type]


def _action(mnemonic: str, source: str, doc: str, attribute: str | None = None) -> Command:
    return Command(mnemonic, "action", source, doc, attribute)  # type: ignore[arg-type]


def _query(mnemonic: str, source: str, doc: str) -> Command:
    return Command(mnemonic, "query", source, doc)  # type: ignore[arg-type]


_FREQ = Argument("quantity", "frequency")
_TIME_POSITIVE = Argument("quantity", "time", low=1e-6, high=1e4)
_FLAG = Argument("flag", low=0, high=1)

COMMANDS: tuple[Command, ...] = (
    # -- identification, reset, measurement control
    _query("ID?", "3562A", "identify: replies HP35660A"),
    _action("RST", "3562A", "preset every setting, clear data and errors"),
    _action("LCL", "3562A", "go to local (front panel)"),
    _action("STRT", "3562A", "start a measurement: clear the average, arm the trigger"),
    _action("PAUS", "3562A", "pause the measurement"),
    _action("CONT", "3562A", "continue a paused measurement"),
    _query("SMSD", "3562A", "measurement done: replies 1 when every average is in, else 0"),
    _action("ACPT", "proj", "preview: accept the pending hit into the average"),
    _action("RJCT", "proj", "preview: reject the pending hit"),
    # -- frequency
    _setting("FRS", "span_hz", _FREQ, "3562A", "frequency span: 102.4 kHz / 2^n, rounded up"),
    _setting(
        "CF",
        "center_hz",
        _FREQ,
        "proj",
        "center frequency: span/2 is baseband, above is a zoom (complex records)",
    ),
    # -- averaging and measurement
    _setting("NAVG", "n_averages", Argument("integer", low=1, high=9999), "3562A", "number of averages"),
    _action("STBL", "3562A", "stable (mean) averaging", "averaging"),
    _action("AVOF", "3562A", "averaging off: every record replaces the last", "averaging"),
    _setting("PRVW", "preview", _FLAG, "proj", "hit preview: each hit waits for ACPT or RJCT"),
    _action("FRQR", "3562A", "frequency response measurement (ch2 / ch1)", "measurement"),
    _action("LNRS", "3562A", "linear resolution mode", "mode"),
    # -- windows
    _action("UNIF", "3562A", "uniform window on both channels", "window"),
    _action("HANN", "3562A", "Hanning window on both channels", "window"),
    _action("FLAT", "3562A", "flat top window on both channels", "window"),
    _setting("WIN1", "window1", Argument("choice", choices=WINDOWS), "proj", "window of channel 1"),
    _setting("WIN2", "window2", Argument("choice", choices=WINDOWS), "proj", "window of channel 2"),
    _setting("FWD1", "force_width1_s", _TIME_POSITIVE, "proj", "force window width, channel 1"),
    _setting("FWD2", "force_width2_s", _TIME_POSITIVE, "proj", "force window width, channel 2"),
    _setting("EXD1", "exp_decay1_s", _TIME_POSITIVE, "proj", "exponential window time constant, ch 1"),
    _setting("EXD2", "exp_decay2_s", _TIME_POSITIVE, "proj", "exponential window time constant, ch 2"),
    # -- inputs
    _setting(
        "RNG1", "range1_v", Argument("quantity", "voltage"), "proj", "ch1 range, V peak (1 dB steps, up)"
    ),
    _setting(
        "RNG2", "range2_v", Argument("quantity", "voltage"), "proj", "ch2 range, V peak (1 dB steps, up)"
    ),
    _action("AU1", "3562A", "autorange channel 1 (up-ranging on overload)", "autorange1"),
    _action("AU2", "proj", "autorange channel 2 (by analogy with AU1)", "autorange2"),
    _setting("C1AC", "ac_coupled1", _FLAG, "3562A", "channel 1 AC coupling (C1AC1) or DC (C1AC0)"),
    _setting("C2AC", "ac_coupled2", _FLAG, "proj", "channel 2 AC coupling (by analogy with C1AC)"),
    _setting(
        "SNS1",
        "sensitivity1_v_per_eu",
        Argument("quantity", "voltage", low=1e-6, high=10.0),
        "proj",
        "ch1 transducer sensitivity, V per N (hammer)",
    ),
    _setting(
        "SNS2",
        "sensitivity2_v_per_eu",
        Argument("quantity", "voltage", low=1e-6, high=10.0),
        "proj",
        "ch2 transducer sensitivity, V per m/s^2 (accelerometer)",
    ),
    # -- trigger
    _setting("TSRC", "trigger_source", Argument("choice", choices=TRIGGER_SOURCES), "proj", "trigger source"),
    _setting(
        "TLVL",
        "trigger_level_v",
        Argument("quantity", "voltage", low=-100, high=100),
        "proj",
        "trigger level, V, on the input before its anti-alias filter",
    ),
    _setting("TSLP", "trigger_slope", Argument("choice", choices=SLOPES), "proj", "trigger slope"),
    _setting(
        "TDLY",
        "trigger_delay_s",
        Argument("quantity", "time", low=-1e4, high=1e4),
        "proj",
        "trigger delay; negative = pre-trigger, at most one record",
    ),
    # -- traces and display functions
    _action("TRCA", "proj", "make trace A active", "trace"),
    _action("TRCB", "proj", "make trace B active", "trace"),
    _action("TIM1", "proj", "active trace shows the channel 1 time record", "display"),
    _action("TIM2", "proj", "active trace shows the channel 2 time record", "display"),
    _action("LSP1", "proj", "active trace shows the channel 1 linear spectrum", "display"),
    _action("LSP2", "proj", "active trace shows the channel 2 linear spectrum", "display"),
    _action("PSP1", "3562A", "active trace shows the channel 1 power spectrum", "display"),
    _action("PSP2", "proj", "active trace shows the channel 2 power spectrum", "display"),
    _action("FRSP", "proj", "active trace shows the frequency response ch2/ch1 (H1)", "display"),
    _action("COHR", "proj", "active trace shows the coherence", "display"),
    _query("DISP?", "proj", "display function of the active trace"),
    _query("TRC?", "proj", "active trace: A or B"),
    # -- transfers
    _query("DDAN", "3562A", "dump the active trace: #A block of big-endian float64, 66-value header"),
    _query("DDAS", "3562A", "dump the active trace as ASCII: #I, the count, one value per line"),
    _query("DSAN", "3562A", "dump the state: #A block of 96 float64 (our settings at words 0-25, proj)"),
    _query("DSAS", "3562A", "dump the state as ASCII: #I, the count 96, one value per line"),
    # -- status
    _query(
        "STA?",
        "proj",
        "status bits: 1 done, 2 waiting for trigger, 4 ch1 overload, 8 ch2 overload, "
        "16 error, 32 hit pending, 64 measuring, 128 paused",
    ),
    _query("ERR?", "proj", 'pop the oldest error: code,"message" (0,"No error" when none)'),
    _action("CLER", "proj", "clear the error queue"),
    _query("OVLD?", "proj", "overload of the last record: ch1,ch2 as 0/1"),
    _query("AVG?", "proj", "number of hits in the average"),
    _query("AVMD?", "proj", "averaging mode: STBL or AVOF"),
    _query("AU1?", "proj", "autorange of channel 1: 1 on, 0 off (a range setting turns it off)"),
    _query("AU2?", "proj", "autorange of channel 2"),
)

BY_MNEMONIC: dict[str, Command] = {c.mnemonic: c for c in COMMANDS}

#: What the 3562A's copy of the table says differently (the commands are the same).
_3562A_DOCS = {
    "ID?": "identify: replies HP3562A",
    "FRS": "frequency span: 100 kHz / 2^n, rounded up",
}


def commands_for(model: str) -> tuple[Command, ...]:
    """The table as the simulated ``model`` ("35660A" or "3562A") documents it."""
    if model == "3562A":
        return tuple(replace(c, doc=_3562A_DOCS.get(c.mnemonic, c.doc)) for c in COMMANDS)
    return COMMANDS


def split_message(message: str) -> list[str]:
    """The commands of one message: separated by ``;`` or line ends (CR, LF), blanks dropped."""
    pieces = message.replace("\r", "\n").replace(";", "\n").split("\n")
    return [piece.strip() for piece in pieces if piece.strip()]


#: Error codes the instrument reports through ERR? (proj).
ERRORS = {
    1: "Undefined command",
    2: "Parameter out of range",
    3: "Invalid parameter",
    4: "Invalid unit",
    5: "No data available",
    6: "Not allowed now",
    7: "Hardware fault",
    8: "Input buffer overflow",
}

#: Status bits of STA? and of the serial poll byte (proj).
STATUS_DONE = 1
STATUS_WAITING_FOR_TRIGGER = 2
STATUS_OVERLOAD_CH1 = 4
STATUS_OVERLOAD_CH2 = 8
STATUS_ERROR = 16
STATUS_HIT_PENDING = 32
STATUS_MEASURING = 64
STATUS_PAUSED = 128

#: Header word 0, the display function: the documented 3562A codes (1 frequency
#: response, 2/3 power spectrum 1/2, 4 coherence, 6/7 input time 1/2, 8/9 linear
#: spectrum 1/2; docs/instrument.md, "Trace format").
DISPLAY_CODES = {"FRSP": 1, "PSP1": 2, "PSP2": 3, "COHR": 4, "TIM1": 6, "TIM2": 7, "LSP1": 8, "LSP2": 9}
#: Header word 9, y units: no codes are documented, these are ours (proj).
Y_UNIT_CODES = {"V": 0, "N": 1, "m/s^2": 2, "(m/s^2)/N": 3, "": 4, "N^2": 5, "(m/s^2)^2": 6}
#: Header word 10, x units (documented: 1 Hz, 4 s); word 7, the domain (0 time, 1 frequency).
X_UNIT_CODES = {"Hz": 1, "s": 4}
DOMAIN_CODES = {"time": 0, "frequency": 1}


def grammar() -> dict[str, dict]:
    """Each mnemonic's grammar, in the shape the driver's independent table gives it
    (tests/test_command_tables_agree.py compares the two).

    Keys: settings under their mnemonic without ``?``, queries as sent (``ID?``,
    ``SMSD``). Each value holds ``kind`` ("action", "setting", "query"), ``source``
    ("3562A", "proj"), ``argument`` (None, "quantity", "integer", "flag", "choice"),
    ``dimension`` (the sims.units dimension of a quantity, whose query replies in its
    SI unit: Hz, s, V; None for anything else), ``choices`` (a tuple, empty if none)
    and ``readback`` (a setting's query, e.g. ``FRS?``; None for actions and queries).
    """
    out: dict[str, dict] = {}
    for c in COMMANDS:
        arg = c.argument
        out[c.mnemonic] = {
            "kind": c.kind,
            "source": c.source,
            "argument": arg.kind if arg is not None else None,
            "dimension": arg.dimension if arg is not None and arg.kind == "quantity" else None,
            "choices": tuple(arg.choices) if arg is not None else (),
            "readback": c.mnemonic + "?" if c.kind == "setting" else None,
        }
    return out
