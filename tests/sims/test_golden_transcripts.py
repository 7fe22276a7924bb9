"""Golden request -> reply transcripts of every simulated model, byte for byte: one
harness over the dialects.

The goldens are written by hand from the documentation, never read back from the
simulator: tests/sims/goldens/mnemonic.py (the HP 35660A and HP 3562A, mnemonic
dialect, docs/instrument.md) and tests/sims/goldens/scpi.py (the HP 35670A and 35665A,
SCPI, docs/instrument-scpi.md). Here each one is played on a fresh in-process
analyzer, with a fake clock where the golden gives times.

``test_goldens_cover_every_command`` fails when a command is added to a model's
table without a golden; ``test_error_goldens_cover_every_error_code`` likewise for
error codes.
"""

from __future__ import annotations

import struct

import numpy as np
import pytest

from sims.command_table import commands_for
from tests.sims.goldens.common import Dialect, Exchange, FakeClock
from tests.sims.goldens.mnemonic import HP3562A, HP35660A, SPAN_3562A
from tests.sims.goldens.scpi import HP35670A, IDN, SPAN200, reply
from tests.sims.wire import ask, decode_trace

pytestmark = pytest.mark.timeout(10)

DIALECTS = (HP35660A, HP3562A, HP35670A)


def _cases(attr: str, tag: str):
    return [
        pytest.param(dialect, gold, id=f"{dialect.model}-{i:03d}-{tag(gold)}")
        for dialect in DIALECTS
        for i, gold in enumerate(getattr(dialect, attr))
    ]


def play(conn, clock: FakeClock, exchanges: tuple[Exchange, ...]) -> None:
    """Each request in turn (the clock set first where a time is given); its reply must
    be exactly the expected bytes, or pass the expected check."""
    for at, request, expected in exchanges:
        if at is not None:
            clock.now = at
        got = ask(conn, request)
        if callable(expected):
            assert expected(got), (at, request, got[:80])
        else:
            assert got == expected, (at, request)


@pytest.mark.parametrize(("dialect", "golden"), _cases("goldens", lambda gold: gold.covers))
def test_golden_transcript(dialect: Dialect, golden, connect):
    clock = FakeClock()
    play(connect(dialect.make_bench(golden.bench, clock)), clock, golden.exchanges)


@pytest.mark.parametrize(("dialect", "golden"), _cases("error_goldens", lambda gold: f"code{gold.code}"))
def test_error_transcript(dialect: Dialect, golden, connect):
    clock = FakeClock()
    play(connect(dialect.make_bench("physics", clock)), clock, golden.exchanges)


@pytest.mark.parametrize("dialect", DIALECTS, ids=lambda d: d.model)
def test_goldens_cover_every_command(dialect: Dialect):
    covered = {gold.covers for gold in dialect.goldens}
    assert dialect.required - covered == set(), "commands without a golden transcript"
    # ... and every golden really sends what it claims to cover.
    for gold in dialect.goldens:
        assert dialect.sends_what_it_covers(gold), gold


@pytest.mark.parametrize("dialect", DIALECTS, ids=lambda d: d.model)
def test_error_goldens_cover_every_error_code(dialect: Dialect):
    assert {gold.code for gold in dialect.error_goldens} == dialect.error_codes
    for gold in dialect.error_goldens:
        assert dialect.error_message_in_reply(gold), gold


# --------------------------------------------------------------------------- one model's own
def test_3562a_documents_its_identity():
    assert [c.doc for c in commands_for("3562A") if c.mnemonic == "ID?"] == ["identify: replies HP3562A"]


def test_3562a_frequency_response_dump_holds_801_lines(connect):
    """Header words of an FRSP dump at 195.3125 Hz and 800 lines; the FRF of two impulses
    (2 N at sample 1, 3 m/s^2 at sample 5, uniform windows) is 1.5 exp(-2 pi j k 4 / 2048)."""
    conn = connect(HP3562A.make_bench("delta", FakeClock()))
    conn.write(f"{SPAN_3562A};UNIF;STRT;FRSP;DDAN\n".encode())
    raw = conn.read(timeout_s=1.0)
    assert raw[:4] == b"#A" + struct.pack(">H", (66 + 2 * 801) * 8)
    header, frf = decode_trace(raw)
    expected_words = {
        0: 1,
        1: 801,
        2: 801,
        3: 1,
        4: 3,
        5: 0,
        7: 1,
        9: 3,
        10: 1,
        36: 0,
        40: 1,
        52: 250.0,
        53: 250.0,
    }
    for word, value in expected_words.items():
        assert header[word] == value, word
    assert header[55] == 195.3125 / 800
    assert header[64] == 0.0
    k = np.arange(801)
    np.testing.assert_allclose(frf, 1.5 * np.exp(-2j * np.pi * k * 4 / 2048), rtol=0, atol=1e-12)


def test_35670a_hardware_fault_holds_until_rst(connect):
    conn = connect(HP35670A.make_bench("delta", FakeClock()))
    assert ask(conn, "SIM:FAULT error;*STB?") == reply("4")
    assert ask(conn, f"{SPAN200};:INIT:IMM;:STAT:OPER:COND?;:SYST:ERR?;:SYST:ERR?") == reply(
        "0",
        '-240,"Hardware error; input A/D converter does not respond"',
        '-240,"Hardware error; input A/D converter does not respond"',
    )
    assert ask(conn, f"*RST;{SPAN200};:INIT:IMM;:STAT:OPER:COND?;:SYST:ERR?") == reply("256", '+0,"No error"')


def test_35670a_sim_controls_answer_with_lf(connect):
    conn = connect(HP35670A.make_bench("physics", FakeClock()))
    assert ask(conn, "SIM:FAULT?") == b"NONE\n"
    assert ask(conn, "*IDN?;SIM:SCEN?;*OPC?") == IDN + b"seed\n" + reply("1")
