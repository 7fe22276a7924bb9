"""The simulated analyzer's settings, their preset and the record geometry they imply.

The geometry (lines, record samples, spans, ranges) comes from the settings'
Model (sims/models.py); the module constants below are the 35660A's, kept for
code that means that instrument.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields

import numpy as np

from sims.command_table import DISPLAY_CODES
from sims.models import DEFAULT_MODEL, SAMPLES_PER_LINE, Model, get_model

#: The 35660A's geometry (the default model): 102.4 kHz / 2^n, 400 lines, 1024 samples.
MAX_SPAN_HZ = DEFAULT_MODEL.top_span_hz
N_SPANS = len(DEFAULT_MODEL.spans_hz)
SPANS_HZ = DEFAULT_MODEL.spans_hz
#: Input ranges of the 35660A, V peak: 1 dB steps from -51 dBV to +27 dBV.
RANGES_V = DEFAULT_MODEL.ranges_v
N_LINES = DEFAULT_MODEL.preset_lines
RECORD_SAMPLES = DEFAULT_MODEL.record_samples(N_LINES)
SAMPLE_RATE_PER_SPAN = SAMPLES_PER_LINE
ADC_BITS = 16

#: The state dump (DSAN, DSAS): its length is documented, its layout is ours (proj,
#: docs/instrument.md, "State dump"). Codes are spelled out, not taken from the order
#: of a tuple, so that reordering a table cannot silently move a dumped value.
STATE_LENGTH = 96
STATE_WINDOWS = {"UNIF": 0, "HANN": 1, "FLAT": 2, "FORC": 3, "EXPO": 4}
STATE_AVERAGING = {"STBL": 1, "AVOF": 0}
STATE_TRIGGER_SOURCES = {"FREE": 0, "CH1": 1, "CH2": 2}
STATE_SLOPES = {"POS": 1, "NEG": -1}


@dataclass
class AnalyzerSettings:
    """Every persistent setting; the defaults are the preset (RST)."""

    span_hz: float = MAX_SPAN_HZ
    center_hz: float = MAX_SPAN_HZ / 2
    n_averages: int = 1
    averaging: str = "AVOF"
    preview: int = 0
    measurement: str = "FRQR"
    mode: str = "LNRS"
    window1: str = "HANN"
    window2: str = "HANN"
    force_width1_s: float = 0.05
    force_width2_s: float = 0.05
    exp_decay1_s: float = 1.0
    exp_decay2_s: float = 1.0
    range1_v: float = 1.0
    range2_v: float = 1.0
    autorange1: int = 0
    autorange2: int = 0
    ac_coupled1: int = 0
    ac_coupled2: int = 0
    sensitivity1_v_per_eu: float = 2.25e-3
    sensitivity2_v_per_eu: float = 1.02e-3
    trigger_source: str = "FREE"
    trigger_level_v: float = 0.0
    trigger_slope: str = "POS"
    trigger_delay_s: float = 0.0
    trace: str = "A"
    display: dict[str, str] = field(default_factory=lambda: {"A": "FRSP", "B": "COHR"})
    lines: int = N_LINES
    model: Model = field(default=DEFAULT_MODEL, repr=False, compare=False)

    @classmethod
    def preset(cls, model: Model | str = DEFAULT_MODEL) -> AnalyzerSettings:
        """The preset of ``model``: its widest span at baseband, its preset lines and range."""
        m = get_model(model)
        top, rng = m.top_span_hz, m.preset_range_v
        return cls(span_hz=top, center_hz=top / 2, range1_v=rng, range2_v=rng, lines=m.preset_lines, model=m)

    # -- derived geometry
    @property
    def zoom(self) -> bool:
        """A zoom measurement: the span does not start at 0 Hz. Its time records are
        complex (the band mixed down by the center frequency), 1.28 x lines points
        at 1.28 x span, so that the record length stays lines / span."""
        return self.start_hz > 1e-9 * self.span_hz

    @property
    def record_samples(self) -> int:
        """Real samples of a baseband record: 2.56 x lines."""
        return self.model.record_samples(self.lines)

    @property
    def record_points(self) -> int:
        return self.record_samples // 2 if self.zoom else self.record_samples

    @property
    def sample_rate_hz(self) -> float:
        return SAMPLES_PER_LINE * self.span_hz / (2 if self.zoom else 1)

    @property
    def record_length_s(self) -> float:
        return self.record_points / self.sample_rate_hz

    @property
    def line_spacing_hz(self) -> float:
        return self.span_hz / self.lines

    @property
    def start_hz(self) -> float:
        return self.center_hz - self.span_hz / 2

    def channel(self, name: str, ch: int) -> object:
        """Per-channel field ``name`` (e.g. ``range``) of channel 1 or 2."""
        for f in fields(self):
            if f.name.startswith(name + str(ch)):
                return getattr(self, f.name)
        raise KeyError(name)

    def state_values(self) -> np.ndarray:
        """The 96-value state dump (DSAN, DSAS), float64 (96,).

        How many values the 3562A family dumps is documented, not what they mean:
        where each setting sits is a project choice (proj, docs/instrument.md,
        "State dump"): 0 span Hz, 1 center Hz, 2 averages, 3 averaging (1 STBL,
        0 AVOF), 4 preview 0/1, 5/6 window of ch1/ch2 (STATE_WINDOWS), 7/8 force
        window widths s, 9/10 exponential time constants s, 11/12 ranges V peak,
        13/14 autorange 0/1, 15/16 AC coupling 0/1, 17/18 sensitivities V/EU,
        19 trigger source (0 FREE, 1 CH1, 2 CH2), 20 trigger level V, 21 slope
        (1 POS, -1 NEG), 22 trigger delay s, 23 active trace (0 A, 1 B), 24/25 the
        display-function codes of traces A and B (header word 0's codes). Every
        other word is 0; the measurement (FRQR) and mode (LNRS), having one value
        each, are not dumped.
        """
        values = np.zeros(STATE_LENGTH)
        values[0:5] = (
            self.span_hz,
            self.center_hz,
            self.n_averages,
            STATE_AVERAGING[self.averaging],
            self.preview,
        )
        for ch in (1, 2):
            values[4 + ch] = STATE_WINDOWS[str(self.channel("window", ch))]
            values[6 + ch] = float(self.channel("force_width", ch))  # type: ignore[arg-type]
            values[8 + ch] = float(self.channel("exp_decay", ch))  # type: ignore[arg-type]
            values[10 + ch] = float(self.channel("range", ch))  # type: ignore[arg-type]
            values[12 + ch] = int(self.channel("autorange", ch))  # type: ignore[arg-type]
            values[14 + ch] = int(self.channel("ac_coupled", ch))  # type: ignore[arg-type]
            values[16 + ch] = float(self.channel("sensitivity", ch))  # type: ignore[arg-type]
        values[19:23] = (
            STATE_TRIGGER_SOURCES[self.trigger_source],
            self.trigger_level_v,
            STATE_SLOPES[self.trigger_slope],
            self.trigger_delay_s,
        )
        values[23] = 0 if self.trace == "A" else 1
        values[24] = DISPLAY_CODES[self.display["A"]]
        values[25] = DISPLAY_CODES[self.display["B"]]
        return values


def coerce_span(value_hz: float, model: Model = DEFAULT_MODEL) -> float:
    """The smallest span ``model`` offers at or above ``value_hz``; ValueError outside the offer."""
    spans, top = model.spans_hz, model.top_span_hz
    if not (math.isfinite(value_hz) and spans[-1] * (1 - 1e-9) <= value_hz <= top * (1 + 1e-9)):
        raise ValueError(f"span must be {spans[-1]:.8g} Hz to {top:g} Hz")
    return min(s for s in spans if s >= value_hz * (1 - 1e-9))


def coerce_range(value_v: float, model: Model = DEFAULT_MODEL) -> float:
    """The smallest input range of ``model`` at or above ``value_v`` (V peak)."""
    ranges = model.ranges_v
    if not (math.isfinite(value_v) and 0 < value_v <= ranges[-1] * (1 + 1e-9)):
        raise ValueError(f"range must be up to {ranges[-1]:.4g} V")
    return min((r for r in ranges if r >= value_v * (1 - 1e-9)), default=ranges[0])


def check_center(center_hz: float, span_hz: float, model: Model = DEFAULT_MODEL) -> float:
    """``center_hz`` if the band [center - span/2, center + span/2] fits 0 .. the top span."""
    top = model.top_span_hz
    low, high = span_hz / 2, top - span_hz / 2
    if not (math.isfinite(center_hz) and low * (1 - 1e-9) <= center_hz <= high + low * 1e-9):
        raise ValueError(f"with a {span_hz:g} Hz span the center must be {low:g} Hz to {high:g} Hz")
    return min(max(center_hz, span_hz / 2), top - span_hz / 2)
