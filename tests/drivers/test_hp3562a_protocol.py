"""The HP 3562A dialect's differences from the 35660A's, pinned byte for byte
(docs/instrument-scpi.md, "The HP 3562A dialect"; docs/instrument.md for the dumps):
``ID?`` answers ``HP3562A``; 800 lines, so an 801-point spectrum, 2048-sample
baseband records and 1024 complex samples in zoom, all sized by the record of 800
lines; a dump of the 35660A's geometry (401 points) is refused.

Dumps are built here word by word: ``#A``, a 2-byte big-endian byte count, then
big-endian float64 (66 header values, then the data, complex interleaved re, im).
"""

from __future__ import annotations

import struct

import numpy as np
import pytest

from drivers.dialects import HP3562A
from drivers.errors import ProtocolError
from drivers.settings import ImpactSettings
from tests.drivers.expected_protocol import expected

NO_ERROR = b'0,"No error"\r\n'
# Header words (docs/instrument.md): 0 display function (1 frequency response,
# 4 coherence, 6/7 time ch1/ch2, 8 linear spectrum ch1), 7 domain (0 time, 1
# frequency), 9 y units (proj: 1 N, 2 m/s^2, 3 (m/s^2)/N, 4 none), 10 x units (1 Hz,
# 4 s), 36 complex (0) or real (1), 52/53 half the sample rate, 55 delta x, 64 start x.
FRF, COHERENCE, TIME_1, TIME_2, LINEAR_1 = 1.0, 4.0, 6.0, 7.0, 8.0


def hp3562a(steps: list[tuple[bytes, bytes | None]], **kwargs: object):
    """The 3562A's driver on a scripted transport (expected_protocol.expected)."""
    return expected(steps, HP3562A, **kwargs)


def dump(header: list[float], data: list[float]) -> bytes:
    payload = struct.pack(f">{len(header) + len(data)}d", *header, *data)
    return b"#A" + struct.pack(">H", len(payload)) + payload


def header(function, n, channel, time, y_units, complex_data, half_fs, delta, start, averages=1):
    h = [0.0] * 66
    h[0], h[1], h[2], h[3], h[4] = function, n, n, averages, channel
    h[7], h[9], h[10] = (0.0 if time else 1.0), y_units, (4.0 if time else 1.0)
    h[36], h[40] = (0.0 if complex_data else 1.0), 1.0
    h[52] = h[53] = half_fs
    h[55], h[64] = delta, start
    return h


def test_identify_answers_hp3562a():
    with hp3562a([(b"ID?", b"HP3562A\r\n")]) as dsa:
        assert dsa.identify() == "HP3562A"
        assert dsa.geometry.lines == 800
        assert dsa.max_trace_values == 66 + 2048


def test_an_801_point_frf_is_accepted():
    z = np.arange(801) * (0.5 - 1j)
    data = np.column_stack([z.real, z.imag]).ravel().tolist()
    frf_dump = dump(header(FRF, 801, 3, False, 3.0, True, 256.0, 0.25, 0.0, averages=4), data)
    assert frf_dump[:4] == b"#A\x34\x20"  # (66 + 1602) x 8 = 13344 = 0x3420 bytes
    with hp3562a([(b"TRCA;FRSP;DDAN", frf_dump)]) as dsa:
        frf = dsa.fetch_frf()
    assert (frf.header.n_points, frf.header.n_averages, frf.header.delta_x) == (801, 4, 0.25)
    assert frf.x[-1] == 200.0  # 800 lines of 0.25 Hz
    np.testing.assert_array_equal(frf.data, z)


def test_an_801_point_coherence_is_accepted():
    coherence = [k / 800 for k in range(801)]
    with hp3562a(
        [(b"TRCA;COHR;DDAN", dump(header(COHERENCE, 801, 3, False, 4.0, False, 256.0, 0.25, 0.0), coherence))]
    ) as dsa:
        np.testing.assert_array_equal(dsa.fetch_coherence().data, coherence)


def test_2048_sample_baseband_records_are_accepted():
    force = [float(k % 5) for k in range(2048)]
    accel = [float(-k) for k in range(2048)]
    steps = [
        (b"TRCA;TIM1;DDAN", dump(header(TIME_1, 2048, 1, True, 1.0, False, 256.0, 1 / 512, -0.125), force)),
        (b"TRCA;TIM2;DDAN", dump(header(TIME_2, 2048, 2, True, 2.0, False, 256.0, 1 / 512, -0.125), accel)),
    ]
    assert steps[0][1][:4] == b"#A\x42\x10"  # (66 + 2048) x 8 = 16912 = 0x4210 bytes
    with hp3562a(steps) as dsa:
        f, a = dsa.fetch_time_records()
    assert (f.header.n_points, f.header.complex_data, f.header.sample_rate_hz) == (2048, False, 512.0)
    np.testing.assert_array_equal(f.data, force)
    np.testing.assert_array_equal(a.data, accel)


def test_1024_complex_samples_in_zoom_are_accepted():
    z = np.arange(1024) * (1 + 1j)
    values = np.column_stack([z.real, z.imag]).ravel().tolist()
    steps = [
        (b"TRCA;TIM1;DDAN", dump(header(TIME_1, 1024, 1, True, 1.0, True, 128.0, 1 / 256, 0.0), values)),
        (b"TRCA;TIM2;DDAN", dump(header(TIME_2, 1024, 2, True, 2.0, True, 128.0, 1 / 256, 0.0), values)),
    ]
    with hp3562a(steps) as dsa:
        f, a = dsa.fetch_time_records()
    assert (f.header.n_points, f.header.complex_data) == (1024, True)
    np.testing.assert_array_equal(a.data, z)


@pytest.mark.parametrize(
    ("message", "function", "n", "time", "complex_data", "reason"),
    [
        (b"TRCA;FRSP;DDAN", FRF, 401, False, True, "a 3562A spectrum has 801 points, got 401"),
        (b"TRCA;COHR;DDAN", COHERENCE, 401, False, False, "a 3562A spectrum has 801 points, got 401"),
        (b"TRCA;TIM1;DDAN", TIME_1, 1024, True, False, "2048 real or 1024 complex points, got 1024"),
        (b"TRCA;TIM1;DDAN", TIME_1, 512, True, True, "2048 real or 1024 complex points, got 512"),
    ],
)
def test_a_dump_of_the_35660a_geometry_is_refused(message, function, n, time, complex_data, reason):
    values = [0.0] * (n * (2 if complex_data else 1))
    reply = dump(
        header(function, n, 1 if time else 3, time, 1.0 if time else 3.0, complex_data, 256.0, 0.5, 0.0),
        values,
    )
    with hp3562a([(message, reply)], retries=0) as dsa, pytest.raises(ProtocolError, match=reason):
        dsa.fetch_trace(message.decode().split(";")[1])


def test_a_linear_spectrum_of_401_points_is_refused_after_the_retries():
    reply = dump(header(LINEAR_1, 401, 1, False, 1.0, True, 256.0, 0.5, 0.0), [0.0] * 802)
    steps = [(b"TRCA;LSP1;DDAN", reply)] * 2
    with (
        hp3562a(steps, retries=1) as dsa,
        pytest.raises(ProtocolError, match=r"801 points.*after 2 attempts"),
    ):
        dsa.fetch_linear_spectra()


def test_configure_sizes_the_windows_to_the_4_s_record_of_800_lines():
    """At 200 Hz an 800-line record lasts 4 s: force window 1/16 (0.25 s), exponential
    1/6 (0.667 s) and pre-trigger 1/32 (0.125 s) of it, where the 35660A's are half."""
    sent = [
        (b"CLER", None),
        (b"FRQR", None),
        (b"LNRS", None),
        (b"FRS 200 HZ", None),
        (b"ERR?", NO_ERROR),
        (b"FRS?", b"+2.000000000E+02\r\n"),
        (b"CF 100 HZ", None),
        (b"WIN1 FORC", None),
        (b"FWD1 0.25 S", None),
        (b"EXD1 0.666666666667 S", None),
        (b"SNS1 0.00225 V", None),
        (b"C1AC 0", None),
        (b"RNG1 0.02 V", None),
        (b"WIN2 EXPO", None),
        (b"FWD2 0.25 S", None),
        (b"EXD2 0.666666666667 S", None),
        (b"SNS2 0.00102 V", None),
        (b"C2AC 0", None),
        (b"RNG2 1 V", None),
        (b"TSRC CH1", None),
        (b"TLVL 0.00225 V", None),
        (b"TSLP POS", None),
        (b"TDLY -0.125 S", None),
        (b"NAVG 5", None),
        (b"STBL", None),
        (b"PRVW 1", None),
        (b"ERR?", NO_ERROR),
    ]
    read_back = [
        (b"FRS?", b"+2.000000000E+02\r\n"),
        (b"CF?", b"+1.000000000E+02\r\n"),
        (b"WIN1?", b"FORC\r\n"),
        (b"SNS1?", b"+2.250000000E-03\r\n"),
        (b"AU1?", b"0\r\n"),
        (b"RNG1?", b"+2.238721139E-02\r\n"),
        (b"FWD1?", b"+2.500000000E-01\r\n"),
        (b"EXD1?", b"+6.666666667E-01\r\n"),
        (b"C1AC?", b"0\r\n"),
        (b"WIN2?", b"EXPO\r\n"),
        (b"SNS2?", b"+1.020000000E-03\r\n"),
        (b"AU2?", b"0\r\n"),
        (b"RNG2?", b"+1.000000000E+00\r\n"),
        (b"FWD2?", b"+2.500000000E-01\r\n"),
        (b"EXD2?", b"+6.666666667E-01\r\n"),
        (b"C2AC?", b"0\r\n"),
        (b"TSRC?", b"CH1\r\n"),
        (b"TLVL?", b"+2.250000000E-03\r\n"),
        (b"AVMD?", b"STBL\r\n"),
        (b"TSLP?", b"POS\r\n"),
        (b"TDLY?", b"-1.250000000E-01\r\n"),
        (b"NAVG?", b"5\r\n"),
        (b"PRVW?", b"1\r\n"),
    ]
    with hp3562a(sent + read_back) as dsa:
        actual = dsa.configure(ImpactSettings())
    assert actual.lines == 800
    assert actual.record_length_s == 4.0
    assert actual.pre_trigger_s == 0.125
    assert actual.hammer.force_width_s == 0.25


def test_configure_refuses_lines_the_3562a_does_not_offer():
    with hp3562a([]) as dsa, pytest.raises(ValueError, match="the 3562A dialect offers 800 lines, not 400"):
        dsa.configure(ImpactSettings(lines=400))


def test_start_waits_are_sized_to_the_800_line_record():
    steps = [(b"FRS?", b"+2.000000000E+02\r\n"), (b"STRT", None), (b"STA?", b"2\r\n")]
    with hp3562a(steps) as dsa:
        dsa.start()
        assert dsa._record_length() == 4.0
