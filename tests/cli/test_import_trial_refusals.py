"""`daq import` of the files a new user brought (trial findings 5, 6, 7, 11, 12, 13):
each refusal is one line on stderr, exit status 1 and nothing in the store; where the
import goes ahead, one `note:` line on stdout says what the user would otherwise miss.
Real files written here, the real command line run in this process."""

from __future__ import annotations

import numpy as np
import pytest
import pyuff

from daq.store import Store
from tests.cli_helpers import assert_one_line_error, daq_import, invoke_daq, refused, runs_in


def table(path, rows, separator: str = "\t", header: str | None = None):
    lines = [] if header is None else [header]
    lines += [separator.join(repr(float(v)) for v in row) for row in rows]
    path.write_text("\n".join(lines) + "\n")
    return path


def time_rows(n: int, rate_hz: float = 51200.0, extra: int = 0) -> np.ndarray:
    """n samples: time, force (a hammer pulse on noise), response and ``extra`` more
    columns (k, 2k, ...)."""
    t = np.arange(n) / rate_hz
    rng = np.random.default_rng(n)
    # One sample: a crest factor of 8 even in 64 samples (file_checks wants 7).
    pulse = np.where(np.arange(n) == 5, 100.0, 0.0) + 0.01 * rng.normal(size=n)
    cols = [t, pulse, rng.normal(size=n)] + [np.full(n, 10.0 * (k + 1)) for k in range(extra)]
    return np.column_stack(cols)


def notes(result) -> list[str]:
    return [line for line in result.stdout.splitlines() if line.startswith("note: ")]


# --- finding 6: too short to analyse ----------------------------------------------------


def test_the_two_row_headerless_table_is_refused_with_the_minimum_said(tmp_path):
    path = tmp_path / "tworows.txt"
    path.write_text("0.0\t1.0\t0.0\n1.0\t2.0\t0.5\n")
    store = tmp_path / "runs"
    message = refused(daq_import(store, path), store, "tworows.txt: too short to analyse")
    assert "2 samples per hit give 0 frequency lines above 0 Hz" in message
    assert "an analysis needs 8, so 21 samples per hit at least" in message


def test_a_two_sample_time_table_with_a_header_is_refused(tmp_path):
    path = tmp_path / "tworows.csv"
    path.write_text("time,force,acc\n0,1,2\n0.001,1,2\n")
    store = tmp_path / "runs"
    refused(daq_import(store, path), store, "too short to analyse", "21 samples per hit at least")


@pytest.mark.parametrize(("n", "short"), [(20, True), (21, False)])
def test_the_minimum_is_what_daq_analyze_needs(tmp_path, n, short):
    """20 samples give 7 lines above 0 Hz, which `daq analyze` refuses even at the lowest
    order; 21 give 8, which it analyses. The import notes the first, not the second."""
    path = table(tmp_path / "hit.csv", time_rows(n, rate_hz=1000.0), ",", "time,force,response")
    store = tmp_path / "runs"
    result = daq_import(store, path)
    assert result.returncode == 0, result.stderr
    said = [line for line in notes(result) if "too short to analyse" in line]
    assert bool(said) == short, result.stdout
    if short:
        assert said == [
            f"note: too short to analyse: {n} samples per hit give 7 frequency lines above 0 Hz "
            "(n samples give n/2.56), and an analysis needs 8, so 21 samples per hit at least; "
            "daq analyze will refuse this run"
        ]
    analysed = invoke_daq("analyze", "latest", "--max-order", "2", "--store", str(store))
    if short:
        assert_one_line_error(analysed, "the run has 7 lines above 0 Hz and an analysis needs 8")
    else:
        assert analysed.returncode == 0, analysed.stderr


@pytest.mark.parametrize(("n", "short"), [(7, True), (8, False)])
def test_an_frf_table_of_fewer_lines_than_an_analysis_needs_is_noted(tmp_path, n, short):
    f = 10.0 * np.arange(1, n + 1)
    h = 1 / (1 - (f / 45) ** 2 + 0.05j * f / 45)
    path = table(tmp_path / "frf.csv", np.column_stack([f, h.real, h.imag]), ",", "Frequency (Hz),Re,Im")
    store = tmp_path / "runs"
    result = daq_import(store, path)
    assert result.returncode == 0, result.stderr
    said = [line for line in notes(result) if "too short to analyse" in line]
    assert said == (
        [f"note: too short to analyse: the FRFs hold {n} frequency lines above 0 Hz, and an analysis "
         "needs 8 at least; daq analyze will refuse this run"] if short else []
    )  # fmt: skip
    analysed = invoke_daq("analyze", "latest", "--max-order", "2", "--store", str(store))
    assert analysed.returncode == (1 if short else 0), analysed.stderr


def test_an_frf_table_with_no_line_above_0_hz_is_refused(tmp_path):
    path = tmp_path / "dc.txt"
    path.write_text("0\t1.5\t0\n")
    store = tmp_path / "runs"
    refused(
        daq_import(store, path, "--format", "frf-text"), store, "the FRFs hold 0 frequency lines above 0 Hz"
    )


# --- finding 5: columns left out, a 1 Hz "time record" -------------------------------------


def test_a_fourth_column_is_named_in_a_note_and_the_note_says_how_to_take_it(tmp_path):
    path = table(tmp_path / "t4.csv", time_rows(64, extra=1), ",", "t,F,a1,a2")
    store = tmp_path / "runs"
    result = daq_import(store, path)
    assert result.returncode == 0, result.stderr
    assert notes(result) == [
        "note: column 4 'a2' ignored: a run holds one time, force and response; give --columns to "
        "choose (header names or 0-based indices), e.g. --columns t,F,a2"
    ]
    # The way out the note gives works, and then a1 is the column left out.
    again = daq_import(store, path, "--columns", "t,F,a2")
    assert again.returncode == 0, again.stderr
    assert "note: column 3 'a1' ignored" in again.stdout
    run = Store(store).open(max(runs_in(store)))
    assert np.all(run.hits.response_m_s2 == 10.0)


def test_headerless_extra_columns_are_noted_by_number_and_index(tmp_path):
    path = table(tmp_path / "t5.txt", time_rows(64, extra=2))
    store = tmp_path / "runs"
    result = daq_import(store, path)
    assert result.returncode == 0, result.stderr
    assert "note: columns 4, 5 ignored: a run holds one time, force and response" in result.stdout
    assert "e.g. --columns 0,1,3" in result.stdout


def test_our_own_export_layout_leaves_nothing_out(tmp_path):
    rows = time_rows(64).tolist()
    path = tmp_path / "hits.csv"
    path.write_text("hit,time,force,response\n" + "".join(f"0,{t!r},{f!r},{a!r}\n" for t, f, a in rows))
    result = daq_import(tmp_path / "runs", path)
    assert result.returncode == 0, result.stderr
    assert notes(result) == []


def test_a_frequency_table_forced_as_csv_is_refused_with_the_way_out(tmp_path):
    f = np.arange(100.0)
    # Re and Im of an FRF (an Im of zeros is now refused sooner, as a response of zeros).
    path = table(tmp_path / "frf.txt", np.column_stack([f, np.ones_like(f), 0.5 * np.ones_like(f)]))
    store = tmp_path / "runs"
    message = refused(
        daq_import(store, path, "--format", "csv"),
        store,
        "its time column steps by 1 s, a sampling rate of 1 Hz, which records no vibration",
        "import it with --format frf-text",
    )
    assert "read as csv" not in message  # the format was given, not detected


def test_a_slow_time_column_under_a_header_is_refused_and_told_about_units(tmp_path):
    path = table(tmp_path / "slow.csv", time_rows(64, rate_hz=1.0), ",", "time,force,response")
    store = tmp_path / "runs"
    refused(daq_import(store, path), store, "records no vibration", "say so in the header (e.g. Time (ms))")
    ms = table(tmp_path / "ms.csv", time_rows(64, rate_hz=1.0), ",", "time (ms),force,response")
    result = daq_import(store, ms)
    assert result.returncode == 0, result.stderr
    assert "at 1000 Hz" in result.stdout


def test_the_even_column_slow_table_is_told_to_get_a_header(tmp_path):
    path = table(tmp_path / "even4.txt", [[k, 1, 0, 1] for k in range(100)])
    store = tmp_path / "runs"
    message = refused(daq_import(store, path), store, "cannot tell its format", "not 4")
    assert "give it a header row naming the columns" in message
    assert "--format csv" not in message  # csv would be refused: 1 Hz records no vibration


# --- finding 11: frf-text forced on a time record -------------------------------------------


def test_frf_text_forced_on_a_51200_hz_time_record_is_refused(tmp_path):
    t = np.arange(512) / 51200.0
    rows = [f"{v:.6e}\t{np.sin(v * 900):.6e}\t{np.cos(v * 700):.6e}" for v in t]
    path = tmp_path / "Point1_Channel1_CH1.txt"
    path.write_text("\n".join(rows) + "\n")
    store = tmp_path / "runs"
    message = refused(
        daq_import(store, path, "--format", "frf-text"),
        store,
        "its first column steps by 1.95313e-05, which as frequency would be FRFs from 0 to 0.00998047 Hz",
        "as time a record sampled at 51200 Hz",
        "import it with --format csv",
    )
    assert "0.1 Hz or more (0.01 Hz from a real value at 0 Hz)" in message
    as_time = daq_import(store, path)
    assert as_time.returncode == 0, as_time.stderr
    assert "(csv: 1 hit of 512 samples at 51200 Hz)" in as_time.stdout


def test_frf_text_forced_on_two_rows_of_a_time_record_is_refused_too(tmp_path):
    """Two rows have one step, enough to tell time from frequency (a new user's trial: two
    rows stepping by 1 ms were stored as FRFs at 0 and 0.001 Hz, ten were refused)."""
    path = table(tmp_path / "t2_nohdr.txt", time_rows(2, 1000.0))
    store = tmp_path / "runs"
    refused(daq_import(store, path, "--format", "frf-text"), store, "its first column steps by 0.001")


def test_a_header_naming_a_frequency_is_heeded_whatever_the_step(tmp_path):
    f = 100 + 0.001 * np.arange(64)
    path = table(
        tmp_path / "zoom.txt",
        np.column_stack([f, np.ones_like(f), np.ones_like(f)]),
        "\t",
        "Frequency (Hz)\tRe\tIm",
    )
    result = daq_import(tmp_path / "runs", path, "--format", "frf-text")
    assert result.returncode == 0, result.stderr
    assert "(frf-text: 1 FRF of 64 points" in result.stdout


# --- finding 7: a broken frequency column, and which reader refused -------------------------


def frequency_table(path, f):
    return table(path, np.column_stack([f, np.ones_like(f), np.zeros_like(f)]))


@pytest.mark.parametrize(
    ("name", "axis", "fragment"),
    [
        ("nonincr.txt", lambda f: np.where(np.arange(f.size) == 50, f[49], f),
         "nonincr.txt line 51: the first column (time or frequency) does not increase"),
        ("swapped.txt", lambda f: f[np.r_[0:50, 51, 50, 52:f.size]],
         "swapped.txt line 51: the first column (time or frequency) steps unevenly"),
        ("decreasing.txt", lambda f: f[::-1] + 1,
         "decreasing.txt line 2: the first column (time or frequency) goes down (from 100 to 99)"),
    ],
)  # fmt: skip
def test_a_broken_frequency_column_gets_a_neutral_message_and_the_reader_tried(
    tmp_path, name, axis, fragment
):
    path = frequency_table(tmp_path / name, axis(np.arange(100.0)))
    store = tmp_path / "runs"
    message = refused(daq_import(store, path), store, fragment)
    assert message.rstrip().endswith("(read as csv: detected: the name ends in .txt)")
    assert "time does not increase" not in message
    assert "hit 0" not in message


def test_a_time_column_under_a_header_is_still_called_time(tmp_path):
    path = tmp_path / "t.csv"
    path.write_text("time,force,response\n" + "".join(f"{k / 1000},1,2\n" for k in (0, 1, 2, 2, 3)))
    store = tmp_path / "runs"
    refused(daq_import(store, path), store, "t.csv line 5: time does not increase (read as csv: detected:")


# --- finding 12: files of other kinds -------------------------------------------------------


@pytest.mark.parametrize("forced", [[], ["--format", "frf-text"]])
def test_python_complex_numbers_are_named_as_such(tmp_path, forced):
    path = tmp_path / "meas_point_1.txt"
    path.write_text("".join(f"({0.1 * k}-{0.02 * k}j)\n" for k in range(1, 40)))
    store = tmp_path / "runs"
    refused(
        daq_import(store, path, *forced),
        store,
        "meas_point_1.txt line 1: cells look like complex numbers (a+bj), e.g. '(0.1-0.02j)'",
        "write the real and imaginary parts as two columns",
    )


def test_a_complex_cell_among_real_ones_is_named_with_its_line(tmp_path):
    path = tmp_path / "c.csv"
    path.write_text("time,force,response\n0,1,2\n0.001,1,3+4i\n")
    refused(
        daq_import(tmp_path / "runs", path),
        tmp_path / "runs",
        "c.csv line 3: cells look like complex numbers",
    )


LVM = (
    "LabVIEW Measurement\t\nWriter_Version\t0.92\nSeparator\tTab\n***End_of_Header***\t\n\t\n"
    "Channels\t3\t\t\t\n***End_of_Header***\t\t\t\t\nX_Value\tF\tm_1\tm_2\tComment\n"
    + "".join(f"\t{0.05 * k}\t{0.2 * k}\t{0.3 * k}\n" for k in range(50))
)


@pytest.mark.parametrize(("name", "forced"), [("m.lvm", ["--format", "csv"]), ("m.txt", ["--format", "csv"])])
def test_a_labview_measurement_file_given_as_csv_is_told_to_take_lvm(tmp_path, name, forced):
    path = tmp_path / name
    path.write_text(LVM)
    store = tmp_path / "runs"
    message = refused(daq_import(store, path, *forced), store, "a LabVIEW measurement file")
    assert "--format lvm" in message
    assert "data column" not in message


def test_a_labview_measurement_file_without_delta_x_asks_for_the_rate(tmp_path):
    path = tmp_path / "m.lvm"
    path.write_text(LVM)
    store = tmp_path / "runs"
    refused(daq_import(store, path), store, "has no Delta_X", "give --sample-rate HZ")


@pytest.mark.parametrize("kind", ["npy", "npz"])
def test_a_numpy_file_gets_no_text_format_suggested(tmp_path, kind):
    path = tmp_path / f"measurements_1.{kind}"
    if kind == "npy":
        np.save(path, np.zeros((3, 100)))
    else:
        np.savez(path, force=np.zeros(100))
    store = tmp_path / "runs"
    message = refused(
        daq_import(store, path), store, f"a binary NumPy file (.{kind}), which daq does not read"
    )
    assert "give --format" not in message
    assert "numpy.savetxt" in message
    forced = daq_import(store, path, "--format", "csv")
    refused(forced, store, "binary NumPy file")


def test_other_binary_content_is_not_sent_to_the_text_readers(tmp_path):
    path = tmp_path / "capture.dat"
    path.write_bytes(b"\x01\x02\x00\x00" + bytes(range(256)) * 4)
    store = tmp_path / "runs"
    message = refused(daq_import(store, path), store, "binary content (NUL bytes)", "export the data as text")
    assert "give --format" not in message


def test_utf16_text_is_told_to_be_saved_as_utf8(tmp_path):
    path = tmp_path / "hits.csv"
    path.write_text("time,force,response\n0,1,2\n", encoding="utf-16")
    refused(daq_import(tmp_path / "runs", path), tmp_path / "runs", "text in UTF-16", "save it as UTF-8")


# --- finding 13: UFF wording, the same file twice ------------------------------------------


def uff_frf_file(path, kinds: list[int]):
    f = np.arange(1.0, 41.0)
    sets = []
    for k, kind in enumerate(kinds):
        dset = pyuff.prepare_58(
            binary=0, id1=f"H{k}", func_type=4, rsp_node=2, rsp_dir=3, ref_node=1, ref_dir=3,
            abscissa_spacing=1, abscissa_spec_data_type=18, ordinate_spec_data_type=kind,
            orddenom_spec_data_type=13, z_axis_spec_data_type=0, data=(1 + 1j) * f, x=f,
        )  # fmt: skip
        dset.update(ordinate_axis_units_lab="NONE", orddenom_axis_units_lab="N")
        sets.append(dset)
    pyuff.UFF(str(path)).write_sets(sets, mode="add")
    return path


def test_uff_records_are_counted_from_1(tmp_path):
    store = tmp_path / "runs"
    mixed = uff_frf_file(tmp_path / "mixed.uff", [8, 12])
    refused(daq_import(store, mixed), store, "FRF records #1 (receptance) and #2 (accelerance)")
    odd = uff_frf_file(tmp_path / "odd.uff", [3])
    refused(daq_import(store, odd), store, "FRF record #1 has ordinate data type 3")


def test_uff_forced_on_a_tab_separated_table_names_its_first_line(tmp_path):
    path = tmp_path / "Point_1.txt"
    path.write_text("0.000000e+000\t3.100538e-020\t2.6e-003\n1.0\t2.0\t3.0\n")
    store = tmp_path / "runs"
    refused(
        daq_import(store, path, "--format", "uff"),
        store,
        "does not look like a UFF file: its first line is not a UFF -1 delimiter line but "
        "'0.000000e+000\\t3.100538e-020\\t2.6e-003'",
    )


def test_importing_the_same_file_again_imports_it_and_names_the_earlier_run(tmp_path):
    path = table(tmp_path / "hit.csv", time_rows(64), ",", "time,force,response")
    store = tmp_path / "runs"
    first = daq_import(store, path)
    assert first.returncode == 0, first.stderr
    assert not [n for n in notes(first) if "imported before" in n]
    (first_id,) = runs_in(store)
    second = daq_import(store, path)
    assert second.returncode == 0, second.stderr
    assert len(runs_in(store)) == 2
    said = [n for n in notes(second) if "imported before" in n]
    assert len(said) == 1
    assert f"was imported before as run {first_id};" in said[0]
    third = daq_import(store, path)
    assert "(and 1 earlier run)" in third.stdout
    # Another file is another file, even under the same name.
    table(path, time_rows(65), ",", "time,force,response")
    other = daq_import(store, path)
    assert other.returncode == 0, other.stderr
    assert "imported before" not in other.stdout


@pytest.mark.parametrize("n", [21, 40, 100])
def test_a_record_the_import_keeps_is_analysed_at_the_order_its_lines_hold(tmp_path, n):
    """21 samples give the 8 lines an analysis needs: the default analysis fits the order
    those lines hold, where it used to refuse for want of the 62 lines of order 30 (a new
    user's trial: 'band (47.61904761904762, 380.95238095238096) holds 8 lines; ...')."""
    path = table(tmp_path / "short.csv", time_rows(n, 1000.0), ",", "time,force,response")
    store = tmp_path / "runs"
    assert daq_import(store, path).returncode == 0
    analysed = invoke_daq("analyze", "latest", "--store", str(store))
    assert analysed.returncode == 0, analysed.stderr
    assert "Traceback" not in analysed.stderr


def test_a_record_too_short_says_so_in_analyze_not_widen_the_band(tmp_path):
    path = table(tmp_path / "ten.csv", time_rows(10, 1000.0), ",", "time,force,response")
    store = tmp_path / "runs"
    assert daq_import(store, path).returncode == 0  # imported with a note
    analysed = invoke_daq("analyze", "latest", "--store", str(store))
    assert_one_line_error(
        analysed, "the run has 3 lines above 0 Hz and an analysis needs 8: the record is too short"
    )
    assert "widen" not in analysed.stderr


# --- a new user's trial, November 25 -------------------------------------------------


def test_a_negative_magnitude_is_named_as_the_file_wrote_it(tmp_path):
    path = tmp_path / "frf.csv"
    rows = ["freq,mag,phase", "1,1.0,0", "2,-2.0,10", *(f"{k},1,0" for k in range(3, 12))]
    path.write_text("\n".join(rows) + "\n")
    store = tmp_path / "runs"
    message = refused(daq_import(store, path), store, "line 3: negative magnitude -2 (dB?")
    assert "np." not in message


def test_spaces_and_decimal_commas_with_a_whole_number_in_the_first_line(tmp_path):
    """ "0 2,46e-07 0,025": the "0" cell made the comma a separator (line 2: 4 columns,
    expected 3) or, without a header, a header '0' in the detection's words."""
    frf = tmp_path / "frf.txt"
    rows = ["0 2,46031e-07 0,0254927"] + [
        f"{k * 0.25:.4f} {1e-3 * k:.6e} {-2e-3 * k:.6e}" for k in range(1, 40)
    ]
    frf.write_text("\n".join(r.replace(".", ",") for r in rows) + "\n")
    result = daq_import(tmp_path / "frf_runs", frf)
    assert result.returncode == 0, result.stderr
    assert "format frf-text: detected: no header, and its first column steps by 0.25" in result.stdout
    hits = tmp_path / "hits.txt"
    rows = ["0 -3 0,5"] + [f"{k / 1000:g} {k % 7 - 3:g} {0.5 * (k % 5) + 0.5:g}" for k in range(1, 64)]
    hits.write_text("\n".join(r.replace(".", ",") for r in rows) + "\n")
    result = daq_import(tmp_path / "hit_runs", hits)
    assert result.returncode == 0, result.stderr
    assert "format csv: detected: the name ends in .txt\n" in result.stdout  # no header '0' said
    (run,) = runs_in(tmp_path / "hit_runs")
    stored = Store(tmp_path / "hit_runs").open(run).hits
    assert stored.response_m_s2[0, :6].tolist() == [0.5, 1.0, 1.5, 2.0, 2.5, 0.5]


def _hits_csv(path, force, response, fs):
    rows = ["hit,t,F,a"]
    for k in range(force.shape[0]):
        rows += [f"{k},{i / fs:.9g},{force[k, i]:.9g},{response[k, i]:.9g}" for i in range(force.shape[1])]
    path.write_text("\n".join(rows) + "\n")


def test_a_double_impact_and_a_clipped_hit_from_a_file_are_noted_and_cautioned(tmp_path):
    from tests.analysis.impact_synth import impact_hits
    from tests.cli_helpers import daq_json

    fs = 2048.0
    force, response = impact_hits([45.0, 132.0, 310.0], [0.015, 0.008, 0.02], [1.0, -0.6, 0.4], fs, 2.0, 3,
                                  0.01, 2e-3, 7)  # fmt: skip
    clean = tmp_path / "clean.csv"
    _hits_csv(clean, force, response, fs)
    result = daq_import(tmp_path / "clean_runs", clean)
    assert result.returncode == 0, result.stderr
    assert "failed the" not in result.stdout
    (info,) = daq_json("analyze", tmp_path / "clean_runs", "latest")
    assert not any("failed" in c for c in info["cautions"])
    shift = round(0.055 * fs)
    force[1] += 0.6 * np.concatenate([np.zeros(shift), force[1, :-shift]])
    top = 0.3 * np.abs(response[2]).max()
    response[2] = np.clip(response[2], -top, top)
    bad = tmp_path / "bad.csv"
    _hits_csv(bad, force, response, fs)
    result = daq_import(tmp_path / "bad_runs", bad)
    assert result.returncode == 0, result.stderr
    said = "note: hit 2 failed the double impact check (second pulse at 60% of the peak, +55.2 ms from it)"
    assert said in result.stdout, result.stdout.splitlines()
    assert "note: hit 3 failed the clipped check (the response reaches its largest value in " in result.stdout
    (info,) = daq_json("analyze", tmp_path / "bad_runs", "latest")
    (caution,) = [c for c in info["cautions"] if "failed their checks" in c]
    assert caution.startswith("2 hits in the average failed their checks, hit 2: double impact (")
    assert "; hit 3: clipped (" in caution
    assert (
        "to leave them out, add the lines '# rejected hit 1: double impact' and '# rejected hit 2: clipped' "
        "to the file and import it again" in caution
    )


def test_hits_from_a_file_show_no_invented_time(tmp_path):
    """The store keeps the file's modification time for every hit; runs show says the
    time was not recorded rather than print one instant for all."""
    path = tmp_path / "hits.csv"
    rows = time_rows(64).tolist()
    path.write_text("hit,time,force,response\n" + "".join(f"{k},{t!r},{f!r},{a!r}\n" for k in (0, 1)
                                                          for t, f, a in rows))  # fmt: skip
    store = tmp_path / "runs"
    assert daq_import(store, path).returncode == 0
    shown = invoke_daq("runs", "show", "latest", "--store", str(store))
    assert shown.returncode == 0, shown.stderr
    lines = [line for line in shown.stdout.splitlines() if "hit   " in line]
    assert len(lines) == 2
    assert all("time not recorded" in line for line in lines)
    as_json = invoke_daq("runs", "show", "latest", "--store", str(store), "--json")
    assert '"time_recorded": false' in as_json.stdout


def test_an_estimator_given_for_a_run_of_frfs_is_said_to_be_unused(tmp_path):
    f = np.arange(1.0, 200.0)
    h = 1.0 / (50.0**2 - f**2 + 2j * 0.02 * 50.0 * f)
    path = table(tmp_path / "frf.txt", np.column_stack([f, h.real, h.imag]), header="freq\tre\tim")
    store = tmp_path / "runs"
    assert daq_import(store, path).returncode == 0
    result = invoke_daq("analyze", "latest", "--store", str(store), "--estimator", "h2")
    assert result.returncode == 0, result.stderr
    assert "caution: --estimator h2 was not used: the run holds FRFs, not hits" in result.stdout


def test_an_frf_table_after_a_preamble_given_as_csv_is_told_to_take_frf_text(tmp_path):
    # A DataPhysics SignalCalc export (ModeLAB's Hxysv00001.txt layout): with --format csv
    # it used to be refused as "line 2: 4 columns, expected 2".
    path = tmp_path / "Hxysv00001.txt"
    rows = [f"{k * 0.5:.13e}\t{1.0 + k!r}\t{0.5 * k!r}" for k in range(64)]
    head = ["Units: Ratio", "Ref Chan:Resp Chan\t0-Z:0-Z", "Channel Name\t : ", "Channel Comment\t : ", ""]
    head += ["Frequency\t Real\t Imaginary", "", "Units:", "Hz\t(m/s²)(N)\t "]
    path.write_bytes(("\r\n".join(head + rows) + "\r\n").encode("latin-1"))
    store = tmp_path / "runs"
    message = refused(
        daq_import(store, path, "--format", "csv"), store, "an FRF table", "'Frequency'", "--format frf-text"
    )
    assert "columns, expected" not in message
    assert invoke_daq("import", str(path), "--store", str(store)).returncode == 0  # auto reads it


def test_a_wav_file_is_named_as_one(tmp_path):
    import wave

    path = tmp_path / "tap.wav"
    with wave.open(str(path), "wb") as out:
        out.setnchannels(2)
        out.setsampwidth(2)
        out.setframerate(48000)
        out.writeframes(b"\x00\x01" * 2 * 4800)
    store = tmp_path / "runs"
    message = refused(daq_import(store, path), store, "tap.wav: a WAV audio file", "as a CSV")
    assert "NUL" not in message
