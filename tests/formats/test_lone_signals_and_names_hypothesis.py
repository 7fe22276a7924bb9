"""Files a new user brought that were read wrong without a word (hypothesis where a reader
changed):

- two column names above two columns of numbers, tab-separated ("Force [N]<TAB>Accel [g]"),
  were taken for a "key<TAB>value" preamble line: skipped, their units lost, g stored as
  m/s^2 (the FRF 9.81 times off);
- time and one signal, with --sample-rate, stored the time ramp as the force;
- a headerless time record in ms (0, 0.488, 0.977, ...) was imported as an FRF table, the
  force as its real part;
- a note's example `--columns -1,1,0` was refused as "no column '-1'", and one without a
  time column offered the column left out as the time;
- jittered time stamps were refused without the way round that --sample-rate gives.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from daq.cli.commands.import_file import hammer_pulse_rows
from daq.formats.csv_text import read_csv
from daq.formats.errors import FormatError
from daq.formats.units import POUND_FORCE_N, STANDARD_GRAVITY_M_S2
from tests.cli_helpers import daq_import, refused

SETTINGS = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
WORK = Path(tempfile.mkdtemp(prefix="lone-signals-"))
FORCE_UNITS = {"N": 1.0, "lbf": POUND_FORCE_N}
RESPONSE_UNITS = {"g": STANDARD_GRAVITY_M_S2, "m/s^2": 1.0}


def hit(n: int = 256, delay: int = 20) -> tuple[np.ndarray, np.ndarray]:
    """A half-sine hammer pulse and a decaying response, (n,) each."""
    k = np.arange(n)
    force = np.where((k >= delay) & (k < delay + 8), 100 * np.sin(np.pi * (k - delay) / 8), 0.0)
    response = np.where(k >= delay, np.exp(-(k - delay) / 40) * np.sin(2 * np.pi * (k - delay) / 16), 0.0)
    return force, response


@SETTINGS
@given(
    sep=st.sampled_from(["\t", ",", ";"]),
    force_unit=st.sampled_from(sorted(FORCE_UNITS)),
    response_unit=st.sampled_from(sorted(RESPONSE_UNITS)),
    brackets=st.sampled_from(["[]", "()"]),
)
def test_two_names_above_two_columns_are_their_header(sep, force_unit, response_unit, brackets):
    force, response = hit()
    a, b = brackets
    lines = [f"Force {a}{force_unit}{b}{sep}Accel {a}{response_unit}{b}"]
    lines += [f"{f:.17g}{sep}{r:.17g}" for f, r in zip(force, response, strict=True)]
    path = WORK / "fa.txt"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    data = read_csv(path, sample_rate_hz=4000.0)
    np.testing.assert_allclose(data.hits.force_n[0], force * FORCE_UNITS[force_unit], rtol=1e-12)
    expected = response * RESPONSE_UNITS[response_unit]
    np.testing.assert_allclose(data.hits.response_m_s2[0], expected, rtol=1e-12)
    assert not any(note.startswith("preamble") for note in data.details["notes"])


@SETTINGS
@given(
    sep=st.sampled_from(["\t", ","]),
    start=st.sampled_from([0.0, -0.01, 0.5]),
    step=st.sampled_from([1 / 4000, 2.5e-4, 1 / 51200]),
    signal_first=st.booleans(),
)
def test_time_and_one_signal_are_refused_not_stored_as_force(sep, start, step, signal_first):
    force, _ = hit()
    time = start + step * np.arange(force.size)
    pair = (force, time) if signal_first else (time, force)
    path = WORK / "tf.txt"
    path.write_text("".join(f"{x:.17g}{sep}{y:.17g}\n" for x, y in zip(*pair, strict=True)), encoding="utf-8")
    role = "response" if signal_first else "force"
    with pytest.raises(FormatError, match=f"taken for the {role}, rises over every row as a time axis"):
        read_csv(path, sample_rate_hz=4000.0)


def test_a_named_time_and_one_signal_are_refused_in_one_line(tmp_path):
    force, _ = hit()
    path = tmp_path / "tf.csv"
    rows = "".join(f"{k / 4000:.17g},{f:.17g}\n" for k, f in enumerate(force))
    path.write_text("Time [s],Force [N]\n" + rows, encoding="utf-8")
    store = tmp_path / "store"
    line = refused(daq_import(store, path, "--sample-rate", "4000"), store, "time 'Time [s]' and 'Force [N]'")
    assert "give --sample-rate" not in line


@SETTINGS
@given(
    step_ms=st.sampled_from([1000 / 2048, 0.25, 1000 / 51200, 1.0]),
    delay=st.integers(10, 120),
    sep=st.sampled_from(["\t", ",", " "]),
)
def test_a_headerless_record_in_ms_is_refused_not_read_as_frfs(step_ms, delay, sep):
    force, response = hit(delay=delay)
    path = WORK / f"ms-{delay}.txt"
    time = step_ms * np.arange(force.size)
    path.write_text(
        "".join(f"{t:.6f}{sep}{f:.6g}{sep}{r:.6g}\n" for t, f, r in zip(time, force, response, strict=True)),
        encoding="utf-8",
    )
    store = WORK / f"store-ms-{delay}"
    hint = "--format csv --columns 1,2 --sample-rate HZ"
    refused(daq_import(store, path), store, "a pulse of one sign", hint)


@SETTINGS
@given(
    n_modes=st.integers(1, 4),
    seed=st.integers(0, 10_000),
    lines=st.sampled_from([401, 801, 1601]),
    form=st.integers(0, 2),
    noise=st.sampled_from([0.0, 0.01]),
)
def test_an_frfs_real_part_is_no_hammer_pulse(n_modes, seed, lines, form, noise):
    # The check must not refuse what it guards: receptance, mobility or accelerance, lightly
    # or heavily damped (a mobility's real part is a peak of one sign, but its imaginary
    # part is not quiet before it). Random FRFs gave 1 false pulse in 200,000 such pairs.
    rng = np.random.default_rng(seed)
    f = np.linspace(0, 1000, lines)
    fn = rng.uniform(50, 950, n_modes)
    zeta = 10 ** rng.uniform(-3.5, -1, n_modes)
    a = rng.uniform(-1, 1, n_modes)
    w, wn = 2 * np.pi * f[:, None], 2 * np.pi * fn[None, :]
    h = np.sum(a * (1j * w) ** form / (wn**2 - w**2 + 2j * zeta * wn * w), axis=1)
    h += noise * np.max(np.abs(h)) * (rng.standard_normal(h.size) + 1j * rng.standard_normal(h.size))
    for first, second in ((h.real, h.imag), (h.imag, h.real), (-h.real, h.imag)):
        assert hammer_pulse_rows(first, second) is None


def test_a_headerless_frf_table_still_imports_as_frfs(tmp_path):
    f = np.arange(0.0, 801.0)
    w, wn = 2 * np.pi * f, 2 * np.pi * 310.0
    h = -(w**2) / (wn**2 - w**2 + 2j * 0.01 * wn * w)
    path = tmp_path / "frf.txt"
    path.write_text("".join(f"{x:g}\t{v.real:.8g}\t{v.imag:.8g}\n" for x, v in zip(f, h, strict=True)))
    result = daq_import(tmp_path / "store", path)
    assert result.returncode == 0, result.stderr
    assert "frf-text: 1 FRF of 801 points" in result.stdout


def test_a_time_column_left_out_for_the_sample_rate_gets_no_example_back(tmp_path):
    force, response = hit()
    path = tmp_path / "hit.csv"
    pairs = enumerate(zip(force, response, strict=True))
    rows = "".join(f"{k / 2048:.17g},{f:.17g},{r:.17g}\n" for k, (f, r) in pairs)
    path.write_text("Time [s],Force [N],Accel [m/s^2]\n" + rows, encoding="utf-8")
    first = daq_import(tmp_path / "a", path, "--columns", "1,2", "--sample-rate", "2048")
    assert first.returncode == 0, first.stderr
    (note,) = [line for line in first.stdout.splitlines() if "ignored" in line]
    assert note.endswith("(the times come from --sample-rate)")
    assert "-1" not in note


def test_another_column_left_out_is_offered_as_the_response_and_that_runs(tmp_path):
    force, response = hit()
    path = tmp_path / "two.csv"
    rows = "".join(f"{f:.17g},{r:.17g},{-r:.17g}\n" for f, r in zip(force, response, strict=True))
    path.write_text("Force [N],Acc1 [g],Acc2 [g]\n" + rows, encoding="utf-8")
    first = daq_import(tmp_path / "a", path, "--columns", "0,1", "--sample-rate", "2048")
    assert first.returncode == 0, first.stderr
    (note,) = [line for line in first.stdout.splitlines() if "e.g. --columns" in line]
    example = note.rsplit("e.g. --columns ", 1)[1].split()
    assert example == ["0,2"]  # before: "2,0,1", Acc2 as the time ("unknown time unit 'g'")
    again = daq_import(tmp_path / "b", path, "--columns", *example, "--sample-rate", "2048")
    assert again.returncode == 0, again.stderr


@pytest.mark.parametrize(("jitter", "offered"), [(0.05, True), (0.0, False)])
def test_jittered_times_are_offered_the_sample_rate_a_dropped_sample_is_not(tmp_path, jitter, offered):
    force, response = hit(512)
    rng = np.random.default_rng(3)
    time = (np.arange(force.size) + jitter * rng.uniform(-1, 1, force.size)) / 2048
    if not jitter:
        time = np.delete(np.arange(force.size + 1) / 2048, 300)  # a sample dropped
    rows = "".join(f"{t:.9f},{f:.17g},{r:.17g}\n" for t, f, r in zip(time, force, response, strict=True))
    path = tmp_path / "hit.csv"
    path.write_text("Time [s],Force [N],Accel [m/s^2]\n" + rows, encoding="utf-8")
    store = tmp_path / "store"
    line = refused(daq_import(store, path), store, "uneven time step")
    assert ("--columns 1,2 --sample-rate HZ" in line) == offered


@pytest.mark.parametrize(
    ("preamble", "rate_hz"),
    [
        ("Title\tHammer test\nSample rate\t2048 Hz\n", 2048.0),
        ("Sample rate,2048 Hz\n", 2048.0),
        ("Sample rate;4000\n", 4000.0),
        ("Input\tHammer\nOutput\tAccelerometer\n", None),
    ],
)
def test_preamble_rows_as_wide_as_two_columns_stay_preamble_rows(preamble, rate_hz):
    # A review of the names-row rule: these rows, as wide as force and response, carry no
    # unit and are no header (the first two lost their rate, the last was read as names).
    force, response = hit()
    sep = "\t" if "\t" in preamble else preamble.split("\n")[0][11]
    path = WORK / "wide-preamble.txt"
    rows = "".join(f"{f:.17g}{sep}{r:.17g}\n" for f, r in zip(force, response, strict=True))
    path.write_text(preamble + rows, encoding="utf-8")
    data = read_csv(path, sample_rate_hz=None if rate_hz else 2048.0)
    assert data.hits.sample_rate_hz == (rate_hz or 2048.0)
    assert any(note.startswith("preamble line") for note in data.details["notes"])


@SETTINGS
@given(
    force_unit=st.sampled_from(sorted(FORCE_UNITS)),
    response_unit=st.sampled_from(sorted(RESPONSE_UNITS)),
    trailing=st.booleans(),
)
def test_a_header_with_units_above_an_extra_column_keeps_its_units(force_unit, response_unit, trailing):
    # Three names with units above four columns (a spare channel, or a delimiter at the end
    # of every row): a header, not a "key,value" row of fewer cells than the data.
    force, response = hit()
    head = f"Time [s],Force [{force_unit}],Accel [{response_unit}]" + ("," if trailing else "")
    pairs = enumerate(zip(force, response, strict=True))
    rows = "".join(f"{k / 2048:.17g},{f:.17g},{r:.17g},0\n" for k, (f, r) in pairs)
    path = WORK / "spare.csv"
    path.write_text(head + "\n" + rows, encoding="utf-8")
    if not trailing:
        with pytest.raises(FormatError, match="4 columns, expected 3"):
            read_csv(path)
        return
    data = read_csv(path)
    np.testing.assert_allclose(data.hits.force_n[0], force * FORCE_UNITS[force_unit], rtol=1e-12)
    assert data.details["units_from"]["response"] == "header"
