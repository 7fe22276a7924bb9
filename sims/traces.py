"""What DDAN and DDAS dump: the active trace, its 66-value header then its data
(docs/instrument.md, "Trace format"; header words in sims/encoding.py).

Time records (TIM1, TIM2) are the last record taken, in engineering units, with
time in s from the trigger; spectral functions are the running average, on the
lines of the span (401 points on the 35660A, 801 on the 3562A), with frequency in Hz.
"""

from __future__ import annotations

import numpy as np

from sims.acquisition import Record
from sims.dsp import Average
from sims.encoding import TraceHeader, trace_values
from sims.settings import AnalyzerSettings

#: Y units of each display function (header word 9; the codes are ours, proj).
Y_UNITS = {
    "TIM1": "N",
    "TIM2": "m/s^2",
    "LSP1": "N",
    "LSP2": "m/s^2",
    "PSP1": "N^2",
    "PSP2": "(m/s^2)^2",
    "FRSP": "(m/s^2)/N",
    "COHR": "",
}


class NoData(LookupError):
    """The active trace has nothing to show yet (the analyzer's error 5)."""


def active_trace_values(
    settings: AnalyzerSettings, average: Average, last_record: Record | None
) -> np.ndarray:
    """Header then data of the active trace, float64 (66 + n,); NoData if there is none."""
    function = settings.display[settings.trace]
    if function in ("TIM1", "TIM2"):
        if last_record is None:
            raise NoData(f"{function}: no time record yet")
        ch = int(function[-1])
        data = last_record.force_n if ch == 1 else last_record.acceleration_m_s2
        fs = last_record.sample_rate_hz
        header = TraceHeader(
            function, data.size, average.count, ch, last_record.overload[ch - 1], True,
            Y_UNITS[function], np.iscomplexobj(data), fs / 2, 1 / fs, last_record.start_s,
        )  # fmt: skip
        return trace_values(header, data)
    try:
        data = average.trace(function)
    except LookupError:
        raise NoData(f"{function}: no averaged data yet") from None
    # Channel 3 stands for "ch2 over ch1" (FRSP, COHR): the family documents the
    # word, not this code (proj).
    channel = int(function[-1]) if function[-1] in "12" else 3
    overflow = any(average.overload) if channel == 3 else average.overload[channel - 1]
    header = TraceHeader(
        function, data.size, average.count, channel, overflow, False, Y_UNITS[function],
        np.iscomplexobj(data), settings.sample_rate_hz / 2, settings.line_spacing_hz, settings.start_hz,
    )  # fmt: skip
    return trace_values(header, data)
