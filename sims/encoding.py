"""Bytes on the wire: ASCII reply lines, the 66-value trace header, ``#A`` blocks and
``#I`` ASCII dumps (docs/instrument.md, "Trace format").

``DDAN`` sends ``#A``, a 2-byte big-endian byte count, then big-endian IEEE
float64 values, a 66-value header followed by the data (real, or interleaved re/im
for complex traces); ``DDAS`` sends ``#I``, then the count of values, then the
values, one per line. Replies are ASCII lines ending CR LF; binary blocks end with
EOI and no terminator.

Header words (index: meaning), as documented for the 3562A family except where
marked proj; a two-way flag is 0 for the first-named option:
0 display function (command_table.DISPLAY_CODES), 1 number of elements,
2 elements displayed, 3 number of averages, 4 channel (1, 2; 3 = ch2 over ch1,
proj), 5 overflow, 6 overlap %, 7 domain (0 time, 1 frequency), 8 peak/rms
(0 peak), 9 y units (codes proj), 10 x units (1 Hz, 4 s), 35 float/integer
(0 float), 36 complex/real (0 complex), 40 log/linear (1 linear), 43 measurement
mode (0 linear resolution), 52 and 53 half the sample rate (Hz), 55 delta-x (s or
Hz), 64 start time (s, relative to the trigger) or start frequency (Hz).
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

import numpy as np

from sims.command_table import DISPLAY_CODES, DOMAIN_CODES, X_UNIT_CODES, Y_UNIT_CODES
from sims.units import format_exact

HEADER_LENGTH = 66
CRLF = b"\r\n"
MAX_BLOCK_BYTES = 0xFFFF


@dataclass(frozen=True)
class TraceHeader:
    display_function: str
    n_points: int
    n_averages: int
    channel: int
    overflow: bool
    time_domain: bool
    y_units: str
    complex_data: bool
    half_sample_rate_hz: float
    delta_x: float
    start_x: float

    def values(self) -> np.ndarray:
        h = np.zeros(HEADER_LENGTH)
        h[0] = DISPLAY_CODES[self.display_function]
        h[1] = h[2] = self.n_points
        h[3] = self.n_averages
        h[4] = self.channel
        h[5] = 1.0 if self.overflow else 0.0
        h[6] = 0.0
        h[7] = DOMAIN_CODES["time" if self.time_domain else "frequency"]
        h[8] = 0.0
        h[9] = Y_UNIT_CODES[self.y_units]
        h[10] = X_UNIT_CODES["s" if self.time_domain else "Hz"]
        h[35] = 0.0
        h[36] = 0.0 if self.complex_data else 1.0
        h[40] = 1.0
        h[43] = 0.0
        h[52] = h[53] = self.half_sample_rate_hz
        h[55] = self.delta_x
        h[64] = self.start_x
        return h


def trace_values(header: TraceHeader, data: np.ndarray) -> np.ndarray:
    """Header then data (complex data interleaved re, im), float64."""
    data = np.asarray(data)
    body = np.column_stack([data.real, data.imag]).ravel() if np.iscomplexobj(data) else data.astype(float)
    return np.concatenate([header.values(), body])


def binary_block(payload: bytes) -> bytes:
    """``#A`` + 2-byte big-endian length + payload."""
    if len(payload) > MAX_BLOCK_BYTES:
        raise ValueError(f"block of {len(payload)} bytes exceeds the #A limit of {MAX_BLOCK_BYTES}")
    return b"#A" + struct.pack(">H", len(payload)) + payload


def float_block(values: np.ndarray) -> bytes:
    """Values as a ``#A`` block of big-endian float64."""
    return binary_block(np.asarray(values, dtype=">f8").tobytes())


def ascii_dump(values: np.ndarray) -> bytes:
    """``#I``, the count of values, then one exact ASCII number per line, CR LF each."""
    body = b"".join(format_exact(float(v)).encode("ascii") + CRLF for v in values)
    return b"#I" + CRLF + str(len(values)).encode("ascii") + CRLF + body


def line(text: str) -> bytes:
    return text.encode("ascii", errors="replace") + CRLF
