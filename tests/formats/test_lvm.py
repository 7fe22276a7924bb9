"""LabVIEW Measurement files (.lvm): read_lvm and `daq import` of one.

Every file here is written by the test in the layout LabVIEW's "Write To Measurement
File" writes (file header, then segments each with its own header, a headings row and
the samples), and every number checked is the one written: values with repr(float), so
a read keeps every bit; rates from how the file was made."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from daq.formats.errors import FormatError
from daq.formats.lvm import read_lvm
from daq.store import Store
from tests.cli_helpers import daq_import, refused, runs_in

G = 9.80665  # m/s^2 per g (standard gravity, exact by definition)

# --- writing .lvm files ------------------------------------------------------------------

Channel = tuple[str, str, list[float]]  # name, Y_Unit_Label, values


def file_header(separator: str = "Tab", decimal: str = ".", x_columns: str = "No") -> list[str]:
    return [
        "LabVIEW Measurement\t",
        "Writer_Version\t2",
        "Reader_Version\t2",
        f"Separator\t{separator}",
        f"Decimal_Separator\t{decimal}",
        "Multiple_Headers\tYes",
        "Randomized_Extension\tNo",
        "Time_Pref\tRelative",
        "Operator\ttester",
        "Date\t2024/05/17",
        "Time\t10:21:33.4462938",
        f"X_Columns\t{x_columns}",
        "***End_of_Header***\t",
        "",
    ]


def segment_lines(
    channels: list[Channel],
    *,
    sep: str = "\t",
    decimal: str = ".",
    x_columns: str = "No",
    delta_x: str | None = "0.000977",
    times: list[str] | None = None,
) -> list[str]:
    """One segment: its header, the headings row and one row per sample."""
    n = len(channels)
    samples = len(channels[0][2])

    def row(key: str, cells: list[str]) -> str:
        if x_columns == "Multi":  # LabVIEW leaves the cell under each channel's time empty
            cells = [c for value in cells for c in (value, "")][:-1]
        return sep.join([key, *cells, ""])

    lines = [
        row("Channels", [str(n)] + [""] * (n - 1)),
        row("Samples", [str(samples)] * n),
        row("Date", ["2024/05/17"] * n),
        row("Time", ["10:21:33.4462938"] * n),
        row("Y_Unit_Label", [unit for _, unit, _ in channels]),
        row("X_Dimension", ["Time"] * n),
        row("X0", ["0.0000000000000000E+0"] * n),
    ]
    if delta_x is not None:
        lines.append(row("Delta_X", [delta_x] * n))
    lines.append(sep.join(["***End_of_Header***"] + [""] * n))
    names = [name for name, _, _ in channels]
    if x_columns == "Multi":
        lines.append(sep.join(["X_Value", *[c for name in names for c in (name, "X_Value")][:-1], "Comment"]))
    else:
        lines.append(sep.join(["X_Value", *names, "Comment"]))

    def cell(x: float) -> str:
        text = repr(float(x))
        return text.replace(".", ",") if decimal == "," else text

    for k in range(samples):
        values = [cell(values[k]) for _, _, values in channels]
        if x_columns == "No":
            lines.append(sep.join(["", *values]))
        elif x_columns == "One":
            assert times is not None
            lines.append(sep.join([times[k], *values]))
        else:
            assert times is not None
            lines.append(sep.join(c for v in values for c in (times[k], v)))
    return lines


def lvm_text(
    segments: list[list[Channel]],
    *,
    separator: str = "Tab",
    decimal: str = ".",
    x_columns: str = "No",
    delta_x: str | None = "0.000977",
    times: list[str] | None = None,
) -> str:
    sep = {"Tab": "\t", "Comma": ","}[separator]
    lines = file_header(separator, decimal, x_columns)
    for channels in segments:
        lines += segment_lines(
            channels, sep=sep, decimal=decimal, x_columns=x_columns, delta_x=delta_x, times=times
        )
        lines.append("")
    return "\n".join(lines) + "\n"


def write(path, text: str, *, crlf: bool = False, bom: bool = False):
    data = (text.replace("\n", "\r\n") if crlf else text).encode()
    path.write_bytes((b"\xef\xbb\xbf" if bom else b"") + data)
    return path


def hammer_hit(
    n: int, rate_hz: float, freq_hz: float, seed: int = 0
) -> tuple[list[float], list[float], list[float]]:
    """Force (N): a 4-sample half-sine pulse of 100 N at sample 10 on 0.01 N noise;
    a1, a2 (m/s^2): a 2 %-damped sine at ``freq_hz`` from the pulse on, a2 at -0.37 times
    a1 with noise of its own. Rounded to 6 decimals as LabVIEW prints them."""
    rng = np.random.default_rng(seed)
    k = np.arange(n)
    force = np.where((k >= 10) & (k < 14), 100 * np.sin(np.pi * (k - 9) / 5), 0.0) + 0.01 * rng.normal(size=n)
    t = (k - 10) / rate_hz
    w = 2 * np.pi * freq_hz
    a1 = np.where(k >= 10, 30 * np.exp(-0.02 * w * t) * np.sin(w * t), 0.0) + 0.002 * rng.normal(size=n)
    a2 = -0.37 * a1 + 0.002 * rng.normal(size=n)
    return [np.round(x, 6).tolist() for x in (force, a1, a2)]  # type: ignore[return-value]


def real_layout(n: int = 700, seed: int = 0) -> tuple[str, list[float], list[float], list[float]]:
    force, a1, a2 = hammer_hit(n, 1024.0, 87.5, seed)
    text = lvm_text([[("F", "N", force), ("a1", "m/s^2", a1), ("a2", "m/s^2", a2)]])
    return text, force, a1, a2


def one_line_refusal(excinfo) -> str:
    message = str(excinfo.value)
    assert "\n" not in message, message
    assert "\r" not in message, message
    assert message.strip(), "an empty refusal"
    return message


# --- 1. the real layout ------------------------------------------------------------------


def test_the_real_layout_reads_at_the_whole_rate_delta_x_allows(tmp_path):
    text, force, a1, _ = real_layout()
    data = read_lvm(write(tmp_path / "hit.lvm", text))
    assert data.format == "lvm"
    # 0.000977 s is 1/1024 s printed to 6 decimals: 1/0.000977 = 1023.54 Hz, but the true
    # step lies within 0.0009765 .. 0.0009775 s, i.e. 1023.02 .. 1024.07 Hz: 1024 Hz only.
    assert data.hits.sample_rate_hz == 1024.0
    assert data.hits.force_n.shape == (1, len(force))
    np.testing.assert_array_equal(data.hits.force_n[0], force)
    np.testing.assert_array_equal(data.hits.response_m_s2[0], a1)
    notes = data.details["notes"]
    rate_notes = [note for note in notes if note.startswith("sample rate ")]
    assert len(rate_notes) == 1, notes
    assert "1024 Hz" in rate_notes[0], rate_notes[0]
    assert "0.000977" in rate_notes[0], rate_notes[0]
    assert "--sample-rate" in rate_notes[0]
    assert data.details["lvm"]["segments"] == 1
    assert data.details["lvm"]["x_columns"] == "no"


def test_the_ignored_channel_is_named_and_columns_suggested(tmp_path):
    text, *_ = real_layout()
    data = read_lvm(write(tmp_path / "hit.lvm", text))
    ignored = [note for note in data.details["notes"] if "a2" in note]
    assert len(ignored) == 1, data.details["notes"]
    assert "ignored" in ignored[0], ignored[0]
    assert "--columns" in ignored[0], ignored[0]
    assert not any("a1" in note for note in data.details["notes"]), data.details["notes"]


@pytest.mark.parametrize("columns", ["F,a2", "0,2", "F (N),a2 (m/s^2)", " 0 , a2 "])
def test_columns_by_name_or_channel_index_take_the_other_response(tmp_path, columns):
    text, force, _a1, a2 = real_layout()
    data = read_lvm(write(tmp_path / "hit.lvm", text), columns=columns)
    np.testing.assert_array_equal(data.hits.force_n[0], force)
    np.testing.assert_array_equal(data.hits.response_m_s2[0], a2)
    assert data.hits.sample_rate_hz == 1024.0
    ignored = [note for note in data.details["notes"] if "ignored" in note]
    assert len(ignored) == 1, ignored
    assert "a1" in ignored[0], ignored
    assert "a2" not in ignored[0].split("--columns")[0], ignored


def test_channels_picked_against_their_units_are_refused_with_columns_that_work(tmp_path):
    text, force, a1, _ = real_layout()
    path = write(tmp_path / "hit.lvm", text)
    with pytest.raises(FormatError) as excinfo:
        read_lvm(path, columns="1,0")
    message = one_line_refusal(excinfo)
    assert "--columns" in message, message
    suggested = message.rsplit("--columns ", 1)[1].split()[0]
    data = read_lvm(path, columns=suggested)
    np.testing.assert_array_equal(data.hits.force_n[0], force)
    np.testing.assert_array_equal(data.hits.response_m_s2[0], a1)


@pytest.mark.parametrize(
    ("columns", "said"), [("0,3", "out of range"), ("F", "two channels"), ("0,1,2", "two")]
)
def test_bad_columns_are_refused_in_one_line(tmp_path, columns, said):
    text, *_ = real_layout()
    with pytest.raises(FormatError) as excinfo:
        read_lvm(write(tmp_path / "hit.lvm", text), columns=columns)
    assert said in one_line_refusal(excinfo)


# --- 2. the same numbers however the file is written -------------------------------------

finite = st.floats(-1e6, 1e6, allow_nan=False, allow_subnormal=False)


@st.composite
def channel_values(draw, min_size: int = 4, max_size: int = 48):
    n = draw(st.integers(min_size, max_size))
    width = draw(st.integers(2, 4))
    columns = [draw(st.lists(finite, min_size=n, max_size=n)) for _ in range(width)]
    assume(any(x != 0 for x in columns[0]))
    return columns


def channels_of(columns: list[list[float]]) -> list[Channel]:
    units = ["N"] + ["m/s^2"] * (len(columns) - 1)
    return [(f"ch{k}", unit, values) for k, (unit, values) in enumerate(zip(units, columns, strict=True))]


@settings(max_examples=30, deadline=None)
@given(columns=channel_values())
def test_a_decimal_comma_reads_the_same_numbers_as_a_point(tmp_path_factory, columns):
    folder = tmp_path_factory.mktemp("decimal")
    point = read_lvm(write(folder / "point.lvm", lvm_text([channels_of(columns)], delta_x="0.000977")))
    comma = read_lvm(
        write(folder / "comma.lvm", lvm_text([channels_of(columns)], decimal=",", delta_x="0,000977"))
    )
    for data in (point, comma):
        np.testing.assert_array_equal(data.hits.force_n[0], columns[0])
        np.testing.assert_array_equal(data.hits.response_m_s2[0], columns[1])
        assert data.hits.sample_rate_hz == 1024.0


@settings(max_examples=30, deadline=None)
@given(
    columns=channel_values(),
    rate=st.sampled_from([1000.0, 1024.0, 2048.0, 2560.0, 5000.0, 12800.0]),
    decimal=st.sampled_from([".", ","]),
)
def test_a_time_column_printed_to_6_decimals_gives_the_rate_fitted_to_it(
    tmp_path_factory, columns, rate, decimal
):
    n = len(columns[0])
    times = [f"{k / rate:.6f}" for k in range(n)]
    step_text = f"{1 / rate:.6f}"
    if decimal == ",":
        times = [t.replace(".", ",") for t in times]
        step_text = step_text.replace(".", ",")
    text = lvm_text([channels_of(columns)], decimal=decimal, x_columns="One", delta_x=step_text, times=times)
    data = read_lvm(write(tmp_path_factory.mktemp("one") / "timed.lvm", text))
    np.testing.assert_array_equal(data.hits.force_n[0], columns[0])
    np.testing.assert_array_equal(data.hits.response_m_s2[0], columns[1])
    assert data.details["lvm"]["x_columns"] == "one"
    assert any("fitted to the time column" in note for note in data.details["notes"]), data.details["notes"]
    # Each printed time is within 5e-7 s of k / rate, so the least-squares step is within
    # 5e-7 * sum|k - mean| / sum (k - mean)^2 of 1 / rate.
    kc = np.arange(n) - (n - 1) / 2
    bound = 5e-7 * np.abs(kc).sum() / (kc**2).sum()
    step = 1.0 / data.hits.sample_rate_hz
    assert abs(step - 1.0 / rate) <= bound * (1 + 1e-6) + 1e-15, (data.hits.sample_rate_hz, rate)


def test_multi_time_columns_are_read_as_one(tmp_path):
    force, a1, _ = hammer_hit(300, 2048.0, 150.0)
    times = [f"{k / 2048:.6f}" for k in range(300)]
    text = lvm_text(
        [[("F", "N", force), ("a1", "m/s^2", a1)]], x_columns="Multi", delta_x="0.000488", times=times
    )
    data = read_lvm(write(tmp_path / "multi.lvm", text))
    np.testing.assert_array_equal(data.hits.force_n[0], force)
    np.testing.assert_array_equal(data.hits.response_m_s2[0], a1)
    assert abs(data.hits.sample_rate_hz - 2048.0) < 2048.0 * 1e-4


@settings(max_examples=30, deadline=None)
@given(columns=channel_values(), crlf=st.booleans(), bom=st.booleans(), decimal=st.sampled_from([".", ","]))
def test_windows_line_ends_and_a_bom_read_the_same(tmp_path_factory, columns, crlf, bom, decimal):
    folder = tmp_path_factory.mktemp("crlf")
    text = lvm_text(
        [channels_of(columns)], decimal=decimal, delta_x="0,000977" if decimal == "," else "0.000977"
    )
    plain = read_lvm(write(folder / "plain.lvm", text))
    other = read_lvm(write(folder / "other.lvm", text, crlf=crlf, bom=bom))
    for data in (plain, other):
        np.testing.assert_array_equal(data.hits.force_n[0], columns[0])
        np.testing.assert_array_equal(data.hits.response_m_s2[0], columns[1])
        assert data.hits.sample_rate_hz == 1024.0
    assert other.details["lvm"]["channels"] == plain.details["lvm"]["channels"]


def test_a_comma_separated_file_reads_the_same(tmp_path):
    _text, force, a1, _ = real_layout()
    comma = lvm_text(
        [[("F", "N", force), ("a1", "m/s^2", a1), ("a2", "m/s^2", [0.0] * len(force))]], separator="Comma"
    )
    data = read_lvm(write(tmp_path / "comma.lvm", comma))
    np.testing.assert_array_equal(data.hits.force_n[0], force)
    np.testing.assert_array_equal(data.hits.response_m_s2[0], a1)
    assert data.hits.sample_rate_hz == 1024.0


# --- 3. segments ---------------------------------------------------------------------------


def test_each_segment_of_equal_length_is_one_hit(tmp_path):
    hits = [hammer_hit(320, 1024.0, 87.5, seed) for seed in range(4)]
    segments = [[("F", "N", f), ("a1", "m/s^2", a), ("a2", "m/s^2", b)] for f, a, b in hits]
    data = read_lvm(write(tmp_path / "four.lvm", lvm_text(segments)))
    assert data.hits.force_n.shape == (4, 320)
    for k, (force, a1, _) in enumerate(hits):
        np.testing.assert_array_equal(data.hits.force_n[k], force)
        np.testing.assert_array_equal(data.hits.response_m_s2[k], a1)
    assert data.hits.sample_rate_hz == 1024.0
    assert data.details["lvm"]["segments"] == 4


def test_segments_with_different_channel_counts_are_refused_in_one_line(tmp_path):
    force, a1, a2 = hammer_hit(320, 1024.0, 87.5)
    first = [("F", "N", force), ("a1", "m/s^2", a1), ("a2", "m/s^2", a2)]
    second = [("F", "N", force), ("a1", "m/s^2", a1)]
    text = lvm_text([first, second])
    # The second segment's header starts after the file header, the first segment's
    # header (8 rows, its end and the headings row), its samples and a blank line.
    second_line = len(file_header()) + 10 + 320 + 1 + 1
    assert text.splitlines()[second_line - 1].startswith("Channels\t2")
    with pytest.raises(FormatError) as excinfo:
        read_lvm(write(tmp_path / "mixed.lvm", text))
    message = one_line_refusal(excinfo)
    assert "mixed.lvm" in message
    assert f"line {second_line}" in message, message


def test_a_file_without_end_of_header_is_refused_in_one_line(tmp_path):
    text, *_ = real_layout()
    broken = (
        "\n".join(line for line in text.splitlines() if not line.startswith("***End_of_Header***")) + "\n"
    )
    with pytest.raises(FormatError) as excinfo:
        read_lvm(write(tmp_path / "noend.lvm", broken))
    message = one_line_refusal(excinfo)
    assert "noend.lvm" in message, message
    assert "End_of_Header" in message, message


def test_a_file_that_is_no_lvm_is_refused_in_one_line(tmp_path):
    with pytest.raises(FormatError) as excinfo:
        read_lvm(write(tmp_path / "plain.lvm", "time,force,response\n0,1,2\n"))
    assert "LabVIEW Measurement" in one_line_refusal(excinfo)


# --- 4. units --------------------------------------------------------------------------------


def test_a_response_in_g_is_stored_in_m_s2(tmp_path):
    force, a1, _a2 = hammer_hit(400, 1024.0, 87.5)
    text = lvm_text([[("F", "N", force), ("a1", "g", a1)]])
    data = read_lvm(write(tmp_path / "g.lvm", text))
    np.testing.assert_array_equal(data.hits.force_n[0], force)
    np.testing.assert_allclose(data.hits.response_m_s2[0], np.array(a1) * G, rtol=1e-15, atol=0)
    assert data.details["response_unit"] == "g"


def test_a_force_in_kn_is_stored_in_n(tmp_path):
    force, a1, _ = hammer_hit(400, 1024.0, 87.5)
    text = lvm_text([[("F", "kN", force), ("a1", "m/s^2", a1)]])
    data = read_lvm(write(tmp_path / "kn.lvm", text))
    np.testing.assert_allclose(data.hits.force_n[0], np.array(force) * 1000.0, rtol=1e-15, atol=0)


def test_a_unit_given_wins_over_the_label(tmp_path):
    force, a1, _ = hammer_hit(400, 1024.0, 87.5)
    text = lvm_text([[("F", "N", force), ("a1", "m/s^2", a1)]])
    data = read_lvm(write(tmp_path / "given.lvm", text), response_unit="g")
    np.testing.assert_allclose(data.hits.response_m_s2[0], np.array(a1) * G, rtol=1e-15, atol=0)


@pytest.mark.parametrize("which", ["force", "response"])
def test_an_unknown_unit_is_refused_naming_the_unit_options(tmp_path, which):
    force, a1, _ = hammer_hit(400, 1024.0, 87.5)
    units = {"force": ("furlongs", "m/s^2"), "response": ("N", "furlongs")}[which]
    text = lvm_text([[("F", units[0], force), ("a1", units[1], a1)]])
    with pytest.raises(FormatError) as excinfo:
        read_lvm(write(tmp_path / "odd.lvm", text))
    message = one_line_refusal(excinfo)
    assert "furlongs" in message, message
    assert f"--{which}-unit" in message, message


# --- 5. the command line -------------------------------------------------------------------


def three_segments(n: int = 600) -> tuple[str, list[tuple[list[float], list[float], list[float]]]]:
    hits = [hammer_hit(n, 1024.0, 87.5, seed) for seed in range(3)]
    return lvm_text([[("F", "N", f), ("a1", "m/s^2", a), ("a2", "m/s^2", b)] for f, a, b in hits]), hits


@pytest.mark.parametrize("name", ["x.lvm", "x.txt"])
def test_daq_import_stores_a_hit_per_segment(tmp_path, name):
    text, hits = three_segments()
    path = write(tmp_path / name, text)
    store = tmp_path / "runs"
    result = daq_import(store, path)
    assert result.returncode == 0, result.stderr
    assert "3 hits of 600 samples at 1024 Hz" in result.stdout, result.stdout
    assert "format lvm" in result.stdout, result.stdout
    (run_id,) = runs_in(store)
    run = Store(store).open(run_id)
    assert run.hits.force_n.shape == (3, 600)
    assert run.hits.sample_rate_hz == 1024.0
    for k, (force, a1, _) in enumerate(hits):
        np.testing.assert_array_equal(run.hits.force_n[k], force)
        np.testing.assert_array_equal(run.hits.response_m_s2[k], a1)


def test_daq_import_as_csv_is_refused_saying_format_lvm(tmp_path):
    text, _ = three_segments()
    path = write(tmp_path / "x.lvm", text)
    store = tmp_path / "runs"
    refused(daq_import(store, path, "--format", "csv"), store, "--format lvm")


def test_columns_on_the_command_line_take_channels(tmp_path):
    text, hits = three_segments()
    path = write(tmp_path / "x.lvm", text)
    store = tmp_path / "runs"
    result = daq_import(store, path, "--columns", "F,a2")
    assert result.returncode == 0, result.stderr
    run = Store(store).open(runs_in(store)[0])
    for k, (_, _, a2) in enumerate(hits):
        np.testing.assert_array_equal(run.hits.response_m_s2[k], a2)


def test_without_delta_x_the_rate_is_asked_for_and_given_it_imports(tmp_path):
    force, a1, _ = hammer_hit(600, 2048.0, 150.0)
    text = lvm_text([[("F", "N", force), ("a1", "m/s^2", a1)]], delta_x=None)
    assert "Delta_X" not in text
    path = write(tmp_path / "nodx.lvm", text)
    store = tmp_path / "runs"
    refused(daq_import(store, path), store, "nodx.lvm", "--sample-rate")
    result = daq_import(store, path, "--sample-rate", "2048")
    assert result.returncode == 0, result.stderr
    (run_id,) = runs_in(store)
    run = Store(store).open(run_id)
    assert run.hits.sample_rate_hz == 2048.0
    np.testing.assert_array_equal(run.hits.force_n[0], force)
    np.testing.assert_array_equal(run.hits.response_m_s2[0], a1)
    assert math.isclose(run.hits.force_n.shape[1] / run.hits.sample_rate_hz, 600 / 2048)


def test_a_sample_rate_given_within_what_delta_x_allows_wins(tmp_path):
    text, _ = three_segments()  # Delta_X 0.000977: 1023.02 to 1024.07 Hz
    path = write(tmp_path / "x.lvm", text)
    store = tmp_path / "runs"
    result = daq_import(store, path, "--sample-rate", "1023.5")
    assert result.returncode == 0, result.stderr
    rate = Store(store).open(runs_in(store)[0]).hits.sample_rate_hz
    assert rate == 1023.5


def test_a_sample_rate_given_against_delta_x_is_refused_as_csv_does_against_its_times(tmp_path):
    # A trial user's --sample-rate 2000 on a 2560 Hz file was taken, and every frequency
    # came out 22 % low with no caution.
    text, _ = three_segments()
    path = write(tmp_path / "x.lvm", text)
    store = tmp_path / "runs"
    refused(daq_import(store, path, "--sample-rate", "2560"), store, "Delta_X 0.000977 s allows only", "2560")


# --- the rate stored is the rate decided -------------------------------------------------


@pytest.mark.parametrize("rate", [1000.0, 2000.0, 25600.0, 51200.0])
def test_the_sample_rate_given_is_stored_exactly(tmp_path, rate):
    force, a1, _ = hammer_hit(600, rate, 87.5)
    path = write(tmp_path / "nodx.lvm", lvm_text([[("F", "N", force), ("a1", "m/s^2", a1)]], delta_x=None))
    assert read_lvm(path, sample_rate_hz=rate).hits.sample_rate_hz == rate


@pytest.mark.parametrize(
    ("delta_x", "rate"), [("0.001000", 1000.0), ("1.000000E-03", 1000.0), ("0.0005", 2000.0)]
)
def test_a_delta_x_of_a_whole_rate_is_stored_exactly(tmp_path, delta_x, rate):
    force, a1, _ = hammer_hit(600, rate, 87.5)
    path = write(tmp_path / "dx.lvm", lvm_text([[("F", "N", force), ("a1", "m/s^2", a1)]], delta_x=delta_x))
    data = read_lvm(path)
    assert data.hits.sample_rate_hz == rate


@pytest.mark.parametrize(
    ("delta_x", "rate"), [("0.000977", 1024.0), ("0.000488", 2048.0), ("2.000000E-04", 5000.0)]
)
def test_these_delta_x_give_these_rates_exactly(tmp_path, delta_x, rate):
    force, a1, _ = hammer_hit(600, rate, 87.5)
    path = write(tmp_path / "dx.lvm", lvm_text([[("F", "N", force), ("a1", "m/s^2", a1)]], delta_x=delta_x))
    assert read_lvm(path).hits.sample_rate_hz == rate


# --- rows and channels the file gets wrong -------------------------------------------------


def sample_line(text: str, k: int) -> int:
    """The 1-based line number of sample ``k`` of the first segment of ``text``."""
    headings = next(i for i, line in enumerate(text.splitlines()) if line.startswith("X_Value"))
    return headings + 2 + k


def refusal_of_sample_4(tmp_path, row) -> tuple[int, str]:
    """(its line, the one-line refusal) of a two-channel file whose sample 4 is written as
    ``row(force)`` instead."""
    force, a1, _ = hammer_hit(300, 1024.0, 87.5)
    text = lvm_text([[("F", "N", force), ("a1", "m/s^2", a1)]])
    line = sample_line(text, 4)
    lines = text.splitlines()
    lines[line - 1] = row(force[4])
    with pytest.raises(FormatError) as excinfo:
        read_lvm(write(tmp_path / "bad.lvm", "\n".join(lines) + "\n"))
    return line, one_line_refusal(excinfo)


def test_a_value_that_is_no_number_is_refused_naming_its_line_and_channel(tmp_path):
    line, message = refusal_of_sample_4(tmp_path, lambda f: f"\t{f!r}\tabc")
    assert f"line {line}" in message, message
    assert "'abc'" in message, message
    # The file's third cell, channel a1: not the table's "column 4" (hit, time, F, a1).
    assert "column 4" not in message, message
    assert "a1" in message or "column 3" in message, message


def test_a_row_short_of_a_channel_is_refused_as_such(tmp_path):
    line, message = refusal_of_sample_4(tmp_path, lambda f: f"\t{f!r}")
    assert f"line {line}" in message, message
    assert "''" not in message, message
    assert "1 of the 2 channels" in message, message


@pytest.mark.parametrize("rate", [None, 1024.0])
def test_a_single_channel_is_refused_saying_two_are_needed(tmp_path, rate):
    force, _, _ = hammer_hit(300, 1024.0, 87.5)
    with pytest.raises(FormatError) as excinfo:
        read_lvm(write(tmp_path / "one.lvm", lvm_text([[("F", "N", force)]])), sample_rate_hz=rate)
    message = one_line_refusal(excinfo)
    assert "channel" in message, message
    assert "--sample-rate" not in message, message
    assert "2 data columns" not in message, message


def test_a_time_column_with_a_dropped_sample_is_not_passed_over(tmp_path):
    force, a1, _ = hammer_hit(301, 1024.0, 87.5)
    times = [f"{k / 1024:.6f}" for k in range(301)]
    del force[150], a1[150], times[150]  # sample 150 lost: the time steps twice as far there
    text = lvm_text([[("F", "N", force), ("a1", "m/s^2", a1)]], x_columns="One", times=times)
    with pytest.raises(FormatError) as excinfo:
        read_lvm(write(tmp_path / "gap.lvm", text))
    assert f"line {sample_line(text, 150)}" in one_line_refusal(excinfo)


@pytest.mark.parametrize(
    "name", ["Acceleration (FFT - (RMS))", "Power Spectrum", "PSD a1", "Force FFT", "Frequency Response"]
)
def test_a_logged_spectrum_is_refused_as_a_spectrum(tmp_path, name):
    """LabVIEW's FFT VIs log a spectrum with X_Dimension 'Time' (a new user's cantilever
    file, PujaChowdhury/Dataset-4...): it was refused as 'has 1 channel', which said nothing
    of why. With a force beside it, it would have been read as a response in time."""
    force, a1, _ = hammer_hit(256, 1024.0, 87.5)
    for channels in ([(name, "g", a1)], [("F", "N", force), (name, "g", a1)]):
        path = write(tmp_path / "spectrum.lvm", lvm_text([channels]))
        with pytest.raises(FormatError) as excinfo:
            read_lvm(path)
        message = one_line_refusal(excinfo)
        assert f"holds a spectrum ({name}" in message or "holds a spectrum (" in message, message
        assert "not time records" in message


def test_channel_names_of_time_records_are_no_spectrum(tmp_path):
    force, a1, a2 = hammer_hit(256, 1024.0, 87.5)
    names = [("Force", "N", force), ("Accel FF-1", "m/s^2", a1), ("Response Spec 2", "m/s^2", a2)]
    data = read_lvm(write(tmp_path / "time.lvm", lvm_text([names])), columns="Force,Accel FF-1")
    assert data.hits.n_samples == 256
