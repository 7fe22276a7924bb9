"""The one error the format readers and writers raise: a one-line message naming the file.

A :class:`FormatError` says a file cannot be read as what it claims to be (a damaged
CSV, UFF 58 or SDF file, an unknown unit), or a run cannot be written as one. It
belongs to this layer, not to the command line's: daq/cli/errors.py turns it into
``daq: error: ...`` and exit status 1.
"""

from __future__ import annotations


class FormatError(Exception):
    """A file that cannot be read (or written) as its format; one-line message, exit status 1.

    No reader or writer asks for another status, so there is no ``exit_code`` argument.
    """

    exit_code = 1

    def __init__(self, message: str) -> None:
        # Messages must stay on one line: the CLI prints them after "daq: error: ".
        super().__init__(" ".join(str(message).split()))


def count(n: int, noun: str) -> str:
    """``n`` and ``noun``, plural unless n is 1: "1 column", "3 columns"."""
    return f"{n} {noun}" if n == 1 else f"{n} {noun}s"
