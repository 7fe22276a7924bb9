"""Two refusals a new user could not act on, now saying what is wrong:

- a line whose cells are separated by another delimiter than the lines above (a tab in a
  comma file) read `line 5: 1 column, expected 3` of a line with three cells (hypothesis);
- a UFF of acceleration records alone (output-only data, pyuff's MPSTD example) read
  `0 force and 4 acceleration time records; they must pair up`.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from daq.formats.csv_text import read_csv
from daq.formats.errors import FormatError
from daq.formats.uff58 import read_uff
from tests.formats.test_uff58 import time_set, write_sets

WORK = Path(tempfile.mkdtemp(prefix="mixed-delimiters-"))
NAMES = {",": "commas", ";": "semicolons", "\t": "tabs"}


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    delimiters=st.sampled_from([(",", "\t"), (",", ";"), (";", "\t"), ("\t", ",")]),
    odd_row=st.integers(0, 60),
)
def test_a_line_with_another_delimiter_is_named_as_such(delimiters, odd_row):
    usual, odd = delimiters
    rows = [usual.join(["Time [s]", "Force [N]", "Accel [m/s^2]"])]
    for k in range(64):
        cells = [f"{k / 2048:.9f}", f"{100.0 if k == 3 else 0.0}", f"{0.001 * (-1) ** k:.6g}"]
        rows.append((odd if k == odd_row else usual).join(cells))
    path = WORK / "mixed.csv"
    path.write_text("\n".join(rows) + "\n", encoding="utf-8")
    said = f"line {odd_row + 2}: .*its cells are separated by {NAMES[odd]}, the lines above by {NAMES[usual]}"
    with pytest.raises(FormatError, match=said):
        read_csv(path)


def test_a_line_short_of_a_cell_is_not_told_of_delimiters(tmp_path):
    path = tmp_path / "short.csv"
    path.write_text("t,F,a\n0,1,2\n0.1,2\n0.2,3,4\n", encoding="utf-8")
    with pytest.raises(FormatError, match=r"line 3: 2 columns, expected 3$"):
        read_csv(path)


def test_acceleration_records_alone_are_refused_as_output_only_data(tmp_path):
    x = np.arange(256) / 1024.0
    sets = [time_set(np.sin(2 * np.pi * 50 * x) * (k + 1), 12, "m/s^2", x) for k in range(4)]
    path = write_sets(tmp_path / "oma.uff", sets)
    with pytest.raises(FormatError, match="4 acceleration time records and no force record") as info:
        read_uff(path)
    assert "pair up" not in str(info.value)
