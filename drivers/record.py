"""The 35660A's record geometry, the default where settings name no other analyzer.

The geometry of every model of the family is in drivers/dialects.py (``Geometry``):
a span resolved into ``lines`` lines (a spectrum holds lines + 1 points), a time
record of 2.56 x lines real samples at 2.56 x span (baseband) or half as many complex
samples at 1.28 x span (zoom), lasting lines / span seconds. The 35660A resolves 400.
"""

from __future__ import annotations

from drivers.dialects import HP35660A, SAMPLE_RATE_PER_SPAN

#: The 35660A's widest span; it offers MAX_SPAN_HZ / 2^n and rounds a request up.
MAX_SPAN_HZ = HP35660A.max_span_hz
#: Lines a 35660A span is resolved into.
RECORD_LINES = HP35660A.default_lines

__all__ = ["MAX_SPAN_HZ", "RECORD_LINES", "SAMPLE_RATE_PER_SPAN"]
