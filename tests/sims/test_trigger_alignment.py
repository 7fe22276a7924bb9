"""The recorded hammer pulse sits where the trigger fired, at every span.

A real analyzer removes the bulk delay of its decimating filters, so the time
record is aligned with the trigger (docs/simulator.md, "Anti-alias filtering and
decimation"). The trigger point is where the header's start time says: sample
index -start_x / delta_x, start_x being word 64 and delta_x word 55 of the
documented 66-word header (docs/instrument.md, "Trace format").
"""

from __future__ import annotations

import struct

import numpy as np
import pytest

SPANS_HZ = [102400.0 / 2**n for n in range(14)]  # 102.4 kHz down to 12.5 Hz
SENSITIVITY_V_PER_N = 2.25e-3
LEVEL_V = 2e-3


def _dump(conn, message: str) -> tuple[np.ndarray, np.ndarray]:
    """Header (66,) and data of the active trace, decoded from the documented #A layout."""
    raw = conn.query(message, timeout_s=30.0)
    assert raw[:2] == b"#A"
    (count,) = struct.unpack(">H", raw[2:4])
    values = np.array(struct.unpack(f">{count // 8}d", raw[4 : 4 + count]))
    return values[:66], values[66:]


@pytest.mark.parametrize("span_hz", SPANS_HZ, ids=[f"{s:g}Hz" for s in SPANS_HZ])
def test_force_crosses_the_trigger_level_at_the_trigger_point(make_analyzer, connect, span_hz):
    conn = connect(make_analyzer("realistic", seed=3, noise=False))
    record_s = 400 / span_hz
    conn.query(
        f"FRS {span_hz} HZ;TSRC CH1;TLVL {LEVEL_V} V;TSLP POS;TDLY {-record_s / 8} S;"
        f"SNS1 {SENSITIVITY_V_PER_N} V;RNG1 50 MV;UNIF;NAVG 1;STBL;PRVW 0;STRT;SMSD"
    )
    header, force_n = _dump(conn, "TIM1;DDAN")
    start_s, dt_s = header[64], header[55]
    assert start_s == pytest.approx(-record_s / 8)
    trigger_index = -start_s / dt_s
    level_n = LEVEL_V / SENSITIVITY_V_PER_N
    pulse_s = 2e-3  # the hammer's nominal contact time (sims/hammer.py), +-10 %
    if pulse_s >= 2 * dt_s:
        # The pulse is resolved: it crosses the level where the trigger fired.
        above = np.flatnonzero(force_n >= level_n)
        assert above.size, "the force never reaches the trigger level"
        first = above[0]
        crossing = first - 1 + (level_n - force_n[first - 1]) / (force_n[first] - force_n[first - 1])
        assert abs(crossing - trigger_index) <= 1.0, (crossing, trigger_index)
    else:
        # Shorter than a few samples: the band-limited pulse peaks at the trigger point.
        assert abs(int(np.argmax(force_n)) - trigger_index) <= 1.0, (np.argmax(force_n), trigger_index)
