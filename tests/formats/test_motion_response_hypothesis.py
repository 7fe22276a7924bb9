"""A time record whose response column is a velocity or a displacement (hypothesis): the
header says `Velocity [m/s]` or `Disp (mm)`, a units row says `m/s`, or --response-unit
does. Time records are read as acceleration over force, so the file is refused, in one
line saying why and what to do (differentiate, or import the FRF table with the matching
--frf-form); before, it was told "unknown response unit 'm/s'", as if a spelling were wrong."""

from __future__ import annotations

import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from daq.formats.csv_text import read_csv
from daq.formats.errors import FormatError

SETTINGS = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
WORK = Path(tempfile.mkdtemp(prefix="motion-response-"))
# unit -> (the --frf-form of that quantity over force, how often to differentiate)
MOTION = {
    "m/s": ("mobility", "once"),
    "mm/s": ("mobility", "once"),
    "m": ("receptance", "twice"),
    "mm": ("receptance", "twice"),
    "um": ("receptance", "twice"),
    "µm": ("receptance", "twice"),
}


def _write(header: list[str], units_row: list[str] | None, delimiter: str) -> Path:
    rows = [delimiter.join(header)]
    if units_row is not None:
        rows.append(delimiter.join(units_row))
    for i in range(64):
        rows.append(delimiter.join([repr(i / 4096), repr(100.0 if i == 3 else 0.01), repr(0.5 * i)]))
    path = WORK / "motion.csv"
    path.write_text("\n".join(rows) + "\n", encoding="utf-8")
    return path


@SETTINGS
@given(
    unit=st.sampled_from(sorted(MOTION)),
    name=st.sampled_from(["Velocity", "vel", "Disp", "x", "Response", "resp"]),
    where=st.sampled_from(["header", "units row", "option"]),
    brackets=st.sampled_from(["[{}]", "({})"]),
    delimiter=st.sampled_from([",", ";", "\t"]),
)
def test_a_velocity_or_displacement_response_is_refused_saying_why(unit, name, where, brackets, delimiter):
    form, times = MOTION[unit]
    if where == "header":
        path = _write(["Time [s]", "Force [N]", f"{name} {brackets.format(unit)}"], None, delimiter)
        option = None
    elif where == "units row":
        path = _write(["Time", "Force", name], ["s", "N", unit], delimiter)
        option = None
    else:
        path = _write(["Time [s]", "Force [N]", name], None, delimiter)
        option = unit
    with pytest.raises(FormatError) as info:
        read_csv(path, response_unit=option)
    message = str(info.value)
    assert "\n" not in message
    assert "\r" not in message
    assert f"{unit!r} is a {'velocity' if form == 'mobility' else 'displacement'}" in message
    assert "a time record's response must be an acceleration" in message
    assert f"differentiate it {times} to m/s^2" in message
    assert message.endswith(f"--format frf-text --frf-form {form}")
    assert "unknown" not in message
    # The same file in an acceleration unit reads.
    accel = "g" if where == "option" else brackets.format("g")
    if where == "units row":
        path = _write(["Time", "Force", name], ["s", "N", "g"], delimiter)
    elif where == "header":
        path = _write(["Time [s]", "Force [N]", f"{name} {accel}"], None, delimiter)
    data = read_csv(path, response_unit="g" if where == "option" else None)
    assert data.details["response_unit"] == "g"
