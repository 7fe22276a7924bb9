"""The SDF builder (sdf_builder.py) against the real 35670A file: its header bytes,
rebuilt with it from the field values the analyzer's ASCII export lists, must be the file's.
"""

from __future__ import annotations

import struct

from tests.formats.sdf_builder import (
    CHANNEL_SIZE,
    DATA_SIZE,
    MEAS_SIZE,
    REAL,
    channel_hdr,
    comment,
    data_hdr,
    meas_hdr,
    scan_big,
    scan_struct,
    scan_var,
    unit,
    values,
    vector_hdr,
    window,
)

# ---------------------------------------------------------------------------------------
# The builder against the real file (revision 2): its header bytes, rebuilt from the field
# values the analyzer's ASCII export lists, must be the file's bytes. Strings in the real
# file carry leftover bytes after their NUL (instrument memory), so those spans are masked.


def _masked(data: bytes, spans: list[tuple[int, int]]) -> bytes:
    out = bytearray(data)
    for start, end in spans:
        out[start:end] = bytes(end - start)
    return bytes(out)


def test_sizes_are_the_guides_table_b1():
    for rev in (1, 2, 3):
        assert len(meas_hdr(rev)) == MEAS_SIZE[rev]
        assert len(data_hdr(rev, n_points=1)) == DATA_SIZE[rev]
        assert len(channel_hdr(rev)) == CHANNEL_SIZE[rev]
    assert len(vector_hdr(0)) == 18
    assert len(scan_big(1, 0, 0)) == 20
    assert len(scan_var("", 3, b"")) == 54
    assert len(comment(b"")) == 24
    assert len(unit()) == 22
    assert len(window()) == 24


def test_the_builder_rebuilds_the_real_files_headers():
    real = REAL.read_bytes()
    meas = meas_hdr(2, 8192.0, 16384.0, 4096, 0, 0, 1600, meas_type=3, real_time=1, detection=0)
    assert _masked(real[66:206], [(38, 98)]) == _masked(meas, [(38, 98)])  # measTitle: "" + leftovers
    hz = unit("Hz", 6.28319, (0, 0, -2, 0, 0, 0, 0, 2))
    dh = data_hdr(
        2, n_points=2049, title="Pwr Spec", domain=0, data_type=2, delta_x=8.0, x_per_point=0,
        power=1, x_unit=hz, y_unit=unit("", 1.0), window_applied=1,
    )  # fmt: skip
    spans = [(10, 26), (68, 78), (92, 102)]  # dataTitle, xUnit.label, yUnit.label leftovers
    assert _masked(real[206:340], spans) == _masked(dh, spans)
    assert real[340:358] == vector_hdr(0, -1, 96, 0)
    # Flat-top constants of SDF_basi.h; range -32.943314 dBV as the file's float32 holds it.
    flat_top = window(2, 0, 3.8193596, 0.0, 0.0, 2.39823509624, 4.6869145)
    volt = unit("V", 1.0, (2, 4, -6, -2, 0, 0, 0, 0))
    channel = channel_hdr(
        2, "Chan  1", win=flat_top, eng=volt, module="HP35670A", serial="MY42506778",
        range=-32.94331359863281, direction=3, point=1, impedance=50.0,
    )  # fmt: skip
    spans = [(10, 40), (106, 126)]  # channelLabel, intLabel and engUnit.label leftovers
    assert _masked(real[358:550], spans) == _masked(channel, spans)
    assert real[550:742] == real[358:550]  # the second channel header is the same
    count = unit("count")
    scans = scan_struct(1, 0, 1, 3, values([85.0], ">f4"), count)
    assert _masked(real[1264:1304], [(14, 24)]) == _masked(scans, [(14, 24)])
    head = b"B\0" + struct.pack(">hihhhhh8s", 10, 64, 2, 10, 2013, 213, 908, b"A.01.11")
    head += struct.pack(">6h7i", 1, 1, 2, 1, 1, 0, 206, 340, 358, 742, 1264, -1, 1304)
    assert real[:66] == head
    assert real[1304:1310] == struct.pack(">hi", 17, 6 + 2049 * 4)
