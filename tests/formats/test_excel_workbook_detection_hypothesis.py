"""An Excel workbook given to `daq import` (hypothesis): an .xlsx is a ZIP of XML parts
(`[Content_Types].xml`, `xl/workbook.xml`, `xl/worksheets/...`), often renamed .csv. It is
refused as a workbook, to be saved as CSV, whatever its name, compression, or a cut end;
any other ZIP keeps the ZIP message. Before, a workbook was told to be unpacked, which
gives XML, not a table."""

from __future__ import annotations

import io
import tempfile
import zipfile
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from daq.cli.commands.import_file import not_readable

SETTINGS = settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow])
WORK = Path(tempfile.mkdtemp(prefix="excel-zip-"))
WORKBOOK_PARTS = [
    "xl/workbook.xml",
    "xl/worksheets/sheet1.xml",
    "xl/styles.xml",
    "xl/_rels/workbook.xml.rels",
]
PACKAGE_PARTS = ["[Content_Types].xml", "_rels/.rels", "docProps/app.xml", "docProps/core.xml"]
OTHER_PARTS = [
    "data.csv",
    "hits/hit1.csv",
    "word/document.xml",
    "ppt/presentation.xml",
    "readme.txt",
    "xl.txt",
]
WORKBOOK = (
    "an Excel workbook (.xlsx), which daq does not read; save the sheet as CSV (or text) from the spreadsheet"
)


def _zip(names: list[str], compression: int) -> bytes:
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w", compression=compression) as archive:
        for name in names:
            archive.writestr(name, "<x/>" * 50)
    return out.getvalue()


def _refusal(data: bytes, suffix: str, cut: bool) -> str:
    if cut:  # copied short: without its end record zipfile cannot read the archive
        data = data[:-22]
    path = WORK / f"upload{suffix}"
    path.write_bytes(data)
    return not_readable(path, data[:16384])


@st.composite
def workbooks(draw):
    names = draw(st.lists(st.sampled_from(WORKBOOK_PARTS), min_size=1, unique=True))
    package = draw(st.lists(st.sampled_from(PACKAGE_PARTS), unique=True))
    if "xl/workbook.xml" not in names and "[Content_Types].xml" not in package:
        package.append("[Content_Types].xml")
    return draw(st.permutations(package + names))


@SETTINGS
@given(
    names=workbooks(),
    compression=st.sampled_from([zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED]),
    suffix=st.sampled_from([".csv", ".txt", ".xlsx", ".dat", ""]),
    cut=st.booleans(),
    others=st.lists(st.sampled_from(OTHER_PARTS + PACKAGE_PARTS), min_size=1, unique=True),
)
def test_a_workbook_is_told_to_be_saved_as_csv(names, compression, suffix, cut, others):
    message = _refusal(_zip(names, compression), suffix, cut)
    assert f"upload{suffix}: {WORKBOOK}" in message
    assert "unpack" not in message
    assert "\n" not in message
    # Any other ZIP (a folder of CSVs, a Word document) keeps the ZIP message.
    message = _refusal(_zip(others, compression), suffix, cut)
    assert message.endswith(f"upload{suffix}: a ZIP archive; unpack it and import the files inside")
