"""A test-only SDF byte builder, and two files built with it (every record type;
one FRF in each revision).

Written field by field from HP's tables (the guide's appendix B, tables B-2 to B-14, and
SDF_comm.h), with struct formats spelled out here, NOT from daq/formats/sdf/layout.py:
the tests build files with it and pin the values the reader must find, so a wrong
table in the package cannot hide behind the same table in the tests. test_sdf_builder.py
rebuilds the real file's headers with it and compares the bytes.
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

DATA = Path(__file__).resolve().parents[1] / "data" / "sdf"
REAL = DATA / "SDF3KHZ.DAT"

FILE_SIZE = {1: 64, 2: 64, 3: 80}
MEAS_SIZE = {1: 102, 2: 140, 3: 156}
DATA_SIZE = {1: 114, 2: 134, 3: 148}
CHANNEL_SIZE = {1: 146, 2: 192, 3: 212}


def _s(text: str) -> bytes:
    return text.encode("latin-1")


def _i16(value: int) -> int:
    return max(-32768, min(32767, value))


def unit(label: str = "", factor: float = 1.0, dims: tuple[int, ...] = (0,) * 8) -> bytes:
    """SDF_UNIT, 22 bytes: char[10] label, float factor, 8 signed chars (2 x exponents)."""
    return struct.pack(">10sf8b", _s(label), factor, *dims)


def window(kind=3, corr=0, bandwidth=1.0, time_const=0.0, trunc=0.0, wide=1.0, narrow=1.0) -> bytes:
    """SDF_WINDOW, 24 bytes: windowType, windowCorrMode (short), then 5 floats."""
    return struct.pack(">hhfffff", kind, corr, bandwidth, time_const, trunc, wide, narrow)


def meas_hdr(rev: int, center=0.0, span=0.0, block=1024, zoom=0, start=0, stop=0, title="", **more) -> bytes:
    """MEAS_HDR (type 11): 102 / 140 / 156 bytes."""
    body = struct.pack(">i", -1)
    body += struct.pack(">ffih", center, span, block, zoom)  # revision 1 fields, "Old" copies later
    body += struct.pack(">hh", _i16(start), _i16(stop))
    body += struct.pack(">hif60sf", more.get("avg_type", 0), more.get("avg_num", 1), 0.0, _s(title), 0.0)
    if rev >= 2:
        sweep = (more.get("meas_type", -99), more.get("real_time", 0), more.get("detection", -99))
        body += struct.pack(">dddhhhd", center, span, 0.0, *sweep, 0.0)
    if rev >= 3:
        body += struct.pack(">iid", start, stop, 0.0)
    record = struct.pack(">hi", 11, MEAS_SIZE[rev]) + body
    assert len(record) == MEAS_SIZE[rev]
    return record


def data_hdr(rev: int, *, n_points: int, first_vector: int = 0, rows: int = 1, cols: int = 1, **f) -> bytes:
    """DATA_HDR (type 12): 114 / 134 / 148 bytes. f: title, domain, data_type, first_x,
    delta_x, x_res, xdata_type, x_per_point, ydata_type, y_per_point, complex, normalized,
    power, valid, x_unit, y_unit_valid, y_unit, scan_data, window_applied, last_valid."""
    last = f.get("last_valid", n_points - 1)
    first_x, delta_x = f.get("first_x", 0.0), f.get("delta_x", 1.0)
    body = struct.pack(">i16shh", -1, _s(f.get("title", "")), f.get("domain", 0), f.get("data_type", 4))
    body += struct.pack(">hhff", _i16(n_points), _i16(last), first_x, delta_x)
    x_fields = (f.get("x_res", 0), f.get("xdata_type", 3), f.get("x_per_point", 1))
    y_fields = (f.get("ydata_type", 3), f.get("y_per_point", 1), f.get("complex", 0), f.get("normalized", 0))
    body += struct.pack(">hhhhhhhhh", *x_fields, *y_fields, f.get("power", 0), f.get("valid", 1))
    body += struct.pack(">ihh", first_vector, rows, cols)
    body += f.get("x_unit", unit()) + struct.pack(">h", f.get("y_unit_valid", 0)) + f.get("y_unit", unit())
    if rev >= 2:
        body += struct.pack(">ddhh", first_x, delta_x, f.get("scan_data", 0), f.get("window_applied", 1))
    if rev >= 3:
        body += struct.pack(">iihhh", n_points, last, 1, 0, 0)
    record = struct.pack(">hi", 12, DATA_SIZE[rev]) + body
    assert len(record) == DATA_SIZE[rev]
    return record


def vector_hdr(row: int, col: int = -1, row_power: int = 48, col_power: int = 0) -> bytes:
    """VECTOR_HDR (type 13), 18 bytes."""
    return struct.pack(">hiihhhh", 13, 18, -1, row, col, row_power, col_power)


def channel_hdr(rev: int, label="", *, win: bytes | None = None, eng=None, int2engr=1.0, **f) -> bytes:
    """CHANNEL_HDR (type 14): 146 / 192 / 212 bytes. f: module, serial, weight, delay,
    range, direction, point, coupling, overloaded, int_label, impedance, attribute,
    alias, digital, scale, offset, number."""
    body = struct.pack(">i30s12s12s", -1, _s(label), _s(f.get("module", "")), _s(f.get("serial", "")))
    body += win if win is not None else window()
    body += struct.pack(">hff", f.get("weight", 0), f.get("delay", 0.0), f.get("range", 0.0))
    body += struct.pack(
        ">hhhh", f.get("direction", 0), f.get("point", 0), f.get("coupling", 0), f.get("overloaded", 0)
    )
    body += struct.pack(">10s", _s(f.get("int_label", "V"))) + (eng if eng is not None else unit("V"))
    body += struct.pack(">ff", int2engr, f.get("impedance", 1.0e6))
    if rev >= 2:
        flags = (f.get("attribute", 0), f.get("alias", 1), f.get("digital", 0))
        body += struct.pack(">hhhddddd", *flags, f.get("scale", 1.0), f.get("offset", 0.0), 0.0, 0.0, 0.0)
    if rev >= 3:
        body += struct.pack(">ddhh", f.get("delay", 0.0), 0.0, f.get("number", 0), 0)
    record = struct.pack(">hi", 14, CHANNEL_SIZE[rev]) + body
    assert len(record) == CHANNEL_SIZE[rev]
    return record


def scan_struct(n: int, last: int, scan_type: int, var_type: int, values: bytes, scan_unit: bytes) -> bytes:
    """SCAN_STRUCT (type 15): 36 bytes, then the scan values."""
    return (
        struct.pack(">hihhhh", 15, 36 + len(values), _i16(n), _i16(last), scan_type, var_type)
        + scan_unit
        + values
    )


def scan_big(n: int, last: int, scan_type: int) -> bytes:
    """SCAN_BIG (type 18), 20 bytes."""
    return struct.pack(">hiiiih", 18, 20, -1, n, last, scan_type)


def scan_var(
    name: str, var_type: int, values: bytes, base=0, order=0, data_record=-1, var_unit=None
) -> bytes:
    """SCAN_VAR (type 19): 54 bytes, then the values."""
    head = struct.pack(
        ">hiiihhh10sh", 19, 54 + len(values), -1, 54, base, order, data_record, _s(name), var_type
    )
    return head + (var_unit if var_unit is not None else unit()) + values


def comment(text: bytes, comment_bytes: int | None = None, scope=0, info=-1) -> bytes:
    """COMMENT (type 20): 24 bytes, then the text."""
    size = len(text) if comment_bytes is None else comment_bytes
    return struct.pack(">hiiiihhh", 20, 24 + len(text), -1, 24, size, 0, scope, info) + text


def block(record_type: int, payload: bytes) -> bytes:
    """XDATA (16) or YDATA (17): 6-byte head, then the values."""
    return struct.pack(">hi", record_type, 6 + len(payload)) + payload


def values(array, dtype: str) -> bytes:
    """Big-endian bytes of ``array`` as ``dtype`` (">i2", ">f4"...)."""
    return np.asarray(array).astype(dtype).tobytes()


def assemble(
    rev: int,
    meas: bytes,
    data: list[bytes],
    vectors: list[bytes],
    channels: list[bytes],
    ydata: bytes,
    *,
    unique: list[bytes] = (),
    scans: bytes | None = None,
    big: list[bytes] = (),
    comments: list[bytes] = (),
    xdata: bytes | None = None,
    applic: int = -99,
    stamp: tuple[int, int, int] = (2026, 1123, 1015),
    version: str = "",
    next_file: int = -1,
) -> bytes:
    """A whole file in SDF_comm.h's order; offsets count from the "B"."""
    position = 2 + FILE_SIZE[rev] + len(meas)
    counts, offsets = [], []
    areas = [data, vectors, channels, unique, [scans] if scans else [], [xdata] if xdata else []]
    body = b""
    for records in areas[:5]:
        counts.append(len(records))
        offsets.append(position if records else -1)
        body += b"".join(records)
        position += sum(len(r) for r in records)
    big_offset, comment_offset = -1, -1
    if rev >= 3:
        big_offset = position if big else -1
        body += b"".join(big)
        position += sum(len(r) for r in big)
        comment_offset = position if comments else -1
        body += b"".join(comments)
        position += sum(len(r) for r in comments)
    counts.append(1 if xdata else 0)
    offsets.append(position if xdata else -1)
    if xdata:
        body += xdata
        position += len(xdata)
    offsets.append(position)
    head = struct.pack(">hihhhhh8s", 10, FILE_SIZE[rev], rev, applic, *stamp, _s(version))
    head += struct.pack(">6h7i", *counts, *offsets)
    if rev >= 3:
        head += struct.pack(">hhiii", len(big), len(comments), big_offset, comment_offset, next_file)
    assert len(head) == FILE_SIZE[rev]
    return b"B\0" + head + meas + body + ydata


XDATA, YDATA = 16, 17
HANNING = window(1, 0, 1.5, 0.0, 0.0, 1.5, 2.0)  # narrow 2.0, wide 1.5, no correction applied


def full_file() -> bytes:
    """Revision 3 with every record type: 2 data headers (time records in 2 scans, an FRF
    with XDATA), 2 channels, an instrument record, scans, a comment, XDATA and YDATA."""
    data = [
        data_hdr(3, n_points=4, first_vector=0, rows=2, domain=1, data_type=0, ydata_type=2, scan_data=1),
        data_hdr(3, n_points=3, first_vector=2, complex=1, ydata_type=4, x_res=3, xdata_type=4, data_type=4),
    ]
    vectors = [vector_hdr(0), vector_hdr(1), vector_hdr(1, 0, 48, -48)]
    channels = [channel_hdr(3, "F", int2engr=2.0), channel_hdr(3, "A", int2engr=0.5)]
    scans = scan_struct(2, 1, 0, 3, values([1, 2], ">f4"), unit("count"))
    big = [scan_big(2, 1, 0), scan_var("t", 4, values([0.5, 1.5], ">f8"), base=2)]
    y = values(range(16), ">i4") + values(range(6), ">f8")
    return assemble(
        3, meas_hdr(3), data, vectors, channels, block(17, y),
        unique=[struct.pack(">hi", 1500, 8) + b"xy"], scans=scans, big=big,
        comments=[comment(b"note")], xdata=block(16, values([1.0, 2.0, 4.0], ">f8")),
    )  # fmt: skip


def frf_file(rev: int) -> bytes:
    """One FRF: response channel 1 (int2engrUnit 0.5), force channel 0 (4.0), Hanning on
    both with no correction applied; stored (1+2j), (-0.5+0.25j), (3-1j) as float32."""
    channels = [
        channel_hdr(rev, "Force", win=HANNING, eng=unit("N", 1.0, (2, 2, -4, 0, 0, 0, 0, 0)), int2engr=4.0),
        channel_hdr(
            rev, "Accel", win=HANNING, eng=unit("g", 9.80665, (0, 2, -4, 0, 0, 0, 0, 0)), int2engr=0.5
        ),
    ]
    dh = data_hdr(rev, n_points=3, title="Freq Resp", first_x=10.0, delta_x=2.5, complex=1, data_type=4)
    stored = values([1, 2, -0.5, 0.25, 3, -1], ">f4")
    meas = meas_hdr(rev, center=1000.0, span=2000.0, block=2048, start=0, stop=2)
    return assemble(rev, meas, [dh], [vector_hdr(1, 0, 48, -48)], channels, block(YDATA, stored))
