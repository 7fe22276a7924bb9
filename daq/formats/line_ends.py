"""The lines of a text file whatever its line ends: LF, CRLF, or CR alone.

Classic Mac OS programs (and Excel's "CSV (Macintosh)") end lines with a CR alone.
Iterating a binary file splits at LF only, so such a file was one long line: its header
and no data rows. The table readers read through :func:`text_lines`, which hands them the
file itself when its start shows no lone CR (the usual file, read at full speed), else a
reader that ends a line at every CR, LF or CRLF and gives each line ending in LF (the
last line keeps its lack of a line end, which the readers note).
"""

from __future__ import annotations

import re
from collections import deque
from typing import IO

#: How much of the file's start decides whether its lines end in CR alone (bytes).
PEEK_BYTES = 1 << 16
_CHUNK_BYTES = 1 << 20
_LONE_CR = re.compile(rb"\r(?!\n)")


def text_lines(handle: IO[bytes]) -> IO[bytes] | CrLines:
    """``handle`` (a regular file open for binary reading, at its start) when its first
    PEEK_BYTES hold no lone CR, else a CrLines over it. Either gives lines by iteration
    and by readline(limit)."""
    start = handle.read(PEEK_BYTES)
    handle.seek(0)
    # A CR as the very last byte read may be the first half of a CRLF cut by the read.
    if _LONE_CR.search(start[:-1] if len(start) == PEEK_BYTES else start):
        return CrLines(handle)
    return handle


class CrLines:
    """Lines of a binary file split at CR, LF and CRLF, each given ending in LF."""

    def __init__(self, handle: IO[bytes], chunk_bytes: int = _CHUNK_BYTES) -> None:
        self._handle = handle
        self._chunk_bytes = chunk_bytes
        self._lines: deque[bytes] = deque()
        self._tail = b""  # the last line read, not known to be whole yet
        self._eof = False

    def _fill(self) -> None:
        chunk = self._handle.read(self._chunk_bytes)
        if not chunk:
            self._eof = True
            if self._tail:
                self._lines.append(_lf(self._tail))
                self._tail = b""
            return
        pieces = (self._tail + chunk).splitlines(keepends=True)  # bytes: CR, LF, CRLF only
        # A last piece without a line end may go on in the next chunk; one ending in CR
        # may be a CRLF whose LF starts the next chunk.
        self._tail = b"" if pieces[-1].endswith(b"\n") else pieces.pop()
        self._lines.extend(_lf(p) for p in pieces)

    def readline(self, limit: int = -1) -> bytes:
        """The next line (ending in LF but the file's last, if that has no line end), at
        most ``limit`` bytes of it when limit >= 0 (the rest comes next); b"" at the end."""
        while not self._lines and not self._eof:
            self._fill()
        if not self._lines:
            return b""
        line = self._lines[0]
        if 0 <= limit < len(line):
            self._lines[0] = line[limit:]
            return line[:limit]
        return self._lines.popleft()

    def __iter__(self) -> CrLines:
        return self

    def __next__(self) -> bytes:
        line = self.readline()
        if not line:
            raise StopIteration
        return line


def _lf(line: bytes) -> bytes:
    """``line`` with its line end (CR, LF or CRLF), if any, as LF."""
    if line.endswith((b"\r", b"\n")):
        return line.rstrip(b"\r\n") + b"\n"
    return line
