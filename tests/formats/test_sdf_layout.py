"""The record tables of daq/formats/sdf/layout.py against HP's numbers: the guide's table
B-1 (record sizes per revision) and the byte positions its tables B-2 to B-14 print
(1-based, "Binary Index"), copied here by hand."""

from __future__ import annotations

import struct

import pytest

from daq.formats.sdf import codes
from daq.formats.sdf.layout import SIZES, TABLES, UNIT_FIELDS, WINDOW_FIELDS, layout

# The guide's table B-1, typed in again here rather than imported.
GUIDE_SIZES = {
    codes.FILE_HDR: (64, 64, 80),
    codes.MEAS_HDR: (102, 140, 156),
    codes.DATA_HDR: (114, 134, 148),
    codes.VECTOR_HDR: (18, 18, 18),
    codes.CHANNEL_HDR: (146, 192, 212),
}

# (record, revision, field, first byte, last byte), 1-based as the guide prints them.
GUIDE_POSITIONS = [
    (codes.FILE_HDR, 2, "applicVer", 17, 24),
    (codes.FILE_HDR, 2, "num_of_VECTOR_record", 27, 28),
    (codes.FILE_HDR, 2, "offset_of_DATA_HDR_record", 37, 40),
    (codes.FILE_HDR, 2, "offset_of_YDATA_record", 61, 64),
    (codes.FILE_HDR, 3, "num_of_SCAN_BIG_record", 65, 66),
    (codes.FILE_HDR, 3, "num_of_COMMENT_record", 67, 68),
    (codes.FILE_HDR, 3, "offset_of_SCAN_BIG_record", 69, 72),
    # The guide's table B-2 skips offset_of_COMMENT_record and prints the next-file
    # offset at 73:76, which would leave the 80-byte record 4 bytes short; HP's
    # SDF_comm.h has the comment offset at 73:76 and the next-file offset at 77:80.
    (codes.FILE_HDR, 3, "offset_of_COMMENT_record", 73, 76),
    (codes.FILE_HDR, 3, "offset_of_next_SDF_FILE", 77, 80),
    (codes.MEAS_HDR, 3, "blockSize", 19, 22),
    (codes.MEAS_HDR, 3, "startFreqIndexOld", 25, 26),
    (codes.MEAS_HDR, 3, "measTitle", 39, 98),
    (codes.MEAS_HDR, 3, "centerFreq", 103, 110),
    (codes.MEAS_HDR, 3, "sweepTime", 133, 140),
    (codes.MEAS_HDR, 3, "startFreqIndex", 141, 144),
    (codes.MEAS_HDR, 3, "expAverageNum", 149, 156),
    (codes.DATA_HDR, 3, "xResolution_type", 43, 44),
    (codes.DATA_HDR, 3, "ydata_type", 49, 50),
    (codes.DATA_HDR, 3, "yIsComplex", 53, 54),
    (codes.DATA_HDR, 3, "yIsValid", 59, 60),
    (codes.DATA_HDR, 3, "first_VECTOR_recordNum", 61, 64),
    (codes.DATA_HDR, 3, "total_cols", 67, 68),
    (codes.DATA_HDR, 3, "xUnit", 69, 90),
    (codes.DATA_HDR, 3, "yUnitValid", 91, 92),
    (codes.DATA_HDR, 3, "yUnit", 93, 114),
    (codes.DATA_HDR, 3, "abscissa_firstX", 115, 122),
    (codes.DATA_HDR, 3, "abscissa_deltaX", 123, 130),
    (codes.DATA_HDR, 3, "windowApplied", 133, 134),
    (codes.DATA_HDR, 3, "num_of_points", 135, 138),
    (codes.DATA_HDR, 3, "last_valid_index", 139, 142),
    (codes.DATA_HDR, 3, "multiPassDecimations", 147, 148),
    (codes.VECTOR_HDR, 3, "the_CHANNEL_record[0]", 11, 12),
    (codes.VECTOR_HDR, 3, "pwrOfChan[0]", 15, 16),
    (codes.CHANNEL_HDR, 3, "channelLabel", 11, 40),
    (codes.CHANNEL_HDR, 3, "serialNum", 53, 64),
    (codes.CHANNEL_HDR, 3, "window", 65, 88),
    (codes.CHANNEL_HDR, 3, "weight", 89, 90),
    (codes.CHANNEL_HDR, 3, "direction", 99, 100),
    (codes.CHANNEL_HDR, 3, "intLabel", 107, 116),
    (codes.CHANNEL_HDR, 3, "engUnit", 117, 138),
    (codes.CHANNEL_HDR, 3, "int2engrUnit", 139, 142),
    (codes.SCAN_STRUCT, 3, "scanUnit", 15, 36),
    (codes.SCAN_BIG, 3, "num_of_scan", 11, 14),
    (codes.SCAN_BIG, 3, "scan_type", 19, 20),
    (codes.SCAN_VAR, 3, "headerSize", 11, 14),
    (codes.SCAN_VAR, 3, "DATA_recordNum", 19, 20),
    (codes.SCAN_VAR, 3, "scan_ID", 21, 30),
    (codes.SCAN_VAR, 3, "scanVar_type", 31, 32),
    (codes.SCAN_VAR, 3, "scanUnit", 33, 54),
    (codes.COMMENT, 3, "comment_bytes", 15, 18),
    (codes.COMMENT, 3, "scope_info", 23, 24),
]


def _size(code: str) -> int:
    parts = UNIT_FIELDS if code == "unit" else WINDOW_FIELDS if code == "window" else (code,)
    return struct.calcsize(">" + "".join(parts))


def _position(record: int, revision: int, name: str) -> tuple[int, int]:
    offset = 0
    for field, _attr, code, _revs in layout(record, revision).fields:
        if field == name:
            return offset + 1, offset + _size(code)
        offset += _size(code)
    raise AssertionError(f"{name} not in the revision {revision} table")


@pytest.mark.parametrize("record", list(GUIDE_SIZES))
@pytest.mark.parametrize("revision", [1, 2, 3])
def test_every_table_adds_up_to_the_guides_size(record, revision):
    assert layout(record, revision).size == GUIDE_SIZES[record][revision - 1]
    assert SIZES[record][revision - 1] == GUIDE_SIZES[record][revision - 1]


def test_the_variable_records_have_their_fixed_heads():
    assert layout(codes.SCAN_STRUCT, 2).size == 36
    assert layout(codes.SCAN_BIG, 3).size == 20
    assert layout(codes.SCAN_VAR, 3).size == 54
    assert layout(codes.COMMENT, 3).size == 24
    assert layout(codes.YDATA, 1).size == 6


@pytest.mark.parametrize(("record", "revision", "name", "first", "last"), GUIDE_POSITIONS)
def test_fields_sit_where_the_guide_prints_them(record, revision, name, first, last):
    assert _position(record, revision, name) == (first, last)


def test_each_revision_has_unique_field_names():
    for record, table in TABLES.items():
        for revision in (1, 2, 3):
            names = [f[0] for f in table if revision in f[3]]
            assert len(names) == len(set(names)), (record, revision)
