"""The analyzers the simulator can be: their dialect, identity and record geometry.

Every geometric fact the simulator uses (lines, record samples, spans, input
ranges) comes from the Model of the instrument being simulated, never from a
constant elsewhere in sims/:

* ``35660A``: the 3562A-family mnemonic dialect, 400 lines, 1024-sample records,
  spans 102.4 kHz / 2^n, ranges in 1 dB steps (docs/instrument.md);
* ``3562A``: the same dialect, ``ID?`` -> ``HP3562A``, 800 lines, 2048-sample
  records, spans 100 kHz / 2^n (100 kHz is the 3562A's published top span; the
  steps are our assumption, proj);
* ``35670A`` and ``35665A``: SCPI (docs/instrument-scpi.md), a choice of lines
  (100..1600, 100..800), spans 51.2 kHz / 2^n with two channels, ranges in 2 dB
  steps of dBVrms (as PyMeasure's 35670A driver lists them).

A record holds 2.56 x lines real samples at 2.56 x span at baseband, half as many
complex samples at 1.28 x span in zoom: it lasts lines / span seconds either way.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

#: Samples per line of a baseband record (and the sample rate per Hz of span).
SAMPLES_PER_LINE = 2.56
#: How many spans each model offers: top / 2^n, n = 0 .. N_SPANS - 1.
N_SPANS = 20


@dataclass(frozen=True)
class Model:
    """One simulated instrument.

    name : "35660A", "3562A", "35670A", "35665A".
    dialect : "hp" (3562A-family mnemonics) or "scpi".
    identity : the identification reply without its terminator (``ID?`` or ``*IDN?``).
    lines_offered : the line counts a measurement may resolve the span into.
    preset_lines : lines after a preset.
    top_span_hz : the widest span (Hz); also the highest frequency a zoom band may
        reach, and the span at which the ADC's 16 bits are not averaged down.
    ranges_v : input ranges, V peak, ascending.
    preset_range_v : range after a preset, V peak.
    """

    name: str
    dialect: Literal["hp", "scpi"]
    identity: str
    lines_offered: tuple[int, ...]
    preset_lines: int
    top_span_hz: float
    ranges_v: tuple[float, ...]
    preset_range_v: float

    @property
    def spans_hz(self) -> tuple[float, ...]:
        """Offered spans, Hz, widest first."""
        return tuple(self.top_span_hz / 2**n for n in range(N_SPANS))

    def record_samples(self, lines: int) -> int:
        """Real samples of a baseband record resolving ``lines`` lines."""
        return round(SAMPLES_PER_LINE * lines)

    @property
    def record_samples_offered(self) -> tuple[int, ...]:
        return tuple(self.record_samples(n) for n in self.lines_offered)


#: 1 dB steps from -51 dBV to +27 dBV, V peak (the 35660A's, proj).
_RANGES_1DB = tuple(10.0 ** (db / 20.0) for db in range(-51, 28))
#: 2 dB steps from -51 dBVrms to +27 dBVrms, as V peak (peer: PyMeasure's 35670A).
_RANGES_2DB_RMS = tuple(10.0 ** (db / 20.0) * math.sqrt(2.0) for db in range(-51, 28, 2))

MODELS: dict[str, Model] = {
    "35660A": Model("35660A", "hp", "HP35660A", (400,), 400, 102_400.0, _RANGES_1DB, 1.0),
    "3562A": Model("3562A", "hp", "HP3562A", (800,), 800, 100_000.0, _RANGES_1DB, 1.0),
    "35670A": Model(
        "35670A",
        "scpi",
        "HEWLETT-PACKARD,35670A,0000A00000,A.00.00",
        (100, 200, 400, 800, 1600),
        400,
        51_200.0,
        _RANGES_2DB_RMS,
        10.0 ** (-3 / 20.0) * math.sqrt(2.0),  # -3 dBVrms, the step nearest 1 V peak
    ),
    "35665A": Model(
        "35665A",
        "scpi",
        "HEWLETT-PACKARD,35665A,0000A00000,A.00.00",
        (100, 200, 400, 800),
        400,
        51_200.0,
        _RANGES_2DB_RMS,
        10.0 ** (-3 / 20.0) * math.sqrt(2.0),
    ),
}

DEFAULT_MODEL = MODELS["35660A"]


def get_model(model: Model | str) -> Model:
    """The Model named ``model`` (case-insensitive); ValueError naming the choices."""
    if isinstance(model, Model):
        return model
    found = MODELS.get(str(model).strip().upper())
    if found is None:
        raise ValueError(f"unknown model {model!r}: choose one of {', '.join(MODELS)}")
    return found
