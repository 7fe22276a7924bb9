"""A column empty on every line, its header cell too (hypothesis): a delimiter at the end
of every line (`0,1,2,`), or an empty column between others. It is no column: the file
reads as it would without it, with one note saying so. A column empty on some lines only
is refused as any empty cell is, at the first line where it is empty. Before, the file was
refused: "line 2 column 4: '' is not a number"."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from daq.formats.csv_text import read_csv
from daq.formats.errors import FormatError
from daq.formats.frf_text import read_frf_text

SETTINGS = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
WORK = Path(tempfile.mkdtemp(prefix="empty-columns-"))
HEADER = ["Time [s]", "Force [N]", "Accel [g]"]


def _table(n: int, seed: int) -> list[list[str]]:
    rng = np.random.default_rng(seed)
    return [
        [f"{i / 4096:.10g}", f"{50.0 if i == 3 else rng.normal():.6g}", f"{rng.normal():.6g}"]
        for i in range(n)
    ]


def _with_empty(rows: list[list[str]], at: list[int]) -> list[list[str]]:
    """Each row with an empty cell inserted at each position of ``at`` (ascending)."""
    out = []
    for row in rows:
        row = list(row)
        for position in at:
            row.insert(position, "")
        out.append(row)
    return out


def _write(rows: list[list[str]], delimiter: str, name: str) -> Path:
    path = WORK / name
    path.write_text("\n".join(delimiter.join(r) for r in rows) + "\n", encoding="utf-8")
    return path


@st.composite
def empty_columns(draw):
    """Positions (in the widened row, ascending) of the empty columns: one or two at the
    end, or one between the time and the data columns."""
    trailing = draw(st.integers(0, 2))
    middle = draw(st.booleans()) if trailing else True
    return ([1] if middle else []) + [3 + middle + k for k in range(trailing)], middle


@SETTINGS
@given(
    n=st.integers(24, 120),
    seed=st.integers(0, 2**16),
    empty=empty_columns(),
    delimiter=st.sampled_from([",", ";", "\t"]),
    header=st.booleans(),
)
def test_an_empty_column_is_no_column(n, seed, empty, delimiter, header):
    at, middle = empty
    rows = _table(n, seed)
    plain = _write(([HEADER] if header else []) + rows, delimiter, "plain.csv")
    wide = _write(_with_empty(([HEADER] if header else []) + rows, at), delimiter, "wide.csv")
    want, got = read_csv(plain), read_csv(wide)
    np.testing.assert_array_equal(got.hits.force_n, want.hits.force_n)
    np.testing.assert_array_equal(got.hits.response_m_s2, want.hits.response_m_s2)
    assert got.hits.sample_rate_hz == want.hits.sample_rate_hz
    said = [note for note in got.details["notes"] if "empty on every line" in note]
    columns = ", ".join(str(c + 1) for c in at)
    verb = "are" if len(at) > 1 else "is"
    why = "" if middle else " (a delimiter at the end of every line)"
    assert said == [f"column{'s' if len(at) > 1 else ''} {columns} {verb} empty on every line{why}: "
                    f"read without {'them' if len(at) > 1 else 'it'}"]  # fmt: skip
    assert not any("ignored" in note for note in got.details["notes"])
    # Filled on one later line, the column is a column with empty cells: refused at the
    # first of them, as before.
    filled = _with_empty(([HEADER] if header else []) + rows, at)
    filled[-1 - seed % (n - 1)][at[-1]] = "1.5"  # any data line but the first
    with pytest.raises(FormatError) as info:
        read_csv(_write(filled, delimiter, "bad.csv"))
    first = 2 if header else 1
    assert str(info.value).endswith(f"bad.csv line {first} column {at[-1] + 1}: '' is not a number")


@SETTINGS
@given(n=st.integers(3, 60), delimiter=st.sampled_from([",", ";", "\t"]), header=st.booleans())
def test_an_frf_table_with_a_delimiter_at_every_line_end_reads(n, delimiter, header):
    rows = [[f"{k + 1}", f"{1.0 / (k + 1):.6g}", f"{-0.5 * k:.6g}"] for k in range(n)]
    lines = ([["Frequency (Hz)", "H Re", "H Im", ""]] if header else []) + [[*r, ""] for r in rows]
    data = read_frf_text(_write(lines, delimiter, "frf.csv"))
    assert data.measured_frfs.frequency_hz.tolist() == [float(r[0]) for r in rows]
    assert data.details["notes"][0].startswith("column 4 is empty on every line")
