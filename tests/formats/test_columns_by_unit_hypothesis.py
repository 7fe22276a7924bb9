"""A header whose units say the force and response columns are not where they are read
(hypothesis): `Time (s),Acceleration (g),Force (N)`, read by position, takes the
acceleration as the force. The reader takes the columns by their units instead, and says
so in one note; where the header cannot say (two columns in a force unit) the refusal
names the --columns that reads the file right, and that value does (before, it said to
give --force-unit, which only moved the error)."""

from __future__ import annotations

import re
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from daq.formats.csv_text import read_csv
from daq.formats.errors import FormatError

SETTINGS = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
WORK = Path(tempfile.mkdtemp(prefix="columns-by-unit-"))
FORCE = {"N": 1.0, "kN": 1000.0, "lbf": 4.4482216152605}
RESPONSE = {"g": 9.80665, "m/s^2": 1.0, "mm/s^2": 1e-3}


def _write(cells: list[str], extra_values: list[str]) -> Path:
    rows = [",".join(cells)]
    for i in range(16):
        rows.append(",".join([f"{i / 4000!r}", f"{0.01 * i!r}", f"{1.5 * i!r}", *extra_values]))
    path = WORK / "swapped.csv"
    path.write_text("\n".join(rows) + "\n", encoding="utf-8")
    return path


def _check(hits, force_unit: str, response_unit: str) -> None:
    np.testing.assert_allclose(hits.force_n[0], 1.5 * np.arange(16) * FORCE[force_unit], rtol=1e-12)
    np.testing.assert_allclose(
        hits.response_m_s2[0], 0.01 * np.arange(16) * RESPONSE[response_unit], rtol=1e-12
    )


@SETTINGS
@given(
    names=st.sampled_from([("Time", "Force", "Acceleration"), ("t", "F", "a"), ("Zeit", "Kraft", "Beschl.")]),
    force_unit=st.sampled_from(sorted(FORCE)),
    response_unit=st.sampled_from(sorted(RESPONSE)),
    brackets=st.sampled_from(["({})", "[{}]"]),
    extra=st.booleans(),
)
def test_a_force_column_in_an_acceleration_unit_is_read_by_the_units(
    names, force_unit, response_unit, brackets, extra
):
    time_name, force_name, response_name = names
    cells = [
        f"{time_name} {brackets.format('s')}",
        f"{response_name} {brackets.format(response_unit)}",
        f"{force_name} {brackets.format(force_unit)}",
    ]
    if extra:
        cells.append("note")  # a column with no unit: neither force nor response
    data = read_csv(_write(cells, ["7"] if extra else []))
    _check(data.hits, force_unit, response_unit)
    said = [n for n in data.details.get("notes", []) if n.startswith("columns taken by their")]
    assert len(said) == 1, data.details
    assert f"force '{cells[2]}'" in said[0]
    assert f"response '{cells[1]}'" in said[0]


@SETTINGS
@given(
    force_unit=st.sampled_from(sorted(FORCE)),
    response_unit=st.sampled_from(sorted(RESPONSE)),
    brackets=st.sampled_from(["({})", "[{}]"]),
)
def test_a_header_that_cannot_say_which_is_the_force_points_at_columns(force_unit, response_unit, brackets):
    """Two columns in a force unit: nothing is guessed; the refusal's --columns reads it."""
    cells = [
        f"Time {brackets.format('s')}",
        f"Acceleration {brackets.format(response_unit)}",
        f"Force {brackets.format(force_unit)}",
        f"Reaction {brackets.format(force_unit)}",
    ]
    path = _write(cells, ["7"])
    with pytest.raises(FormatError) as info:
        read_csv(path)
    message = str(info.value)
    assert "\n" not in message
    assert "--force-unit" not in message
    found = re.search(r"--columns (\S+) \(time, force, response\)", message)
    assert found, message
    _check(read_csv(path, columns=found.group(1)).hits, force_unit, response_unit)
