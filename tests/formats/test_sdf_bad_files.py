"""Damaged SDF files: cut short anywhere, sizes, offsets and types corrupted, unknown
records and codes, counts that would need absurd memory. Each gives one FormatError line
naming the file; through `daq import`, one line on stderr, exit status 1 and a store
left as it was."""

from __future__ import annotations

import struct

import pytest

from daq.cli.commands.import_file import guess_format
from daq.formats.errors import FormatError
from daq.formats.sdf import parse_sdf, read_sdf
from daq.store import Store
from tests.cli_helpers import assert_one_line_error, invoke_daq
from tests.formats.sdf_builder import (
    full_file,
)

NAME = "damaged.sdf"
# Record starts in FULL (set below from its FILE_HDR, read here with struct).
FIELDS = ">hihhhhh8s6h7ihhiii"


FULL = full_file()
_HEAD = struct.unpack_from(FIELDS, FULL, 2)
START = {
    "FILE_HDR": 2,
    "MEAS_HDR": 82,
    "DATA_HDR": _HEAD[14],
    "VECTOR_HDR": _HEAD[15],
    "CHANNEL_HDR": _HEAD[16],
    "UNIQUE": _HEAD[17],
    "SCAN_STRUCT": _HEAD[18],
    "SCAN_BIG": _HEAD[23],
    "COMMENT": _HEAD[24],
    "XDATA": _HEAD[19],
    "YDATA": _HEAD[20],
}


def refused(data: bytes, *fragments: str) -> str:
    with pytest.raises(FormatError) as info:
        parse_sdf(data, NAME)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(NAME + ": ")
    for fragment in fragments:
        assert fragment in message, message
    return message


def patched(offset: int, fmt: str, *numbers) -> bytes:
    data = bytearray(FULL)
    struct.pack_into(fmt, data, offset, *numbers)
    return bytes(data)


def test_the_full_file_reads():
    sdf = parse_sdf(FULL, NAME)
    assert len(sdf.data) == 2
    assert sdf.data[0].y.shape == (2, 2, 4)
    assert [c.text for c in sdf.comments] == ["note"]


def test_cut_short_at_any_byte_is_refused():
    for length in range(len(FULL)):
        refused(FULL[:length])


def test_a_wrong_signature():
    refused(b"A\0" + FULL[2:], "not an SDF file")
    refused(b"PK\x03\x04" + bytes(100), "not an SDF file")


@pytest.mark.parametrize(
    ("where", "fmt", "number", "fragment"),
    [
        ("FILE_HDR", ">h", 99, "expected type 10"),
        ("DATA_HDR", ">h", 13, "is a VECTOR_HDR record (type 13), expected type 12"),
        ("DATA_HDR", ">h", 77, "unknown record type 77"),
        ("VECTOR_HDR", ">h", 2000, "instrument-specific record (type 2000)"),
        ("CHANNEL_HDR", ">h", 12, "expected type 14"),
        ("UNIQUE", ">h", 7, "unknown record type 7"),
        ("SCAN_STRUCT", ">h", 18, "expected type 15"),
        ("SCAN_BIG", ">h", 20, "expected type 18"),
        ("COMMENT", ">h", -1, "unknown record type -1"),
        ("XDATA", ">h", 17, "expected type 16"),
        ("YDATA", ">h", 16, "expected type 17"),
    ],
)
def test_a_record_of_the_wrong_or_an_unknown_type(where, fmt, number, fragment):
    refused(patched(START[where], fmt, number), fragment)


@pytest.mark.parametrize("where", list(START))
@pytest.mark.parametrize(("size", "fragment"), [(5, "at least"), (2**31 - 1, "truncated or damaged")])
def test_a_record_size_too_small_or_past_the_end(where, size, fragment):
    refused(patched(START[where] + 2, ">i", size), fragment)


@pytest.mark.parametrize("field", range(14, 21))
@pytest.mark.parametrize(("offset", "fragment"), [(-7, "negative offset"), (10**6, "truncated or damaged")])
def test_an_offset_outside_the_file(field, offset, fragment):
    position = 2 + struct.calcsize(FIELDS[: FIELDS.index("7i")]) + 4 * (field - 14)
    message = refused(patched(position, ">i", offset))
    assert fragment in message or "expected type" in message


@pytest.mark.parametrize(
    ("where", "at", "fmt", "number", "fragment"),
    [
        ("FILE_HDR", 6, ">h", 7, "revision 7"),
        ("FILE_HDR", 24, ">h", 0, "num_of_DATA_HDR_record is 0"),
        ("FILE_HDR", 26, ">h", -3, "num_of_VECTOR_record is -3"),
        ("DATA_HDR", 48, ">h", 5, "ydata_type 5"),
        ("DATA_HDR", 48, ">h", 0, "ydata_type 0"),
        ("DATA_HDR", 64, ">h", 32767, "uses VECTOR_HDR #0..#32766"),
        ("DATA_HDR", 134, ">i", 2**31 - 1, "the headers need"),
        ("DATA_HDR", 134, ">i", -4, "points"),
        ("DATA_HDR", 50, ">h", 0, "points of 0 values"),
        ("DATA_HDR", 42, ">h", 9, "xResolution_type 9"),
        ("SCAN_STRUCT", 12, ">h", 9, "data type code 9"),
        ("SCAN_BIG", 18, ">h", 3, "scan_type 3"),
        ("SCAN_BIG", 10, ">i", 2**31 - 1, "more scans than a file"),
        ("SCAN_BIG", 10, ">i", 0, "num_of_scan = 0"),
        ("VECTOR_HDR", 10, ">h", 5, "refers to channel header 5"),
        ("CHANNEL_HDR", 138, ">f", 0.0, "int2engrUnit 0.0"),
        ("XDATA", 2, ">i", 6 + 8, "bytes of x values"),
        ("YDATA", 2, ">i", 6 + 100, "bytes of y values"),
    ],
)
def test_damaged_fields(where, at, fmt, number, fragment):
    refused(patched(START[where] + at, fmt, number), fragment)


def test_a_data_header_pointing_past_the_last_vector():
    second = START["DATA_HDR"] + 148
    refused(patched(second + 60, ">i", 3), "uses VECTOR_HDR #3..#3; the file has 3")


def test_a_chain_of_logical_files_past_the_end():
    refused(patched(78, ">i", 10**6), "next logical SDF file")


def test_read_sdf_refuses_what_is_not_a_file(tmp_path):
    with pytest.raises(FormatError, match="no such file"):
        read_sdf(tmp_path / "missing.sdf")
    (tmp_path / "empty.sdf").write_bytes(b"")
    with pytest.raises(FormatError, match="is empty"):
        read_sdf(tmp_path / "empty.sdf")
    (tmp_path / "big.sdf").write_bytes(FULL)
    with pytest.raises(FormatError, match="import limit"):
        read_sdf(tmp_path / "big.sdf", max_bytes=100)


CLI_CASES = {
    **{f"cut in {where}": FULL[: START[where] + 3] for where in START},
    "cut in the values": FULL[:-5],
    "size too small": patched(START["DATA_HDR"] + 2, ">i", 20),
    "size past the end": patched(START["CHANNEL_HDR"] + 2, ">i", 10**7),
    "offset past the end": patched(2 + 36, ">i", 10**7),
    "unknown record": patched(START["VECTOR_HDR"], ">h", 55),
    "unknown data type": patched(START["DATA_HDR"] + 48, ">h", 8),
    "absurd point count": patched(START["DATA_HDR"] + 134, ">i", 2**30),
    "not sdf": b"B\0" + b"\xff" * 40,
}


@pytest.mark.parametrize("case", list(CLI_CASES))
@pytest.mark.parametrize("how", [(), ("--format", "sdf")])
def test_daq_import_of_a_damaged_file_is_one_line_and_writes_nothing(tmp_path, case, how):
    store = tmp_path / "store"
    Store(store).ensure_writable()
    path = tmp_path / f"{case.replace(' ', '-')}.sdf"
    path.write_bytes(CLI_CASES[case])
    before = sorted(p.name for p in store.iterdir())
    result = invoke_daq("import", str(path), *how, "--store", str(store))
    assert_one_line_error(result, str(path))
    assert result.returncode == 1
    assert sorted(p.name for p in store.iterdir()) == before
    assert Store(store).list() == []


def test_format_guessing_trusts_the_content(tmp_path):
    sdf_dat = tmp_path / "a.dat"
    sdf_dat.write_bytes(FULL)
    assert guess_format(sdf_dat) == "sdf"
    text_dat = tmp_path / "b.dat"
    text_dat.write_text("0,1,2\n")
    assert guess_format(text_dat) == "csv"
    uff_named_sdf = tmp_path / "c.sdf"
    uff_named_sdf.write_text("    -1\n    58\n")
    assert guess_format(uff_named_sdf) == "uff"
    no_suffix = tmp_path / "d"
    no_suffix.write_bytes(FULL)
    assert guess_format(no_suffix) == "sdf"
    damaged = tmp_path / "e.sdf"
    damaged.write_bytes(b"B\0" + bytes(3))
    assert guess_format(damaged) == "sdf"


def test_a_file_forced_as_sdf_is_refused_with_its_first_bytes_shown_plainly():
    """No Python bytes repr (b'a,') in a technician's error line: hex, and the text if printable."""
    refused(
        b"a,b,c\n1,2,3\n" + bytes(100), "its first two bytes are 61 2C ('a,'), not SDF's 42 00 ('B' and NUL)"
    )
