"""Other spellings of acceleration units (hypothesis): `G`, `g's`, `G's` for g and
`m/s/s`, `mm/s/s` for m/s^2 and mm/s^2, as accelerometer software prints them, in the
header, a units row, --response-unit or a sensitivity (`mV@100mV/G`). Each reads as the
usual spelling, and the units line says how it was read. `G` is g only as an
acceleration: a force in G, or G as a prefix (`GN`, `mG`), stays refused. Before, all
of them were refused as unknown units."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from daq.formats.csv_text import read_csv
from daq.formats.errors import FormatError
from daq.formats.units import frf_unit, parse_unit

SETTINGS = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
WORK = Path(tempfile.mkdtemp(prefix="accel-spellings-"))
SPELLINGS = {"G": "g", "g's": "g", "G's": "g", "m/s/s": "m/s^2", "mm/s/s": "mm/s^2"}


def _write(header: list[str], units_row: list[str] | None, name: str, seed: int) -> Path:
    rng = np.random.default_rng(seed)
    rows = [",".join(header)] + ([",".join(units_row)] if units_row else [])
    rows += [f"{i / 4096!r},{50.0 if i == 3 else rng.normal():.6g},{rng.normal():.6g}" for i in range(64)]
    path = WORK / name
    path.write_text("\n".join(rows) + "\n", encoding="utf-8")
    return path


@SETTINGS
@given(
    spelling=st.sampled_from(sorted(SPELLINGS)),
    where=st.sampled_from(["header", "units row", "option", "sensitivity"]),
    brackets=st.sampled_from(["[{}]", "({})"]),
    name=st.sampled_from(["Acceleration", "Accel", "a", "Response", "ch2"]),
    seed=st.integers(0, 2**16),
)
def test_another_spelling_reads_as_the_usual_one(spelling, where, brackets, name, seed):
    usual = SPELLINGS[spelling]
    option, usual_option = None, None
    if where == "header":
        header, units_row = ["Time [s]", "Force [N]", f"{name} {brackets.format(spelling)}"], None
        usual_header = [*header[:2], f"{name} {brackets.format(usual)}"]
    elif where == "units row":
        header, units_row = ["Time", "Force", name], ["s", "N", spelling]
        usual_header = header
    else:
        header, units_row = ["Time [s]", "Force [N]", name], None
        usual_header = header
        option = spelling if where == "option" else f"mV@100mV/{spelling}"
        usual_option = usual if where == "option" else f"mV@100mV/{usual}"
    got = read_csv(_write(header, units_row, "other.csv", seed), response_unit=option)
    usual_row = [*units_row[:2], usual] if units_row else None
    want = read_csv(_write(usual_header, usual_row, "usual.csv", seed), response_unit=usual_option)
    np.testing.assert_array_equal(got.hits.response_m_s2, want.hits.response_m_s2)
    assert got.details["response_unit"] == (option or spelling)
    if where in ("header", "units row"):
        assert got.details["units_from"]["response"] == f"{where}, read as {usual}"


@pytest.mark.parametrize(
    ("unit", "quantity"), [("G", "force"), ("GN", "force"), ("mG", "response"), ("Gm/s^2", "response")]
)
def test_g_is_no_prefix_and_no_force(unit, quantity):
    with pytest.raises(FormatError, match=f"unknown {quantity} unit"):
        parse_unit(unit, quantity)
    # ... while the acceleration spellings are units, and FRF numerators too.
    assert parse_unit("G", "response") == parse_unit("g", "response")
    assert frf_unit("G/N") == frf_unit("g/N")
    assert frf_unit("(m/s/s)/N") == frf_unit("(m/s^2)/N")


def test_a_force_column_in_g_stays_refused(tmp_path):
    # Read by position, the force column is in G, an acceleration: the columns are swapped.
    with pytest.raises(
        FormatError, match="'Force \\[G\\]' is read as the force, but 'G' is an acceleration unit"
    ):
        read_csv(_write(["Time [s]", "Force [G]", "Accel [N]"], None, "force-g.csv", 1))
