"""The driver's command table for the HP 35660A (DESIGN.md section 4), in one place.

No public copy of the 35660A programming manual exists, so the driver speaks the
mnemonic dialect of its documented sibling, the HP 3562A. Every entry names its
source so that a technician with the real manual can correct this table alone:

* ``3562A``: seen in public code driving an HP 3562A;
* ``proj``: a project choice where no source was found, to be confirmed on a real
  35660A (per-channel windows, ranges, sensitivities, trigger, preview, queries).

The simulator keeps an independent copy (sims/command_table.py); golden byte
transcripts in the tests pin both to the same bytes.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Mnemonic:
    text: str
    source: str
    meaning: str
    #: Safe to send again after a failed transfer (a setting, a query); False for
    #: commands whose repetition changes the outcome (ACPT, RJCT).
    idempotent: bool = True
    #: What the instrument sends back: nothing, one line, many lines or an #A block.
    reply: str = "none"


def _m(text: str, source: str, meaning: str, idempotent: bool = True) -> Mnemonic:
    reply = "line" if text.endswith("?") or text == "SMSD" else "none"
    return Mnemonic(text, source, meaning, idempotent, reply)


COMMANDS: dict[str, Mnemonic] = {
    m.text: m
    for m in (
        _m("ID?", "3562A", "identify; the 35660A replies HP35660A"),
        _m("RST", "3562A", "preset"),
        _m("LCL", "3562A", "go to local"),
        _m("STRT", "3562A", "start a measurement (clears the average, arms)"),
        _m("PAUS", "3562A", "pause"),
        _m("CONT", "3562A", "continue"),
        _m("SMSD", "3562A", "measurement done? 1 or 0"),
        _m("ACPT", "proj", "preview: accept the pending hit", idempotent=False),
        _m("RJCT", "proj", "preview: reject the pending hit", idempotent=False),
        _m("FRS", "3562A", "frequency span, e.g. FRS 200 HZ"),
        _m("CF", "proj", "center frequency (span/2 = baseband)"),
        _m("NAVG", "3562A", "number of averages"),
        _m("STBL", "3562A", "stable (mean) averaging"),
        _m("AVOF", "3562A", "averaging off"),
        _m("PRVW", "proj", "hit preview on/off"),
        _m("FRQR", "3562A", "frequency response measurement"),
        _m("LNRS", "3562A", "linear resolution"),
        _m("UNIF", "3562A", "uniform window, both channels"),
        _m("HANN", "3562A", "Hanning window, both channels"),
        _m("FLAT", "3562A", "flat top window, both channels"),
        _m("WIN1", "proj", "channel 1 window: UNIF HANN FLAT FORC EXPO"),
        _m("WIN2", "proj", "channel 2 window"),
        _m("FWD1", "proj", "channel 1 force window width"),
        _m("FWD2", "proj", "channel 2 force window width"),
        _m("EXD1", "proj", "channel 1 exponential window time constant"),
        _m("EXD2", "proj", "channel 2 exponential window time constant"),
        _m("RNG1", "proj", "channel 1 input range, V peak"),
        _m("RNG2", "proj", "channel 2 input range, V peak"),
        _m("AU1", "3562A", "autorange channel 1"),
        _m("AU2", "proj", "autorange channel 2"),
        _m("C1AC", "3562A", "channel 1 AC (1) or DC (0) coupling"),
        _m("C2AC", "proj", "channel 2 AC (1) or DC (0) coupling"),
        _m("SNS1", "proj", "channel 1 sensitivity, V per N"),
        _m("SNS2", "proj", "channel 2 sensitivity, V per m/s^2"),
        _m("TSRC", "proj", "trigger source: CH1 CH2 FREE"),
        _m("TLVL", "proj", "trigger level, V"),
        _m("TSLP", "proj", "trigger slope: POS NEG"),
        _m("TDLY", "proj", "trigger delay, negative = pre-trigger"),
        _m("TRCA", "proj", "trace A active"),
        _m("TRCB", "proj", "trace B active"),
        _m("TIM1", "proj", "display: channel 1 time record"),
        _m("TIM2", "proj", "display: channel 2 time record"),
        _m("LSP1", "proj", "display: channel 1 linear spectrum"),
        _m("LSP2", "proj", "display: channel 2 linear spectrum"),
        _m("PSP1", "3562A", "display: channel 1 power spectrum"),
        _m("PSP2", "proj", "display: channel 2 power spectrum"),
        _m("FRSP", "proj", "display: frequency response ch2/ch1"),
        _m("COHR", "proj", "display: coherence"),
        _m("DISP?", "proj", "display function of the active trace"),
        _m("TRC?", "proj", "active trace"),
        Mnemonic("DDAN", "3562A", "dump the active trace, binary #A block", reply="block"),
        Mnemonic("DDAS", "3562A", "dump the active trace, ASCII, one value per line", reply="lines"),
        Mnemonic("DSAN", "3562A", "dump the state, binary #A block", reply="block"),
        Mnemonic("DSAS", "3562A", "dump the state, one ASCII line", reply="line"),
        _m("STA?", "proj", "status bits"),
        _m("ERR?", "proj", 'oldest error: code,"message"'),
        _m("CLER", "proj", "clear the error queue"),
        _m("OVLD?", "proj", "overload of the last record: ch1,ch2"),
        _m("AVG?", "proj", "hits in the average"),
        _m("AVMD?", "proj", "averaging mode: STBL or AVOF"),
        _m("AU1?", "proj", "autorange of channel 1 on (1) or off (0)"),
        _m("AU2?", "proj", "autorange of channel 2 on (1) or off (0)"),
    )
}

#: STA? bits (proj).
STATUS_BITS = {
    "done": 1,
    "waiting_for_trigger": 2,
    "overload_ch1": 4,
    "overload_ch2": 8,
    "error": 16,
    "hit_pending": 32,
    "measuring": 64,
    "paused": 128,
}

#: Display-function codes in header word 0, y-unit codes in word 9, x-unit codes in word 10 (proj).
DISPLAY_CODES = {1: "TIM1", 2: "TIM2", 3: "LSP1", 4: "LSP2", 5: "PSP1", 6: "PSP2", 7: "FRSP", 8: "COHR"}
Y_UNITS = {0: "V", 1: "N", 2: "m/s^2", 3: "(m/s^2)/N", 4: "", 5: "N^2", 6: "(m/s^2)^2"}
X_UNITS = {0: "s", 1: "Hz"}

UNIT_SUFFIX = {"frequency": "HZ", "time": "S", "voltage": "V"}


def number(value: float) -> str:
    """A numeric argument: enough digits to round-trip what the instrument resolves."""
    text = f"{float(value):.12g}"
    return text


def command(mnemonic: str, *args: object) -> bytes:
    """``command("FRS", 200.0, "HZ")`` -> b"FRS 200 HZ"; the mnemonic must be in the table."""
    base = mnemonic[:-1] if mnemonic.endswith("?") and mnemonic not in COMMANDS else mnemonic
    if base not in COMMANDS:
        raise KeyError(f"{mnemonic} is not in the driver's command table")
    parts = [mnemonic]
    for arg in args:
        parts.append(number(arg) if isinstance(arg, float) else str(arg))
    return " ".join(parts).encode("ascii")


def replies(text: str) -> list[str]:
    """The reply kind of each command in a message that answers (``FRS?`` -> line).

    A setting's query form (``FRS?``) answers a line; a mnemonic the table does
    not know is taken to answer a line if it ends with ``?``.
    """
    kinds = []
    for part in text.split(";"):
        head = part.strip().split(" ")[0].upper()
        if not head:
            continue
        entry = COMMANDS.get(head)
        kind = entry.reply if entry is not None else ("line" if head.endswith("?") else "none")
        if kind != "none":
            kinds.append(kind)
    return kinds
