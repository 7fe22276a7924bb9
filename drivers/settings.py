"""Typed settings of an impact test, and the commands that apply them.

Units are SI; a channel's engineering unit (EU) is N for the hammer (channel 1)
and m/s^2 for the accelerometer (channel 2).
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field
from enum import StrEnum

from drivers.commands import command

RECORD_LINES = 400


class Window(StrEnum):
    UNIFORM = "UNIF"
    HANNING = "HANN"
    FLAT_TOP = "FLAT"
    FORCE = "FORC"
    EXPONENTIAL = "EXPO"


def _positive(name: str, value: float) -> None:
    if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
        raise ValueError(f"{name} must be a positive number, got {value!r}")


@dataclass(frozen=True)
class ChannelSetup:
    """One input: its window (with parameters), range, coupling and transducer.

    sensitivity_v_per_eu : V per N (hammer) or V per m/s^2 (accelerometer).
    range_v : full-scale peak input voltage; None = autorange.
    force_width_s : width of the force window from the start of the record, s.
    exp_decay_s : time constant of the exponential window, s.
    """

    window: Window
    sensitivity_v_per_eu: float
    range_v: float | None = 1.0
    force_width_s: float = 0.05
    exp_decay_s: float = 1.0
    ac_coupled: bool = False

    def __post_init__(self) -> None:
        object.__setattr__(self, "window", Window(self.window))
        _positive("sensitivity_v_per_eu", self.sensitivity_v_per_eu)
        if self.range_v is not None:
            _positive("range_v", self.range_v)
        _positive("force_width_s", self.force_width_s)
        _positive("exp_decay_s", self.exp_decay_s)


def _hammer() -> ChannelSetup:
    # PCB 086C03-like hammer, 2.25 mV/N; the force window keeps the pulse only.
    return ChannelSetup(Window.FORCE, 2.25e-3, range_v=0.02, force_width_s=0.05)


def _accelerometer() -> ChannelSetup:
    # 10 mV/g = 1.02 mV/(m/s^2); a tap at the tip of the light beam peaks near
    # 1000 m/s^2 before the anti-alias filter, hence 1 V. An exponential window makes
    # the response decay within the record (it adds known damping: 1/exp_decay_s, rad/s).
    return ChannelSetup(Window.EXPONENTIAL, 1.02e-3, range_v=1.0, exp_decay_s=0.5)


@dataclass(frozen=True)
class ImpactSettings:
    """An impact test on the HP 35660A.

    span_hz : frequency span (the analyzer rounds up to 102.4 kHz / 2^n).
    center_hz : None for baseband (0 to span); otherwise a zoom around it.
    trigger_level_eu : level in the trigger channel's unit (N for CH1).
    pre_trigger_s : how much of the record comes before the trigger, s (<= one record).
    averages : hits averaged (stable averaging).
    preview : every hit waits to be accepted or rejected.
    """

    span_hz: float = 200.0
    center_hz: float | None = None
    hammer: ChannelSetup = field(default_factory=_hammer)
    accelerometer: ChannelSetup = field(default_factory=_accelerometer)
    trigger_source: str = "CH1"
    trigger_level_eu: float = 1.0
    trigger_slope: str = "POS"
    pre_trigger_s: float = 0.02
    averages: int = 5
    preview: bool = True

    def __post_init__(self) -> None:
        _positive("span_hz", self.span_hz)
        if self.center_hz is not None and not (
            math.isfinite(self.center_hz) and self.center_hz >= self.span_hz / 2 * (1 - 1e-12)
        ):
            raise ValueError(f"center_hz must be at least span/2 = {self.span_hz / 2:g} Hz")
        if self.trigger_source not in ("CH1", "CH2", "FREE"):
            raise ValueError(f"trigger_source must be CH1, CH2 or FREE, got {self.trigger_source!r}")
        if self.trigger_slope not in ("POS", "NEG"):
            raise ValueError(f"trigger_slope must be POS or NEG, got {self.trigger_slope!r}")
        if not math.isfinite(self.trigger_level_eu):
            raise ValueError("trigger_level_eu must be finite")
        if not (math.isfinite(self.pre_trigger_s) and 0 <= self.pre_trigger_s <= self.record_length_s):
            raise ValueError(f"pre_trigger_s must be 0..{self.record_length_s:g} s (one record)")
        if not (isinstance(self.averages, numbers.Integral) and 1 <= self.averages <= 9999):
            raise ValueError(f"averages must be an integer 1..9999, got {self.averages!r}")
        object.__setattr__(self, "averages", int(self.averages))

    @property
    def record_length_s(self) -> float:
        """Length of one time record: 400 lines / span."""
        return RECORD_LINES / self.span_hz

    @property
    def trigger_level_v(self) -> float:
        channel = self.accelerometer if self.trigger_source == "CH2" else self.hammer
        return self.trigger_level_eu * channel.sensitivity_v_per_eu

    def commands(self, actual_span_hz: float | None = None) -> list[bytes]:
        """The messages that apply these settings, in order.

        ``actual_span_hz`` is the span the analyzer made of ours (it rounds up to
        102.4 kHz / 2^n); at baseband the center must be half of that one.
        """
        span = self.span_hz if actual_span_hz is None else actual_span_hz
        out = [
            command("FRQR"),
            command("LNRS"),
            command("FRS", float(self.span_hz), "HZ"),
            command("CF", float(self.center_hz if self.center_hz is not None else span / 2), "HZ"),
        ]
        for ch, setup in ((1, self.hammer), (2, self.accelerometer)):
            out += [
                command(f"WIN{ch}", setup.window.value),
                command(f"FWD{ch}", float(setup.force_width_s), "S"),
                command(f"EXD{ch}", float(setup.exp_decay_s), "S"),
                command(f"SNS{ch}", float(setup.sensitivity_v_per_eu), "V"),
                command(f"C{ch}AC", int(setup.ac_coupled)),
                command(f"AU{ch}")
                if setup.range_v is None
                else command(f"RNG{ch}", float(setup.range_v), "V"),
            ]
        out += [
            command("TSRC", self.trigger_source),
            command("TLVL", float(self.trigger_level_v), "V"),
            command("TSLP", self.trigger_slope),
            command("TDLY", -float(self.pre_trigger_s) + 0.0, "S"),  # + 0.0: never "-0"
            command("NAVG", self.averages),
            command("STBL"),
            command("PRVW", int(self.preview)),
        ]
        return out
