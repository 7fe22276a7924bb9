"""The HP 35660A driver end to end against the simulated analyzer, over both wires:
TCP (pyvisa-py ``TCPIP::127.0.0.1::<port>::SOCKET``) and the Prologix pty
(``PROLOGIX::<pty>::11`` through pyserial).

Every number the driver returns is compared with what the simulator generated
(its ``Analyzer`` object: ``last_record`` for time records, ``average`` for the
averaged traces, ``settings`` for what it holds), bit for bit in float64; the
rounding rules of the read-back settings are computed here from the
instrument's offer (102.4 kHz / 2^n spans, 1 dB input ranges).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
import pytest

from drivers.errors import InstrumentError, ResourceBusy
from drivers.hp_mnemonic import HPMnemonicAnalyzer as HP35660A
from drivers.settings import ChannelSetup, ImpactSettings, Window
from sims.instrument import Analyzer
from sims.prologix import PrologixPty
from sims.sources import PhysicsSource
from sims.tcp_server import TcpServer

TRANSPORTS = ("tcp", "prologix")
#: Driver I/O timeout: the simulator answers at once, so a short one only bounds failures.
TIMEOUT_S = 2.0


# ------------------------------------------------------------------ expectations
def offered_span(requested_hz: float) -> float:
    """The smallest 102.4 kHz / 2^n span at or above the request."""
    return min(s for s in (102_400.0 / 2**n for n in range(20)) if s >= requested_hz)


def offered_range(requested_v: float) -> float:
    """The smallest 1 dB step (10^(dB/20) V) at or above the request."""
    return 10.0 ** (math.ceil(20.0 * math.log10(requested_v) - 1e-9) / 20.0)


# ------------------------------------------------------------------ fixtures
@dataclass
class Bench:
    analyzer: Analyzer
    resource: str


@pytest.fixture(autouse=True)
def _lock_dir(monkeypatch: pytest.MonkeyPatch, tmp_path) -> None:
    monkeypatch.setenv("DAQ_LOCK_DIR", str(tmp_path))


@pytest.fixture(params=TRANSPORTS)
def bench(request) -> Iterator[Bench]:
    analyzer = Analyzer(PhysicsSource("seed", seed=7), time_scale=0.0)
    if request.param == "tcp":
        with TcpServer(analyzer, port=0) as server:
            yield Bench(analyzer, server.resource)
    else:
        with PrologixPty(analyzer, 11) as pty:
            yield Bench(analyzer, f"PROLOGIX::{pty.port}::11")


@pytest.fixture
def driver(bench: Bench) -> Iterator[HP35660A]:
    with HP35660A.open(bench.resource, timeout_s=TIMEOUT_S) as drv:
        yield drv


def _hammer(range_v: float | None = 0.02) -> ChannelSetup:
    return ChannelSetup(Window.FORCE, 2.25e-3, range_v=range_v, force_width_s=0.05)


def _accelerometer(range_v: float | None = 0.5) -> ChannelSetup:
    return ChannelSetup(Window.EXPONENTIAL, 1.02e-3, range_v=range_v, exp_decay_s=0.5)


# ------------------------------------------------------------------ tests
@pytest.mark.timeout(10)
def test_identify(driver: HP35660A) -> None:
    assert driver.identify() == "HP35660A"


@pytest.mark.timeout(10)
def test_configure_rounds_ranges_up_to_1_db_steps_and_reads_everything_back(
    driver: HP35660A, bench: Bench
) -> None:
    wanted = ImpactSettings(
        span_hz=400.0,
        hammer=ChannelSetup(Window.FORCE, 2.25e-3, range_v=0.02, force_width_s=0.04, ac_coupled=True),
        accelerometer=ChannelSetup(Window.EXPONENTIAL, 1.02e-3, range_v=0.5, exp_decay_s=0.25),
        trigger_source="CH1",
        trigger_level_eu=2.0,
        trigger_slope="POS",
        pre_trigger_s=0.05,
        averages=4,
        preview=True,
    )
    got = driver.configure(wanted)

    # 0.02 V is -33.98 dBV -> -33 dBV; 0.5 V is -6.02 dBV -> -6 dBV.
    assert offered_range(0.02) == 10 ** (-33 / 20)
    assert offered_range(0.5) == 10 ** (-6 / 20)
    assert math.isclose(got.hammer.range_v, offered_range(0.02), rel_tol=1e-9)
    assert math.isclose(got.accelerometer.range_v, offered_range(0.5), rel_tol=1e-9)
    assert got.hammer.range_v > 0.02
    assert got.accelerometer.range_v > 0.5
    # What the simulator holds is what the driver read back.
    s = bench.analyzer.settings
    assert math.isclose(s.range1_v, offered_range(0.02), rel_tol=1e-12)
    assert math.isclose(s.range2_v, offered_range(0.5), rel_tol=1e-12)
    assert s.span_hz == 400.0
    assert s.center_hz == 200.0

    assert got.span_hz == 400.0
    assert got.center_hz is None
    assert got.hammer.window is Window.FORCE
    assert got.accelerometer.window is Window.EXPONENTIAL
    assert math.isclose(got.hammer.force_width_s, 0.04, rel_tol=1e-9)
    assert math.isclose(got.accelerometer.exp_decay_s, 0.25, rel_tol=1e-9)
    assert math.isclose(got.hammer.sensitivity_v_per_eu, 2.25e-3, rel_tol=1e-9)
    assert math.isclose(got.accelerometer.sensitivity_v_per_eu, 1.02e-3, rel_tol=1e-9)
    assert got.hammer.ac_coupled is True
    assert got.accelerometer.ac_coupled is False
    assert got.trigger_source == "CH1"
    assert got.trigger_slope == "POS"
    assert math.isclose(got.trigger_level_eu, 2.0, rel_tol=1e-9)
    assert math.isclose(got.pre_trigger_s, 0.05, rel_tol=1e-9)
    assert got.averages == 4
    assert got.preview is True
    assert s.n_averages == 4
    assert s.averaging == "STBL"
    assert s.preview == 1


@pytest.mark.timeout(10)
def test_configure_autorange_reads_back_as_none(driver: HP35660A, bench: Bench) -> None:
    wanted = ImpactSettings(span_hz=200.0, hammer=_hammer(None), accelerometer=_accelerometer())
    got = driver.configure(wanted)
    assert got.hammer.range_v is None
    assert math.isclose(got.accelerometer.range_v, offered_range(0.5), rel_tol=1e-9)
    assert bench.analyzer.settings.autorange1 == 1
    assert bench.analyzer.settings.autorange2 == 0


@pytest.mark.timeout(10)
@pytest.mark.parametrize(
    ("requested_hz", "center_hz"),
    [
        pytest.param(150.0, None, id="baseband"),
        pytest.param(300.0, 1000.0, id="zoom"),
    ],
)
def test_configure_rounds_the_span_up_to_an_offered_span(
    driver: HP35660A, bench: Bench, requested_hz: float, center_hz: float | None
) -> None:
    """The analyzer offers 102.4 kHz / 2^n spans; configure() promises the rounded one.

    Baseband with a span it does not offer fails today (see the report): the driver
    sends ``CF <requested span / 2>`` after ``FRS``, which the analyzer has already
    rounded up, so the center lies below the new span/2 and is refused.
    """
    expected = offered_span(requested_hz)
    assert expected == (200.0 if requested_hz == 150.0 else 400.0)
    got = driver.configure(
        ImpactSettings(span_hz=requested_hz, center_hz=center_hz, pre_trigger_s=0.01, averages=1)
    )
    assert got.span_hz == expected
    assert bench.analyzer.settings.span_hz == expected
    if center_hz is None:
        assert got.center_hz is None
        assert bench.analyzer.settings.center_hz == expected / 2
    else:
        assert got.center_hz == center_hz
        assert bench.analyzer.settings.center_hz == center_hz


@pytest.mark.timeout(15)
def test_hit_by_hit_time_records_accept_reject_and_averaged_traces(driver: HP35660A, bench: Bench) -> None:
    analyzer = bench.analyzer
    span, pre = 200.0, 0.02
    driver.configure(
        ImpactSettings(
            span_hz=span,
            hammer=_hammer(),
            accelerometer=_accelerometer(),
            trigger_level_eu=1.0,
            pre_trigger_s=pre,
            averages=2,
            preview=True,
        )
    )
    driver.start()
    assert analyzer.average.count == 0

    fs = 2.56 * span
    seen_forces: list[np.ndarray] = []
    for decision, count_after in (("accept", 1), ("reject", 1), ("accept", 2)):
        status = driver.wait_for_hit(timeout_s=5.0)
        assert status.hit_pending
        assert analyzer.state == "pending"
        record = analyzer.last_record
        assert record is not None
        expected_force = record.force_n.copy()
        expected_accel = record.acceleration_m_s2.copy()

        force, accel = driver.fetch_time_records()
        assert force.data.dtype == np.float64
        assert accel.data.dtype == np.float64
        assert np.array_equal(force.data, expected_force)
        assert np.array_equal(accel.data, expected_accel)
        # A new hit each time, not the previous record again.
        assert not any(np.array_equal(expected_force, old) for old in seen_forces)
        seen_forces.append(expected_force)
        for trace, channel, units in ((force, 1, "N"), (accel, 2, "m/s^2")):
            h = trace.header
            assert h.display_function == f"TIM{channel}"
            assert h.channel == channel
            assert h.y_units == units
            assert h.n_points == 1024
            assert trace.data.shape == (1024,)
            assert h.time_domain is True
            assert h.x_units == "s"
            assert h.complex_data is False
            assert h.sample_rate_hz == fs
            assert h.delta_x == 1 / fs
            assert abs(h.start_x - (-pre)) <= 1 / fs
            assert h.n_averages == analyzer.average.count

        getattr(driver, decision)()
        assert analyzer.average.count == count_after
        assert driver.averages_done() == count_after

    status = driver.wait_until_done(timeout_s=5.0)
    assert status.done
    assert analyzer.state == "done"
    assert not analyzer.errors

    frf = driver.fetch_frf()
    assert np.array_equal(frf.data, analyzer.average.trace("FRSP"))
    assert frf.data.dtype == np.complex128
    coh = driver.fetch_coherence()
    assert np.array_equal(coh.data, analyzer.average.trace("COHR"))
    assert coh.data.dtype == np.float64
    lsp1, lsp2 = driver.fetch_linear_spectra()
    assert np.array_equal(lsp1.data, analyzer.average.trace("LSP1"))
    assert np.array_equal(lsp2.data, analyzer.average.trace("LSP2"))

    for trace, function, channel, is_complex in (
        (frf, "FRSP", 3, True),
        (coh, "COHR", 3, False),
        (lsp1, "LSP1", 1, True),
        (lsp2, "LSP2", 2, True),
    ):
        h = trace.header
        assert h.display_function == function
        assert h.channel == channel
        assert h.n_points == 401
        assert trace.data.shape == (401,)
        assert h.complex_data is is_complex
        assert h.time_domain is False
        assert h.x_units == "Hz"
        assert h.n_averages == 2
        assert h.start_x == 0.0
        assert h.delta_x == span / 400
        assert trace.x[-1] == span
    assert frf.header.y_units == "(m/s^2)/N"
    assert lsp1.header.y_units == "N"
    assert lsp2.header.y_units == "m/s^2"
    assert np.all((coh.data >= 0.0) & (coh.data <= 1.0 + 1e-12))


@pytest.mark.timeout(10)
def test_zoom_gives_512_complex_time_points_and_lines_from_center_minus_half_span(
    driver: HP35660A, bench: Bench
) -> None:
    analyzer = bench.analyzer
    span, center = 400.0, 1000.0
    got = driver.configure(
        ImpactSettings(span_hz=span, center_hz=center, pre_trigger_s=0.02, averages=1, preview=False)
    )
    assert got.center_hz == center
    assert got.span_hz == span
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
        assert h.n_points == 512
        assert trace.data.shape == (512,)
        assert h.complex_data is True
        assert h.time_domain is True
        # 512 complex points in the same 400/span record: 1.28 x span.
        assert h.sample_rate_hz == 1.28 * span
        assert abs(h.start_x + 0.02) <= 1 / h.sample_rate_hz

    frf = driver.fetch_frf()
    assert np.array_equal(frf.data, analyzer.average.trace("FRSP"))
    assert frf.header.n_points == 401
    assert frf.header.start_x == center - span / 2
    assert frf.header.delta_x == span / 400
    assert frf.x[-1] == center + span / 2
    coh = driver.fetch_coherence()
    assert np.array_equal(coh.data, analyzer.average.trace("COHR"))
    assert coh.header.start_x == center - span / 2


@pytest.mark.timeout(10)
def test_send_and_query_raw(driver: HP35660A, bench: Bench) -> None:
    driver.send("FRS 800 HZ")
    # send() returns once the bytes are out; a query's reply proves the analyzer has them.
    assert float(driver.query("FRS?")) == 800.0
    assert bench.analyzer.settings.span_hz == 800.0
    driver.send("NAVG 7;TSLP NEG")
    assert driver.query("NAVG?") == "7"
    assert driver.query("TSLP?") == "NEG"
    assert bench.analyzer.settings.n_averages == 7
    assert bench.analyzer.settings.trigger_slope == "NEG"
    assert driver.query("ID?") == "HP35660A"
    assert driver.query_values("FRS?", 1) == [800.0]


@pytest.mark.timeout(10)
def test_check_errors_raises_for_a_queued_instrument_error(driver: HP35660A, bench: Bench) -> None:
    driver.check_errors()  # nothing queued
    driver.send("FOO")
    assert driver.query("ID?") == "HP35660A"  # the analyzer has read FOO by now
    assert len(bench.analyzer.errors) == 1
    with pytest.raises(InstrumentError) as caught:
        driver.check_errors()
    assert caught.value.code == 1
    assert "FOO" in caught.value.instrument_message
    assert not bench.analyzer.errors  # drained
    driver.check_errors()


@pytest.mark.timeout(10)
def test_a_second_driver_on_the_same_resource_is_refused(bench: Bench) -> None:
    with HP35660A.open(bench.resource, timeout_s=TIMEOUT_S) as first:
        with pytest.raises(ResourceBusy):
            HP35660A.open(bench.resource, timeout_s=TIMEOUT_S)
        assert first.identify() == "HP35660A"  # the refusal did not disturb the holder
    with HP35660A.open(bench.resource, timeout_s=TIMEOUT_S) as again:
        assert again.identify() == "HP35660A"
