"""The cells of one line of delimited text, with quoted cells read as RFC 4180 has them.

Spreadsheets and some loggers quote every cell (``"Time [s]","Force [N]"`` then
``"0","-0.06"``): the quotes are no part of the value, so ``"0.5"`` is the number 0.5. A
quoted cell may hold the delimiter, and ``""`` inside the quotes is one literal quote.
A cell does not run on to the next line: no impact-test export breaks a number over
lines, and the table readers number and check each line on its own.

A cell that is quoted wrongly (``"0.5`` with no closing quote, ``"1"2``) is kept as
written, so that the reader's refusal shows it.
"""

from __future__ import annotations

import re

QUOTE = '"'
# A quoted cell, "" inside it a literal quote: what choose_delimiter must look past.
_QUOTED = re.compile(r'"(?:[^"]|"")*"')
_SPACE = re.compile(r"\s")


def outside_quotes(line: str) -> str:
    """``line`` with the text inside each quoted cell taken out (``"a;b",1`` -> ``"",1``):
    a delimiter inside quotes says nothing about the line's delimiter."""
    return _QUOTED.sub('""', line) if QUOTE in line else line


def split_line(line: str, delimiter: str | None) -> list[str]:
    """The cells of ``line``, stripped of surrounding spaces and of their quotes.

    delimiter: the cell delimiter (",", ";", tab), or None for runs of whitespace.
    """
    if QUOTE not in line:  # the usual line: as fast as str.split
        return [c.strip() for c in (line.split(delimiter) if delimiter else line.split())]
    cells: list[str] = []
    i, n = 0, len(line)
    while True:
        while i < n and line[i] in " \t" and line[i] != delimiter:
            i += 1
        if delimiter is None and i >= n:
            return cells
        start = i
        value = None
        if i < n and line[i] == QUOTE:
            value, i = _quoted(line, i + 1)
        end = _cell_end(line, i, delimiter)
        if value is None or line[i:end].strip():
            value = line[start:end].strip()  # unquoted, or quoted wrongly: as written
        cells.append(value)
        if end >= n:
            return cells
        i = end + 1


def _quoted(line: str, i: int) -> tuple[str | None, int]:
    """(the value of the quoted cell whose text starts at ``i``, the index after its closing
    quote), or (None, i) when it has no closing quote on this line."""
    parts = []
    while True:
        k = line.find(QUOTE, i)
        if k < 0:
            return None, i
        if line.startswith(QUOTE, k + 1):  # "" inside quotes: one literal quote
            parts.append(line[i : k + 1])
            i = k + 2
            continue
        parts.append(line[i:k])
        return "".join(parts), k + 1


def _cell_end(line: str, i: int, delimiter: str | None) -> int:
    """The index of the delimiter that ends the cell at ``i`` (len(line) at the last)."""
    if delimiter is None:
        match = _SPACE.search(line, i)
        return match.start() if match else len(line)
    k = line.find(delimiter, i)
    return k if k >= 0 else len(line)
