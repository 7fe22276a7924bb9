"""The driver's command table (drivers/commands.py) and the simulator's
(sims/command_table.py) are written independently on purpose, so that a mistake in
one is caught by the other: they must name the same mnemonics with the same
grammar (kind, source, argument, dimension, choices, read-back query)."""

import pytest

from drivers import commands as driver_table
from sims import command_table as sim_table

KEYS = {"kind", "source", "argument", "dimension", "choices", "readback"}


def _grammars():
    if not hasattr(sim_table, "grammar"):
        pytest.fail("sims.command_table has no grammar() yet (issue 7, simulator side)")
    return driver_table.grammar(), sim_table.grammar()


def test_both_tables_describe_every_entry_with_the_same_keys():
    for name, table in zip(("driver", "simulator"), _grammars(), strict=True):
        for mnemonic, entry in table.items():
            assert set(entry) == KEYS, f"{name} {mnemonic}: keys {sorted(entry)}"
            assert isinstance(entry["choices"], tuple), f"{name} {mnemonic}: choices must be a tuple"


def test_both_tables_name_the_same_mnemonics():
    driver, sim = _grammars()
    assert sorted(set(driver) - set(sim)) == [], "only in the driver's table"
    assert sorted(set(sim) - set(driver)) == [], "only in the simulator's table"


def test_both_tables_give_each_mnemonic_the_same_grammar():
    driver, sim = _grammars()
    differences = {
        mnemonic: {
            key: (driver[mnemonic][key], sim[mnemonic][key])
            for key in KEYS
            if driver[mnemonic][key] != sim[mnemonic][key]
        }
        for mnemonic in sorted(set(driver) & set(sim))
    }
    assert {m: d for m, d in differences.items() if d} == {}, "(driver, simulator) per differing key"


def test_the_grammar_spells_what_the_documents_give():
    """Pinned from outside both tables: the 3562A-documented entries and the issue's
    vocabulary (kind, argument, dimension), so that both tables cannot drift together."""
    driver = driver_table.grammar()
    assert driver["FRS"] == {
        "kind": "setting",
        "source": "3562A",
        "argument": "quantity",
        "dimension": "frequency",
        "choices": (),
        "readback": "FRS?",
    }
    assert driver["TDLY"]["dimension"] == "time"
    assert driver["RNG1"]["dimension"] == "voltage"
    assert driver["WIN1"]["choices"] == ("UNIF", "HANN", "FLAT", "FORC", "EXPO")
    assert driver["TSRC"]["choices"] == ("CH1", "CH2", "FREE")
    assert driver["NAVG"]["argument"] == "integer"
    assert driver["C1AC"]["argument"] == "flag"
    assert driver["DDAN"]["kind"] == "query"
    assert driver["ID?"]["readback"] is None
    assert driver["STBL"] == {
        "kind": "action",
        "source": "3562A",
        "argument": None,
        "dimension": None,
        "choices": (),
        "readback": None,
    }
