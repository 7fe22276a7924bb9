"""A header with units in brackets, in a table whose cells are separated by spaces: each
unit belongs to the name before it ("Time (s)" is one column), so a one-column file gets
the message about the columns it needs, and a three-column one imports with its units."""

from __future__ import annotations

import pytest

from daq.formats.csv_text import join_units
from tests.cli_helpers import assert_one_line_error, invoke_daq


def test_a_one_column_file_headed_time_in_seconds_is_told_what_columns_it_needs(tmp_path):
    path = tmp_path / "onecol.csv"
    path.write_text("Time (s)\n" + "".join(f"{i / 1000:g}\n" for i in range(32)))
    result = invoke_daq("import", str(path), "--store", str(tmp_path / "runs"))
    assert_one_line_error(result, "onecol.csv has 1 data column; need time, force and response")
    assert "expected 2" not in result.stderr


def test_a_whitespace_table_with_units_in_its_header_imports_with_them(tmp_path):
    path = tmp_path / "ws.txt"
    rows = ["Time (ms)  Force [kN]  acc (g)"]
    rows += [f"{i * 0.5:g}  {0.2 if i == 3 else 0.0:g}  {(-1) ** i * 0.5:g}" for i in range(64)]
    path.write_text("\n".join(rows) + "\n")
    store = tmp_path / "runs"
    result = invoke_daq("import", str(path), "--store", str(store))
    assert result.returncode == 0, result.stderr
    assert "units: time ms, force kN (header), response g (header)" in result.stdout
    from daq.store import Store

    (summary,) = Store(store).list()
    hits = Store(store).open(summary.run_id).hits
    assert hits.sample_rate_hz == pytest.approx(2000.0)
    assert hits.force_n.max() == pytest.approx(200.0)
    assert abs(hits.response_m_s2[0, 0]) == pytest.approx(0.5 * 9.80665)


@pytest.mark.parametrize(
    ("cells", "joined"),
    [
        (["Time", "(s)"], ["Time (s)"]),
        (["t", "[s]", "F", "[N]", "a", "[m", "/", "s^2]"], ["t [s]", "F [N]", "a [m / s^2]"]),
        (["hit", "time", "force", "response"], ["hit", "time", "force", "response"]),
        (["(s)", "x"], ["(s)", "x"]),
    ],
)
def test_units_join_the_name_before_them(cells, joined):
    assert join_units(cells) == joined
