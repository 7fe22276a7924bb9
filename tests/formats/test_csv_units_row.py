"""A row of units under a CSV time record's header (hypothesis), as LabVIEW, DEWESoft and
Excel users write it: `Time,Force,Accel` then `s,N,g`. Each unit fills the one its
column's name lacks and is applied; a row of words that are not all units is refused in
one line saying how to write them (a new user's file was refused with "'s' is not a
number")."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from daq.formats.csv_text import read_csv
from daq.formats.errors import FormatError
from tests.cli_helpers import assert_one_line_error, invoke_daq

SETTINGS = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
WORK = Path(tempfile.mkdtemp(prefix="units-row-"))
TIME = {"s": 1.0, "ms": 1e-3}
FORCE = {"N": 1.0, "kN": 1000.0, "lbf": 4.4482216152605}
RESPONSE = {"g": 9.80665, "m/s^2": 1.0, "mm/s^2": 1e-3}


def _table(delimiter: str, units: list[str], wrap: str) -> str:
    comma = delimiter != ","
    rows = [delimiter.join(["Time", "Force", "Accel"]), delimiter.join(wrap.format(u) for u in units)]
    step = 1 / 4000 / TIME[units[0]]
    for i in range(16):
        cells = [f"{i * step!r}", f"{1.5 * i!r}", f"{0.01 * i!r}"]
        rows.append(delimiter.join(c.replace(".", ",") if comma else c for c in cells))
    return "\n".join(rows) + "\n"


@SETTINGS
@given(
    time_unit=st.sampled_from(sorted(TIME)),
    force_unit=st.sampled_from(sorted(FORCE)),
    response_unit=st.sampled_from(sorted(RESPONSE)),
    delimiter=st.sampled_from([",", ";", "\t"]),
    wrap=st.sampled_from(["{}", "[{}]", "({})"]),
)
def test_a_units_row_is_read_and_applied(time_unit, force_unit, response_unit, delimiter, wrap):
    path = WORK / "units_row.csv"
    path.write_text(_table(delimiter, [time_unit, force_unit, response_unit], wrap), encoding="utf-8")
    data = read_csv(path)
    assert data.hits.sample_rate_hz == pytest.approx(4000.0, rel=1e-9)
    np.testing.assert_allclose(data.hits.force_n[0], 1.5 * np.arange(16) * FORCE[force_unit], rtol=1e-12)
    np.testing.assert_allclose(
        data.hits.response_m_s2[0], 0.01 * np.arange(16) * RESPONSE[response_unit], rtol=1e-12
    )


@SETTINGS
@given(word=st.sampled_from(["zz", "volts?", "Kraft", "unit"]))
def test_a_row_of_words_that_are_not_all_units_is_refused_saying_how_to_write_them(word):
    path = WORK / "words_row.csv"
    path.write_text(_table(",", ["s", "N", word], "{}"), encoding="utf-8")
    with pytest.raises(FormatError) as info:
        read_csv(path)
    message = str(info.value)
    assert "\n" not in message
    assert f"'{word}' is none; write the units in the header instead" in message


def test_daq_import_of_a_units_row_file_and_of_a_bad_one(tmp_path):
    good, bad = tmp_path / "good.csv", tmp_path / "bad.csv"
    good.write_text(_table(";", ["s", "N", "g"], "{}"), encoding="utf-8")
    bad.write_text(_table(";", ["s", "N", "zz"], "{}"), encoding="utf-8")
    store = tmp_path / "store"
    result = invoke_daq("import", str(good), "--store", str(store))
    assert result.returncode == 0, result.stderr
    assert "units: time s, force N (units row), response g (units row)" in result.stdout
    before = sorted(p.name for p in store.iterdir())
    result = invoke_daq("import", str(bad), "--store", str(store))
    assert_one_line_error(result, "line 2: a row of words under the header", "'zz' is none")
    assert sorted(p.name for p in store.iterdir()) == before
