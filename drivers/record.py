"""The 35660A's record geometry (docs/instrument.md), the one place the driver keeps it.

A measurement resolves its span into 400 lines (a spectrum holds 401: 0 to 400).
The time record behind it holds 1024 real samples at 2.56 x span (baseband), or
512 complex samples at 1.28 x span (zoom: the band mixed down by the center
frequency); either way it lasts 400 / span seconds.
"""

from __future__ import annotations

#: The widest span; the analyzer offers MAX_SPAN_HZ / 2^n and rounds a request up.
MAX_SPAN_HZ = 102_400.0
#: Lines a span is resolved into; a spectrum trace holds one more (both ends).
RECORD_LINES = 400
SPECTRUM_POINTS = RECORD_LINES + 1
#: Points of a time record: real at baseband, complex in zoom.
TIME_POINTS = {False: 1024, True: 512}
#: Sample rate of a baseband time record over the span (halved in zoom).
SAMPLE_RATE_PER_SPAN = 2.56


def record_length_s(span_hz: float) -> float:
    """Length of one time record, s: 400 lines / span (Hz)."""
    return RECORD_LINES / span_hz


def sample_rate_hz(span_hz: float, zoom: bool) -> float:
    """Sample rate of the time record, Hz: 2.56 x span at baseband, 1.28 x span in zoom."""
    return SAMPLE_RATE_PER_SPAN * span_hz / (2 if zoom else 1)
