"""The driver of each dialect against every fault of the simulator's menu (sims/faults.py:
slow, no_hit, truncate, garbage, drop, error), over TCP (pyvisa-py socket) and over the
Prologix pty, with each model simulated (35660A and 3562A: HP mnemonic, 35670A: SCPI):
each ends in a bounded retry that succeeds with the right data (bit for bit what the
simulated analyzer holds) or in a clear DriverError subclass, never in a hang and never
in wrong data.

Where faults live: a TcpServer arms its ``faults=[...]`` on every new connection,
and the TCP driver reconnects to recover, so a one-shot fault (count=1) is armed
in-band on the current connection (``SIM:FAULT ...``) and a lasting one on the
server. The pty has one session for its life: in-band and server-wide are the same.

The measurement behind the fetched traces is made on the analyzer directly, so
that a fault armed for every reply cannot stop the set-up; the driver only fetches.
What differs between the dialects is a parameter (``Dialect`` below).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np
import pytest

from drivers.errors import DriverError, InstrumentError, InstrumentTimeout, ProtocolError
from drivers.family import open_analyzer
from drivers.hp_mnemonic import HPMnemonicAnalyzer
from drivers.scpi_analyzer import ScpiAnalyzer
from drivers.settings import ImpactSettings
from sims.instrument import Analyzer
from sims.units import format_number
from tests.drivers.fault_bench import TRANSPORTS, Bench, bench_factory, outcome_of, recoveries


@dataclass(frozen=True)
class Dialect:
    """What the fault tests expect of one model (docs/dialects.md)."""

    model: str
    driver: type
    #: What the model answers to its identity query.
    identity: str
    #: The probe the driver sends after a timeout (named in the "answers nothing" error).
    probe: str
    #: The span query, and how the analyzer formats its span in the reply.
    span_query: str
    span_reply: Callable[[float], str]
    #: A measurement the analyzer runs at once (time scale 0): 200 Hz span, 2 averages.
    measurement: str
    #: The status query that lets every hit in.
    settle_query: str
    #: The error an unknown command FOO queues, and the code of a hardware fault.
    foo_error: tuple[int, str]
    hardware_fault_code: int
    #: A fault armed for a fetch's first block: SCPI fetches ask a state line first.
    block_fault: str


MNEMONIC_MEASUREMENT = (
    "FRS 200 HZ;TSRC CH1;TLVL 2.25 MV;TDLY -20 MS;WIN1 FORC;WIN2 EXPO;RNG1 20 MV;RNG2 0.5 V;NAVG 2;STBL;STRT"
)
DIALECTS = {
    model: Dialect(
        model=model,
        driver=HPMnemonicAnalyzer,
        identity=f"HP{model}",
        probe="ID?",
        span_query="FRS?",
        span_reply=format_number,
        measurement=MNEMONIC_MEASUREMENT,
        settle_query="STA?",
        foo_error=(1, "Undefined command: FOO"),
        hardware_fault_code=7,
        block_fault="",
    )
    for model in ("35660A", "3562A")
}
DIALECTS["35670A"] = Dialect(
    model="35670A",
    driver=ScpiAnalyzer,
    identity="HEWLETT-PACKARD,35670A,0000A00000,A.00.00",
    probe="*IDN?",
    span_query="SENS:FREQ:SPAN?",
    span_reply=lambda span_hz: f"{span_hz:+.9E}",  # NR3, 10 significant digits
    measurement=(
        "SENS:FREQ:SPAN 200 HZ;:TRIG:SOUR INT1;:TRIG:LEV 2.25 MV;:TRIG:STAR1 -20 MS;:TRIG:STAR2 -20 MS"
        ";:SENS:WIND1:TYPE FORC;:SENS:WIND2:TYPE EXP;:SENS:VOLT1:RANG 20 MV;:SENS:VOLT2:RANG 0.5 V"
        ";:SENS:AVER:STAT ON;:SENS:AVER:COUN 2;:INIT:IMM"
    ),
    settle_query="STAT:OPER:COND?",
    foo_error=(-113, "Undefined header; FOO"),
    hardware_fault_code=-240,
    block_fault=",after=1",
)
#: A short driver timeout keeps the failing paths quick; the simulator answers at once.
TIMEOUT_S = 0.4


@pytest.fixture(autouse=True)
def _lock_dir(monkeypatch: pytest.MonkeyPatch, tmp_path) -> None:
    monkeypatch.setenv("DAQ_LOCK_DIR", str(tmp_path))


@pytest.fixture(autouse=True)
def _capture_driver_warnings(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.WARNING, logger="drivers.analyzer")


@pytest.fixture(params=list(DIALECTS))
def dialect(request: pytest.FixtureRequest) -> Dialect:
    return DIALECTS[request.param]


@pytest.fixture
def make_bench(dialect: Dialect) -> Iterator[Callable[..., Bench]]:
    """make_bench(kind, faults=(), measured=True) -> Bench (fault_bench.py); every test
    runs against each model."""
    with bench_factory(dialect.model, dialect.measurement, dialect.settle_query) as make:
        yield make


@contextmanager
def opened(bench: Bench, retries: int = 2, timeout_s: float = TIMEOUT_S) -> Iterator:
    # Forced: detection would meet the faults too; that is test_dialect_detection's part.
    with open_analyzer(bench.resource, timeout_s=timeout_s, dialect=bench.model, retries=retries) as drv:
        assert isinstance(drv, DIALECTS[bench.model].driver)
        yield drv


def span_of(drv, bench: Bench) -> str:
    """The span query's reply through the driver."""
    return drv.query(DIALECTS[bench.model].span_query)


def expected_span(bench: Bench) -> str:
    """The span as the analyzer formats it (computed from its settings, not asked)."""
    return DIALECTS[bench.model].span_reply(bench.analyzer.settings.span_hz)


def assert_frf_exact(drv, analyzer: Analyzer) -> None:
    frf = drv.fetch_frf()
    assert np.array_equal(frf.data, analyzer.average.trace("FRSP"))
    assert frf.header.n_averages == analyzer.average.count


# ================================================================== slow
@pytest.mark.timeout(15)
@pytest.mark.parametrize("kind", TRANSPORTS)
def test_slow_reply_within_the_timeout_succeeds(make_bench, dialect, kind, caplog) -> None:
    bench = make_bench(kind, faults=["slow,delay=0.25"])
    with opened(bench, timeout_s=1.0) as drv:
        t0 = time.monotonic()
        assert drv.identify() == dialect.identity
        assert time.monotonic() - t0 >= 0.2  # the fault was there
        assert_frf_exact(drv, bench.analyzer)
    assert recoveries(caplog) == []


@pytest.mark.timeout(15)
@pytest.mark.parametrize("kind", TRANSPORTS)
def test_one_reply_slower_than_the_timeout_is_retried_and_succeeds(make_bench, dialect, kind, caplog) -> None:
    bench = make_bench(kind)
    with opened(bench) as drv:
        drv.send("SIM:FAULT slow,delay=1.0,count=1")
        assert span_of(drv, bench) == expected_span(bench)
        assert len(recoveries(caplog)) == 1
        # The late reply was discarded with the link: each query gets its own reply.
        assert drv.identify() == dialect.identity
        assert span_of(drv, bench) == expected_span(bench)
        assert_frf_exact(drv, bench.analyzer)


@pytest.mark.timeout(15)
@pytest.mark.parametrize("kind", TRANSPORTS)
def test_one_slow_fetch_is_fetched_again_bit_exact(make_bench, dialect, kind, caplog) -> None:
    bench = make_bench(kind)
    record = bench.analyzer.last_record
    with opened(bench) as drv:
        drv.send(f"SIM:FAULT slow,delay=1.0,count=1{dialect.block_fault}")  # a late block
        force, accel = drv.fetch_time_records()
        assert len(recoveries(caplog)) == 1
        assert np.array_equal(force.data, record.force_n)
        assert np.array_equal(accel.data, record.acceleration_m_s2)


@pytest.mark.timeout(20)
@pytest.mark.parametrize("kind", TRANSPORTS)
def test_replies_always_slower_than_the_timeout_end_in_a_timeout_and_the_driver_recovers(
    make_bench, dialect, kind, caplog
) -> None:
    """Every reply is late: the driver's identity probe after the first timeout goes
    unanswered too, so it gives up at once (no point waiting out more timeouts),
    and leaves the link clean: the late replies never answer later queries."""
    bench = make_bench(kind, faults=["slow,delay=0.8,count=always"])
    with opened(bench, retries=1) as drv:
        outcome = outcome_of(lambda: span_of(drv, bench))
        assert isinstance(outcome, InstrumentTimeout), f"the query returned {outcome!r} instead of timing out"
        assert f"the instrument answers nothing, not even {dialect.probe}" in str(outcome)
        outcome = outcome_of(drv.fetch_frf)
        assert isinstance(outcome, InstrumentTimeout), outcome
        # The fault goes away: the next queries get their own replies, not late ones.
        bench.clear_server_faults()
        drv.send("SIM:FAULT CLEAR")
        assert drv.identify() == dialect.identity
        assert span_of(drv, bench) == expected_span(bench)
        assert_frf_exact(drv, bench.analyzer)


@pytest.mark.timeout(15)
@pytest.mark.parametrize("kind", TRANSPORTS)
def test_a_slow_reply_does_not_pop_an_error_left_by_an_earlier_command(
    make_bench, dialect, kind, caplog
) -> None:
    """FOO is queued as an instrument error; the span query is then answered late once.
    The driver's recovery must tell a live instrument from a silent one without asking
    the error queue: the query gets its own reply, and the FOO error is still queued
    for errors()."""
    bench = make_bench(kind)
    with opened(bench) as drv:
        drv.send("FOO")
        drv.send("SIM:FAULT slow,delay=1.0,count=1")
        assert span_of(drv, bench) == expected_span(bench)
        assert len(recoveries(caplog)) == 1
        assert [code for code, _ in bench.analyzer.errors] == [dialect.foo_error[0]]  # still queued
        assert drv.errors() == [dialect.foo_error]


# ================================================================== no_hit
@pytest.mark.timeout(15)
@pytest.mark.parametrize("kind", TRANSPORTS)
def test_no_hit_ends_in_a_trigger_timeout(make_bench, kind) -> None:
    bench = make_bench(kind, measured=False)
    with opened(bench) as drv:
        drv.configure(ImpactSettings(span_hz=200.0, averages=1, preview=False))
        drv.send("SIM:FAULT no_hit")
        drv.start()
        t0 = time.monotonic()
        with pytest.raises(InstrumentTimeout) as caught:
            drv.wait_for_hit(timeout_s=0.3)
        assert time.monotonic() - t0 >= 0.3  # the timeout was waited out
        assert "no trigger" in str(caught.value)
        assert bench.analyzer.state == "waiting"
        assert bench.analyzer.last_record is None
        assert bench.analyzer.average.count == 0
        # A fresh start is not affected (the fault fired once).
        drv.start()
        assert drv.wait_until_done(timeout_s=3.0).done
        assert_frf_exact(drv, bench.analyzer)


# ================================================================== truncate
@pytest.mark.timeout(15)
@pytest.mark.parametrize("kind", TRANSPORTS)
def test_one_truncated_block_is_fetched_again_bit_exact(make_bench, kind, caplog) -> None:
    bench = make_bench(kind)
    record = bench.analyzer.last_record
    assert record is not None
    with opened(bench) as drv:
        drv.send("SIM:FAULT truncate")
        force, accel = drv.fetch_time_records()
        assert len(recoveries(caplog)) == 1
        assert "truncated" in recoveries(caplog)[0]
        assert np.array_equal(force.data, record.force_n)
        assert np.array_equal(accel.data, record.acceleration_m_s2)
        assert_frf_exact(drv, bench.analyzer)
        assert len(recoveries(caplog)) == 1


@pytest.mark.timeout(15)
@pytest.mark.parametrize("kind", TRANSPORTS)
def test_blocks_always_truncated_end_in_a_protocol_error(make_bench, dialect, kind) -> None:
    bench = make_bench(kind, faults=["truncate,count=always"])
    with opened(bench) as drv:
        with pytest.raises(ProtocolError, match="truncated") as caught:
            drv.fetch_frf()
        assert "after 3 attempts" in str(caught.value)
        # Line replies are not blocks: the driver talks on.
        assert drv.identify() == dialect.identity
        assert span_of(drv, bench) == expected_span(bench)


# ================================================================== garbage
@pytest.mark.timeout(15)
@pytest.mark.parametrize("kind", TRANSPORTS)
def test_one_garbled_reply_is_retried_for_a_query_a_status_and_a_fetch(
    make_bench, dialect, kind, caplog
) -> None:
    bench = make_bench(kind)
    with opened(bench) as drv:
        drv.send("SIM:FAULT garbage")
        assert drv.identify() == dialect.identity
        assert len(recoveries(caplog)) == 1
        drv.send("SIM:FAULT garbage")
        assert drv.status().done
        assert len(recoveries(caplog)) == 2
        drv.send(f"SIM:FAULT garbage,nbytes=3{dialect.block_fault}")  # the first block of the fetch
        assert_frf_exact(drv, bench.analyzer)
        assert len(recoveries(caplog)) == 3
        assert span_of(drv, bench) == expected_span(bench)


@pytest.mark.timeout(15)
@pytest.mark.parametrize("kind", TRANSPORTS)
def test_replies_always_garbled_end_in_a_protocol_error(make_bench, dialect, kind) -> None:
    bench = make_bench(kind, faults=["garbage,count=always"])
    with opened(bench) as drv:
        with pytest.raises(ProtocolError, match="not ASCII"):
            drv.identify()
        with pytest.raises(ProtocolError):
            drv.fetch_frf()
        bench.clear_server_faults()
        drv.send("SIM:FAULT CLEAR")
        assert drv.identify() == dialect.identity
        assert_frf_exact(drv, bench.analyzer)


# ================================================================== drop
@pytest.mark.timeout(15)
def test_a_dropped_tcp_connection_is_reconnected_and_the_fetch_succeeds(make_bench, dialect, caplog) -> None:
    bench = make_bench("tcp")
    with opened(bench) as drv:
        drv.send("SIM:FAULT drop")
        assert_frf_exact(drv, bench.analyzer)
        assert bench.connections == 2  # the server closed the first one
        assert len(recoveries(caplog)) == 1
        assert drv.identify() == dialect.identity


@pytest.mark.timeout(15)
def test_a_dropped_transfer_over_the_pty_behaves_as_a_truncated_one(make_bench, dialect, caplog) -> None:
    """sims/prologix.py: "drop over a serial line cannot close anything: it behaves as
    a truncated transfer". Pins that the pty's session stays alive after a drop: the
    retry gets the whole block, and later queries their own replies."""
    bench = make_bench("prologix")
    with opened(bench) as drv:
        drv.send("SIM:FAULT drop")
        assert_frf_exact(drv, bench.analyzer)
        assert len(recoveries(caplog)) == 1
        assert drv.identify() == dialect.identity


@pytest.mark.timeout(15)
@pytest.mark.parametrize("kind", TRANSPORTS)
def test_blocks_always_dropped_end_in_a_clear_error(make_bench, kind) -> None:
    bench = make_bench(kind, faults=["drop,count=always"])
    with opened(bench) as drv:
        with pytest.raises(DriverError) as caught:
            drv.fetch_frf()
        assert "attempts" in str(caught.value)  # a message for the technician
    if kind == "tcp":
        # One connection per attempt (3), perhaps a fresh one after the last: bounded.
        assert 3 <= bench.connections <= 4


# ================================================================== error
@pytest.mark.timeout(15)
@pytest.mark.parametrize("kind", TRANSPORTS)
def test_a_hardware_fault_refuses_start_until_reset(make_bench, dialect, kind) -> None:
    bench = make_bench(kind, measured=False)
    settings = ImpactSettings(span_hz=200.0, averages=1, preview=False)
    with opened(bench) as drv:
        drv.configure(settings)
        drv.send("SIM:FAULT error")
        with pytest.raises(InstrumentError) as caught:
            drv.start()
        assert caught.value.code == dialect.hardware_fault_code
        assert bench.analyzer.hardware_fault
        assert bench.analyzer.average.count == 0
        drv.reset()
        drv.configure(settings)
        assert not bench.analyzer.hardware_fault
        drv.start()
        assert drv.wait_until_done(timeout_s=3.0).done
        assert_frf_exact(drv, bench.analyzer)


# ================================================================== no retries
@pytest.mark.timeout(15)
@pytest.mark.parametrize(
    ("kind", "fault", "action", "error"),
    [
        ("tcp", "truncate", "fetch", ProtocolError),
        ("prologix", "truncate", "fetch", ProtocolError),
        ("tcp", "garbage", "query", ProtocolError),
        ("prologix", "garbage", "query", ProtocolError),
        ("tcp", "garbage{block}", "fetch", ProtocolError),
        ("prologix", "garbage{block}", "fetch", ProtocolError),
        ("tcp", "drop", "fetch", DriverError),
        ("tcp", "slow,delay=0.8,count=1", "query", InstrumentTimeout),
        ("prologix", "slow,delay=0.8,count=1", "query", InstrumentTimeout),
    ],
)
def test_without_retries_the_first_fault_surfaces_and_the_next_exchange_is_clean(
    make_bench, dialect, kind, fault, action, error, caplog
) -> None:
    """Pins that the link is cleared after the last failed attempt, so nothing the
    failed exchange left on it is read by the next one. slow: the timed-out identity
    query's late reply must not come in as the reply to the span query (wrong data);
    garbage: the rest of the garbled block must not be read as the span query's reply
    (a ProtocolError for an exchange that had nothing wrong)."""
    bench = make_bench(kind)
    with opened(bench, retries=0) as drv:
        drv.send(f"SIM:FAULT {fault.format(block=dialect.block_fault)}")
        with pytest.raises(error):
            drv.fetch_frf() if action == "fetch" else drv.identify()
        assert recoveries(caplog) == []  # the failed exchange was not repeated
        if fault == "drop":
            # The server closed the link and no retry may reconnect: the next query may
            # fail again (clearly) or get its own reply, never another one.
            outcome = outcome_of(lambda: span_of(drv, bench))
            assert isinstance(outcome, DriverError) or outcome == expected_span(bench), outcome
            return
        drv.send("SIM:FAULT CLEAR")
        assert span_of(drv, bench) == expected_span(bench)
        assert_frf_exact(drv, bench.analyzer)


# ================================================================== accept
@pytest.mark.timeout(15)
@pytest.mark.parametrize("fault", ["slow,delay=1.0,count=1", "garbage"])
@pytest.mark.parametrize("kind", TRANSPORTS)
def test_accept_is_never_sent_twice(make_bench, kind, fault, caplog) -> None:
    """The status reply after the accept fails once; the driver asks the status again,
    never accepts again: the analyzer's average holds the one hit, and no 'accept with
    no hit waiting' error."""
    bench = make_bench(kind, measured=False)
    analyzer = bench.analyzer
    with opened(bench) as drv:
        drv.configure(ImpactSettings(span_hz=200.0, averages=3, preview=True))
        drv.start()
        assert drv.wait_for_hit(timeout_s=3.0).hit_pending
        assert analyzer.average.count == 0
        drv.send(f"SIM:FAULT {fault}")
        drv.accept()
        assert len(recoveries(caplog)) == 1
        assert analyzer.average.count == 1
        assert not analyzer.errors
        assert drv.averages_done() == 1
        # A rejected hit leaves the average alone, and the next hit is accepted as usual.
        assert drv.wait_for_hit(timeout_s=3.0).hit_pending
        drv.reject()
        assert analyzer.average.count == 1
        assert drv.wait_for_hit(timeout_s=3.0).hit_pending
        drv.accept()
        assert analyzer.average.count == 2
        assert not analyzer.errors
