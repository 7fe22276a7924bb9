"""Lines that end in CR alone (classic Mac OS, Excel's "CSV (Macintosh)"), hypothesis:
such a file reads as the same file with LF line ends, CRLF and LF mixed in too, each
line keeping its number in messages. Before, the whole file was one line, its header,
and it was refused as holding no data rows."""

from __future__ import annotations

import io
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from daq.formats.csv_text import read_csv
from daq.formats.errors import FormatError
from daq.formats.frf_text import read_frf_text
from daq.formats.line_ends import CrLines

SETTINGS = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
WORK = Path(tempfile.mkdtemp(prefix="cr-line-ends-"))
ENDS = [b"\r", b"\n", b"\r\n"]


@SETTINGS
@given(
    lines=st.lists(
        st.binary(max_size=12).map(lambda b: b.replace(b"\r", b"").replace(b"\n", b"")), max_size=20
    ),
    ends=st.lists(st.sampled_from(ENDS), min_size=20, max_size=20),
    last_ended=st.booleans(),
    chunk=st.integers(1, 9),
    limit=st.integers(1, 6),
)
def test_cr_lf_and_crlf_each_end_one_line(lines, ends, last_ended, chunk, limit):
    data = b"".join(line + end for line, end in zip(lines, ends, strict=False))
    if lines and not last_ended:
        data = data[: -len(ends[len(lines) - 1])]
    # Python's universal newlines are the reference: CR, LF and CRLF each end a line.
    universal = io.TextIOWrapper(io.BytesIO(data), encoding="latin-1", newline=None)
    want = [line.encode("latin-1") for line in universal]
    assert list(CrLines(io.BytesIO(data), chunk_bytes=chunk)) == want
    # readline(limit) gives the same bytes in pieces of at most ``limit``.
    reader, pieces = CrLines(io.BytesIO(data), chunk_bytes=chunk), []
    while piece := reader.readline(limit):
        assert len(piece) <= limit
        pieces.append(piece)
    assert b"".join(pieces) == b"".join(want)


def _rows(n: int, seed: int) -> list[str]:
    rng = np.random.default_rng(seed)
    rows = ["Time [s],Force [kN],Accel [g]"]
    rows += [f"{i / 4096:.10g},{50.0 if i == 3 else rng.normal():.6g},{rng.normal():.6g}" for i in range(n)]
    return rows


def _write(rows: list[str], ends: list[str], name: str) -> Path:
    path = WORK / name
    path.write_bytes("".join(r + e for r, e in zip(rows, ends, strict=True)).encode())
    return path


@SETTINGS
@given(
    n=st.integers(24, 300),
    seed=st.integers(0, 2**16),
    mixed=st.booleans(),
    comment=st.booleans(),
    bad=st.none() | st.integers(0, 22),  # a data line, with or without the comment line
)
def test_a_cr_only_time_record_reads_as_its_lf_twin(n, seed, mixed, comment, bad):
    rows = _rows(n, seed)
    if comment:
        rows.insert(0, "# exported on a Mac")
    if bad is not None:
        rows[2 + bad] = rows[2 + bad].rsplit(",", 1)[0] + ",oops"
    rng = np.random.default_rng(seed + 1)
    ends = [str(rng.choice(["\r", "\n", "\r\n"])) if mixed else "\r" for _ in rows]
    cr = _write(rows, ends, "cr.csv")
    lf = _write(rows, ["\n"] * len(rows), "lf.csv")
    if bad is not None:
        with pytest.raises(FormatError) as info:
            read_csv(cr)
        assert f"line {3 + bad} column 3: 'oops' is not a number" in str(info.value)
        return
    got, want = read_csv(cr), read_csv(lf)
    np.testing.assert_array_equal(got.hits.force_n, want.hits.force_n)
    np.testing.assert_array_equal(got.hits.response_m_s2, want.hits.response_m_s2)
    assert got.hits.sample_rate_hz == want.hits.sample_rate_hz
    assert got.details.get("notes") == want.details.get("notes")


@SETTINGS
@given(n=st.integers(3, 200), header=st.booleans())
def test_a_cr_only_frf_table_reads(n, header):
    rows = ["Frequency (Hz),H Re,H Im"] if header else []
    rows += [f"{k + 1},{1.0 / (k + 1):.6g},{-0.5 * k:.6g}" for k in range(n)]
    frfs = read_frf_text(_write(rows, ["\r"] * len(rows), "frf-cr.csv")).measured_frfs
    assert frfs.frequency_hz.tolist() == [float(k + 1) for k in range(n)]
