"""Practice hits: find the input ranges and the trigger level from a few hits before
the real ones (docs/setups.md, "Auto-range").

The analyzer is set up with the setup's transducers, windows and trigger, but with
both inputs at its largest range, so that no practice hit overloads, and at its widest
span: the input range and the overload detector see the signal before the anti-alias
and decimating filters, and at a low span those filters lower a short hammer pulse's
recorded peak to a fraction of what the input saw (at 200 Hz on the simulator, about
half), so a range chosen from a low span's record would overload. At the widest span
the record keeps the pulse whole. Each hit is read (its peak force and response) and
rejected, so none enters an average or a run. Then:

* each channel's range is the smallest of the analyzer's input ranges at or above
  1.5 x the largest practice peak on that input, in volts (peak EU x sensitivity);
* the trigger level is 10 % of the smallest practice peak force.

Like the capture, this module never prints or prompts.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from daq.workflows.errors import WorkflowError
from daq.workflows.setups import analyzer_ranges_v, max_span_hz, validate_for_model
from drivers.analyzer import SignalAnalyzer
from drivers.dialects import model_of
from drivers.settings import ChannelSetup, ImpactSettings

#: Headroom of a chosen range over the largest practice peak.
RANGE_MARGIN = 1.5
#: The trigger level, as a fraction of the weakest practice hit's peak force.
TRIGGER_FRACTION = 0.10


@dataclass(frozen=True)
class AutoRange:
    """What the practice hits found.

    peaks_force_n, peaks_response_m_s2 : each practice hit's peak |force| (N) and
    |response| (m/s^2), in order. hammer_range_v, accelerometer_range_v : the ranges
    chosen, V peak. trigger_level_eu : the trigger level chosen, N (CH1) or m/s^2 (CH2).
    settings : the setup's settings with those ranges and that level. setup_settings :
    the setup's own settings, None when not known.
    """

    peaks_force_n: list[float]
    peaks_response_m_s2: list[float]
    hammer_range_v: float
    accelerometer_range_v: float
    trigger_level_eu: float
    settings: ImpactSettings
    setup_settings: ImpactSettings | None = None

    def record(self) -> dict[str, object]:
        """What a run captured with these ranges stores as ``provenance["auto_range"]``:
        practice_hits, peaks_force_n, hammer_range_v, accelerometer_range_v,
        trigger_level_eu, and ``setup`` the setup's own values of the last three (a
        range None: "auto"), so that the run says what it changed."""
        record: dict[str, object] = {
            "practice_hits": len(self.peaks_force_n),
            "peaks_force_n": list(self.peaks_force_n),
            "hammer_range_v": self.hammer_range_v,
            "accelerometer_range_v": self.accelerometer_range_v,
            "trigger_level_eu": self.trigger_level_eu,
        }
        if self.setup_settings is not None:
            own = self.setup_settings
            record["setup"] = {
                "hammer_range_v": own.hammer.range_v,
                "accelerometer_range_v": own.accelerometer.range_v,
                "trigger_level_eu": own.trigger_level_eu,
            }
        return record

    def to_dict(self) -> dict[str, object]:
        return {
            "hits_taken": len(self.peaks_force_n),
            "peaks_force_n": list(self.peaks_force_n),
            "peaks_response_m_s2": list(self.peaks_response_m_s2),
            "hammer_range_v": self.hammer_range_v,
            "accelerometer_range_v": self.accelerometer_range_v,
            "trigger_level_eu": self.trigger_level_eu,
        }


def range_for(peak_v: float, ranges_v: tuple[float, ...]) -> float:
    """The smallest of ``ranges_v`` at or above RANGE_MARGIN x ``peak_v``; WorkflowError
    when even the largest is too small."""
    want = RANGE_MARGIN * peak_v
    for candidate in ranges_v:
        if candidate >= want * (1 - 1e-9):
            return candidate
    raise WorkflowError(
        f"a practice hit peaked at {peak_v:.3g} V: above what the analyzer's largest range "
        f"({ranges_v[-1]:.3g} V) holds with a {RANGE_MARGIN:g} x margin; hit softer or use a "
        "less sensitive transducer"
    )


def choose(
    settings: ImpactSettings, peaks_force_n: list[float], peaks_response_m_s2: list[float], model: str
) -> AutoRange:
    """The ranges and trigger level for ``settings`` from practice peaks (EU) on ``model``."""
    if not peaks_force_n:
        raise WorkflowError("no practice hit was taken")
    ranges = analyzer_ranges_v(model)
    hammer_v = range_for(max(peaks_force_n) * settings.hammer.sensitivity_v_per_eu, ranges)
    accel_v = range_for(max(peaks_response_m_s2) * settings.accelerometer.sensitivity_v_per_eu, ranges)
    if settings.trigger_source == "CH2":
        level = TRIGGER_FRACTION * min(peaks_response_m_s2)
    else:
        level = TRIGGER_FRACTION * min(peaks_force_n)
    chosen = replace(
        settings,
        hammer=replace(settings.hammer, range_v=hammer_v),
        accelerometer=replace(settings.accelerometer, range_v=accel_v),
        trigger_level_eu=float(f"{level:.3g}"),
    )
    return AutoRange(
        list(peaks_force_n),
        list(peaks_response_m_s2),
        hammer_v,
        accel_v,
        chosen.trigger_level_eu,
        chosen,
        settings,
    )


def practice_hits(
    driver: SignalAnalyzer,
    settings: ImpactSettings,
    n_hits: int,
    timeout_s: float | None = None,
    on_hit=None,
) -> AutoRange:
    """Take ``n_hits`` practice hits with ``driver`` (each waited for up to
    ``timeout_s``; None: the driver's allowance), reject them all, and choose the
    ranges and trigger level for ``settings``. ``on_hit(index, peak_force_n,
    peak_response_m_s2)``, when given, is called after each hit (a display).

    Before any hit, WorkflowError naming the field when the analyzer's model cannot
    measure ``settings`` (validate_for_model), or when the trigger level is beyond
    what even the largest range reaches (no practice hit could ever trigger)."""
    if not 1 <= n_hits <= 100:
        raise WorkflowError(f"practice hits: must be 1..100, got {n_hits}")
    model = model_of(driver.dialect, driver.identify())
    # The setup first: one the analyzer cannot measure is refused before any practice hit.
    validate_for_model(settings, model)
    largest = analyzer_ranges_v(model)[-1]
    practice = ImpactSettings(
        span_hz=max_span_hz(model),
        hammer=ChannelSetup(settings.hammer.window, settings.hammer.sensitivity_v_per_eu, largest),
        accelerometer=ChannelSetup(
            settings.accelerometer.window, settings.accelerometer.sensitivity_v_per_eu, largest
        ),
        trigger_source=settings.trigger_source,
        trigger_level_eu=settings.trigger_level_eu,
        trigger_slope=settings.trigger_slope,
        averages=n_hits,
        preview=True,
    )
    # And a trigger level the largest range cannot reach (a setup whose ranges are
    # "auto"): the practice hits would wait for a trigger that never comes.
    try:
        validate_for_model(practice, model)
    except WorkflowError as exc:
        raise WorkflowError(f"{exc} (at the largest range the practice hits use)") from None
    try:
        driver.configure(practice)
    except ValueError as exc:
        raise WorkflowError(f"{driver.dialect.name} analyzer: {exc}") from None
    driver.start()
    forces: list[float] = []
    responses: list[float] = []
    for index in range(n_hits):
        driver.wait_for_hit(timeout_s=timeout_s)
        force, response = driver.fetch_time_records()
        forces.append(float(np.max(np.abs(force.data))))
        responses.append(float(np.max(np.abs(response.data))))
        driver.reject()
        if on_hit is not None:
            on_hit(index, forces[-1], responses[-1])
    return choose(settings, forces, responses, model)
