"""Quoted cells (hypothesis): spreadsheets and loggers quote every cell, RFC 4180 style
(`"Time [s]","Force [N]","Accel [g]"` then `"0","-0.06","0.001"`). The quotes are no
part of the value, a quoted cell may hold the delimiter, and `""` inside quotes is one
literal quote. Such a file reads as the same file without quotes; before, its first
quoted data row was taken for a row of units and refused."""

from __future__ import annotations

import csv
import io
import tempfile
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from daq.formats.cells import split_line
from daq.formats.csv_text import read_csv
from daq.formats.frf_text import read_frf_text

SETTINGS = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
WORK = Path(tempfile.mkdtemp(prefix="quoted-cells-"))
DELIMITERS = [",", ";", "\t"]
# Cell text as spreadsheets hold it: no line breaks, no spaces at either end.
CELL = st.text(st.sampled_from([*"abcXYZ019.-+[]()/ ", '"', ",", ";", "\t", "µ"]), max_size=12).map(
    lambda s: s.strip(" \t")
)


@SETTINGS
@given(
    cells=st.lists(CELL, min_size=1, max_size=6), delimiter=st.sampled_from(DELIMITERS), every=st.booleans()
)
def test_cells_written_rfc_4180_style_read_back(cells, delimiter, every):
    out = io.StringIO()
    quoting = csv.QUOTE_ALL if every else csv.QUOTE_MINIMAL
    csv.writer(out, delimiter=delimiter, quoting=quoting, lineterminator="").writerow(cells)
    assert split_line(out.getvalue(), delimiter) == cells


def _quote(cell: str) -> str:
    return '"' + cell.replace('"', '""') + '"'


@SETTINGS
@given(
    delimiter=st.sampled_from(DELIMITERS),
    quoted=st.sampled_from(["all", "header", "data", "some"]),
    label=st.sampled_from(["Accel", 'Accel "tip"', "Accel, tip", "Accel; tip"]),
    n=st.integers(24, 80),
    seed=st.integers(0, 2**16),
)
def test_a_quoted_time_record_reads_as_the_plain_one(delimiter, quoted, label, n, seed):
    rng = np.random.default_rng(seed)
    header = ["Time [s]", "Force [N]", f"{label} [g]"]
    rows = [
        [f"{i / 4096:.10g}", f"{100.0 if i == 3 else rng.normal():.6g}", f"{rng.normal():.6g}"]
        for i in range(n)
    ]
    pick = rng.random((n + 1, 3)) < 0.5

    def line(k: int, cells: list[str]) -> str:
        # A cell holding a delimiter or a quote must be quoted (unquoted, "Accel; tip"
        # would make ";" the delimiter of a comma file).
        must = [any(ch in c for ch in ',;\t"') for c in cells]
        wanted = {"all": [True] * 3, "header": [k == 0] * 3, "data": [k > 0] * 3, "some": list(pick[k])}[
            quoted
        ]
        return delimiter.join(_quote(c) if w or m else c for c, w, m in zip(cells, wanted, must, strict=True))

    path = WORK / "quoted.csv"
    path.write_text(
        "\n".join(line(k, cells) for k, cells in enumerate([header, *rows])) + "\n", encoding="utf-8"
    )
    data = read_csv(path)
    assert data.details["columns"] == header
    assert data.details["response_unit"] == "g"
    np.testing.assert_array_equal(data.hits.force_n[0], [float(r[1]) for r in rows])
    np.testing.assert_array_equal(data.hits.response_m_s2[0], [float(r[2]) * 9.80665 for r in rows])
    assert abs(data.hits.sample_rate_hz - 4096.0) < 1e-5


@SETTINGS
@given(delimiter=st.sampled_from(DELIMITERS), header=st.booleans(), n=st.integers(3, 30))
def test_a_quoted_frf_table_reads(delimiter, header, n):
    rows = [[f"{k + 1}", f"{1.0 / (k + 1):.6g}", f"{-0.5 * k:.6g}"] for k in range(n)]
    lines = [delimiter.join(_quote(c) for c in ["Frequency (Hz)", "H Re", "H Im"])] if header else []
    lines += [delimiter.join(_quote(c) for c in row) for row in rows]
    path = WORK / "quoted-frf.csv"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    frfs = read_frf_text(path).measured_frfs
    assert frfs.frequency_hz.tolist() == [float(r[0]) for r in rows]
    np.testing.assert_array_equal(frfs.frf[0].imag, [float(r[2]) for r in rows])
