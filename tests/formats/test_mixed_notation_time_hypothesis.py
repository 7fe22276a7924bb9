"""Time columns printed in two notations, as spreadsheets export them (hypothesis): 3
significant digits with an exponent below a switch ("7.08E-02"), every digit above it
("0.10025"). Each value holds its own last digit; the digits of the other notation are no
precision of it (the trial's 4 kHz impact files were refused at line 284, "7.08E-02")."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from daq.formats.axis import printed_half_units
from daq.formats.csv_text import read_csv
from daq.formats.errors import FormatError

SETTINGS = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
WORK = Path(tempfile.mkdtemp(prefix="mixed-notation-"))


def spreadsheet(value: float, switch: float) -> str:
    return f"{value:.2E}" if value < switch else f"{value:.15g}"


def put(texts: list[str], name: str, sep: str) -> Path:
    rows = [sep.join(("Time (s)", "Force (N)", "Acc (m/s^2)"))]
    rows += [sep.join((t, f"{np.sin(i):.6g}", f"{np.cos(i):.6g}")) for i, t in enumerate(texts)]
    path = WORK / name
    path.write_text("\r\n".join(rows) + "\r\n", encoding="utf-8")
    return path


@st.composite
def mixed_axes(draw):
    """(rate Hz, n, switch s, texts): a regular axis from 0 crossing the switch, whose
    3-digit values are at most a quarter of the step off (else no file can show a dropped
    sample in them)."""
    rate = draw(st.sampled_from([1000.0, 1024.0, 2000.0, 2500.0, 4000.0, 5000.0]))
    switch = draw(st.sampled_from([0.01, 0.1]))
    step = 1.0 / rate
    below = int(np.ceil(switch * rate))
    n = below + draw(st.integers(2, 200))
    assume(0.5 * 10.0 ** (np.floor(np.log10(switch * 0.999)) - 2) <= 0.25 * step)
    t = np.arange(n) / rate
    return rate, n, switch, [spreadsheet(v, switch) for v in t]


@SETTINGS
@given(axis=mixed_axes(), sep=st.sampled_from([",", "\t"]))
def test_a_column_in_two_notations_imports_at_its_rate(axis, sep):
    rate, n, _, texts = axis
    # A zero ("0.00E+00") is exact, not half a unit of its second decimal.
    assert printed_half_units(texts)[0] <= printed_half_units(texts)[1]
    hits = read_csv(put(texts, "mixed.txt", sep)).hits
    assert hits.n_samples == n
    # The values below the switch are up to half a unit (5e-5 s at 0.07 s) off the line.
    assert abs(1.0 / hits.sample_rate_hz - 1.0 / rate) * (n - 1) <= 0.25 / rate


@SETTINGS
@given(axis=mixed_axes(), data=st.data())
def test_a_dropped_sample_in_the_coarse_notation_is_still_refused(axis, data):
    rate, n, switch, _ = axis
    below = int(np.ceil(switch * rate))
    assume(below >= 5)
    at = data.draw(st.integers(2, below - 2))
    t = np.delete(np.arange(n) / rate, at)
    path = put([spreadsheet(v, switch) for v in t], "dropped.txt", ",")
    with pytest.raises(FormatError, match=f"line {at + 2}: uneven time step"):
        read_csv(path)


@SETTINGS
@given(
    rate=st.floats(1e3, 1e5),
    n=st.integers(8, 300),
    start=st.sampled_from([0.0, 1.0, -0.125]),
    whole=st.booleans(),
)
def test_repr_printed_columns_keep_the_columns_precision(rate, n, start, whole):
    """Python's repr prints whole floats as "0.0", "1.0": no sign of a padding writer,
    and no value of such a column is held to its own short last digit."""
    t = start + np.arange(n) / (round(rate) if whole else rate)
    texts = [repr(float(v)) for v in t]
    half = printed_half_units(texts)
    whole_values = np.array([v == round(v) for v in t])
    if whole_values.any() and not whole_values.all():
        assert half[whole_values].max() <= half[~whole_values].max()


def test_a_zeros_half_unit_is_the_columns_finest_to_the_last_bit():
    """'0.00E+00' takes the column's finest half unit (0.5 x 10**-5 s from '1.00E-03'),
    reached by another power than its neighbour's: the two are one float, not 5e-06
    against 4.9999999999999996e-06 (hypothesis found the zero a bit looser)."""
    texts = ["0.00E+00", "1.00E-03", "2.00E-03", "0.01", "0.011"]
    half = printed_half_units(texts)
    assert half[0] == half[1] == 5e-06


@SETTINGS
@given(
    rate=st.sampled_from([1000.0, 1024.0, 2000.0, 2500.0, 4000.0, 5000.0]),
    switch=st.sampled_from([0.01, 0.1]),
    fine_share=st.floats(1.0, 9.0),
)
def test_the_rate_is_read_from_the_finely_printed_values(rate, switch, fine_share):
    """Each value weighs by its printed precision: the few-digit values below the switch,
    off the line by up to 20 % of a step, no longer pull the rate (a new user's 4 kHz
    file read 3999.9929 Hz, and every mode moved by 3 of its ± when the rate was given)."""
    below = int(np.ceil(switch * rate))
    n = below + int(fine_share * below)
    texts = [spreadsheet(v, switch) for v in np.arange(n) / rate]
    # Their precision shows where a value keeps a trailing zero ("2.50E-04"): without one,
    # "9.77E-04" may as well be every digit of 0.000977 (printed_half_units).
    assume(any(t.split("E")[0].endswith("0") and t.split("E")[0].rstrip("0") != "0." for t in texts[1:below]))
    hits = read_csv(put(texts, "weighed.txt", ",")).hits
    assert abs(hits.sample_rate_hz / rate - 1.0) < 1e-7, hits.sample_rate_hz
