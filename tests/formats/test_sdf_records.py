"""Every record type, revisions 1 to 3, the four number types, real and complex data,
log and XDATA x axes, scans in depth and scan order, SCAN_BIG / SCAN_VAR, comments,
instrument-specific records and chained logical files. Files are built byte by byte
with the test builder (test_sdf_builder.py); expected values are worked out by hand
from the format definition, next to each test."""

from __future__ import annotations

import struct

import numpy as np
import pytest

from daq.formats.sdf import parse_sdf
from daq.formats.sdf.writer import encode_sdf
from tests.formats.sdf_builder import (
    XDATA,
    YDATA,
    assemble,
    block,
    channel_hdr,
    comment,
    data_hdr,
    frf_file,
    meas_hdr,
    scan_big,
    scan_struct,
    scan_var,
    unit,
    values,
    vector_hdr,
    window,
)


@pytest.mark.parametrize("rev", [1, 2, 3])
def test_an_frf_reads_the_same_in_every_revision(rev):
    sdf = parse_sdf(frf_file(rev), "frf.sdf")
    assert sdf.file.revision == rev
    (dh,) = sdf.data
    # Window factor 2.0 on both channels: (2.0 / 0.5) ** 1 * (2.0 / 4.0) ** -1 = 4 * 2 = 8.
    assert dh.y.dtype == np.complex128
    np.testing.assert_array_equal(dh.y, [[[8 + 16j, -4 + 2j, 24 - 8j]]])
    np.testing.assert_array_equal(dh.x, [10.0, 12.5, 15.0])
    assert (dh.title, dh.n_points, dh.data_type) == ("Freq Resp", 3, 4)
    assert (sdf.meas.center_freq, sdf.meas.span_freq, sdf.meas.block_size) == (1000.0, 2000.0, 2048)
    assert [c.label for c in sdf.channels] == ["Force", "Accel"]
    assert sdf.channels[1].eng_unit.factor == pytest.approx(9.80665)


def _time_channel(rev: int) -> bytes:
    # Volts = 0.25 + stored / 1024 for integers (revision 2, 3); EU = volts / 0.5.
    return channel_hdr(rev, "Ch", int2engr=0.5, scale=2.0**-10, offset=0.25)


@pytest.mark.parametrize("rev", [2, 3])
def test_the_four_number_types(rev):
    kinds = [(1, ">i2", [1024, -2048, 0, 512]), (2, ">i4", [2**20, -(2**20), 3, 0])]
    kinds += [(3, ">f4", [1.5, -2.0, 0.0, 8.0]), (4, ">f8", [0.1, -0.3, 1e300, 2.5])]
    data, stored, vectors = [], b"", []
    for k, (code, dtype, numbers) in enumerate(kinds):
        data.append(data_hdr(rev, n_points=4, first_vector=k, domain=1, data_type=0, ydata_type=code))
        vectors.append(vector_hdr(0))
        stored += values(numbers, dtype)
    meas = meas_hdr(rev)
    sdf = parse_sdf(assemble(rev, meas, data, vectors, [_time_channel(rev)], block(YDATA, stored)), "t.sdf")
    got = [dh.y[0, 0] for dh in sdf.data]
    # int16: (0.25 + s / 1024) / 0.5 -> 1024: 2.5, -2048: -3.5, 0: 0.5, 512: 1.5.
    np.testing.assert_array_equal(got[0], [2.5, -3.5, 0.5, 1.5])
    # int32: 2**20 -> (0.25 + 1024) / 0.5 = 2048.5; -2**20 -> -2047.5; 3 -> 0.505859375; 0 -> 0.5.
    np.testing.assert_array_equal(got[1], [2048.5, -2047.5, 0.505859375, 0.5])
    # float32 and float64: no scale and offset, only / 0.5.
    np.testing.assert_array_equal(got[2], [3.0, -4.0, 0.0, 16.0])
    np.testing.assert_array_equal(got[3], [0.2, -0.6, 2e300, 5.0])
    assert all(g.dtype == np.float64 for g in got)


def test_revision_1_integers_have_no_scale_or_offset():
    channel = channel_hdr(1, "Ch", int2engr=0.5)
    dh = data_hdr(1, n_points=2, domain=1, data_type=0, ydata_type=1)
    sdf = parse_sdf(
        assemble(1, meas_hdr(1), [dh], [vector_hdr(0)], [channel], block(YDATA, values([1024, -3], ">i2"))),
        "r1",
    )
    np.testing.assert_array_equal(sdf.data[0].y, [[[2048.0, -6.0]]])


def test_complex_integer_time_data():
    channel = channel_hdr(2, "Zoom", int2engr=0.5, scale=0.25)
    dh = data_hdr(2, n_points=2, domain=1, data_type=0, ydata_type=1, complex=1)
    stored = values([100, -200, -4, 8], ">i2")  # (100 - 200j), (-4 + 8j)
    sdf = parse_sdf(assemble(2, meas_hdr(2), [dh], [vector_hdr(0)], [channel], block(YDATA, stored)), "z")
    # (0 + s / 4) / 0.5 for both parts.
    np.testing.assert_array_equal(sdf.data[0].y, [[[50 - 100j, -2 + 4j]]])


@pytest.mark.parametrize(
    ("corr_mode", "domain", "policy", "expected"),
    [
        (0, 0, "narrow", 4.0),  # (2.0 / 0.5) ** 2 * 0.25
        (0, 0, "wide", 2.25),  # (1.5 / 0.5) ** 2 * 0.25
        (0, 0, "none", 1.0),  # (1 / 0.5) ** 2 * 0.25
        (1, 0, "narrow", 1.0),  # narrow correction already applied: (1 / 0.5) ** 2 * 0.25
        (2, 4, "narrow", 1.0),  # order domain, wide already applied
        (0, 4, "narrow", 4.0),  # order domain is windowed too
        (0, 1, "narrow", 1.0),  # time domain: never a window correction
    ],
)
def test_window_and_engineering_unit_correction(corr_mode, domain, policy, expected):
    win = window(1, corr_mode, 1.5, 0.0, 0.0, 1.5, 2.0)
    channel = channel_hdr(2, "Ch", win=win, int2engr=0.5)
    dh = data_hdr(2, n_points=1, domain=domain, data_type=2, power=1)
    file = assemble(
        2, meas_hdr(2), [dh], [vector_hdr(0, -1, 96, 0)], [channel], block(YDATA, values([0.25], ">f4"))
    )
    assert parse_sdf(file, "p", window=policy).data[0].y[0, 0, 0] == expected


def test_a_log_x_axis():
    dh = data_hdr(3, n_points=4, x_res=1, first_x=10.0, delta_x=2.0)
    sdf = parse_sdf(
        assemble(3, meas_hdr(3), [dh], [vector_hdr(0)], [channel_hdr(3)], block(YDATA, bytes(16))), "l"
    )
    np.testing.assert_array_equal(sdf.data[0].x, [10.0, 20.0, 40.0, 80.0])  # 10 * 2 ** n


def test_xdata_per_file_per_data_header_and_per_trace():
    rev = 3
    data = [
        data_hdr(rev, n_points=3, first_vector=0, x_res=2, xdata_type=1),  # shares the file's x
        data_hdr(rev, n_points=3, first_vector=1, x_res=2, xdata_type=1),
        data_hdr(rev, n_points=3, first_vector=2, x_res=3, xdata_type=3),  # its own x
        data_hdr(rev, n_points=3, first_vector=3, rows=2, x_res=4, xdata_type=4),  # one x per trace
    ]
    x = values([1, 2, 4], ">i2") + values([0.5, 1.5, 2.5], ">f4") + values([1, 2, 3, 4, 5, 6], ">f8")
    vectors = [vector_hdr(0)] * 5
    y = bytes(5 * 3 * 4)
    sdf = parse_sdf(
        assemble(
            rev, meas_hdr(rev), data, vectors, [channel_hdr(rev)], block(YDATA, y), xdata=block(XDATA, x)
        ),
        "x",
    )
    np.testing.assert_array_equal(sdf.data[0].x, [1.0, 2.0, 4.0])
    np.testing.assert_array_equal(sdf.data[1].x, [1.0, 2.0, 4.0])
    np.testing.assert_array_equal(sdf.data[2].x, [0.5, 1.5, 2.5])
    np.testing.assert_array_equal(sdf.data[3].x, [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]])
    np.testing.assert_array_equal(sdf.data[3].x_of(1), [4.0, 5.0, 6.0])


def _scanned_file(scan_type: int) -> bytes:
    """dh0: 1 trace of 2 points, dh1: 2 traces of 2 points, both scanned (3 scans); dh2:
    1 trace of 1 point, not scanned. Stored float32 values 0, 1, 2, ... in file order."""
    rev = 2
    data = [
        data_hdr(rev, n_points=2, first_vector=0, scan_data=1),
        data_hdr(rev, n_points=2, first_vector=1, rows=2, scan_data=1),
        data_hdr(rev, n_points=1, first_vector=3, scan_data=0),
    ]
    scans = scan_struct(3, 2, scan_type, 3, values([10, 20, 30], ">f4"), unit("s", 1.0))
    y = values(np.arange(19), ">f4")
    return assemble(
        rev, meas_hdr(rev), data, [vector_hdr(0)] * 4, [channel_hdr(rev)], block(YDATA, y), scans=scans
    )


def test_scans_in_depth_order():
    sdf = parse_sdf(_scanned_file(0), "depth")
    dh0, dh1, dh2 = sdf.data
    # dh0: scans 0, 1, 2 of its one trace: [0, 1], [2, 3], [4, 5]; dh1 from 6: scan s,
    # trace v at 6 + 4 s + 2 v; dh2 last, once: [18].
    np.testing.assert_array_equal(dh0.y, [[[0, 1]], [[2, 3]], [[4, 5]]])
    np.testing.assert_array_equal(dh1.y, [[[6, 7], [8, 9]], [[10, 11], [12, 13]], [[14, 15], [16, 17]]])
    np.testing.assert_array_equal(dh2.y, [[[18]]])
    assert sdf.scans.n_scans == 3
    np.testing.assert_array_equal(sdf.scans.variables[0].values, [10, 20, 30])
    assert sdf.scans.variables[0].unit.label == "s"


def test_scans_in_scan_order():
    sdf = parse_sdf(_scanned_file(1), "scan")
    dh0, dh1, dh2 = sdf.data
    # Scan s holds dh0's trace then dh1's two: from 6 s: [6s, 6s+1], [6s+2, 6s+3], [6s+4, 6s+5].
    np.testing.assert_array_equal(dh0.y, [[[0, 1]], [[6, 7]], [[12, 13]]])
    np.testing.assert_array_equal(dh1.y, [[[2, 3], [4, 5]], [[8, 9], [10, 11]], [[14, 15], [16, 17]]])
    np.testing.assert_array_equal(dh2.y, [[[18]]])


def test_scan_big_and_scan_var_hold_more_than_32767_scans():
    n = 40_000
    dh = data_hdr(3, n_points=1, scan_data=1)
    count = values(np.arange(n), ">i4")
    scans = scan_struct(n, n - 1, 0, 2, count, unit("count"))  # num_of_scan clipped to 32767
    rpm = scan_var(
        "rpm", 4, values(100.0 * np.arange(n), ">f8"), base=3, order=1, data_record=0, var_unit=unit("rpm")
    )
    y = values(np.arange(n) / 4, ">f4")
    file = assemble(
        3,
        meas_hdr(3),
        [dh],
        [vector_hdr(0)],
        [channel_hdr(3)],
        block(YDATA, y),
        scans=scans,
        big=[scan_big(n, n - 1, 0), rpm],
    )
    sdf = parse_sdf(file, "big")
    assert sdf.scans.n_scans == n
    assert sdf.data[0].y.shape == (n, 1, 1)
    np.testing.assert_array_equal(sdf.data[0].y[:, 0, 0], np.arange(n) / 4)
    counts, speeds = sdf.scans.variables
    np.testing.assert_array_equal(counts.values, np.arange(n))
    assert (speeds.name, speeds.base_type, speeds.order_type, speeds.data_record) == ("rpm", 3, 1, 0)
    assert speeds.values[-1] == 100.0 * (n - 1)


def test_comments_instrument_records_and_a_second_logical_file():
    second = frf_file(3)
    unique = struct.pack(">hi", 1005, 16) + b"0123456789"
    notes = [comment(b"hello\r\nworld\0\0\0", comment_bytes=-1), comment(b"abcdef", 3)]
    y = block(YDATA, values([7.0], ">f4"))
    first = assemble(
        3,
        meas_hdr(3),
        [data_hdr(3, n_points=1)],
        [vector_hdr(0)],
        [channel_hdr(3)],
        y,
        unique=[unique],
        comments=notes,
    )
    first = first[:2] + first[2:78] + struct.pack(">i", len(first)) + first[82:]  # offset_of_next_SDF_FILE
    sdf = parse_sdf(first + second, "chain")
    assert [c.text for c in sdf.comments] == ["hello\r\nworld", "abc"]
    assert sdf.unique == [(1005, 16)]
    assert sdf.data[0].y[0, 0, 0] == 7.0
    assert sdf.next_file is not None
    np.testing.assert_array_equal(sdf.next_file.data[0].y, [[[8 + 16j, -4 + 2j, 24 - 8j]]])
    assert sdf.next_file.next_file is None


def test_two_values_per_point():
    dh = data_hdr(3, n_points=2, y_per_point=2)
    sdf = parse_sdf(
        assemble(
            3, meas_hdr(3), [dh], [vector_hdr(0)], [channel_hdr(3)], block(YDATA, values([1, 2, 3, 4], ">f4"))
        ),
        "2",
    )
    np.testing.assert_array_equal(sdf.data[0].y, [[[[1, 2], [3, 4]]]])


def test_a_record_longer_than_its_revision_needs_is_read():
    dh = data_hdr(3, n_points=1)
    longer = dh[:2] + struct.pack(">i", len(dh) + 4) + dh[6:] + b"\0\0\0\0"
    file = assemble(
        3, meas_hdr(3), [longer], [vector_hdr(0)], [channel_hdr(3)], block(YDATA, values([5.0], ">f4"))
    )
    assert parse_sdf(file, "long").data[0].y[0, 0, 0] == 5.0


@pytest.mark.parametrize("rev", [1, 2, 3])
def test_our_writer_writes_the_builders_bytes(rev):
    """Same content, two independent encoders: byte for byte the same file."""
    built = frf_file(rev)
    assert encode_sdf(parse_sdf(built, "b"), revision=rev) == built


def test_our_writer_writes_the_builders_scans():
    built = _scanned_file(0)
    assert encode_sdf(parse_sdf(built, "b"), revision=2) == built
