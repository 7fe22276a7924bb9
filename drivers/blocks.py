"""Binary blocks of floating-point values: HP ``#A`` blocks and IEEE 488.2 blocks.

* HP (3562A family, docs/instrument.md): ``#A``, a 2-byte big-endian byte count,
  then the payload.
* IEEE 488.2 definite length: ``#``, one digit n (1-9), n digits of byte count,
  then the payload.
* IEEE 488.2 indefinite length: ``#0``, the payload, then LF with EOI.

Payloads are big-endian float64 (``>f8``) or float32 (``>f4``). Anything that is
not exactly that raises ProtocolError naming the command and the bytes: a wrong
or non-numeric length, a truncated payload, stray bytes after it, a payload that
is not whole values, non-finite values, a wrong number of points.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from drivers.errors import ProtocolError

DTYPES = {">f8": np.dtype(">f8"), ">f4": np.dtype(">f4")}
#: Line ends some transports leave after a block (pyvisa issue #348); tolerated, nothing else.
TRAILERS = (b"", b"\n", b"\r\n")


@dataclass(frozen=True)
class BlockHeader:
    """Where the payload of a block starts and how long it is (None: up to the end)."""

    kind: str  # "A", "definite" or "indefinite"
    header_bytes: int
    payload_bytes: int | None


def parse_block_header(data: bytes, command: str) -> BlockHeader:
    """Decode the header at the start of ``data`` (which may hold more than the header).

    Raises ProtocolError if ``data`` does not start with a complete, valid header.
    """
    if not data.startswith(b"#"):
        raise ProtocolError(command, "expected a binary block starting with '#'", data)
    if len(data) < 2:
        raise ProtocolError(command, "truncated block header", data)
    kind = data[1:2]
    if kind == b"A":
        if len(data) < 4:
            raise ProtocolError(command, "truncated #A header (needs 4 bytes)", data)
        (length,) = struct.unpack(">H", data[2:4])
        return BlockHeader("A", 4, length)
    if kind == b"0":
        return BlockHeader("indefinite", 2, None)
    if kind.isdigit():
        n = int(kind)
        digits = data[2 : 2 + n]
        if len(digits) < n:
            raise ProtocolError(command, f"truncated IEEE block header (needs {2 + n} bytes)", data)
        if not digits.isdigit():
            raise ProtocolError(command, f"non-numeric IEEE block length {digits!r}", data)
        return BlockHeader("definite", 2 + n, int(digits))
    raise ProtocolError(command, f"unknown block type {kind!r} after '#'", data)


def parse_block(
    data: bytes,
    command: str,
    dtype: str = ">f8",
    expected_values: int | None = None,
) -> np.ndarray:
    """The values of the complete block in ``data``, as native float64, shape (n,).

    ``data`` is everything the instrument sent for the command: one block,
    optionally followed by LF or CR LF.
    """
    if dtype not in DTYPES:
        raise ValueError(f"dtype must be one of {', '.join(DTYPES)}")
    header = parse_block_header(data, command)
    body = data[header.header_bytes :]
    if header.payload_bytes is None:  # #0: up to the final LF
        if not body.endswith(b"\n"):
            raise ProtocolError(command, "indefinite (#0) block without its final LF", data)
        payload = body[:-1]
    else:
        payload, trailer = body[: header.payload_bytes], body[header.payload_bytes :]
        if len(payload) < header.payload_bytes:
            raise ProtocolError(
                command, f"truncated block: {len(payload)} of {header.payload_bytes} payload bytes", data
            )
        if trailer not in TRAILERS:
            raise ProtocolError(command, f"{len(trailer)} unexpected bytes after the block", data)
    return decode_values(payload, command, dtype, expected_values, data)


def decode_values(
    payload: bytes,
    command: str,
    dtype: str = ">f8",
    expected_values: int | None = None,
    received: bytes | None = None,
) -> np.ndarray:
    """Big-endian floats -> native float64 (n,), with the count and finiteness checked."""
    size = DTYPES[dtype].itemsize
    shown = payload if received is None else received
    if len(payload) % size:
        raise ProtocolError(
            command, f"payload of {len(payload)} bytes is not whole {size}-byte values", shown
        )
    values = np.frombuffer(payload, dtype=DTYPES[dtype]).astype(np.float64)
    if expected_values is not None and values.size != expected_values:
        raise ProtocolError(command, f"expected {expected_values} values, got {values.size}", shown)
    if not np.all(np.isfinite(values)):
        bad = int(np.flatnonzero(~np.isfinite(values))[0])
        raise ProtocolError(command, f"non-finite value at index {bad}", shown)
    return values


def read_ascii_dump(read_line: Callable[[], bytes], command: str, max_values: int) -> np.ndarray:
    """An HP ASCII dump (DDAS, DSAS), read line by line: ``#I``, then the count of
    values, then that many values, one per line (docs/instrument.md).

    The sources do not say whether the count shares the ``#I`` line, so both are
    taken. ``max_values`` bounds the count, so that a garbled count line cannot make
    the driver wait for thousands of lines. Returns float64 (n,).
    """
    head = read_line().strip()
    if not head.startswith(b"#I"):
        raise ProtocolError(command, "expected an ASCII dump starting with '#I'", head)
    count_text = head[2:].strip() or read_line().strip()
    count = _ascii_number(count_text, command, "the count")
    if count != int(count) or not 0 <= count <= max_values:
        raise ProtocolError(command, f"the count must be a whole number 0..{max_values}", count_text)
    values = np.empty(int(count))
    for i in range(int(count)):
        values[i] = _ascii_number(read_line().strip(), command, f"value {i}")
    return values


def _ascii_number(text: bytes, command: str, what: str) -> float:
    try:
        value = float(text.decode("ascii"))
    except (UnicodeDecodeError, ValueError):
        raise ProtocolError(command, f"{what} of the ASCII dump is not a number", text) from None
    if not math.isfinite(value):
        raise ProtocolError(command, f"{what} of the ASCII dump is not finite", text)
    return value
