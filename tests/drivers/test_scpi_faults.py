"""The SCPI driver against every fault of the simulator's menu (sims/faults.py: slow,
no_hit, truncate, garbage, drop, error), over TCP (pyvisa-py socket) and over the
Prologix pty, with the 35670A simulated: each ends in a bounded retry that succeeds
with the right data (bit for bit what the simulated analyzer holds) or in a clear
DriverError, never in a hang and never in wrong data.

The bench, and where faults live, are test_driver_faults.py's (fault_bench.py).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np
import pytest

from drivers.errors import DriverError, InstrumentError, InstrumentTimeout, ProtocolError
from drivers.family import open_analyzer
from drivers.scpi_analyzer import ScpiAnalyzer
from drivers.settings import ImpactSettings
from sims.instrument import Analyzer
from tests.drivers.fault_bench import TRANSPORTS, Bench, bench_factory, outcome_of, recoveries

#: A short driver timeout keeps the failing paths quick; the simulator answers at once.
TIMEOUT_S = 0.4
IDN = "HEWLETT-PACKARD,35670A,0000A00000,A.00.00"
#: A measurement the analyzer runs at once (time scale 0): 200 Hz span, 2 averages.
MEASUREMENT = (
    "SENS:FREQ:SPAN 200 HZ;:TRIG:SOUR INT1;:TRIG:LEV 2.25 MV;:TRIG:STAR1 -20 MS;:TRIG:STAR2 -20 MS"
    ";:SENS:WIND1:TYPE FORC;:SENS:WIND2:TYPE EXP;:SENS:VOLT1:RANG 20 MV;:SENS:VOLT2:RANG 0.5 V"
    ";:SENS:AVER:STAT ON;:SENS:AVER:COUN 2;:INIT:IMM"
)


@pytest.fixture(autouse=True)
def _lock_dir(monkeypatch: pytest.MonkeyPatch, tmp_path) -> None:
    monkeypatch.setenv("DAQ_LOCK_DIR", str(tmp_path))


@pytest.fixture
def make_bench() -> Iterator:
    """make_bench(kind, faults=(), measured=True) -> Bench (fault_bench.py), the 35670A."""
    with bench_factory("35670A", MEASUREMENT, "STAT:OPER:COND?") as make:
        yield make


@contextmanager
def opened(bench: Bench, retries: int = 2, timeout_s: float = TIMEOUT_S) -> Iterator[ScpiAnalyzer]:
    # Forced: detection would meet the faults too; that is test_dialect_detection's part.
    with open_analyzer(bench.resource, timeout_s=timeout_s, dialect="35670A", retries=retries) as drv:
        assert isinstance(drv, ScpiAnalyzer)
        yield drv


def expected_span(analyzer: Analyzer) -> str:
    """SENS:FREQ:SPAN? as the page formats it: NR3, 10 significant digits."""
    return f"{analyzer.settings.span_hz:+.9E}"


def assert_frf_exact(drv: ScpiAnalyzer, analyzer: Analyzer) -> None:
    frf = drv.fetch_frf()
    assert np.array_equal(frf.data, analyzer.average.trace("FRSP"))
    assert frf.header.n_averages == analyzer.average.count


@pytest.fixture(autouse=True)
def _capture_driver_warnings(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.WARNING, logger="drivers.analyzer")


# ================================================================== slow
@pytest.mark.timeout(15)
@pytest.mark.parametrize("kind", TRANSPORTS)
def test_slow_reply_within_the_timeout_succeeds(make_bench, kind, caplog) -> None:
    bench = make_bench(kind, faults=["slow,delay=0.25"])
    with opened(bench, timeout_s=1.0) as drv:
        t0 = time.monotonic()
        assert drv.identify() == IDN
        assert time.monotonic() - t0 >= 0.2  # the fault was there
        assert_frf_exact(drv, bench.analyzer)
    assert recoveries(caplog) == []


@pytest.mark.timeout(15)
@pytest.mark.parametrize("kind", TRANSPORTS)
def test_one_reply_slower_than_the_timeout_is_retried_and_succeeds(make_bench, kind, caplog) -> None:
    bench = make_bench(kind)
    with opened(bench) as drv:
        drv.send("SIM:FAULT slow,delay=1.0,count=1")
        assert drv.query("SENS:FREQ:SPAN?") == expected_span(bench.analyzer)
        assert len(recoveries(caplog)) == 1
        # The late reply went with the link: each query gets its own reply.
        assert drv.identify() == IDN
        assert drv.query("SENS:FREQ:SPAN?") == expected_span(bench.analyzer)
        assert_frf_exact(drv, bench.analyzer)


@pytest.mark.timeout(15)
@pytest.mark.parametrize("kind", TRANSPORTS)
def test_one_slow_fetch_is_fetched_again_bit_exact(make_bench, kind, caplog) -> None:
    bench = make_bench(kind)
    record = bench.analyzer.last_record
    with opened(bench) as drv:
        drv.send("SIM:FAULT slow,delay=1.0,count=1,after=1")  # the state line, then a late block
        force, accel = drv.fetch_time_records()
        assert len(recoveries(caplog)) == 1
        assert np.array_equal(force.data, record.force_n)
        assert np.array_equal(accel.data, record.acceleration_m_s2)


@pytest.mark.timeout(20)
@pytest.mark.parametrize("kind", TRANSPORTS)
def test_replies_always_slower_than_the_timeout_end_in_a_timeout_and_the_driver_recovers(
    make_bench, kind, caplog
) -> None:
    bench = make_bench(kind, faults=["slow,delay=0.8,count=always"])
    with opened(bench, retries=1) as drv:
        outcome = outcome_of(lambda: drv.query("SENS:FREQ:SPAN?"))
        assert isinstance(outcome, InstrumentTimeout), f"the query returned {outcome!r} instead of timing out"
        assert r"not even *IDN?" in str(outcome)
        outcome = outcome_of(drv.fetch_frf)
        assert isinstance(outcome, InstrumentTimeout), outcome
        bench.clear_server_faults()
        drv.send("SIM:FAULT CLEAR")
        assert drv.identify() == IDN
        assert drv.query("SENS:FREQ:SPAN?") == expected_span(bench.analyzer)
        assert_frf_exact(drv, bench.analyzer)


@pytest.mark.timeout(15)
@pytest.mark.parametrize("kind", TRANSPORTS)
def test_a_slow_reply_does_not_pop_an_error_left_by_an_earlier_command(make_bench, kind, caplog) -> None:
    bench = make_bench(kind)
    with opened(bench) as drv:
        drv.send("FOO")
        drv.send("SIM:FAULT slow,delay=1.0,count=1")
        assert drv.query("SENS:FREQ:SPAN?") == expected_span(bench.analyzer)
        assert len(recoveries(caplog)) == 1
        assert [code for code, _ in bench.analyzer.errors] == [-113]  # still queued
        ((code, message),) = drv.errors()
        assert code == -113
        assert message.startswith("Undefined header")


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
def test_blocks_always_truncated_end_in_a_protocol_error(make_bench, kind) -> None:
    bench = make_bench(kind, faults=["truncate,count=always"])
    with opened(bench) as drv:
        with pytest.raises(ProtocolError, match="truncated") as caught:
            drv.fetch_frf()
        assert "after 3 attempts" in str(caught.value)
        # Line replies are not blocks: the driver talks on.
        assert drv.identify() == IDN
        assert drv.query("SENS:FREQ:SPAN?") == expected_span(bench.analyzer)


# ================================================================== garbage
@pytest.mark.timeout(15)
@pytest.mark.parametrize("kind", TRANSPORTS)
def test_one_garbled_reply_is_retried_for_a_query_a_status_and_a_fetch(make_bench, kind, caplog) -> None:
    bench = make_bench(kind)
    with opened(bench) as drv:
        drv.send("SIM:FAULT garbage")
        assert drv.identify() == IDN
        assert len(recoveries(caplog)) == 1
        drv.send("SIM:FAULT garbage")
        assert drv.status().done
        assert len(recoveries(caplog)) == 2
        drv.send("SIM:FAULT garbage,nbytes=3,after=1")  # the first block of the fetch
        assert_frf_exact(drv, bench.analyzer)
        assert len(recoveries(caplog)) == 3
        assert drv.query("SENS:FREQ:SPAN?") == expected_span(bench.analyzer)


@pytest.mark.timeout(15)
@pytest.mark.parametrize("kind", TRANSPORTS)
def test_replies_always_garbled_end_in_a_protocol_error(make_bench, kind) -> None:
    bench = make_bench(kind, faults=["garbage,count=always"])
    with opened(bench) as drv:
        with pytest.raises(ProtocolError, match="not ASCII"):
            drv.identify()
        with pytest.raises(ProtocolError):
            drv.fetch_frf()
        bench.clear_server_faults()
        drv.send("SIM:FAULT CLEAR")
        assert drv.identify() == IDN
        assert_frf_exact(drv, bench.analyzer)


# ================================================================== drop
@pytest.mark.timeout(15)
def test_a_dropped_tcp_connection_is_reconnected_and_the_fetch_succeeds(make_bench, caplog) -> None:
    bench = make_bench("tcp")
    with opened(bench) as drv:
        drv.send("SIM:FAULT drop")
        assert_frf_exact(drv, bench.analyzer)
        assert bench.connections == 2  # the server closed the first one
        assert len(recoveries(caplog)) == 1
        assert drv.identify() == IDN


@pytest.mark.timeout(15)
def test_a_dropped_transfer_over_the_pty_behaves_as_a_truncated_one(make_bench, caplog) -> None:
    bench = make_bench("prologix")
    with opened(bench) as drv:
        drv.send("SIM:FAULT drop")
        assert_frf_exact(drv, bench.analyzer)
        assert len(recoveries(caplog)) == 1
        assert drv.identify() == IDN


@pytest.mark.timeout(15)
@pytest.mark.parametrize("kind", TRANSPORTS)
def test_blocks_always_dropped_end_in_a_clear_error(make_bench, kind) -> None:
    bench = make_bench(kind, faults=["drop,count=always"])
    with opened(bench) as drv:
        with pytest.raises(DriverError) as caught:
            drv.fetch_frf()
        assert "attempts" in str(caught.value)
    if kind == "tcp":
        # One connection per attempt (3), perhaps a fresh one after the last: bounded.
        assert 3 <= bench.connections <= 4


# ================================================================== error
@pytest.mark.timeout(15)
@pytest.mark.parametrize("kind", TRANSPORTS)
def test_a_hardware_fault_refuses_start_until_reset(make_bench, kind) -> None:
    bench = make_bench(kind, measured=False)
    settings = ImpactSettings(span_hz=200.0, averages=1, preview=False)
    with opened(bench) as drv:
        drv.configure(settings)
        drv.send("SIM:FAULT error")
        with pytest.raises(InstrumentError) as caught:
            drv.start()
        assert caught.value.code == -240
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
        ("tcp", "garbage,after=1", "fetch", ProtocolError),
        ("prologix", "garbage,after=1", "fetch", ProtocolError),
        ("tcp", "drop", "fetch", DriverError),
        ("tcp", "slow,delay=0.8,count=1", "query", InstrumentTimeout),
        ("prologix", "slow,delay=0.8,count=1", "query", InstrumentTimeout),
    ],
)
def test_without_retries_the_first_fault_surfaces_and_the_next_exchange_is_clean(
    make_bench, kind, fault, action, error, caplog
) -> None:
    """The link is cleared after the last failed attempt: a late *IDN? reply must not
    answer SENS:FREQ:SPAN?, the rest of a garbled block must not be read as a line."""
    bench = make_bench(kind)
    with opened(bench, retries=0) as drv:
        drv.send(f"SIM:FAULT {fault}")
        with pytest.raises(error):
            drv.fetch_frf() if action == "fetch" else drv.identify()
        assert recoveries(caplog) == []  # the failed exchange was not repeated
        if fault == "drop":
            outcome = outcome_of(lambda: drv.query("SENS:FREQ:SPAN?"))
            assert isinstance(outcome, DriverError) or outcome == expected_span(bench.analyzer), outcome
            return
        drv.send("SIM:FAULT CLEAR")
        assert drv.query("SENS:FREQ:SPAN?") == expected_span(bench.analyzer)
        assert_frf_exact(drv, bench.analyzer)


# ================================================================== accept
@pytest.mark.timeout(15)
@pytest.mark.parametrize("fault", ["slow,delay=1.0,count=1", "garbage"])
@pytest.mark.parametrize("kind", TRANSPORTS)
def test_accept_is_never_sent_twice(make_bench, kind, fault, caplog) -> None:
    """The status reply after SENS:AVER:PREV:ACC fails once; the driver asks the status
    again, never accepts again: one hit in the average, no -221 (no hit pending)."""
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
        assert drv.wait_for_hit(timeout_s=3.0).hit_pending
        drv.reject()
        assert analyzer.average.count == 1
        assert drv.wait_for_hit(timeout_s=3.0).hit_pending
        drv.accept()
        assert analyzer.average.count == 2
        assert not analyzer.errors
