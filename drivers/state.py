"""The instrument state the analyzer dumps (DSAN, DSAS): 96 float64 values.

The 3562A family documents the size of the state dump, not what its 96 values
mean. Where our settings sit in it is a project choice (proj, docs/instrument.md),
to be confirmed on a real 35660A: STATE_WORDS below. Every other word is
undocumented: the simulator sends 0 there, and the driver keeps whatever comes
as a raw value (``InstrumentState.values``) without reading meaning into it.

How a placed word encodes its setting follows the command table entry it names
(drivers/commands.py): a quantity in SI units, an integer, a flag 0/1, a choice
as the index of the word among the entry's choices (WIN1: 0 UNIF, 1 HANN, 2 FLAT,
3 FORC, 4 EXPO; TRC?: 0 A, 1 B) unless CHOICE_CODES gives the codes (TSRC: 0 FREE,
1 CH1, 2 CH2; TSLP: 1 POS, -1 NEG; AVMD?: 1 STBL, 0 AVOF), and a trace's display
function as its documented display-function code (drivers/trace.py: 1 FRSP ... 9
LSP2).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drivers.commands import COMMANDS
from drivers.errors import ProtocolError
from drivers.trace import DISPLAY_CODES

STATE_LENGTH = 96

#: Choice words whose codes are not the index among the table's choices (proj).
CHOICE_CODES: dict[str, dict[int, str]] = {
    "TSRC": {0: "FREE", 1: "CH1", 2: "CH2"},
    "TSLP": {1: "POS", -1: "NEG"},
    "AVMD?": {1: "STBL", 0: "AVOF"},
}

#: (word, field of InstrumentState, the table entry that types it), proj.
STATE_WORDS: tuple[tuple[int, str, str], ...] = (
    (0, "span_hz", "FRS"),
    (1, "center_hz", "CF"),
    (2, "n_averages", "NAVG"),
    (3, "averaging", "AVMD?"),
    (4, "preview", "PRVW"),
    (5, "window1", "WIN1"),
    (6, "window2", "WIN2"),
    (7, "force_width1_s", "FWD1"),
    (8, "force_width2_s", "FWD2"),
    (9, "exp_decay1_s", "EXD1"),
    (10, "exp_decay2_s", "EXD2"),
    (11, "range1_v", "RNG1"),
    (12, "range2_v", "RNG2"),
    (13, "autorange1", "AU1?"),
    (14, "autorange2", "AU2?"),
    (15, "ac_coupled1", "C1AC"),
    (16, "ac_coupled2", "C2AC"),
    (17, "sensitivity1_v_per_eu", "SNS1"),
    (18, "sensitivity2_v_per_eu", "SNS2"),
    (19, "trigger_source", "TSRC"),
    (20, "trigger_level_v", "TLVL"),
    (21, "trigger_slope", "TSLP"),
    (22, "trigger_delay_s", "TDLY"),
    (23, "active_trace", "TRC?"),
    (24, "display_a", "DISP?"),
    (25, "display_b", "DISP?"),
)


@dataclass(frozen=True)
class InstrumentState:
    """A decoded state dump. Units SI: Hz, s, V; sensitivities V per N (channel 1)
    and V per m/s^2 (channel 2). ``values``: all 96 words as dumped."""

    values: np.ndarray
    span_hz: float
    center_hz: float
    n_averages: int
    averaging: str
    preview: bool
    window1: str
    window2: str
    force_width1_s: float
    force_width2_s: float
    exp_decay1_s: float
    exp_decay2_s: float
    range1_v: float
    range2_v: float
    autorange1: bool
    autorange2: bool
    ac_coupled1: bool
    ac_coupled2: bool
    sensitivity1_v_per_eu: float
    sensitivity2_v_per_eu: float
    trigger_source: str
    trigger_level_v: float
    trigger_slope: str
    trigger_delay_s: float
    active_trace: str
    display_a: str
    display_b: str

    @classmethod
    def decode(cls, values: np.ndarray, command: str) -> InstrumentState:
        if values.shape != (STATE_LENGTH,):
            raise ProtocolError(command, f"a state dump holds {STATE_LENGTH} values, got {values.size}")
        fields = {name: _word(values[word], word, mnemonic, command) for word, name, mnemonic in STATE_WORDS}
        return cls(values=values.copy(), **fields)


def _word(value: float, word: int, mnemonic: str, command: str) -> float | int | bool | str:
    entry = COMMANDS[mnemonic] if mnemonic in COMMANDS else COMMANDS[mnemonic[:-1]]
    if entry.reply == "number":
        return float(value)
    if entry.reply == "flag" and value in (0.0, 1.0):
        return bool(value)
    if entry.reply == "integer" and value == int(value):
        return int(value)
    if entry.reply == "choice":
        table = (
            DISPLAY_CODES
            if mnemonic == "DISP?"
            else CHOICE_CODES.get(mnemonic, dict(enumerate(entry.reply_choices)))
        )
        if value == int(value) and int(value) in table:
            return table[int(value)]
    raise ProtocolError(command, f"state word {word} ({mnemonic}, {entry.reply}) holds {value!r}")
