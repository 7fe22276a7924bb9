"""The files of an HP analyzer's ASCII export (a text SDF_FILE_HDR header, and one number
per line in .X and .TXT beside it) are refused in one line that points to the binary
SDF file, which holds both. They were read as a one-column CSV ("1 data column") or not
recognised at all. The files are the 35670A export in tests/data/sdf (sdfascii, MIT)."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from tests.cli_helpers import daq_import, refused

SDF = Path(__file__).resolve().parent.parent / "data" / "sdf"


@pytest.mark.parametrize("suffix", [".HDR", ".X", ".TXT"])
def test_each_file_of_the_export_points_to_the_sdf_file(tmp_path, suffix):
    for part in SDF.glob("ASCII3KH.*"):
        shutil.copy(part, tmp_path / part.name)
    store = tmp_path / "runs"
    refused(
        daq_import(store, tmp_path / f"ASCII3KH{suffix}"), store,
        "part of an HP analyzer's ASCII export (header ASCII3KH.HDR", "import the SDF file",
    )  # fmt: skip


def test_a_column_of_numbers_beside_an_unrelated_hdr_file_is_read_as_before(tmp_path):
    (tmp_path / "scan.hdr").write_text("some other program's header\n", encoding="utf-8")
    (tmp_path / "scan.txt").write_text("1.0\n2.0\n3.0\n", encoding="utf-8")
    result = daq_import(tmp_path / "runs", tmp_path / "scan.txt")
    assert result.returncode != 0
    assert "1 data column" in result.stderr
