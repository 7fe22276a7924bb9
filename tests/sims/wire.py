"""Test-side decoding of what the analyzer sends, written from the documented formats
(docs/instrument.md, "Trace format"; not shared with sims/ or drivers/, so a bug
there cannot hide here)."""

from __future__ import annotations

import struct

import numpy as np

HEADER_LENGTH = 66


def split_block(data: bytes) -> tuple[bytes, bytes]:
    """(payload, rest) of an ``#A`` block at the start of ``data``."""
    assert data[:2] == b"#A", data[:16]
    (length,) = struct.unpack(">H", data[2:4])
    payload = data[4 : 4 + length]
    assert len(payload) == length, f"block claims {length} bytes, {len(payload)} arrived"
    return payload, data[4 + length :]


def decode_trace(data: bytes) -> tuple[np.ndarray, np.ndarray]:
    """(header (66,), data) of a DDAN reply; data complex when header word 36 is 0."""
    payload, rest = split_block(data)
    assert rest == b"", rest[:16]
    values = np.frombuffer(payload, dtype=">f8").astype(float)
    header, body = values[:HEADER_LENGTH], values[HEADER_LENGTH:]
    if header[36] == 0.0:  # complex: interleaved re, im
        body = body[0::2] + 1j * body[1::2]
    assert body.size == int(header[1])
    return header, body


def decode_ascii_trace(data: bytes) -> np.ndarray:
    """Every value of a DDAS reply (``#I``, the count, one value per line), (66 + n,) float."""
    lines = data.split(b"\r\n")
    assert lines[0] == b"#I", lines[0]
    assert lines[-1] == b""
    values = np.array([float(x) for x in lines[2:-1]])
    assert values.size == int(lines[1]), (lines[1], values.size)
    return values


def ask(conn, text: str) -> bytes:
    """Send one message; every byte the analyzer replies (b"" for none)."""
    conn.write(text.encode("ascii") + b"\n")
    try:
        return conn.read(timeout_s=0.0)
    except TimeoutError:
        return b""
