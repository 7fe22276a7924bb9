"""The driver of the HP dynamic signal analyzer family, as the application names it.

The top of the driver's imports: the base driver is drivers/base.py, the dialects
drivers/hp_mnemonic.py and drivers/scpi_analyzer.py, the one factory
``drivers.family.open_analyzer``. ``SignalAnalyzer.open`` is that factory under the name
the application's code calls it by (kept for it; new code calls ``open_analyzer``).
"""

from __future__ import annotations

from drivers import base
from drivers.base import HIT_ALLOWANCE_S, PROBE_TIMEOUT_S
from drivers.family import open_analyzer
from drivers.messages import STATUS_BITS, Status, ascii_message, decode_line


class SignalAnalyzer(base.SignalAnalyzer):
    """``drivers.base.SignalAnalyzer`` with the family's factory as ``open``: what answers
    at a resource, driven in its dialect (an instance of the base, not of this class)."""

    open = staticmethod(open_analyzer)  # type: ignore[assignment]


__all__ = [
    "HIT_ALLOWANCE_S",
    "PROBE_TIMEOUT_S",
    "STATUS_BITS",
    "SignalAnalyzer",
    "Status",
    "ascii_message",
    "decode_line",
]
