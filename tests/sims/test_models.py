"""Every simulated model measures the same physics at its own geometry, through the same
faults, front ends and replay (docs/simulator.md, "Models").

Geometry expected here is written out from docs/instrument-scpi.md ("Record
geometry", "The HP 3562A dialect"), not taken from sims/models.py. The FRF
tolerance is the one tests/sims/test_physics.py holds the 35660A to: 1 % on every
line where |H| is above 1 % of its peak, against analysis.response's modal sum.
"""

from __future__ import annotations

import struct
import time

import numpy as np
import pytest
import serial

from analysis.response import frequency_response
from sims.inprocess import InProcessConnection
from sims.instrument import Analyzer
from sims.prologix import PrologixPty
from sims.scenarios import build_specimen
from sims.sources import PhysicsSource, RecordedHit, ReplaySource
from tests.sims.wire import ask, decode_trace

pytestmark = pytest.mark.timeout(60)


def physics(model: str, scenario: str = "seed", seed: int = 5, noise: bool = False) -> Analyzer:
    source = PhysicsSource(scenario, seed=seed)
    source.set_noise(noise)
    return Analyzer(source, model=model)


def scpi_block(data: bytes) -> np.ndarray:
    """The float64 values of a ``#<d><len>`` block ending with LF."""
    assert data[:1] == b"#", data[:16]
    digits = int(data[1:2])
    length = int(data[2 : 2 + digits])
    assert len(data) == 2 + digits + length + 1, (len(data), length)
    assert data.endswith(b"\n")
    return np.frombuffer(data[2 + digits : -1], dtype=">f8").astype(float)


def assert_frf_is_the_beam(scenario: str, f: np.ndarray, frf: np.ndarray) -> None:
    spec = build_specimen(scenario)
    h = frequency_response(spec.model, spec.damping, f, "acceleration")
    strong = np.abs(h) > 0.01 * np.abs(h).max()
    strong[f == 0] = False
    rel = np.abs(frf - h)[strong] / np.abs(h)[strong]
    assert rel.max() < 0.01, f"worst {rel.max():.4f} at {f[strong][np.argmax(rel)]:.4f} Hz"


# ------------------------------------------------------------------ physics per model
@pytest.mark.parametrize(
    ("span_hz", "center_hz"),
    [(100000 / 2**11, 100000 / 2**12), (100000 / 2**13, 36.0)],
    ids=["baseband", "zoom-mode2"],
)
def test_3562a_frf_equals_the_beam_at_800_lines(span_hz, center_hz):
    conn = InProcessConnection(physics("3562A"))
    record_s = 800 / span_hz
    setup = (
        f"FRS {span_hz} HZ;CF {center_hz} HZ;TSRC CH1;TLVL 2 MV;TDLY {-record_s / 32} S;UNIF;NAVG 2;STBL;"
        "RNG1 20 MV;RNG2 0.5 V;STRT"
    )
    assert ask(conn, setup + ";SMSD;ERR?") == b'1\r\n0,"No error"\r\n'
    conn.write(b"FRSP;DDAN\n")
    header, frf = decode_trace(conn.read(timeout_s=5.0))
    assert header[1] == 801
    assert header[3] == 2
    assert header[55] == span_hz / 800
    f = header[64] + np.arange(801) * header[55]
    assert f[0] == pytest.approx(center_hz - span_hz / 2)
    assert_frf_is_the_beam("seed", f, frf)
    conn.write(b"TIM1;DDAN\n")
    header, force = decode_trace(conn.read(timeout_s=5.0))
    zoom = center_hz > span_hz / 2
    assert force.size == (1024 if zoom else 2048)
    assert np.iscomplexobj(force) == zoom


@pytest.mark.parametrize(
    ("model", "lines", "span_hz", "center_hz", "scenario"),
    [
        ("35670A", 400, 50.0, 25.0, "seed"),
        ("35670A", 1600, 50.0, 25.0, "seed"),
        ("35670A", 100, 12.5, 6.25, "seed"),
        ("35670A", 800, 12.5, 6.25, "realistic"),
        ("35670A", 400, 12.5, 36.0, "seed"),
        ("35665A", 800, 12.5, 98.0, "realistic"),
    ],
    ids=["400", "1600", "100", "realistic-800", "zoom-400", "35665A-zoom-800"],
)
def test_scpi_frf_equals_the_beam_at_its_lines(model, lines, span_hz, center_hz, scenario):
    conn = InProcessConnection(physics(model, scenario))
    # The pre-trigger holds the spread the zero-phase filter gives the hammer pulse,
    # some 10 samples (docs/simulator.md): 1/32 of the record, or 16 samples if longer.
    pre_s = max(lines / span_hz / 32, 16 / (2.56 * span_hz))
    setup = (
        f"SENS:FREQ:RES {lines};SPAN {span_hz} HZ;CENT {center_hz} HZ;:TRIG:SOUR INT1;LEV 2 MV;"
        f"STAR1 {-pre_s} S;STAR2 {-pre_s} S;:SENS:WIND1:TYPE UNIF;:SENS:WIND2:TYPE UNIF;"
        ":SENS:AVER:STAT ON;COUN 2;:SENS:VOLT1:RANG 20 MV;:SENS:VOLT2:RANG 0.5 V;"
        ":FORM:DATA REAL,64;:CALC1:FORM NYQ;:INIT:IMM"
    )
    assert ask(conn, setup + ";:STAT:OPER:COND?;:SYST:ERR?") == b'256;+0,"No error"\n'
    conn.write(b"CALC1:DATA?\n")
    pairs = scpi_block(conn.read(timeout_s=5.0))
    conn.write(b"CALC1:X:DATA?\n")
    f = scpi_block(conn.read(timeout_s=5.0))
    assert pairs.size == 2 * (lines + 1)
    assert f.size == lines + 1
    assert f[1] - f[0] == pytest.approx(span_hz / lines)
    assert f[0] == pytest.approx(center_hz - span_hz / 2)
    assert_frf_is_the_beam(scenario, f, pairs[0::2] + 1j * pairs[1::2])
    zoom = center_hz > span_hz / 2
    assert ask(conn, "CALC3:DATA:HEAD:POIN?") == f"{int(2.56 * lines) // (2 if zoom else 1)}\n".encode()


def test_the_35670a_records_16_bits_at_its_top_span():
    """The ADC quantisation follows the model's top span: 16 bits exactly at 51.2 kHz."""
    conn = InProcessConnection(physics("35670A", noise=True, seed=1))
    setup = (
        "SENS:FREQ:SPAN 51.2 KHZ;:SENS:VOLT1:RANG -23;:SENS:VOLT2:RANG -3;:FORM:DATA REAL,64;"
        ":CALC3:FEED 'XTIM:VOLT 1';:CALC4:FEED 'XTIM:VOLT 2';:INIT:IMM"
    )
    ask(conn, setup)
    for trace, sens, db in ((3, 2.25e-3, -23), (4, 1.02e-3, -3)):
        conn.write(f"CALC{trace}:DATA?\n".encode())
        values = scpi_block(conn.read(timeout_s=5.0))
        rng = 10 ** (db / 20) * np.sqrt(2)
        codes = values * sens / (rng / 32768)
        np.testing.assert_allclose(codes, np.round(codes), atol=1e-6)
        assert np.unique(np.round(codes)).size > 2


# ------------------------------------------------------------------ replay and faults
def _hits(n_samples: int, rate_hz: float, count: int = 2) -> list[RecordedHit]:
    rng = np.random.default_rng(n_samples)
    return [
        RecordedHit(rng.normal(size=n_samples), rng.normal(size=n_samples), rate_hz) for _ in range(count)
    ]


def test_a_1024_sample_replay_into_a_3562a_is_refused_at_once():
    with pytest.raises(ValueError, match=r"2048-sample real channels \(the 3562A records 2048\)"):
        ReplaySource(_hits(1024, 512.0), model="3562A")
    ReplaySource(_hits(2048, 500.0), model="3562A")  # its own length is fine


def test_a_35670a_replays_a_recording_once_its_lines_match():
    hits = _hits(1024, 512.0)
    conn = InProcessConnection(Analyzer(ReplaySource(hits, model="35670A"), model="35670A"))
    assert ask(conn, "SENS:FREQ:SPAN 200 HZ;RES 800;:INIT:IMM;:STAT:OPER:COND?") == b"0\n"
    assert ask(conn, "SYST:ERR?") == (
        b'-221,"Settings conflict; replay holds 1024-sample records, '
        b'the analyzer records 2048: set 400 lines"\n'
    )
    assert ask(conn, "SENS:FREQ:RES 400;:INIT:IMM;:STAT:OPER:COND?;:SYST:ERR?") == b'256;+0,"No error"\n'
    conn.write(b"FORM:DATA REAL,64;:CALC3:DATA?\n")
    assert (
        scpi_block(conn.read(timeout_s=2.0)).tobytes()
        == hits[0].force_n.astype(">f8").astype(float).tobytes()
    )


def test_a_recording_of_the_35670a_geometry_replays_into_it():
    hits = _hits(4096, 128.0)  # 1600 lines at 50 Hz
    conn = InProcessConnection(Analyzer(ReplaySource(hits, model="35670A"), model="35670A"))
    assert ask(conn, "SENS:FREQ:RES 1600;SPAN 50 HZ;:INIT:IMM;:STAT:OPER:COND?") == b"256\n"


def test_replay_refuses_sim_physics_controls_on_scpi():
    conn = InProcessConnection(Analyzer(ReplaySource(_hits(1024, 512.0), model="35670A"), model="35670A"))
    assert ask(conn, "SIM:SEED 3;SYST:ERR?") == (
        b'-224,"Illegal parameter value; SIM:SEED needs the physics source, not a replay"\n'
    )


def test_faults_act_on_scpi_transfers_and_init():
    analyzer = physics("35670A")
    conn = InProcessConnection(analyzer, faults=("truncate,keep=0.5",))
    ask(conn, "SENS:FREQ:SPAN 200 HZ;:TRIG:SOUR INT1;LEV 2 MV;:FORM:DATA REAL,64;:INIT:IMM")
    conn.write(b"CALC3:DATA?\n")
    data = conn.read(timeout_s=1.0)
    assert data.startswith(b"#48192")
    assert len(data) == (6 + 8192 + 1) // 2
    # no_hit fires on INIT: the analyzer waits for a trigger that never comes.
    conn = InProcessConnection(analyzer, faults=("no_hit",))
    assert ask(conn, "ABOR;INIT:IMM;:STAT:OPER:COND?") == b"48\n"
    assert ask(conn, "SIM:FAULT?") == b"NONE\n"  # the one no_hit is spent
    conn.write(b"*OPC?\n")
    with pytest.raises(TimeoutError):
        conn.read(timeout_s=0.2)


def test_slow_fault_holds_scpi_replies():
    conn = InProcessConnection(physics("35670A"), faults=("slow,delay=0.2",))
    t0 = time.monotonic()
    assert ask(conn, "*IDN?") == b""
    assert conn.read(timeout_s=2.0).startswith(b"HEWLETT-PACKARD,35670A")
    assert time.monotonic() - t0 >= 0.19


# ------------------------------------------------------------------ the Prologix pty
def _read_until(port: serial.Serial, end: bytes, timeout: float = 5.0) -> bytes:
    port.timeout = timeout
    data = port.read_until(end)
    assert data.endswith(end), data
    return data


def test_scpi_through_the_prologix_pty():
    with PrologixPty(physics("35670A"), 11) as pty:
        port = serial.Serial(pty.port, baudrate=115200, timeout=3)
        try:
            port.write(b"++mode 1\n++addr 11\n++auto 0\n++eoi 1\n++eos 2\n")
            port.write(b"*IDN?\n++read eoi\n")
            assert _read_until(port, b"\n") == b"HEWLETT-PACKARD,35670A,0000A00000,A.00.00\n"
            port.write(b"SENS:FREQ:SPAN 200 HZ;:TRIG:SOUR INT1;LEV 2 MV;:FORM:DATA REAL,64;:INIT:IMM\n")
            port.write(b"*OPC?\n++read eoi\n")
            assert _read_until(port, b"\n") == b"1\n"
            port.write(b"CALC3:DATA?\n++read eoi\n")
            head = port.read(6)
            assert head == b"#48192"
            payload = port.read(8192 + 1)
            assert len(payload) == 8193
            assert payload.endswith(b"\n")
            assert struct.unpack(">d", payload[:8])[0] == pytest.approx(pty.analyzer.last_record.force_n[0])
            port.write(b"FOO\n++spoll\n")
            assert _read_until(port, b"\r\n") == b"4\r\n"  # the SCPI status byte: an error queued
        finally:
            port.close()


def test_every_model_speaks_only_its_own_identify():
    replies = {}
    for model in ("35660A", "3562A", "35670A", "35665A"):
        conn = InProcessConnection(physics(model))
        replies[model] = (ask(conn, "ID?"), ask(conn, "*IDN?"))
    assert replies == {
        "35660A": (b"HP35660A\r\n", b""),
        "3562A": (b"HP3562A\r\n", b""),
        "35670A": (b"", b"HEWLETT-PACKARD,35670A,0000A00000,A.00.00\n"),
        "35665A": (b"", b"HEWLETT-PACKARD,35665A,0000A00000,A.00.00\n"),
    }
