"""The SCPI driver (HP 35670A, 35665A) and the mnemonic driver of the HP 3562A end to
end against the simulated analyzer of that model, over both wires: TCP (pyvisa-py
``TCPIP::127.0.0.1::<port>::SOCKET``) and the Prologix pty (``PROLOGIX::<pty>::11``).

Every array the driver returns is compared bit for bit (float64) with what the
simulated analyzer holds (``last_record`` for the time records, ``average`` for the
averaged traces); every setting with what it holds (``settings``). The rounding the
analyzer does is computed here from docs/instrument-scpi.md: spans 51.2 kHz / 2^n
(the 3562A: 100 kHz / 2^n) rounded up, ranges up to the next 2 dB step of dBVrms.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
import pytest

from daq.workflows.capture import Capture, Finished, HitArrived
from drivers.analyzer import SignalAnalyzer
from drivers.dialects import HP3562A, SCPI
from drivers.errors import InstrumentError
from drivers.family import open_analyzer
from drivers.hp_mnemonic import HPMnemonicAnalyzer
from drivers.scpi_analyzer import ScpiAnalyzer
from drivers.settings import ChannelSetup, ImpactSettings, Window
from sims.instrument import Analyzer
from sims.prologix import PrologixPty
from sims.sources import PhysicsSource
from sims.tcp_server import TcpServer

TRANSPORTS = ("tcp", "prologix")
TIMEOUT_S = 2.0


def offered_span(requested_hz: float, top_hz: float) -> float:
    """The smallest top / 2^n span at or above the request."""
    return min(s for s in (top_hz / 2**n for n in range(20)) if s >= requested_hz)


def offered_range_2db(requested_v: float) -> float:
    """The smallest 10^(dB/20) x sqrt(2) V peak, dB = -51, -49 .. +27 dBVrms, at or above."""
    return min(
        r
        for r in (10 ** (db / 20) * math.sqrt(2) for db in range(-51, 28, 2))
        if r >= requested_v * (1 - 1e-12)
    )


@dataclass
class Bench:
    analyzer: Analyzer
    resource: str


@pytest.fixture(autouse=True)
def _lock_dir(monkeypatch: pytest.MonkeyPatch, tmp_path) -> None:
    monkeypatch.setenv("DAQ_LOCK_DIR", str(tmp_path))


def _bench(model: str, wire: str) -> Iterator[Bench]:
    analyzer = Analyzer(PhysicsSource("seed", seed=7), time_scale=0.0, model=model)
    if wire == "tcp":
        with TcpServer(analyzer, port=0) as server:
            yield Bench(analyzer, server.resource)
    else:
        with PrologixPty(analyzer, 11) as pty:
            yield Bench(analyzer, f"PROLOGIX::{pty.port}::11")


@pytest.fixture(params=TRANSPORTS)
def bench(request) -> Iterator[Bench]:
    yield from _bench("35670A", request.param)


@pytest.fixture
def driver(bench: Bench) -> Iterator[ScpiAnalyzer]:
    with open_analyzer(bench.resource, timeout_s=TIMEOUT_S) as drv:
        assert isinstance(drv, ScpiAnalyzer)
        yield drv


def _settings(**changes: object) -> ImpactSettings:
    base = {
        "span_hz": 200.0,
        "hammer": ChannelSetup(Window.FORCE, 2.25e-3, range_v=0.02, force_width_s=0.05),
        "accelerometer": ChannelSetup(Window.EXPONENTIAL, 1.02e-3, range_v=0.5, exp_decay_s=0.5),
        "trigger_level_eu": 1.0,
        "pre_trigger_s": 0.02,
        "averages": 2,
        "preview": True,
    }
    return ImpactSettings(**{**base, **changes})  # type: ignore[arg-type]


def run_hits_and_compare(
    drv: SignalAnalyzer, analyzer: Analyzer, samples: int, lines: int, span: float
) -> None:
    """Start; three hits in preview (accept, reject, accept), each hit's records
    compared with the analyzer's; then the averaged traces compared with its average."""
    drv.start()
    assert analyzer.average.count == 0
    seen: list[np.ndarray] = []
    for decision, count_after in (("accept", 1), ("reject", 1), ("accept", 2)):
        status = drv.wait_for_hit(timeout_s=5.0)
        assert status.hit_pending
        record = analyzer.last_record
        assert record is not None
        force, accel = drv.fetch_time_records()
        assert np.array_equal(force.data, record.force_n)
        assert np.array_equal(accel.data, record.acceleration_m_s2)
        assert not any(np.array_equal(record.force_n, old) for old in seen)  # a new hit each time
        seen.append(record.force_n.copy())
        for trace, channel, units in ((force, 1, "N"), (accel, 2, "m/s^2")):
            h = trace.header
            assert (h.display_function, h.channel, h.y_units) == (f"TIM{channel}", channel, units)
            assert (h.n_points, trace.data.shape, trace.data.dtype) == (samples, (samples,), np.float64)
            assert (h.time_domain, h.x_units, h.complex_data) == (True, "s", False)
            assert h.sample_rate_hz == record.sample_rate_hz == 2.56 * span
            assert math.isclose(h.delta_x, 1 / h.sample_rate_hz, rel_tol=1e-12)
            assert math.isclose(h.start_x, record.start_s, rel_tol=1e-9, abs_tol=1e-12)
            assert h.overflow is record.overload[channel - 1]
            assert h.n_averages == analyzer.average.count
        getattr(drv, decision)()
        assert analyzer.average.count == count_after
        assert drv.averages_done() == count_after
    assert drv.wait_until_done(timeout_s=5.0).done
    assert analyzer.state == "done"
    assert not analyzer.errors

    frf, coh = drv.fetch_frf(), drv.fetch_coherence()
    lsp1, lsp2 = drv.fetch_linear_spectra()
    for trace, function, channel, is_complex in (
        (frf, "FRSP", 3, True),
        (coh, "COHR", 3, False),
        (lsp1, "LSP1", 1, True),
        (lsp2, "LSP2", 2, True),
    ):
        assert np.array_equal(trace.data, analyzer.average.trace(function)), function
        h = trace.header
        assert (h.display_function, h.channel, h.complex_data, h.n_averages) == (
            function,
            channel,
            is_complex,
            2,
        )
        assert trace.data.dtype == (np.complex128 if is_complex else np.float64)
        assert (h.n_points, h.time_domain, h.x_units, h.start_x) == (lines + 1, False, "Hz", 0.0)
        assert math.isclose(h.delta_x, span / lines, rel_tol=1e-12)
        assert math.isclose(trace.x[-1], span, rel_tol=1e-12)
    assert (frf.header.y_units, coh.header.y_units, lsp1.header.y_units, lsp2.header.y_units) == (
        "(m/s^2)/N",
        "",
        "N",
        "m/s^2",
    )
    assert np.all((coh.data >= 0.0) & (coh.data <= 1.0 + 1e-12))


# ================================================================== 35670A
@pytest.mark.timeout(15)
def test_configure_rounds_span_and_ranges_up_and_reads_everything_back(
    driver: ScpiAnalyzer, bench: Bench
) -> None:
    wanted = _settings(
        span_hz=300.0,
        hammer=ChannelSetup(Window.FORCE, 2.25e-3, range_v=0.02, force_width_s=0.04, ac_coupled=True),
        pre_trigger_s=0.05,
        averages=4,
        lines=800,
    )
    got = driver.configure(wanted)
    s = bench.analyzer.settings
    assert got.span_hz == s.span_hz == offered_span(300.0, 51_200.0) == 400.0
    assert got.center_hz is None
    assert s.center_hz == 200.0
    assert got.lines == s.lines == 800
    assert driver.geometry.lines == 800
    assert math.isclose(got.hammer.range_v, offered_range_2db(0.02), rel_tol=1e-9)  # -35 dBVrms
    assert math.isclose(got.accelerometer.range_v, offered_range_2db(0.5), rel_tol=1e-9)  # -7 dBVrms
    assert math.isclose(s.range1_v, offered_range_2db(0.02), rel_tol=1e-12)
    assert got.hammer.window is Window.FORCE
    assert got.accelerometer.window is Window.EXPONENTIAL
    assert (s.window1, s.window2) == ("FORC", "EXPO")
    assert math.isclose(got.hammer.force_width_s, 0.04, rel_tol=1e-9)
    assert math.isclose(got.accelerometer.exp_decay_s, 0.5, rel_tol=1e-9)
    assert got.hammer.ac_coupled is True
    assert got.accelerometer.ac_coupled is False
    assert (got.trigger_source, got.trigger_slope) == ("CH1", "POS")
    assert math.isclose(got.trigger_level_eu, 1.0, rel_tol=1e-9)
    assert math.isclose(s.trigger_level_v, 2.25e-3, rel_tol=1e-12)
    assert math.isclose(got.pre_trigger_s, 0.05, rel_tol=1e-9)
    assert math.isclose(s.trigger_delay_s, -0.05, rel_tol=1e-12)
    assert (got.averages, got.preview) == (4, True)
    assert s.n_averages == 4
    assert not bench.analyzer.errors


@pytest.mark.timeout(15)
def test_configure_autorange_free_run_and_no_preview(driver: ScpiAnalyzer, bench: Bench) -> None:
    got = driver.configure(
        _settings(
            hammer=ChannelSetup(Window.UNIFORM, 2.25e-3, range_v=None),
            trigger_source="FREE",
            trigger_level_eu=0.0,
            averages=1,
            preview=False,
        )
    )
    assert got.hammer.range_v is None
    assert got.hammer.window is Window.UNIFORM
    assert got.trigger_source == "FREE"
    assert bench.analyzer.settings.autorange1 == 1
    assert bench.analyzer.settings.autorange2 == 0
    assert (got.averages, got.preview) == (1, False)


@pytest.mark.timeout(20)
def test_hit_by_hit_time_records_accept_reject_and_averaged_traces(
    driver: ScpiAnalyzer, bench: Bench
) -> None:
    driver.configure(_settings())
    run_hits_and_compare(driver, bench.analyzer, samples=1024, lines=400, span=200.0)


@pytest.mark.timeout(30)
@pytest.mark.parametrize("lines", [100, 1600])
def test_other_line_counts_give_their_records(lines: int) -> None:
    for bench in _bench("35670A", "tcp"):
        with open_analyzer(bench.resource, timeout_s=TIMEOUT_S) as drv:
            got = drv.configure(_settings(lines=lines, pre_trigger_s=None))
            assert got.lines == lines
            assert got.record_length_s == lines / 200.0
            run_hits_and_compare(drv, bench.analyzer, samples=lines * 256 // 100, lines=lines, span=200.0)


@pytest.mark.timeout(15)
def test_zoom_gives_half_as_many_complex_time_points_and_a_band_around_the_center(
    driver: ScpiAnalyzer, bench: Bench
) -> None:
    analyzer = bench.analyzer
    span, center = 400.0, 1000.0
    got = driver.configure(_settings(span_hz=span, center_hz=center, averages=1, preview=False))
    assert (got.span_hz, got.center_hz) == (span, center)
    assert analyzer.settings.center_hz == center
    driver.start()
    assert driver.wait_until_done(timeout_s=5.0).done
    record = analyzer.last_record
    assert record is not None
    force, accel = driver.fetch_time_records()
    assert force.data.dtype == np.complex128
    assert np.array_equal(force.data, record.force_n)
    assert np.array_equal(accel.data, record.acceleration_m_s2)
    for trace in (force, accel):
        h = trace.header
        assert (h.n_points, trace.data.shape, h.complex_data, h.time_domain) == (512, (512,), True, True)
        assert h.sample_rate_hz == record.sample_rate_hz == 1.28 * span
        assert math.isclose(h.start_x, record.start_s, rel_tol=1e-9, abs_tol=1e-12)
    frf, coh = driver.fetch_frf(), driver.fetch_coherence()
    assert np.array_equal(frf.data, analyzer.average.trace("FRSP"))
    assert np.array_equal(coh.data, analyzer.average.trace("COHR"))
    for trace in (frf, coh):
        assert trace.header.n_points == 401
        assert trace.header.start_x == center - span / 2
        assert math.isclose(trace.header.delta_x, span / 400, rel_tol=1e-12)
        assert math.isclose(trace.x[-1], center + span / 2, rel_tol=1e-12)


@pytest.mark.timeout(15)
def test_check_errors_raises_a_queued_scpi_error(driver: ScpiAnalyzer, bench: Bench) -> None:
    driver.check_errors()
    driver.send("SENS:FREQ:SPAN 1e9 HZ")
    assert driver.identify().startswith("HEWLETT-PACKARD,35670A")  # the analyzer has read it
    with pytest.raises(InstrumentError) as caught:
        driver.check_errors()
    assert caught.value.code == -222
    assert "Data out of range" in caught.value.instrument_message
    assert not bench.analyzer.errors
    assert driver.status().error is False


@pytest.mark.timeout(30)
def test_the_capture_workflow_runs_on_the_scpi_driver(driver: ScpiAnalyzer, bench: Bench) -> None:
    """daq/workflows/capture.py as the application drives it: preview, every hit accepted."""
    capture = Capture(driver, _settings(), hits_wanted=2, policy=lambda hit: (True, ""), hit_timeout_s=5.0)
    events = list(capture)
    hits = [e for e in events if isinstance(e, HitArrived)]
    assert len(hits) == 2
    assert hits[0].force_n.shape == (1024,)
    assert isinstance(events[-1], Finished)
    run = events[-1].run
    assert run.complete
    assert run.instrument.dialect == "SCPI"
    assert run.instrument.model == "HP 35670A"
    assert np.array_equal(run.analyzer.frf[0], bench.analyzer.average.trace("FRSP"))
    assert np.array_equal(run.analyzer.coherence[0], bench.analyzer.average.trace("COHR"))


@pytest.mark.timeout(15)
def test_the_35665a_offers_no_1600_lines() -> None:
    for bench in _bench("35665A", "tcp"):
        with open_analyzer(bench.resource, timeout_s=TIMEOUT_S) as drv:
            assert drv.dialect is SCPI
            with pytest.raises(InstrumentError) as caught:
                drv.configure(_settings(lines=1600, pre_trigger_s=None))
            assert caught.value.code == -224
            got = drv.configure(_settings(lines=800, pre_trigger_s=None))
            assert got.lines == 800


# ================================================================== 3562A, mnemonic dialect
@pytest.fixture(params=TRANSPORTS)
def bench_3562a(request) -> Iterator[Bench]:
    yield from _bench("3562A", request.param)


@pytest.mark.timeout(20)
def test_3562a_hit_by_hit_2048_sample_records_and_801_point_traces(bench_3562a: Bench) -> None:
    with open_analyzer(bench_3562a.resource, timeout_s=TIMEOUT_S) as drv:
        assert isinstance(drv, HPMnemonicAnalyzer)
        assert drv.dialect is HP3562A
        got = drv.configure(_settings(span_hz=150.0))
        assert got.span_hz == offered_span(150.0, 100_000.0) == 100_000.0 / 2**9
        assert got.lines == 800
        run_hits_and_compare(drv, bench_3562a.analyzer, samples=2048, lines=800, span=got.span_hz)


@pytest.mark.timeout(20)
def test_3562a_zoom_gives_1024_complex_samples(bench_3562a: Bench) -> None:
    analyzer = bench_3562a.analyzer
    with open_analyzer(bench_3562a.resource, timeout_s=TIMEOUT_S) as drv:
        span = offered_span(300.0, 100_000.0)
        drv.configure(_settings(span_hz=span, center_hz=1000.0, averages=1, preview=False))
        drv.start()
        assert drv.wait_until_done(timeout_s=5.0).done
        force, accel = drv.fetch_time_records()
        assert (force.header.n_points, force.header.complex_data) == (1024, True)
        assert np.array_equal(force.data, analyzer.last_record.force_n)
        assert np.array_equal(accel.data, analyzer.last_record.acceleration_m_s2)
        frf = drv.fetch_frf()
        assert frf.header.n_points == 801
        assert np.array_equal(frf.data, analyzer.average.trace("FRSP"))
        assert frf.header.start_x == 1000.0 - span / 2
