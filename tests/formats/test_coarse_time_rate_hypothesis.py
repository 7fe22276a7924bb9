"""A time column printed coarsely, 3 significant digits at 1-5 kHz (hypothesis): the rate
fitted to it is off by up to a few hertz (3998.49 Hz for times i/4000), and the import
says so in a note with the spread the printed times allow, which holds the true rate;
--sample-rate gives the exact rate, and is refused when the printed times do not allow it."""

from __future__ import annotations

import re
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from daq.formats.axis import printed_half_units
from daq.formats.csv_text import read_csv
from daq.formats.errors import FormatError
from tests.cli_helpers import assert_one_line_error, invoke_daq

SETTINGS = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
WORK = Path(tempfile.mkdtemp(prefix="coarse-time-"))
_SPREAD = re.compile(r"allow any rate within ([0-9.e+-]+) Hz of the fitted ([0-9.e+-]+) Hz")


def put(texts: list[str], name: str = "coarse.csv") -> Path:
    rows = ["t,F,a"] + [f"{t},{100.0 if i == 3 else 0.0},{np.sin(i):.6g}" for i, t in enumerate(texts)]
    path = WORK / name
    path.write_text("\n".join(rows) + "\n", encoding="utf-8")
    return path


def coarse_notes(details: dict) -> list[str]:
    return [n for n in details.get("notes") or [] if "printed coarsely" in n]


@st.composite
def coarse_axes(draw):
    rate = draw(st.sampled_from([1000.0, 1024.0, 2000.0, 2500.0, 4000.0, 5000.0]))
    n = draw(st.integers(20, 400))
    style = draw(st.sampled_from(["{:.2E}", "{:.3g}"]))
    texts = [style.format(v) for v in np.arange(n) / rate]
    half = printed_half_units(texts)
    assume(half.max() <= 0.25 / rate)  # else the column cannot be regular within its print
    return rate, n, texts, float(half.max())


@SETTINGS
@given(axis=coarse_axes())
def test_a_coarse_time_column_says_how_well_it_knows_the_rate(axis):
    rate, n, texts, half = axis
    data = read_csv(put(texts))
    said = coarse_notes(data.details)
    ends = sum(max(float(h), 0.01 / rate) for h in printed_half_units(texts)[[0, -1]])
    if half <= 0.01 / rate or 2.0 * ends / (n - 1) * rate**2 < 0.9e-4 * rate:
        assert said == []  # fine enough, or coarse over so many samples that the rate is known
        return
    if not said:  # near the limit: the fitted step decides
        assert 2.0 * ends / (n - 1) * rate**2 < 1.1e-4 * rate
        return
    (note,) = said
    spread, fitted = (float(x) for x in _SPREAD.search(note).groups())
    assert fitted == pytest.approx(data.hits.sample_rate_hz, rel=1e-5)
    assert abs(data.hits.sample_rate_hz - rate) <= spread * 1.05  # printed to 2 digits
    assert note.endswith("if you know the exact rate, give it with --sample-rate HZ")
    exact = read_csv(put(texts), sample_rate_hz=rate)
    assert exact.hits.sample_rate_hz == rate
    assert coarse_notes(exact.details) == []


@SETTINGS
@given(axis=coarse_axes(), factor=st.sampled_from([0.9, 0.97, 1.03, 1.1, 2.0]))
def test_a_sample_rate_the_printed_times_do_not_allow_is_refused(axis, factor):
    rate, n, texts, _ = axis
    assume(n >= 100)
    with pytest.raises(FormatError) as info:
        read_csv(put(texts), sample_rate_hz=rate * factor)
    message = str(info.value)
    assert "\n" not in message
    assert f"--sample-rate gives a sample rate of {rate * factor:g} Hz" in message


def test_the_trial_file_and_the_option_through_the_cli(tmp_path):
    texts = [f"{v:.2E}" for v in np.arange(400) / 4000.0]
    path = put(texts, "time_3sig_halfup_400.csv")
    store = str(tmp_path / "store")
    result = invoke_daq("import", str(path), "--store", store)
    assert result.returncode == 0, result.stderr
    assert "note: the time column is printed coarsely" in result.stdout
    again = invoke_daq("import", str(path), "--sample-rate", "4000", "--store", store)
    assert again.returncode == 0, again.stderr
    assert "at 4000 Hz" in again.stdout
    assert "printed coarsely" not in again.stdout
    zero = invoke_daq("import", str(path), "--sample-rate", "0", "--store", store)
    assert_one_line_error(zero, "--sample-rate 0: give a rate above 0 Hz")
    assert zero.returncode == 2
    frf = tmp_path / "frf.csv"
    frf.write_text("Frequency (Hz),H Re,H Im\n" + "".join(f"{i},1,0\n" for i in range(1, 20)))
    refused = invoke_daq("import", str(frf), "--sample-rate", "4000", "--store", store)
    assert_one_line_error(refused, "an FRF table has no sample rate")
    assert refused.returncode == 2
