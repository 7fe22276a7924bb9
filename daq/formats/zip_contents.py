"""What a ZIP archive given to `daq import` holds, so that its refusal says what it is.

An Excel workbook (.xlsx, and .xlsm and .xltx alike) is an Office Open XML package: a ZIP
whose members are XML parts, `[Content_Types].xml` and the workbook's parts under `xl/`
(`xl/workbook.xml`, `xl/worksheets/sheet1.xml`, ...). Renamed `.csv`, it was told to be
unpacked, which gives XML, not a table: it must be saved as CSV from the spreadsheet.
"""

from __future__ import annotations

import struct
import zipfile
from pathlib import Path

LOCAL_HEADER = b"PK\x03\x04"  # a ZIP member's local file header: 30 bytes, then its name


def member_names(path: Path, head: bytes) -> list[str]:
    """The names of the members of the ZIP archive at ``path``: from its central directory,
    else (an archive cut short or damaged) from the local headers in ``head``, its first
    bytes."""
    try:
        with zipfile.ZipFile(path) as archive:
            return archive.namelist()
    except (zipfile.BadZipFile, OSError, EOFError, ValueError):
        pass
    names, at = [], head.find(LOCAL_HEADER)
    while at >= 0 and at + 30 <= len(head):
        size, extra = struct.unpack_from("<HH", head, at + 26)
        names.append(head[at + 30 : at + 30 + size].decode("utf-8", errors="replace"))
        at = head.find(LOCAL_HEADER, at + 30 + size + extra)
    return names


def is_excel_workbook(names: list[str]) -> bool:
    """Whether ZIP members of these ``names`` make an Excel workbook: parts under `xl/` with
    the package's `[Content_Types].xml`, or the workbook part `xl/workbook.xml` itself."""
    in_xl = any(name.startswith("xl/") for name in names)
    return in_xl and ("[Content_Types].xml" in names or "xl/workbook.xml" in names)
