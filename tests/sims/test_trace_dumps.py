"""DDAN and DDAS of the spectral display functions, byte for byte, from a record whose
spectra are known by hand (two delayed impulses), and the ASCII dump's read-back.

Expected bytes come from the documented formats (docs/instrument.md, "Trace
format"): ``#A`` + 2-byte big-endian byte count + big-endian float64, 66 header
words then the data, complex data interleaved re, im; header word 0 the display
function (1 frequency response, 2/3 power spectrum ch1/ch2, 4 coherence, 8/9
linear spectrum ch1/ch2), 7 the domain (1 frequency), 10 the x units (1 Hz),
36 complex (0) or real (1). Y-unit codes (word 9) and channel 3 for ch2 over ch1
(word 4) are the project's (proj).
"""

from __future__ import annotations

import re
import struct

import numpy as np
import pytest

from sims.instrument import Analyzer
from sims.sources import RecordedHit, ReplaySource
from tests.sims.wire import ask

pytestmark = pytest.mark.timeout(10)

CRLF = b"\r\n"
SPAN_HZ = 200.0
RATE_HZ = 512.0  # 2.56 x 200 Hz
N = 1024

# Two delayed impulses: force 2 N at sample 1, acceleration 3 m/s^2 at sample 5.
DELTA_FORCE = np.zeros(N)
DELTA_FORCE[1] = 2.0
DELTA_ACCEL = np.zeros(N)
DELTA_ACCEL[5] = 3.0
DELTA_HIT = RecordedHit(DELTA_FORCE, DELTA_ACCEL, RATE_HZ)


_K = np.arange(401)
_SCALE = np.full(401, 2 / N)  # 2 / sum(uniform window): a sinusoid's line reads its peak
_SCALE[0] = 1 / N  # the DC line of a real record
_X1 = 2.0 * np.exp(-2j * np.pi * _K * 1 / N)  # 2 N at sample 1
_X2 = 3.0 * np.exp(-2j * np.pi * _K * 5 / N)  # 3 m/s^2 at sample 5
# function: (display code, channel, y-units code, complex, expected data)
SPECTRAL = {
    "LSP1": (8, 1, 1, True, _X1 * _SCALE),
    "LSP2": (9, 2, 2, True, _X2 * _SCALE),
    "PSP1": (2, 1, 5, False, 4.0 * _SCALE**2),
    "PSP2": (3, 2, 6, False, 9.0 * _SCALE**2),
    # H1 = G21 / G11 = conj(X1) X2 / |X1|^2: the response lags the force by 4 samples,
    # so the phase falls with frequency (a conjugated H1 would rise).
    "FRSP": (1, 3, 3, True, 1.5 * np.exp(-2j * np.pi * _K * 4 / N)),
    "COHR": (4, 3, 4, False, np.ones(401)),
}


@pytest.mark.parametrize("function", list(SPECTRAL))
def test_spectral_dump_header_bytes_and_values(function: str, connect):
    code, channel, y_code, is_complex, expected = SPECTRAL[function]
    conn = connect(Analyzer(ReplaySource([DELTA_HIT], loop=True)))
    reply = ask(conn, f"FRS 200 HZ;UNIF;STRT;TRCB;{function};DDAN")
    n_values = 66 + 401 * (2 if is_complex else 1)
    h = [0.0] * 66
    h[0] = code
    h[1] = h[2] = 401
    h[3] = 1
    h[4] = channel
    h[7] = 1  # frequency domain
    h[9] = y_code
    h[10] = 1  # x in Hz
    h[36] = 0 if is_complex else 1
    h[40] = 1
    h[52] = h[53] = RATE_HZ / 2
    h[55] = SPAN_HZ / 400
    h[64] = 0.0
    assert reply[:4] == b"#A" + struct.pack(">H", 8 * n_values)
    assert reply[4 : 4 + 66 * 8] == struct.pack(">66d", *h)
    assert len(reply) == 4 + 8 * n_values
    body = np.array(struct.unpack(f">{n_values - 66}d", reply[4 + 66 * 8 :]))
    if is_complex:
        body = body[0::2] + 1j * body[1::2]
    np.testing.assert_allclose(body, expected, rtol=1e-12, atol=1e-12 * np.max(np.abs(expected)))


def test_ascii_dump_reads_back_bit_exact(connect):
    """DDAS and DDAN carry the same values; DDAS text parses back to the same float64s."""
    conn = connect(Analyzer(ReplaySource([DELTA_HIT], loop=True)))
    binary = ask(conn, "FRS 200 HZ;UNIF;STRT;DDAN")
    text = ask(conn, "DDAS")
    values = struct.unpack(f">{(len(binary) - 4) // 8}d", binary[4:])
    rows = text.split(CRLF)
    assert rows[:2] == [b"#I", str(len(values)).encode("ascii")]
    assert rows[-1] == b""
    assert [float(r) for r in rows[2:-1]] == list(values)
    assert all(re.fullmatch(rb"[+-]\d\.\d{16}E[+-]\d\d", r) for r in rows[2:-1])
