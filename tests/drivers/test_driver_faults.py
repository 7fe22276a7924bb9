"""The driver against every fault of the simulator's menu (sims/faults.py), over TCP
(pyvisa-py socket) and over the Prologix pty: each ends in a bounded retry that
succeeds with the right data (bit for bit what the simulated analyzer holds) or in
a clear DriverError subclass, never in a hang and never in wrong data.

Where faults live: a TcpServer arms its ``faults=[...]`` on every new connection,
and the TCP driver reconnects to recover, so a one-shot fault (count=1) is armed
in-band on the current connection (``SIM:FAULT ...``) and a lasting one on the
server. The pty has one session for its life: in-band and server-wide are the same.

The measurement behind the fetched traces is made on the analyzer directly, so
that a fault armed for every reply cannot stop the set-up; the driver only fetches.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np
import pytest

from drivers.errors import DriverError, InstrumentError, InstrumentTimeout, ProtocolError
from drivers.hp_mnemonic import HPMnemonicAnalyzer as HP35660A
from drivers.settings import ImpactSettings
from sims.instrument import Analyzer
from sims.units import format_number
from tests.drivers.fault_bench import TRANSPORTS, Bench, bench_factory, outcome_of, recoveries

#: What each model answers to ID? (docs/dialects.md).
IDENTITY = {"35660A": "HP35660A", "3562A": "HP3562A"}
#: A short driver timeout keeps the failing paths quick; the simulator answers at once.
TIMEOUT_S = 0.4
#: A measurement the analyzer runs at once (time scale 0): 200 Hz span, 2 averages.
MEASUREMENT = (
    "FRS 200 HZ;TSRC CH1;TLVL 2.25 MV;TDLY -20 MS;WIN1 FORC;WIN2 EXPO;RNG1 20 MV;RNG2 0.5 V;NAVG 2;STBL;STRT"
)


@pytest.fixture(autouse=True)
def _lock_dir(monkeypatch: pytest.MonkeyPatch, tmp_path) -> None:
    monkeypatch.setenv("DAQ_LOCK_DIR", str(tmp_path))


@pytest.fixture(params=["35660A", "3562A"])
def make_bench(request: pytest.FixtureRequest) -> Iterator:
    """make_bench(kind, faults=(), measured=True) -> Bench (fault_bench.py); every test
    runs against both models of the mnemonic dialect (400 and 800 lines)."""
    with bench_factory(request.param, MEASUREMENT, "STA?") as make:
        yield make


@contextmanager
def opened(bench: Bench, retries: int = 2, timeout_s: float = TIMEOUT_S) -> Iterator[HP35660A]:
    with HP35660A.open(bench.resource, timeout_s=timeout_s, retries=retries, dialect=bench.model) as drv:
        yield drv


def expected_span(analyzer: Analyzer) -> str:
    """FRS? as the analyzer formats its span (computed from its settings, not asked)."""
    return format_number(analyzer.settings.span_hz)


def assert_frf_exact(drv: HP35660A, analyzer: Analyzer) -> None:
    frf = drv.fetch_frf()
    assert np.array_equal(frf.data, analyzer.average.trace("FRSP"))
    assert frf.header.n_averages == analyzer.average.count


@pytest.fixture(autouse=True)
def _capture_driver_warnings(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.WARNING, logger="drivers.analyzer")


# ================================================================== slow
@pytest.mark.timeout(10)
@pytest.mark.parametrize("kind", TRANSPORTS)
def test_slow_reply_within_the_timeout_succeeds(make_bench, kind, caplog) -> None:
    bench = make_bench(kind, faults=["slow,delay=0.25"])
    with opened(bench, timeout_s=1.0) as drv:
        t0 = time.monotonic()
        assert drv.identify() == IDENTITY[bench.model]
        assert time.monotonic() - t0 >= 0.2  # the fault was there
        assert_frf_exact(drv, bench.analyzer)
    assert recoveries(caplog) == []


@pytest.mark.timeout(10)
@pytest.mark.parametrize("kind", TRANSPORTS)
def test_one_reply_slower_than_the_timeout_is_retried_and_succeeds(make_bench, kind, caplog) -> None:
    bench = make_bench(kind)
    with opened(bench) as drv:
        drv.send("SIM:FAULT slow,delay=1.0,count=1")
        assert drv.query("FRS?") == expected_span(bench.analyzer)
        assert len(recoveries(caplog)) == 1
        # The late reply was discarded with the link: each query gets its own reply.
        assert drv.identify() == IDENTITY[bench.model]
        assert drv.query("FRS?") == expected_span(bench.analyzer)
        assert_frf_exact(drv, bench.analyzer)


@pytest.mark.timeout(15)
@pytest.mark.parametrize("kind", TRANSPORTS)
def test_replies_always_slower_than_the_timeout_end_in_a_timeout_and_the_driver_recovers(
    make_bench, kind, caplog
) -> None:
    """Every reply is late: the driver's ID? probe after the first timeout goes
    unanswered too, so it gives up at once (no point waiting out more timeouts),
    and leaves the link clean: the late replies never answer later queries."""
    bench = make_bench(kind, faults=["slow,delay=0.8,count=always"])
    with opened(bench, retries=1) as drv:
        outcome = outcome_of(lambda: drv.query("FRS?"))
        assert isinstance(outcome, InstrumentTimeout), f"FRS? returned {outcome!r} instead of timing out"
        assert "the instrument answers nothing" in str(outcome)
        # The fault goes away: the next queries get their own replies, not late ones.
        bench.clear_server_faults()
        drv.send("SIM:FAULT CLEAR")
        assert drv.identify() == IDENTITY[bench.model]
        assert drv.query("FRS?") == expected_span(bench.analyzer)


@pytest.mark.timeout(10)
@pytest.mark.parametrize("kind", TRANSPORTS)
def test_a_slow_reply_does_not_pop_an_error_left_by_an_earlier_command(make_bench, kind, caplog) -> None:
    """FOO is queued as an instrument error; FRS? is then answered late once. The
    driver's recovery must tell a live instrument from a silent one without ERR?:
    FRS? gets its own reply, and the FOO error is still queued for check_errors()."""
    bench = make_bench(kind)
    with opened(bench) as drv:
        drv.send("FOO")
        drv.send("SIM:FAULT slow,delay=1.0,count=1")
        assert drv.query("FRS?") == expected_span(bench.analyzer)
        assert len(recoveries(caplog)) == 1
        assert [code for code, _ in bench.analyzer.errors] == [1]  # still queued
        assert drv.errors() == [(1, "Undefined command: FOO")]


# ================================================================== no_hit
@pytest.mark.timeout(10)
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
        assert "trigger" in str(caught.value)
        assert bench.analyzer.state == "waiting"
        assert bench.analyzer.last_record is None
        assert bench.analyzer.average.count == 0
        # A fresh start is not affected (the fault fired once).
        drv.start()
        assert drv.wait_until_done(timeout_s=3.0).done
        assert_frf_exact(drv, bench.analyzer)


# ================================================================== truncate
@pytest.mark.timeout(10)
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


@pytest.mark.timeout(10)
@pytest.mark.parametrize("kind", TRANSPORTS)
def test_blocks_always_truncated_end_in_a_protocol_error(make_bench, kind) -> None:
    bench = make_bench(kind, faults=["truncate,count=always"])
    with opened(bench) as drv:
        with pytest.raises(ProtocolError, match="truncated") as caught:
            drv.fetch_frf()
        assert "after 3 attempts" in str(caught.value)
        # Line replies are not blocks: the driver talks on.
        assert drv.identify() == IDENTITY[bench.model]
        assert drv.query("FRS?") == expected_span(bench.analyzer)


# ================================================================== garbage
@pytest.mark.timeout(10)
@pytest.mark.parametrize("kind", TRANSPORTS)
def test_one_garbled_reply_is_retried_for_a_query_and_a_fetch(make_bench, kind, caplog) -> None:
    bench = make_bench(kind)
    with opened(bench) as drv:
        drv.send("SIM:FAULT garbage")
        assert drv.identify() == IDENTITY[bench.model]
        assert len(recoveries(caplog)) == 1
        drv.send("SIM:FAULT garbage,nbytes=3")
        assert_frf_exact(drv, bench.analyzer)
        assert len(recoveries(caplog)) == 2
        assert drv.query("FRS?") == expected_span(bench.analyzer)


@pytest.mark.timeout(10)
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
        assert drv.identify() == IDENTITY[bench.model]
        assert_frf_exact(drv, bench.analyzer)


# ================================================================== drop
@pytest.mark.timeout(10)
def test_a_dropped_tcp_connection_is_reconnected_and_the_fetch_succeeds(make_bench, caplog) -> None:
    bench = make_bench("tcp")
    with opened(bench) as drv:
        drv.send("SIM:FAULT drop")
        assert_frf_exact(drv, bench.analyzer)
        assert bench.connections == 2  # the server closed the first one
        assert len(recoveries(caplog)) == 1
        assert drv.identify() == IDENTITY[bench.model]


@pytest.mark.timeout(10)
def test_a_dropped_transfer_over_the_pty_behaves_as_a_truncated_one(make_bench, caplog) -> None:
    """sims/prologix.py: "drop over a serial line cannot close anything: it behaves as
    a truncated transfer". Pins that the pty's session stays alive after a drop: the
    retry gets the whole block, and later queries their own replies."""
    bench = make_bench("prologix")
    with opened(bench) as drv:
        drv.send("SIM:FAULT drop")
        assert_frf_exact(drv, bench.analyzer)
        assert drv.identify() == IDENTITY[bench.model]


@pytest.mark.timeout(10)
@pytest.mark.parametrize("kind", TRANSPORTS)
def test_blocks_always_dropped_end_in_a_clear_error(make_bench, kind) -> None:
    bench = make_bench(kind, faults=["drop,count=always"])
    with opened(bench) as drv:
        with pytest.raises(DriverError) as caught:
            drv.fetch_frf()
        assert str(caught.value)  # a message for the technician
        assert "attempts" in str(caught.value)
    if kind == "tcp":
        # One connection per attempt (3), perhaps a fresh one after the last: bounded.
        assert 3 <= bench.connections <= 4


# ================================================================== error
@pytest.mark.timeout(10)
@pytest.mark.parametrize("kind", TRANSPORTS)
def test_a_hardware_fault_refuses_start_until_reset(make_bench, kind) -> None:
    bench = make_bench(kind, measured=False)
    settings = ImpactSettings(span_hz=200.0, averages=1, preview=False)
    with opened(bench) as drv:
        drv.configure(settings)
        drv.send("SIM:FAULT error")
        with pytest.raises(InstrumentError) as caught:
            drv.start()
        assert caught.value.code == 7
        assert bench.analyzer.hardware_fault
        assert bench.analyzer.average.count == 0
        drv.reset()
        drv.configure(settings)
        assert not bench.analyzer.hardware_fault
        drv.start()
        assert drv.wait_until_done(timeout_s=3.0).done
        assert_frf_exact(drv, bench.analyzer)


# ================================================================== no retries
@pytest.mark.timeout(10)
@pytest.mark.parametrize(
    ("kind", "fault", "action", "error"),
    [
        ("tcp", "truncate", "fetch", ProtocolError),
        ("prologix", "truncate", "fetch", ProtocolError),
        ("tcp", "garbage", "query", ProtocolError),
        ("prologix", "garbage", "query", ProtocolError),
        ("tcp", "garbage", "fetch", ProtocolError),
        ("prologix", "garbage", "fetch", ProtocolError),
        ("tcp", "drop", "fetch", DriverError),
        ("tcp", "slow,delay=0.8,count=1", "query", InstrumentTimeout),
        ("prologix", "slow,delay=0.8,count=1", "query", InstrumentTimeout),
    ],
)
def test_without_retries_the_first_fault_surfaces_and_the_next_exchange_is_clean(
    make_bench, kind, fault, action, error, caplog
) -> None:
    """Pins that the link is cleared after the last failed attempt, so nothing the
    failed exchange left on it is read by the next one. slow: the timed-out ID?'s
    late reply must not come in as the reply to FRS? (wrong data, ``HP35660A``);
    garbage: the rest of the garbled block must not be read as FRS?'s reply (a
    ProtocolError for an exchange that had nothing wrong)."""
    bench = make_bench(kind)
    with opened(bench, retries=0) as drv:
        drv.send(f"SIM:FAULT {fault}")
        with pytest.raises(error):
            drv.fetch_frf() if action == "fetch" else drv.identify()
        assert recoveries(caplog) == []  # the failed exchange was not repeated
        if fault == "drop":
            # The server closed the link and no retry may reconnect: the next query may
            # fail again (clearly) or get its own reply, never another one.
            outcome = outcome_of(lambda: drv.query("FRS?"))
            assert isinstance(outcome, DriverError) or outcome == expected_span(bench.analyzer), outcome
            return
        drv.send("SIM:FAULT CLEAR")
        assert drv.query("FRS?") == expected_span(bench.analyzer)
        assert_frf_exact(drv, bench.analyzer)


# ================================================================== ACPT
@pytest.mark.timeout(10)
@pytest.mark.parametrize("fault", ["slow,delay=1.0,count=1", "garbage"])
@pytest.mark.parametrize("kind", TRANSPORTS)
def test_accept_is_never_sent_twice(make_bench, kind, fault, caplog) -> None:
    """The reply after ACPT (STA?) fails once; the driver retries the STA?, never the ACPT:
    the analyzer's average holds the one hit, and no 'ACPT with no hit waiting' error."""
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
        # And the next hit can be accepted as usual.
        assert drv.wait_for_hit(timeout_s=3.0).hit_pending
        drv.accept()
        assert analyzer.average.count == 2
        assert not analyzer.errors
