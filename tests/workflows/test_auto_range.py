"""Practice hits (daq/workflows/auto_range.py) on the simulator: the ranges chosen hold
the peaks, the trigger level is 10 % of the weakest practice hit, and a capture with
them sees no overload."""

from __future__ import annotations

import contextlib

import pytest

from daq.workflows.auto_range import RANGE_MARGIN, choose, practice_hits
from daq.workflows.capture import Capture, HitArrived
from daq.workflows.connect import open_analyzer, serve_simulator, simulator_source
from daq.workflows.errors import WorkflowError
from daq.workflows.setups import analyzer_ranges_v
from drivers.settings import ChannelSetup, ImpactSettings, Window


@pytest.mark.parametrize("model", ["35660A", "35670A"])
def test_practice_hits_choose_ranges_that_hold_the_peaks(model):
    settings = ImpactSettings()
    with contextlib.ExitStack() as stack:
        resource = serve_simulator(stack, simulator_source("realistic", 5), 0.0, model)
        dsa = stack.enter_context(open_analyzer(resource))
        found = practice_hits(dsa, settings, 3, timeout_s=10.0)
        ranges = analyzer_ranges_v(model)
        for peaks, channel, chosen in (
            (found.peaks_force_n, settings.hammer, found.hammer_range_v),
            (found.peaks_response_m_s2, settings.accelerometer, found.accelerometer_range_v),
        ):
            peak_v = max(peaks) * channel.sensitivity_v_per_eu
            assert chosen in ranges
            assert chosen >= RANGE_MARGIN * peak_v
            assert ranges.index(chosen) == 0 or ranges[ranges.index(chosen) - 1] < RANGE_MARGIN * peak_v
        assert len(found.peaks_force_n) == 3
        assert found.trigger_level_eu == pytest.approx(0.1 * min(found.peaks_force_n), rel=1e-2)
        assert found.settings.hammer.range_v == found.hammer_range_v
        job = Capture(dsa, found.settings, 3, max_hits=6)
        hits = [e for e in job if isinstance(e, HitArrived)]
    assert hits
    assert not any(any(h.overload) for h in hits)
    assert all(h.passed for h in hits), [h.suggested_reason for h in hits]


def test_a_peak_beyond_the_largest_range_is_refused():
    with pytest.raises(WorkflowError, match="above what the analyzer's largest range"):
        choose(ImpactSettings(), [20_000.0], [1.0], "35660A")


class _NoHits:
    """The analyzer, but any attempt to set it up or wait for a hit fails the test."""

    def __init__(self, driver):
        self._driver = driver

    def __getattr__(self, name):
        if name in ("configure", "start", "wait_for_hit", "fetch_time_records"):
            raise AssertionError(f"{name} called before the setup was checked")
        return getattr(self._driver, name)


@pytest.mark.parametrize(
    ("settings", "message"),
    [
        (ImpactSettings(trigger_level_eu=1000.0), r"^trigger_level_eu: 1000 N is above the hammer's range"),
        (ImpactSettings(lines=800), r"^lines: the 35660A offers 400 lines only, not 800$"),
        # Ranges "auto": the setup passes, but 20 kN is beyond even the largest range
        # (22.4 V / 2.25 mV/N = 9.96 kN): the practice hits would wait for ever.
        (
            ImpactSettings(
                trigger_level_eu=20_000.0,
                hammer=ChannelSetup(Window.FORCE, 2.25e-3, range_v=None),
            ),
            r"^trigger_level_eu: 20000 N is above the hammer's range .*\(at the largest range",
        ),
    ],
)
def test_a_setup_the_analyzer_cannot_measure_is_refused_before_any_practice_hit(settings, message):
    with contextlib.ExitStack() as stack:
        resource = serve_simulator(stack, simulator_source("realistic", 5), 0.0, "35660A")
        dsa = stack.enter_context(open_analyzer(resource))
        with pytest.raises(WorkflowError, match=message):
            practice_hits(_NoHits(dsa), settings, 2, timeout_s=60.0)


def test_the_record_a_run_keeps_says_what_was_chosen_and_what_the_setup_had():
    found = choose(ImpactSettings(), [5.0, 4.0], [100.0, 90.0], "35660A")
    record = found.record()
    assert set(record) == {
        "practice_hits", "peaks_force_n", "hammer_range_v", "accelerometer_range_v", "trigger_level_eu",
        "setup",
    }  # fmt: skip
    assert record["practice_hits"] == 2
    assert record["trigger_level_eu"] == pytest.approx(0.4)
    assert record["setup"] == {"hammer_range_v": 0.02, "accelerometer_range_v": 1.0, "trigger_level_eu": 1.0}
