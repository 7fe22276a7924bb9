"""The FRF unit of a SignalCalc-style units row: an imperial unit is converted, an unknown
one over a force is refused, and a label that is no unit ("Ratio") is still passed over.

A new user's SignalCalc export with the units row ``(in/s²)(lbf)`` was stored as
(m/s^2)/N, 175 times off, with a caution pointing to --frf-form, which cannot scale."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from daq.formats.errors import FormatError
from daq.formats.frf_text import read_frf_text
from daq.formats.units import INCH_M, POUND_FORCE_N

LINES = 64


def signalcalc(path, unit: str) -> np.ndarray:
    """Write a SignalCalc ASCII export (CRLF, Latin-1, 9 header lines) with ``unit`` in its
    units row; the FRF's values as written, (LINES,) complex."""
    f = np.arange(LINES) * 0.5
    h = (1.0 + 0.25 * np.arange(LINES)) * np.exp(1j * 0.1 * np.arange(LINES))
    head = [
        "Units: Ratio",
        "Ref Chan:Resp Chan\t0-Z:0-Z",
        "Channel Name\t : ",
        "Channel Comment\t : ",
        "",
        "Frequency\t Real\t Imaginary",
        "",
        "Units:",
        f"Hz\t{unit}\t ",
    ]
    rows = [f"{x:.13e}\t{float(v.real)!r}\t{float(v.imag)!r}" for x, v in zip(f, h, strict=True)]
    path.write_bytes(("\r\n".join(head + rows) + "\r\n").encode("latin-1"))
    return h


@pytest.mark.parametrize(
    ("unit", "form", "factor"),
    [
        ("(in/s²)(lbf)", "accelerance", INCH_M / POUND_FORCE_N),
        ("(in/s)(lbf)", "mobility", INCH_M / POUND_FORCE_N),
        ("(in)(N)", "receptance", INCH_M),
        ("(m/s²)(N)", "accelerance", 1.0),
        ("(g)(lbf)", "accelerance", 9.80665 / POUND_FORCE_N),
    ],
)
def test_a_units_row_in_imperial_or_si_units_is_converted(tmp_path, unit, form, factor):
    h = signalcalc(tmp_path / "Hxysv00001.txt", unit)
    data = read_frf_text(tmp_path / "Hxysv00001.txt")
    assert data.measured_frfs.form == form
    np.testing.assert_allclose(data.measured_frfs.frf[0], h * factor, rtol=1e-12)


@pytest.mark.parametrize("unit", ["(furlong/s²)(N)", "(in/s²)(ozf)", "furlong/lbf"])
def test_an_unknown_unit_over_a_force_is_refused_in_one_line(tmp_path, unit):
    signalcalc(tmp_path / "Hxysv00001.txt", unit)
    with pytest.raises(FormatError) as excinfo:
        read_frf_text(tmp_path / "Hxysv00001.txt")
    message = str(excinfo.value)
    assert "\n" not in message
    assert "unknown FRF unit" in message
    assert "if the values are in SI units, give --frf-form" in message


def test_a_label_that_is_no_unit_still_leaves_the_default(tmp_path):
    h = signalcalc(tmp_path / "Hxysv00001.txt", "Ratio")
    data = read_frf_text(tmp_path / "Hxysv00001.txt")
    assert data.measured_frfs.form == "accelerance"
    np.testing.assert_array_equal(data.measured_frfs.frf[0], h)
    assert "no FRF unit" in data.details["form_from"]


UNITS = {
    "(in/s²)(lbf)": ("accelerance", INCH_M / POUND_FORCE_N),
    "(in/s)(N)": ("mobility", INCH_M),
    "(in)(kN)": ("receptance", INCH_M / 1000.0),
    "(g)(N)": ("accelerance", 9.80665),
    "(mm)(N)": ("receptance", 1e-3),
}


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    unit=st.sampled_from(sorted(UNITS)),
    values=st.lists(st.floats(-1e6, 1e6, allow_nan=False).filter(lambda v: abs(v) > 1e-300), min_size=16),
)
def test_any_values_under_a_units_row_come_out_in_si_times_its_factor(tmp_path, unit, values):
    form, factor = UNITS[unit]
    f = np.arange(len(values)) * 0.5
    head = ["Units: Ratio", "", "Frequency\t Real\t Imaginary", "", "Units:", f"Hz\t{unit}\t "]
    rows = [f"{x:.13e}\t{v!r}\t{-v!r}" for x, v in zip(f, values, strict=True)]
    path = tmp_path / "Hxysv.txt"
    path.write_bytes(("\r\n".join(head + rows) + "\r\n").encode("latin-1"))
    frfs = read_frf_text(path).measured_frfs
    assert frfs.form == form
    want = np.array(values) * (1 - 1j) * factor
    np.testing.assert_allclose(frfs.frf[0], want, rtol=1e-12)
