"""The bytes of an SDF file with bounds-checked access: every read names the record it
wants, and anything outside the file becomes a one-line FormatError naming the file."""

from __future__ import annotations

from typing import Any, NoReturn

from daq.formats.errors import FormatError
from daq.formats.imported import one_line, show_path
from daq.formats.sdf import codes
from daq.formats.sdf.layout import Layout

HEAD_SIZE = 6  # recordType int16 + recordSize int32


class Source:
    """``data``: the whole physical file; ``base``: where the current logical file's
    "B\\0" is (every offset in a logical file counts from there)."""

    def __init__(self, data: bytes, name: str, base: int = 0) -> None:
        self.data = data
        self.name = show_path(name)
        self.base = base
        self.view = memoryview(data)

    def fail(self, what: str) -> NoReturn:
        raise FormatError(f"{self.name}: {one_line(what)}")

    def at(self, offset: int) -> int:
        """The absolute position of ``offset`` (relative to the logical file)."""
        return self.base + offset

    def need(self, start: int, size: int, what: str) -> None:
        """Fail unless bytes [start, start + size) of the physical file exist."""
        if start < 0 or size < 0 or start + size > len(self.data):
            end = start + size
            self.fail(
                f"truncated or damaged SDF file: {what} needs bytes {start}..{end} "
                f"but the file has {len(self.data)}"
            )

    def record(self, offset: int, expect: int, what: str, min_size: int) -> tuple[int, int]:
        """Check the record head at ``offset`` (relative): its type must be ``expect``
        (for codes.UNIQUE_TYPES: any instrument-specific type), its size at least
        ``min_size`` and inside the file. Returns (absolute start, record size)."""
        if offset < 0:
            self.fail(f"{what} has a negative offset ({offset})")
        start = self.at(offset)
        self.need(start, HEAD_SIZE, f"{what} at byte {start}")
        kind = int.from_bytes(self.data[start : start + 2], "big", signed=True)
        size = int.from_bytes(self.data[start + 2 : start + 6], "big", signed=True)
        if expect == codes.UNIQUE_TYPES.start:
            if kind not in codes.UNIQUE_TYPES:
                self.fail(
                    _type_problem(kind, f"{what} at byte {start}", "an instrument-specific type 1000..2000")
                )
        elif kind != expect:
            self.fail(
                _type_problem(kind, f"{what} at byte {start}", f"{expect} ({codes.RECORD_NAMES[expect]})")
            )
        if size < min_size:
            self.fail(f"{what} at byte {start} says it is {size} bytes long; it needs at least {min_size}")
        self.need(start, size, f"{what} at byte {start} ({size} bytes)")
        return start, size

    def unpack(self, layout: Layout, start: int, what: str) -> dict[str, Any]:
        self.need(start, layout.size, what)
        return layout.unpack(self.view, start)


def _type_problem(kind: int, where: str, wanted: str) -> str:
    if kind in codes.RECORD_NAMES:
        return f"{where} is a {codes.RECORD_NAMES[kind]} record (type {kind}), expected type {wanted}"
    if kind in codes.UNIQUE_TYPES:
        return f"{where} is an instrument-specific record (type {kind}), expected type {wanted}"
    return f"{where} has an unknown record type {kind}, expected type {wanted}"
