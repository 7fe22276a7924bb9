"""sims.command_table.grammar(): the simulator's table in the shape the driver's
independent table is compared in (tests/test_command_tables_agree.py).

The expected entries are written here from the command set (docs/instrument.md):
which mnemonics public 3562A code uses, what each setting takes and in which unit
its query replies. They are not read back from the table, so that the table and
the grammar cannot drift together.
"""

from __future__ import annotations

import pytest

from sims.command_table import grammar
from tests.sims.wire import ask

CRLF = b"\r\n"
KEYS = {"kind", "source", "argument", "dimension", "choices", "readback"}

#: Seen in public code driving an HP 3562A; everything else is a project choice.
FROM_3562A = {
    "ID?", "RST", "LCL", "STRT", "PAUS", "CONT", "SMSD", "FRS", "NAVG", "STBL", "AVOF",
    "FRQR", "LNRS", "UNIF", "HANN", "FLAT", "AU1", "C1AC", "PSP1", "DDAN", "DDAS", "DSAN", "DSAS",
}  # fmt: skip
#: Settings: (argument, dimension, choices). A quantity's query replies in Hz, s or V.
SETTINGS = {
    "FRS": ("quantity", "frequency", ()),
    "CF": ("quantity", "frequency", ()),
    "NAVG": ("integer", None, ()),
    "PRVW": ("flag", None, ()),
    "WIN1": ("choice", None, ("UNIF", "HANN", "FLAT", "FORC", "EXPO")),
    "WIN2": ("choice", None, ("UNIF", "HANN", "FLAT", "FORC", "EXPO")),
    "FWD1": ("quantity", "time", ()),
    "FWD2": ("quantity", "time", ()),
    "EXD1": ("quantity", "time", ()),
    "EXD2": ("quantity", "time", ()),
    "RNG1": ("quantity", "voltage", ()),
    "RNG2": ("quantity", "voltage", ()),
    "C1AC": ("flag", None, ()),
    "C2AC": ("flag", None, ()),
    "SNS1": ("quantity", "voltage", ()),
    "SNS2": ("quantity", "voltage", ()),
    "TSRC": ("choice", None, ("CH1", "CH2", "FREE")),
    "TLVL": ("quantity", "voltage", ()),
    "TSLP": ("choice", None, ("POS", "NEG")),
    "TDLY": ("quantity", "time", ()),
}
ACTIONS = {
    "RST", "LCL", "STRT", "PAUS", "CONT", "ACPT", "RJCT", "STBL", "AVOF", "FRQR", "LNRS",
    "UNIF", "HANN", "FLAT", "AU1", "AU2", "TRCA", "TRCB", "TIM1", "TIM2", "LSP1", "LSP2",
    "PSP1", "PSP2", "FRSP", "COHR", "CLER",
}  # fmt: skip
QUERIES = {
    "ID?", "SMSD", "DISP?", "TRC?", "DDAN", "DDAS", "DSAN", "DSAS", "STA?", "ERR?", "OVLD?",
    "AVG?", "AVMD?", "AU1?", "AU2?",
}  # fmt: skip


def test_grammar_names_every_command_once_settings_without_their_question_mark():
    table = grammar()
    assert set(table) == set(SETTINGS) | ACTIONS | QUERIES
    for mnemonic, entry in table.items():
        assert set(entry) == KEYS, mnemonic


@pytest.mark.parametrize("mnemonic", sorted(SETTINGS))
def test_a_setting_gives_its_argument_dimension_choices_and_query(mnemonic):
    argument, dimension, choices = SETTINGS[mnemonic]
    assert grammar()[mnemonic] == {
        "kind": "setting",
        "source": "3562A" if mnemonic in FROM_3562A else "proj",
        "argument": argument,
        "dimension": dimension,
        "choices": choices,
        "readback": mnemonic + "?",
    }


@pytest.mark.parametrize("mnemonic", sorted(ACTIONS | QUERIES))
def test_actions_and_queries_take_nothing_and_have_no_readback(mnemonic):
    assert grammar()[mnemonic] == {
        "kind": "action" if mnemonic in ACTIONS else "query",
        "source": "3562A" if mnemonic in FROM_3562A else "proj",
        "argument": None,
        "dimension": None,
        "choices": (),
        "readback": None,
    }


# A value of each dimension with a non-SI suffix, and what the query must reply in SI
# (1.6 kHz is a span the analyzer offers, 102.4 kHz / 64; 100 mV is a range, -20 dBV).
SPOKEN = {"frequency": ("1.6 KHZ", 1600.0), "time": ("20 MS", 0.02), "voltage": ("100 MV", 0.1)}


@pytest.mark.parametrize("mnemonic", sorted(m for m, s in SETTINGS.items() if s[0] == "quantity"))
def test_the_analyzer_reads_each_quantity_in_its_dimension_and_replies_in_si(mnemonic, connect):
    """The grammar's dimension is the one the analyzer parses: a suffix of that
    dimension is taken (the reply in SI units), a frequency suffix elsewhere is error 4."""
    dimension = grammar()[mnemonic]["dimension"]
    text, si = SPOKEN[dimension]
    conn = connect()
    if mnemonic == "CF":  # at the preset 102.4 kHz span the center can only be 51.2 kHz
        ask(conn, "FRS 3.2 KHZ")
    reply = ask(conn, f"{mnemonic} {text};{grammar()[mnemonic]['readback']};ERR?")
    value, error = reply.split(CRLF)[:2]
    assert float(value) == pytest.approx(si, rel=1e-9), reply
    assert error == b'0,"No error"'
    if dimension != "frequency":
        assert ask(conn, f"{mnemonic} 1 HZ;ERR?").startswith(b"4,"), mnemonic
