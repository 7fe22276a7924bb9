"""The simulated 35670A as a plain pyvisa client sees it over TCP: the documented SCPI
(docs/instrument-scpi.md) and nothing of the project's code on the client side.

A whole frequency-response measurement: configure, ``ABOR;INIT:IMM``, poll
``STAT:OPER:COND?`` until done (bit 8), then the FRF, the coherence, the x axis and
the two time records, fetched with ``query_binary_values`` as big-endian float64.
Expectations come from the documented formats and from the data themselves (the
FRF is H1 of the time records the same instrument serves).
"""

from __future__ import annotations

import time

import numpy as np
import pytest
import pyvisa

from sims.instrument import Analyzer
from sims.sources import PhysicsSource
from sims.tcp_server import TcpServer

pytestmark = pytest.mark.timeout(60)

OPER_MEASURING, OPER_WAITING, OPER_DONE, OPER_PENDING = 16, 32, 256, 512  # docs/instrument-scpi.md


@pytest.fixture
def server():
    source = PhysicsSource("seed", seed=3)
    source.set_noise(True)
    # A little real time, so that *OPC? and the status bits are seen waiting.
    analyzer = Analyzer(source, time_scale=0.02, model="35670A")
    with TcpServer(analyzer) as srv:
        srv.analyzer = analyzer  # type: ignore[attr-defined]
        yield srv


@pytest.fixture
def inst(server):
    rm = pyvisa.ResourceManager("@py")
    try:
        resource = rm.open_resource(
            server.resource, read_termination="\n", write_termination="\n", timeout=20000
        )
        try:
            yield resource
        finally:
            resource.close()
    finally:
        rm.close()


def configure(inst, lines: int = 400, averages: int = 3) -> None:
    for command in (
        "*RST",
        "*CLS",
        "FORM:DATA REAL,64",
        "SENS:FREQ:SPAN 200 HZ",
        f"SENS:FREQ:RES {lines}",
        "SENS:AVER:STAT ON",
        f"SENS:AVER:COUN {averages}",
        "SENS:AVER:TYPE RMS",
        "SENS:AVER:TCON FREE",
        "SENS:WIND1:TYPE FORC",
        "SENS:WIND1:FORC 0.125 S",
        "SENS:WIND2:TYPE EXP",
        "SENS:WIND2:EXP 0.5 S",
        "INP1:COUP DC",
        "INP2:COUP DC",
        "SENS:VOLT1:RANG 0.02 V",
        "SENS:VOLT2:RANG 1 V",
        "SENS:VOLT1:RANG:UNIT:XDCR:SFAC 0.00225",
        "SENS:VOLT2:RANG:UNIT:XDCR:SFAC 0.00102",
        "SENS:VOLT1:RANG:UNIT:XDCR:LAB N",
        "SENS:VOLT2:RANG:UNIT:XDCR:LAB M/S2",
        "SENS:VOLT1:RANG:UNIT:XDCR ON",
        "SENS:VOLT2:RANG:UNIT:XDCR ON",
        "TRIG:SOUR INT1",
        "TRIG:LEV 0.00225 V",
        "TRIG:SLOP POS",
        "TRIG:STAR1 -0.0625 S",
        "TRIG:STAR2 -0.0625 S",
        "CALC1:FEED 'XFR:POW:RAT 2,1'",
        "CALC1:FORM NYQ",
        "CALC2:FEED 'XFR:POW:COH 1,2'",
        "CALC2:FORM REAL",
        "CALC3:FEED 'XTIM:VOLT 1'",
        "CALC3:FORM REAL",
        "CALC4:FEED 'XTIM:VOLT 2'",
        "CALC4:FORM REAL",
    ):
        inst.write(command)
    assert inst.query("SYST:ERR?") == '+0,"No error"'


def fetch(inst, command: str) -> np.ndarray:
    return np.array(inst.query_binary_values(command, datatype="d", is_big_endian=True))


def test_a_whole_frf_measurement_with_plain_pyvisa(inst, server):
    assert inst.query("*IDN?") == "HEWLETT-PACKARD,35670A,0000A00000,A.00.00"
    configure(inst)
    inst.write("ABOR;INIT:IMM")
    deadline = time.monotonic() + 30
    while True:
        condition = int(inst.query("STAT:OPER:COND?"))
        if condition & OPER_DONE:
            break
        assert condition & OPER_MEASURING
        assert time.monotonic() < deadline, condition
        time.sleep(0.005)
    # The event register latched what the measurement went through, however fast:
    # waiting for the trigger, measuring, done.
    events = int(inst.query("STAT:OPER?"))
    assert events & (OPER_WAITING | OPER_MEASURING | OPER_DONE) == OPER_WAITING | OPER_MEASURING | OPER_DONE
    assert inst.query("STAT:OPER?") == "0"  # read and cleared
    assert int(inst.query("SENS:AVER:COUN:INT?")) == 3
    assert inst.query("STAT:QUES:VOLT:COND?") == "0"
    assert int(inst.query("*STB?")) & 4 == 0  # no error queued

    assert inst.query("CALC1:DATA:HEAD:POIN?") == "401"
    pairs = fetch(inst, "CALC1:DATA?")
    assert pairs.size == 802
    frf = pairs[0::2] + 1j * pairs[1::2]
    coherence = fetch(inst, "CALC2:DATA?")
    freq = fetch(inst, "CALC1:X:DATA?")
    force = fetch(inst, "CALC3:DATA?")
    accel = fetch(inst, "CALC4:DATA?")
    t = fetch(inst, "CALC3:X:DATA?")
    assert coherence.shape == freq.shape == (401,)
    np.testing.assert_array_equal(freq, np.arange(401) * 0.5)
    assert force.shape == accel.shape == t.shape == (1024,)
    np.testing.assert_allclose(np.diff(t), 1 / 512.0)
    assert t[0] == pytest.approx(-0.0625)
    assert np.all((coherence >= 0) & (coherence <= 1 + 1e-12))
    # The force is the hammer's pulse, in newtons, a few N at the trigger.
    assert 1.0 < force.max() < 20.0
    assert abs(t[np.argmax(force)]) < 0.01
    # The time records are the last hit's, bit for bit.
    record = server.analyzer.last_record
    assert force.tobytes() == np.asarray(record.force_n, dtype=float).tobytes()
    # Resonances of the seed beam (5.59, 36.1 Hz) show as FRF peaks.
    peak = freq[1:][np.argmax(np.abs(frf[1:]))]
    assert abs(peak - 5.59) < 1.0 or abs(peak - 36.09) < 1.0


def test_opc_query_answers_when_the_measurement_is_done(inst):
    configure(inst, lines=200, averages=2)
    inst.write("ABOR;INIT:IMM")
    assert inst.query("*OPC?") == "1"  # only once every average is in
    assert int(inst.query("STAT:OPER:COND?")) == OPER_DONE
    assert inst.query("SENS:AVER:COUN:INT?") == "2"
    assert fetch(inst, "CALC1:DATA?").size == 2 * 201
    assert fetch(inst, "CALC3:DATA?").size == 512


def test_preview_accept_and_reject_over_pyvisa(inst):
    configure(inst, averages=2)
    inst.write("SENS:AVER:PREV MAN")
    inst.write("ABOR;INIT:IMM")
    decisions = []
    while not int(inst.query("STAT:OPER:COND?")) & OPER_DONE:
        if int(inst.query("STAT:OPER:COND?")) & OPER_PENDING:
            # Reject the first hit, accept the others.
            inst.write("SENS:AVER:PREV:REJ" if not decisions else "SENS:AVER:PREV:ACC")
            decisions.append(len(decisions))
        time.sleep(0.005)
    assert len(decisions) == 3
    assert inst.query("SENS:AVER:COUN:INT?") == "2"
    assert inst.query("SYST:ERR?") == '+0,"No error"'


def test_ascii_and_float32_transfers_carry_the_same_record(inst):
    configure(inst, averages=1)
    inst.write("ABOR;INIT:IMM")
    assert inst.query("*OPC?") == "1"
    as_float64 = fetch(inst, "CALC3:DATA?")
    inst.write("FORM:DATA ASC")
    assert inst.query("FORM:DATA?") == "ASC,0"
    as_ascii = np.array(inst.query_ascii_values("CALC3:DATA?"))
    np.testing.assert_array_equal(as_ascii, as_float64)
    inst.write("FORM:DATA REAL,32")
    as_float32 = np.array(inst.query_binary_values("CALC3:DATA?", datatype="f", is_big_endian=True))
    np.testing.assert_array_equal(as_float32, as_float64.astype(np.float32))
