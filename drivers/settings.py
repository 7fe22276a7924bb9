"""Typed settings of an impact test, and the commands that apply them.

Units are SI; a channel's engineering unit (EU) is N for the hammer (channel 1)
and m/s^2 for the accelerometer (channel 2).
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from typing import Any

from drivers.commands import SETTINGS, command
from drivers.record import RECORD_LINES
from drivers.setting_table import SLOPES, TRIGGER_SOURCES, Window, write_steps

__all__ = ["ChannelSetup", "ImpactSettings", "Window"]

#: The fields of a channel, as the tables name them.
CHANNEL_FIELDS = ("window", "sensitivity_v_per_eu", "range_v", "force_width_s", "exp_decay_s", "ac_coupled")


#: Defaults that scale with the record (T = 400 / span), so that one setup suits
#: every span. The analyzer's decimating filters spread a hammer pulse shorter than a
#: sample over some ten samples on either side of it (docs/simulator.md,
#: "Anti-alias filtering and decimation"); a fixed 20 ms pre-trigger or 50 ms force
#: window is less than one sample at a 12.5 Hz span and cuts that spread off.
#: - pre-trigger T/32 (32 samples): the pulse's spread before the trigger;
#: - force window T/16 from the record's start: the pulse and its spread after it;
#: - exponential decay T/6: the response falls to e^-6 = 0.25 % by the record's end.
#: Measured (bench/sim_frf_accuracy.py): the simulated FRF is then the window-corrected
#: model within 0.5 % from 3.125 Hz to 200 Hz spans, baseband and zoom.
PRE_TRIGGER_PER_RECORD = 1 / 32
FORCE_WIDTH_PER_RECORD = 1 / 16
EXP_DECAY_PER_RECORD = 1 / 6


def _positive(name: str, value: float) -> None:
    if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
        raise ValueError(f"{name} must be a positive number, got {value!r}")


@dataclass(frozen=True)
class ChannelSetup:
    """One input: its window (with parameters), range, coupling and transducer.

    sensitivity_v_per_eu : V per N (hammer) or V per m/s^2 (accelerometer).
    range_v : full-scale peak input voltage; None = autorange.
    force_width_s : width of the force window from the start of the record, s;
        None = FORCE_WIDTH_PER_RECORD of the record (set by ImpactSettings).
    exp_decay_s : time constant of the exponential window, s; None =
        EXP_DECAY_PER_RECORD of the record (set by ImpactSettings).
    """

    window: Window
    sensitivity_v_per_eu: float
    range_v: float | None = 1.0
    force_width_s: float | None = None
    exp_decay_s: float | None = None
    ac_coupled: bool = False

    def __post_init__(self) -> None:
        object.__setattr__(self, "window", Window(self.window))
        _positive("sensitivity_v_per_eu", self.sensitivity_v_per_eu)
        if self.range_v is not None:
            _positive("range_v", self.range_v)
        if self.force_width_s is not None:
            _positive("force_width_s", self.force_width_s)
        if self.exp_decay_s is not None:
            _positive("exp_decay_s", self.exp_decay_s)

    def for_record(self, record_s: float) -> ChannelSetup:
        """This setup with the windows it leaves open sized to a record of ``record_s``."""
        return replace(
            self,
            force_width_s=FORCE_WIDTH_PER_RECORD * record_s
            if self.force_width_s is None
            else self.force_width_s,
            exp_decay_s=EXP_DECAY_PER_RECORD * record_s if self.exp_decay_s is None else self.exp_decay_s,
        )


def _hammer() -> ChannelSetup:
    # PCB 086C03-like hammer, 2.25 mV/N; the force window keeps the pulse only.
    return ChannelSetup(Window.FORCE, 2.25e-3, range_v=0.02)


def _accelerometer() -> ChannelSetup:
    # 10 mV/g = 1.02 mV/(m/s^2); a tap at the tip of the light beam peaks near
    # 1000 m/s^2 before the anti-alias filter, hence 1 V. An exponential window makes
    # the response decay within the record (it adds known damping: 1/exp_decay_s, rad/s).
    return ChannelSetup(Window.EXPONENTIAL, 1.02e-3, range_v=1.0)


@dataclass(frozen=True)
class ImpactSettings:
    """An impact test on the HP 35660A.

    span_hz : frequency span (the analyzer rounds up to 102.4 kHz / 2^n).
    center_hz : None for baseband (0 to span); otherwise a zoom around it.
    trigger_level_eu : level in the trigger channel's unit (N for CH1).
    pre_trigger_s : how much of the record comes before the trigger, s (<= one record);
        None = PRE_TRIGGER_PER_RECORD of the record.
    Window widths and the pre-trigger left as None are sized to the record on
    construction, so every field of a constructed ImpactSettings holds a number.
    averages : hits averaged (stable averaging).
    preview : every hit waits to be accepted or rejected.
    lines : the resolution, lines (None: the analyzer's own; the 35660A offers 400, the
        3562A 800, the 35665A/35670A 100 to 1600). The record lasts lines / span.
    """

    span_hz: float = 200.0
    center_hz: float | None = None
    hammer: ChannelSetup = field(default_factory=_hammer)
    accelerometer: ChannelSetup = field(default_factory=_accelerometer)
    trigger_source: str = "CH1"
    trigger_level_eu: float = 1.0
    trigger_slope: str = "POS"
    pre_trigger_s: float | None = None
    averages: int = 5
    preview: bool = True
    lines: int | None = None
    #: Which of the fields sized to the record were left to their default, so that
    #: ``with_lines`` can size them again for another record (not part of the settings).
    defaulted: frozenset[str] = field(default=frozenset(), compare=False, repr=False)

    def __post_init__(self) -> None:
        _positive("span_hz", self.span_hz)
        if self.lines is not None and not (
            isinstance(self.lines, numbers.Integral) and not isinstance(self.lines, bool) and self.lines > 0
        ):
            raise ValueError(f"lines must be a positive integer, got {self.lines!r}")
        left = {
            f"{name}.{part}"
            for name in ("hammer", "accelerometer")
            for part in ("force_width_s", "exp_decay_s")
            if getattr(getattr(self, name), part) is None
        }
        if self.pre_trigger_s is None:
            left.add("pre_trigger_s")
        object.__setattr__(self, "defaulted", frozenset(self.defaulted | left))
        if self.center_hz is not None and not (
            math.isfinite(self.center_hz) and self.center_hz >= self.span_hz / 2 * (1 - 1e-12)
        ):
            raise ValueError(f"center_hz must be at least span/2 = {self.span_hz / 2:g} Hz")
        if self.trigger_source not in TRIGGER_SOURCES:
            raise ValueError(
                f"trigger_source must be one of {', '.join(TRIGGER_SOURCES)}, got {self.trigger_source!r}"
            )
        if self.trigger_slope not in SLOPES:
            raise ValueError(f"trigger_slope must be one of {', '.join(SLOPES)}, got {self.trigger_slope!r}")
        if not math.isfinite(self.trigger_level_eu):
            raise ValueError("trigger_level_eu must be finite")
        record_s = self.record_length_s
        object.__setattr__(self, "hammer", self.hammer.for_record(record_s))
        object.__setattr__(self, "accelerometer", self.accelerometer.for_record(record_s))
        if self.pre_trigger_s is None:
            object.__setattr__(self, "pre_trigger_s", PRE_TRIGGER_PER_RECORD * record_s)
        if not (math.isfinite(self.pre_trigger_s) and 0 <= self.pre_trigger_s <= self.record_length_s):
            raise ValueError(f"pre_trigger_s must be 0..{self.record_length_s:g} s (one record)")
        if not (isinstance(self.averages, numbers.Integral) and 1 <= self.averages <= 9999):
            raise ValueError(f"averages must be an integer 1..9999, got {self.averages!r}")
        object.__setattr__(self, "averages", int(self.averages))

    @property
    def record_length_s(self) -> float:
        """Length of one time record, s: lines / span (400 lines when none is named)."""
        return (self.lines or RECORD_LINES) / self.span_hz

    def with_lines(self, lines: int) -> ImpactSettings:
        """These settings at ``lines`` lines (see ``sized_for``)."""
        return self.sized_for(lines, self.span_hz)

    def sized_for(self, lines: int, span_hz: float) -> ImpactSettings:
        """These settings at ``lines`` lines and ``span_hz``, the windows and pre-trigger
        that were left to their defaults sized again to the new record (lines / span):
        e.g. to the span an analyzer made of the one asked for."""
        if lines == self.lines and span_hz == self.span_hz:
            return self

        def again(name: str) -> ChannelSetup:
            setup = getattr(self, name)
            return replace(
                setup,
                force_width_s=None if f"{name}.force_width_s" in self.defaulted else setup.force_width_s,
                exp_decay_s=None if f"{name}.exp_decay_s" in self.defaulted else setup.exp_decay_s,
            )

        return replace(
            self,
            span_hz=span_hz,
            lines=lines,
            hammer=again("hammer"),
            accelerometer=again("accelerometer"),
            pre_trigger_s=None if "pre_trigger_s" in self.defaulted else self.pre_trigger_s,
        )

    @property
    def trigger_level_v(self) -> float:
        channel = self.accelerometer if self.trigger_source == "CH2" else self.hammer
        return self.trigger_level_eu * channel.sensitivity_v_per_eu

    def wire_fields(self, actual_span_hz: float | None = None) -> tuple[dict[str, Any], dict[int, dict]]:
        """These settings as the analyzer holds them, by the names of the command tables'
        rows (drivers/setting_table.py): the measurement's fields and each channel's.

        ``actual_span_hz`` is the span the analyzer made of ours (it rounds up to
        102.4 kHz / 2^n); at baseband the center must be half of that one.
        """
        span = self.span_hz if actual_span_hz is None else actual_span_hz
        fields = {
            "span_hz": self.span_hz,
            "center_hz": self.center_hz if self.center_hz is not None else span / 2,
            "lines": self.lines,
            "trigger_source": self.trigger_source,
            "trigger_level_v": self.trigger_level_v,
            "trigger_slope": self.trigger_slope,
            "trigger_delay_s": -self.pre_trigger_s,
            "averages": self.averages,
            "preview": self.preview,
        }
        channels = {
            ch: {name: getattr(setup, name) for name in CHANNEL_FIELDS}
            for ch, setup in ((1, self.hammer), (2, self.accelerometer))
        }
        return fields, channels

    @classmethod
    def from_fields(
        cls,
        fields: Mapping[str, Any],
        channels: Mapping[int, Mapping[str, Any]],
        lines: int,
        baseband: Callable[[float, float], bool],
    ) -> ImpactSettings:
        """The settings an analyzer holds, from the fields its table read back
        (``wire_fields``' names); ``baseband(span, center)`` tells a zoom from baseband."""
        hammer, accelerometer = (
            ChannelSetup(
                window=Window(channels[ch]["window"]),
                sensitivity_v_per_eu=float(channels[ch]["sensitivity_v_per_eu"]),
                range_v=None if channels[ch]["range_v"] is None else float(channels[ch]["range_v"]),
                force_width_s=float(channels[ch]["force_width_s"]),
                exp_decay_s=float(channels[ch]["exp_decay_s"]),
                ac_coupled=bool(channels[ch]["ac_coupled"]),
            )
            for ch in (1, 2)
        )
        span, center = float(fields["span_hz"]), float(fields["center_hz"])
        source = str(fields["trigger_source"])
        trigger_channel = accelerometer if source == "CH2" else hammer
        return cls(
            span_hz=span,
            center_hz=None if baseband(span, center) else center,
            hammer=hammer,
            accelerometer=accelerometer,
            trigger_source=source,
            trigger_level_eu=float(fields["trigger_level_v"]) / trigger_channel.sensitivity_v_per_eu,
            trigger_slope=str(fields["trigger_slope"]),
            pre_trigger_s=max(0.0, -float(fields["trigger_delay_s"])),
            averages=int(fields["averages"]),
            preview=bool(fields["preview"]),
            lines=lines,
        )

    def commands(self, actual_span_hz: float | None = None) -> list[bytes]:
        """The HP mnemonic messages that apply these settings, in order (drivers/commands.py
        ``SETTINGS``); ``actual_span_hz`` as in ``wire_fields``."""
        return [
            command(mnemonic.format(ch=ch), value)
            for mnemonic, value, ch in write_steps(SETTINGS, *self.wire_fields(actual_span_hz))
        ]
