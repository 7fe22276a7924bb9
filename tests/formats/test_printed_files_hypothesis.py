"""Files as instruments and programs really write them, generated at random (hypothesis):
time columns printed with 4-12 significant digits, decimal commas, units in the header,
FRF tables (Re/Im and magnitude/phase), UFF 58 FRFs of every form. Each must read back
as written; a dropped sample, a jump or an unknown FRF type is refused in one line that
names the file (and the line), with nothing in the store."""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

import numpy as np
import pytest
import pyuff
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from daq.formats.axis import printed_half_units
from daq.formats.csv_text import read_csv
from daq.formats.errors import FormatError
from daq.formats.frf_text import read_frf_text
from daq.formats.uff58 import read_uff
from daq.store import Store
from tests.cli_helpers import assert_one_line_error, invoke_daq

SETTINGS = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
WORK = Path(tempfile.mkdtemp(prefix="printed-files-"))
STYLES = ("g", "e", "f")


def put(text: str, name: str) -> Path:
    path = WORK / name
    path.write_text(text, encoding="utf-8")
    return path


def printed(value: float, style: str, digits: int) -> str:
    if style == "g":
        return f"{value:.{digits}g}"
    if style == "e":
        return f"{value:.{digits - 1}e}"
    return f"{value:.{digits}f}"  # digits after the point


@st.composite
def printed_axes(draw):
    """(rate Hz, n, start s, style, digits, texts) of a regular axis printed so that half
    a unit of the last digit is at most a tenth of the step (else no file can show a
    dropped sample)."""
    rate = draw(st.floats(1e3, 1e5))
    n = draw(st.integers(8, 400))
    step = 1.0 / rate
    start = draw(st.sampled_from([0.0, -0.125, 1.0, -step * 7]))
    style = draw(st.sampled_from(STYLES))
    digits = draw(st.integers(4, 12))
    t = start + np.arange(n) * step
    texts = [printed(v, style, digits) for v in t]
    half = float(printed_half_units(texts).max())
    assume(half <= step / 10)
    return rate, n, start, style, digits, texts


def time_file(texts: list[str], sep: str = ",", comma: bool = False) -> str:
    rows = ["time,force,response".replace(",", sep)]
    for i, t in enumerate(texts):
        cells = [t, f"{math.sin(i) * 10:.6g}", f"{math.cos(i):.6g}"]
        if comma:
            cells = [c.replace(".", ",") for c in cells]
        rows.append(sep.join(cells))
    return "\n".join(rows) + "\n"


@SETTINGS
@given(axis=printed_axes())
def test_a_printed_regular_axis_imports_with_the_fitted_step(axis):
    rate, n, start, _, _, texts = axis
    hits = read_csv(put(time_file(texts), "axis.csv")).hits
    half = float(printed_half_units(texts).max())
    step = 1.0 / hits.sample_rate_hz
    # The fitted axis stays within the printed precision (or 1 % of the step) of the true one.
    tol = max(half, 0.01 / rate)
    assert abs(hits.start_s - start) <= tol * 1.0000001
    assert abs(step - 1.0 / rate) * (n - 1) <= 2 * tol * 1.0000001
    assert hits.n_samples == n


@SETTINGS
@given(axis=printed_axes(), data=st.data())
def test_a_dropped_sample_or_a_jump_is_refused_with_its_line(axis, data):
    rate, n, start, style, digits, _ = axis
    step = 1.0 / rate
    at = data.draw(st.integers(2, n - 3))
    t = start + np.arange(n) * step
    if data.draw(st.booleans()):
        t = np.delete(t, at)  # a dropped sample: one step twice as long
    else:
        t[at:] += data.draw(st.floats(0.5, 3.0)) * step  # a jump
    texts = [printed(v, style, digits) for v in t]
    path = put(time_file(texts), "uneven.csv")
    with pytest.raises(FormatError) as info:
        read_csv(path)
    message = str(info.value)
    assert "\n" not in message
    assert str(path) in message
    # Line 1 is the header: sample k is on line k + 2.
    assert f"line {at + 2}: uneven time step" in message


def test_the_51200_hz_impact_test_printed_to_7_digits():
    """The report that started it: a tab-separated 51.2 kHz export, time to 7 digits."""
    t = np.arange(51200) / 51200.0
    rows = ["Time (s)\tForce (N)\tAcc (g)"] + [f"{v:.7g}\t0.5\t0.01" for v in t[:4096]]
    hits = read_csv(put("\n".join(rows) + "\n", "impact.txt")).hits
    assert hits.sample_rate_hz == pytest.approx(51200.0, rel=1e-7)
    assert hits.response_m_s2[0, 0] == pytest.approx(0.0980665)


@SETTINGS
@given(
    sep=st.sampled_from([";", "\t", " ", "   "]),
    values=st.lists(
        st.floats(-1e3, 1e3, allow_nan=False).map(lambda v: round(v, 4)), min_size=6, max_size=30
    ),
    header=st.booleans(),
    whole=st.booleans(),
)
def test_decimal_commas_with_semicolons_tabs_and_spaces(sep, values, header, whole):
    """``whole``: numbers without a fraction printed without one ("0", "12"), as %g
    does: a line "0 2,46e-07 0,025" is still read with decimal commas. (A force of zeros
    only is refused as no hit at all: tests/cli/test_import_force_checks.py.)"""
    assume(any(values))
    names = (
        ["Zeit (s)", "Kraft (N)", "Beschl. (m/s^2)"]
        if sep.strip()
        else ["Zeit[s]", "Kraft[N]", "Beschl[m/s^2]"]
    )
    rows = [sep.join(names)] if header else []
    rows += ["# exportiert", "% und kommentiert"]
    text = (lambda v: f"{v:.12g}") if whole else (lambda v: f"{v}")
    rows += [sep.join(text(v).replace(".", ",") for v in (i * 0.001, x, -x)) for i, x in enumerate(values)]
    hits = read_csv(put("\n".join(rows) + "\n", "komma.csv")).hits
    assert hits.force_n[0].tolist() == values
    assert hits.response_m_s2[0].tolist() == [-v for v in values]
    assert hits.sample_rate_hz == pytest.approx(1000.0)


@SETTINGS
@given(
    sep=st.sampled_from([";", "\t", " "]),
    n=st.integers(4, 30),
    grouped=st.integers(1, 999).flatmap(lambda a: st.sampled_from([f"{a}.000", f"{a}.500", f"-{a}.250"])),
    data=st.data(),
)
def test_a_thousands_point_in_a_decimal_comma_file_is_refused_with_the_line(sep, n, grouped, data):
    """ "1.500" beside "0,25" may be 1500 or 1.5: refused, never read one way silently."""
    rows = [sep.join(f"{v:.4f}".replace(".", ",") for v in (i * 0.001, i + 0.5, -i - 0.25)) for i in range(n)]
    k = data.draw(st.integers(0, n - 1))
    cells = rows[k].split(sep)
    cells[data.draw(st.integers(1, 2))] = grouped
    rows[k] = sep.join(cells)
    with pytest.raises(FormatError) as caught:
        read_csv(put("\n".join(rows) + "\n", "gemischt.csv"))
    message = str(caught.value)
    assert (
        f"gemischt.csv line {k + 1}: '{grouped}' could mean {grouped.replace('.', '')} (a thousands point)"
        in message
    )
    assert "decimal commas (line 1)" in message
    assert "\n" not in message


@SETTINGS
@given(digits=st.integers(4, 9), n=st.integers(8, 40))
def test_decimal_points_that_cannot_be_thousands_points_mix_with_decimal_commas(digits, n):
    """A time column printed with points ("1.953125e-05") beside data with decimal commas
    is read: such a point is no thousands point."""
    rows = ["Time (s)\tForce [N]\tacc"] + [f"{i / 51200:.{digits}g}\t0,5\t{i},25" for i in range(n)]
    hits = read_csv(put("\n".join(rows) + "\n", "zeit.txt")).hits
    assert hits.force_n[0].tolist() == [0.5] * n
    assert hits.response_m_s2[0].tolist() == [i + 0.25 for i in range(n)]


def test_a_point_after_a_leading_zero_is_no_thousands_point():
    """ "0.125" (a time column printed to milliseconds) beside decimal commas: nobody
    writes 125 as 0.125, so it is a decimal point and the file reads."""
    rows = ["t (ms)\tF\ta"] + [f"{i * 0.125:.3f}\t0,5\t{i},25" for i in range(8)]
    hits = read_csv(put("\n".join(rows) + "\n", "ms.txt")).hits
    assert hits.response_m_s2[0].tolist() == [i + 0.25 for i in range(8)]
    assert hits.sample_rate_hz == pytest.approx(8000.0)


UNITS = {
    "force": [("N", 1.0), ("kN", 1000.0), ("lbf", 4.4482216152605)],
    "response": [("m/s^2", 1.0), ("g", 9.80665), ("mm/s^2", 1e-3), ("m/s²", 1.0)],
    "time": [("s", 1.0), ("ms", 1e-3)],
}


@SETTINGS
@given(
    force=st.sampled_from(UNITS["force"]),
    response=st.sampled_from(UNITS["response"]),
    time=st.sampled_from(UNITS["time"]),
    brackets=st.sampled_from(["[{}]", "({})"]),
    option=st.booleans(),
)
def test_units_in_the_header_are_applied_and_an_option_wins(force, response, time, brackets, option):
    head = [f"Time {brackets.format(time[0])}", f"Force {brackets.format(force[0])}"]
    head.append(f"acc {brackets.format(response[0])}")
    rows = [",".join(head)] + [f"{i * 0.5},{1.5},{-2.0}" for i in range(8)]
    kwargs = {"response_unit": "g"} if option else {}
    got = read_csv(put("\n".join(rows) + "\n", "units.csv"), **kwargs)
    assert got.hits.force_n[0, 0] == pytest.approx(1.5 * force[1])
    factor = 9.80665 if option else response[1]
    assert got.hits.response_m_s2[0, 0] == pytest.approx(-2.0 * factor)
    assert got.hits.sample_rate_hz == pytest.approx(1 / (0.5 * time[1]))
    assert got.details["units_from"] == {
        "force": "header",
        "response": f"option; the header says {response[0].replace('²', '^2')}" if option else "header",
    }


def test_a_voltage_header_needs_a_sensitivity():
    path = put("t (s);F (N);a (mV)\n0;1;2\n0,001;1;2\n", "volts.csv")
    with pytest.raises(FormatError, match=r"--response-unit mV@10\.2mV/g"):
        read_csv(path)
    hits = read_csv(path, response_unit="mV@10mV/g").hits
    assert hits.response_m_s2[0, 0] == pytest.approx(0.2 * 9.80665)


# --- FRF tables ------------------------------------------------------------------------------

FORM_UNITS = {"receptance": "m/N", "mobility": "(m/s)/N", "accelerance": "(m/s^2)/N"}


@st.composite
def frf_tables(draw):
    n_frf = draw(st.integers(1, 3))
    n = draw(st.integers(3, 40))
    freq = np.round(np.sort(list(draw(st.sets(st.integers(0, 100000), min_size=n, max_size=n)))) * 0.125, 3)
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    frf = rng.normal(size=(n_frf, n)) + 1j * rng.normal(size=(n_frf, n))
    layout = draw(st.sampled_from(["re-im", "mag-db-deg", "mag-lin-rad"]))
    form = draw(st.sampled_from([*FORM_UNITS, None]))
    sep = draw(st.sampled_from([",", ";", "\t"]))
    return freq, frf, layout, form, sep


def frf_text(freq, frf, layout, form, sep) -> str:
    unit = f" [{FORM_UNITS[form]}]" if form else ""
    head = ["Frequency (Hz)"]
    cols = [freq]
    for k, h in enumerate(frf):
        if layout == "re-im":
            head += [f"H{k}1 Re{unit}", f"H{k}1 Im{unit}"]
            cols += [h.real, h.imag]
        elif layout == "mag-db-deg":
            head += [
                f"H{k}1 mag [dB re 1 {FORM_UNITS[form]}]" if form else f"H{k}1 mag [dB]",
                f"H{k}1 phase [deg]",
            ]
            cols += [20 * np.log10(np.abs(h)), np.degrees(np.angle(h))]
        else:
            head += [f"H{k}1 magnitude{unit}", f"H{k}1 phase (rad)"]
            cols += [np.abs(h), np.angle(h)]
    rows = [sep.join(head)]
    for row in np.array(cols).T:
        cells = [repr(float(v)) for v in row]
        rows.append(sep.join(c.replace(".", ",") if sep != "," else c for c in cells))
    return "\n".join(rows) + "\n"


@SETTINGS
@given(table=frf_tables())
def test_frf_tables_round_trip(table):
    freq, frf, layout, form, sep = table
    got = read_frf_text(put(frf_text(freq, frf, layout, form, sep), "frf.csv"))
    measured = got.measured_frfs
    assert got.hits is None
    np.testing.assert_array_equal(measured.frequency_hz, freq)
    np.testing.assert_allclose(measured.frf, frf, rtol=1e-12, atol=1e-12)
    assert measured.form == (form or "accelerance")
    assert got.details["form_from"].startswith("header" if form else "default")
    assert [str(x) for x in measured.labels] == [f"H{k}1" for k in range(frf.shape[0])]


@pytest.mark.parametrize("form", list(FORM_UNITS))
def test_frf_form_option_wins(form):
    text = "freq,re,im\n1,1,0\n2,0,1\n"
    assert read_frf_text(put(text, "opt.csv"), frf_form=form).measured_frfs.form == form


# --- UFF 58 forms ------------------------------------------------------------------------------

UFF_FORMS = {"receptance": (8, "m"), "mobility": (11, "m/s"), "accelerance": (12, "m/s^2")}


def uff_frf(path: Path, kind: int, unit: str, data: np.ndarray, freq: np.ndarray) -> Path:
    dset = pyuff.prepare_58(
        binary=0, id1="H21", func_type=4, rsp_node=2, rsp_dir=3, ref_node=1, ref_dir=3,
        abscissa_spacing=1, abscissa_spec_data_type=18, ordinate_spec_data_type=kind,
        orddenom_spec_data_type=13, z_axis_spec_data_type=0, data=data, x=freq,
    )  # fmt: skip
    dset.update(ordinate_axis_units_lab=unit, orddenom_axis_units_lab="N")
    if path.exists():
        path.unlink()
    pyuff.UFF(str(path)).write_sets([dset], mode="add")
    return path


@SETTINGS
@given(
    form=st.sampled_from(list(UFF_FORMS)),
    seed=st.integers(0, 2**32 - 1),
    label=st.booleans(),
)
def test_uff58_frfs_read_back_in_their_form(form, seed, label):
    rng = np.random.default_rng(seed)
    freq = np.arange(1.0, 33.0)
    data = rng.normal(size=32) + 1j * rng.normal(size=32)
    kind, unit = UFF_FORMS[form]
    # ASCII 58 (pyuff's binary writer leaves its file open; our own binary export is
    # checked through the CLI below).
    path = uff_frf(WORK / "form.uff", kind, unit if label else "NONE", data, freq)
    got = read_uff(path)
    assert got.measured_frfs.form == form
    np.testing.assert_allclose(got.measured_frfs.frf[0], data, rtol=1e-5)


def test_uff58_displacement_in_mm_is_receptance_in_m():
    path = uff_frf(WORK / "mm.uff", 8, "mm", np.array([1 + 1j, 2, 3j]), np.array([1.0, 2.0, 3.0]))
    got = read_uff(path).measured_frfs
    assert got.form == "receptance"
    np.testing.assert_allclose(got.frf[0], np.array([1 + 1j, 2, 3j]) * 1e-3, rtol=1e-5)


@pytest.mark.parametrize(
    ("kind", "unit", "words"),
    [
        (2, "Pa", "ordinate data type 2"),  # pressure over force: no form of ours
        (0, "NONE", "ordinate data type 0"),  # says nothing at all
        (8, "m/s^2", "which is it"),  # displacement by type, acceleration by unit
    ],
)
def test_uff58_unknown_or_contradictory_frf_types_refused(tmp_path, kind, unit, words):
    path = uff_frf(tmp_path / "bad.uff", kind, unit, np.array([1 + 1j, 2, 3j]), np.array([1.0, 2.0, 3.0]))
    with pytest.raises(FormatError, match=words):
        read_uff(path)
    store = tmp_path / "store"
    result = invoke_daq("import", str(path), "--store", str(store))
    assert_one_line_error(result, words)
    assert not store.exists() or Store(store).list() == []


def test_uff58_receptance_through_the_cli_and_back_out(tmp_path):
    data = np.array([1 + 1j, 2, 3j, -1])
    path = uff_frf(tmp_path / "rec.uff", 8, "m", data, np.arange(1.0, 5.0))
    store = tmp_path / "store"
    result = invoke_daq("import", str(path), "--store", str(store))
    assert result.returncode == 0, result.stderr
    assert "receptance" in result.stdout
    (only,) = Store(store).list()
    assert Store(store).open(only.run_id).measured_frfs.form == "receptance"
    out = tmp_path / "again.uff"
    assert (
        invoke_daq("export", only.run_id, "--format", "uff", "-o", str(out), "--store", str(store)).returncode
        == 0
    )
    again = read_uff(out).measured_frfs  # binary 58 from our exporter: exact
    assert again.form == "receptance"
    np.testing.assert_array_equal(again.frf[0], Store(store).open(only.run_id).measured_frfs.frf[0])
