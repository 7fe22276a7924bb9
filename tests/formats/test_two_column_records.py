"""Files of force and response alone, with no time column (a logger's export of hits at a
rate stated elsewhere, as the spruce-plate hits of a public data set are: `force,acceleration`
at 48 kHz): read with --sample-rate, sample k of each hit at k / rate; refused without it,
in one line that says what to give."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from daq.formats.csv_text import read_csv
from daq.formats.imported import MIN_MAGNITUDE
from daq.store import Store
from tests.cli_helpers import assert_one_line_error, invoke_daq


def _pulse_rows(n: int = 256) -> tuple[list[float], list[float]]:
    k = np.arange(n)
    force = np.where(k < 8, 100 * np.sin(np.pi * k / 8), 0.0)
    response = np.exp(-k / 40) * np.sin(2 * np.pi * k / 16)
    return [float(f) for f in force], [float(a) for a in response]


def _write(path, header: str, first: list[float], second: list[float]):
    path.write_text(header + "\n" + "".join(f"{x!r},{y!r}\n" for x, y in zip(first, second, strict=True)))
    return path


def test_force_and_response_alone_are_read_at_the_rate_given(tmp_path):
    force, response = _pulse_rows()
    data = read_csv(
        _write(tmp_path / "hit.csv", "force,acceleration", force, response), sample_rate_hz=48000.0
    )
    assert data.hits.sample_rate_hz == 48000.0
    assert data.hits.force_n.shape == (1, len(force))
    np.testing.assert_array_equal(data.hits.force_n[0], force)
    np.testing.assert_array_equal(data.hits.response_m_s2[0], response)
    assert any("no time column" in note for note in data.details["notes"])


def test_the_header_units_say_which_column_is_the_force(tmp_path):
    force, response = _pulse_rows()
    data = read_csv(
        _write(tmp_path / "swapped.csv", "acc (g),Force [N]", response, force), sample_rate_hz=1000.0
    )
    np.testing.assert_array_equal(data.hits.force_n[0], force)
    np.testing.assert_allclose(data.hits.response_m_s2[0], np.array(response) * 9.80665, rtol=1e-15)
    assert (
        "columns taken by their names or units: force 'Force [N]', response 'acc (g)'"
        in data.details["notes"][0]
    )


def test_a_hit_column_splits_the_hits(tmp_path):
    force, response = _pulse_rows(64)
    rows = "".join(f"{h},{f!r},{a!r}\n" for h in (1, 2) for f, a in zip(force, response, strict=True))
    path = tmp_path / "hits.csv"
    path.write_text("hit,force,response\n" + rows)
    data = read_csv(path, sample_rate_hz=2048.0)
    assert data.hits.force_n.shape == (2, 64)


def test_without_a_rate_it_is_refused_in_one_line_saying_what_to_give(tmp_path):
    force, response = _pulse_rows()
    path = _write(tmp_path / "hit.csv", "force,acceleration", force, response)
    store = tmp_path / "runs"
    result = invoke_daq("import", str(path), "--store", str(store))
    assert_one_line_error(
        result, "hit.csv has 2 data columns; need time, force and response", "--sample-rate"
    )
    assert not store.exists() or not Store(store).list()
    ok = invoke_daq("import", str(path), "--sample-rate", "48000", "--store", str(store))
    assert ok.returncode == 0, ok.stderr
    assert "units: time s (made from the sample rate)" in ok.stdout


@settings(max_examples=40, deadline=None)
@given(
    values=st.lists(
        st.tuples(
            st.floats(-1e6, 1e6, allow_nan=False, allow_subnormal=False),
            st.floats(-1e6, 1e6, allow_nan=False, allow_subnormal=False),
        ),
        min_size=4,
        max_size=64,
    ),
    rate=st.sampled_from([1000.0, 2560.0, 25600.0, 48000.0, 51200.0]),
    decimal_comma=st.booleans(),
)
def test_any_values_keep_every_bit_and_take_times_k_over_the_rate(
    tmp_path_factory, values, rate, decimal_comma
):
    # A force and a response that move, within what any measurement reaches (imported.py
    # refuses the others: a response of zeros, values beyond 1e100 or all below 1e-100).
    assume(any(f != 0 for f, _ in values))
    assume(any(a != 0 for _, a in values))
    assume(max(abs(f) for f, _ in values) >= MIN_MAGNITUDE)
    assume(max(abs(a) for _, a in values) >= MIN_MAGNITUDE)
    path = tmp_path_factory.mktemp("two") / "hit.csv"
    sep = ";" if decimal_comma else ","

    def cell(x: float) -> str:
        return repr(x).replace(".", ",") if decimal_comma else repr(x)

    path.write_text(f"force{sep}response\n" + "".join(f"{cell(f)}{sep}{cell(a)}\n" for f, a in values))
    data = read_csv(path, sample_rate_hz=rate)
    expected = np.array(values)
    np.testing.assert_array_equal(data.hits.force_n[0], expected[:, 0])
    np.testing.assert_array_equal(data.hits.response_m_s2[0], expected[:, 1])
    assert data.hits.sample_rate_hz == rate


def test_swapped_columns_are_said_with_the_two_columns_that_read_them_right(tmp_path):
    """A headerless file of response then force: the import said so, then stopped with an
    internal error after storing the run, and every later command on it did too."""
    force, response = _pulse_rows()
    path = tmp_path / "swapped.csv"
    path.write_text("".join(f"{a!r},{f!r}\n" for f, a in zip(force, response, strict=True)))
    store = tmp_path / "runs"
    result = invoke_daq("import", str(path), "--sample-rate", "2048", "--store", str(store))
    assert result.returncode == 0, result.stderr
    assert "import the file again with --columns 1,0 --sample-rate 2048" in result.stdout
    analysed = invoke_daq("analyze", "latest", "--store", str(store))
    assert analysed.returncode == 0, analysed.stderr
    assert "--columns 1,0 --sample-rate 2048; until then" in analysed.stdout
    again = invoke_daq(
        "import", str(path), "--sample-rate", "2048", "--columns", "1,0", "--store", str(store)
    )
    assert again.returncode == 0, again.stderr
    assert "look swapped" not in again.stdout


def test_two_columns_named_without_a_rate_are_refused_saying_what_to_give(tmp_path):
    force, response = _pulse_rows()
    path = _write(tmp_path / "hit.csv", "force,acceleration", force, response)
    result = invoke_daq(
        "import", str(path), "--columns", "force,acceleration", "--store", str(tmp_path / "runs")
    )
    assert_one_line_error(result, "must name three columns", "or two (force, response) with --sample-rate")


@pytest.mark.parametrize(
    ("preamble", "header"),
    [
        ("Sample rate: 2048 Hz", "force,response\n"),
        ("fs: 2048", "force,response\n"),
        ("Sampling frequency\t2048", "force,response\n"),
        ("Sample rate: 2048 Hz\nOperator: me", ""),
    ],
)
def test_a_preamble_gives_the_rate_of_a_file_of_force_and_response_alone(tmp_path, preamble, header):
    """A preamble was looked for only before rows of 3 numbers or more: these files were
    refused as "1 column, expected 4"."""
    force, response = _pulse_rows()
    path = tmp_path / "pre.csv"
    path.write_text(
        f"{preamble}\n{header}" + "".join(f"{f!r},{a!r}\n" for f, a in zip(force, response, strict=True))
    )
    data = read_csv(path)
    assert data.hits.sample_rate_hz == 2048.0
    np.testing.assert_array_equal(data.hits.force_n[0], force)


def test_a_rate_too_low_for_vibration_is_told_as_the_rate_given(tmp_path):
    """--sample-rate 5 was refused as "its time column steps by 0.2 s ... if the first
    column is a frequency ...": the file has no time column; the rate is what is wrong."""
    force, response = _pulse_rows()
    path = _write(tmp_path / "hit.csv", "force,acceleration", force, response)
    store = tmp_path / "runs"
    result = invoke_daq("import", str(path), "--sample-rate", "5", "--store", str(store))
    assert_one_line_error(result, "a sampling rate of 5 Hz records no vibration", "--sample-rate HZ")
    assert "time column" not in result.stderr


def test_two_force_columns_are_told_as_such(tmp_path):
    force, response = _pulse_rows()
    path = _write(tmp_path / "ff.csv", "Force (N),Load (N)", force, response)
    result = invoke_daq("import", str(path), "--sample-rate", "1000", "--store", str(tmp_path / "runs"))
    assert_one_line_error(result, "both columns ('Force (N)', 'Load (N)') are forces", "needs one of each")
