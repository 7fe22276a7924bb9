"""`daq import` of the files a new user brought, each in its exact shape (written here):
a refusal is one line on stderr, exit status 1 and nothing in the store; a file whose
meaning is plain is read, with a `note:` where the reader decided something."""

from __future__ import annotations

import numpy as np

from daq.store import Store
from tests.cli.test_import_trial_refusals import daq_import, refused, runs_in

RATE_HZ = 4096.0


def notes(result) -> list[str]:
    return [line for line in result.stdout.splitlines() if line.startswith("note: ")]


def hit_rows(n: int = 1024, hit: int = 0) -> list[tuple[str, str, str]]:
    """(time, force, response) as the user's files print them: time to 10 digits at
    4096 Hz, a hammer pulse, a decaying response, 6 significant digits; ``hit`` moves the
    force's noise, so that hits differ (a hit repeating another is a copy, left out)."""
    t = np.arange(n) / RATE_HZ
    force = np.where(np.arange(n) == 4, 50.0, 0.0) + 0.05 * np.sin(7.0 * np.arange(n) + hit)
    response = np.exp(-3.0 * t) * np.sin(2 * np.pi * 45.0 * t)
    return [(f"{a:.10g}", f"{b:.6g}", f"{c:.6g}") for a, b, c in zip(t, force, response, strict=True)]


def write_rows(path, header: str, rows, cell: str = "{}", end: str = "\n", after: str = ""):
    """``header`` then ``rows`` comma-separated, each cell as ``cell`` formats it, each
    line ending in ``after`` and ``end``."""
    lines = [header + after] + [",".join(cell.format(c) for c in row) + after for row in rows]
    path.write_bytes((end.join(lines) + end).encode("utf-8"))
    return path


# --- 1: a velocity column in a time record ------------------------------------------------


def test_a_velocity_response_is_refused_as_no_acceleration(tmp_path):
    path = write_rows(tmp_path / "q_velocity.csv", "Time [s],Force [N],Velocity [m/s]", hit_rows())
    store = tmp_path / "runs"
    message = refused(
        daq_import(store, path),
        store,
        "column 'Velocity [m/s]': 'm/s' is a velocity, and a time record's response must be an acceleration",
        "differentiate it once to m/s^2 and import that",
        "--format frf-text --frf-form mobility",
    )
    assert "unknown response unit" not in message


# --- 2: every cell in double quotes -------------------------------------------------------


def test_a_fully_quoted_csv_is_read(tmp_path):
    rows = hit_rows()
    path = write_rows(tmp_path / "q_quoted.csv", '"Time [s]","Force [N]","Accel [g]"', rows, cell='"{}"')
    store = tmp_path / "runs"
    result = daq_import(store, path)
    assert result.returncode == 0, result.stderr
    assert "(csv: 1 hit of 1024 samples at 4096 Hz)" in result.stdout
    assert "units: time s, force N (header), response g (header)" in result.stdout
    (run_id,) = runs_in(store)
    hits = Store(store).open(run_id).hits
    np.testing.assert_array_equal(hits.force_n[0], [float(r[1]) for r in rows])
    np.testing.assert_array_equal(hits.response_m_s2[0], [float(r[2]) * 9.80665 for r in rows])


# --- 3: lines ending in CR alone (classic Mac OS) ------------------------------------------


def test_a_csv_with_cr_line_ends_is_read(tmp_path):
    rows = [row for k in range(3) for row in hit_rows(hit=k)]  # three hits, the time starting over
    path = write_rows(tmp_path / "b_cr.csv", "Time [s],Force [kN],Accel [g]", rows, end="\r")
    assert b"\n" not in path.read_bytes()
    store = tmp_path / "runs"
    result = daq_import(store, path)
    assert result.returncode == 0, result.stderr
    assert "(csv: 3 hits of 1024 samples at 4096 Hz)" in result.stdout
    (run_id,) = runs_in(store)
    hits = Store(store).open(run_id).hits
    np.testing.assert_array_equal(hits.force_n[2], [float(r[1]) * 1000.0 for r in rows[2048:]])
    assert "no line end" not in result.stdout  # the last line ends in CR


# --- 4: an Excel workbook renamed .csv ------------------------------------------------------


def test_an_excel_workbook_renamed_csv_is_told_to_be_saved_as_csv(tmp_path):
    import zipfile

    path = tmp_path / "b_excel.csv"
    with zipfile.ZipFile(path, "w") as archive:  # the user's file: the workbook part alone
        archive.writestr("xl/workbook.xml", "<x/>")
    store = tmp_path / "runs"
    for forced in ([], ["--format", "csv"]):
        message = refused(
            daq_import(store, path, *forced),
            store,
            "b_excel.csv: an Excel workbook (.xlsx), which daq does not read; "
            "save the sheet as CSV (or text) from the spreadsheet and import that",
        )
        assert "unpack" not in message
    other = tmp_path / "hits.csv"
    with zipfile.ZipFile(other, "w") as archive:
        archive.writestr("hit1.csv", "t,F,a\n")
    refused(daq_import(store, other), store, "hits.csv: a ZIP archive; unpack it and import the files inside")


# --- 5: a delimiter at the end of every line --------------------------------------------------


def test_a_trailing_comma_on_every_line_is_no_column(tmp_path):
    rows = [row for k in range(3) for row in hit_rows(hit=k)]
    path = write_rows(tmp_path / "q_trailing_comma.csv", "Time [s],Force [N],Accel [g]", rows, after=",")
    store = tmp_path / "runs"
    result = daq_import(store, path)
    assert result.returncode == 0, result.stderr
    assert "(csv: 3 hits of 1024 samples at 4096 Hz)" in result.stdout
    assert notes(result) == [
        "note: column 4 is empty on every line (a delimiter at the end of every line): read without it"
    ]
    (run_id,) = runs_in(store)
    hits = Store(store).open(run_id).hits
    np.testing.assert_array_equal(hits.response_m_s2[1], [float(r[2]) * 9.80665 for r in rows[:1024]])
    # Filled on one line only, the column is a column with empty cells, refused as before.
    text = path.read_text().splitlines()
    text[500] += "7"
    path.write_text("\n".join(text) + "\n")
    refused(daq_import(tmp_path / "again", path), tmp_path / "again", "line 2 column 4: '' is not a number")


# --- 6: a phase in radians with no unit --------------------------------------------------------


def test_a_unitless_phase_in_radians_is_noted(tmp_path):
    f = 0.25 * np.arange(1, 4001)
    h = 1.0 / (1.0 - (f / 45.0) ** 2 + 0.024j * f / 45.0) + 0.05 * np.exp(0.3j * np.arange(4000))
    rows = [(f"{a:g}", f"{abs(b):.6e}", f"{np.angle(b):.6f}") for a, b in zip(f, h, strict=True)]
    path = write_rows(tmp_path / "f_rad_unlabelled.csv", "Frequency (Hz),H11 mag,H11 phase", rows)
    store = tmp_path / "runs"
    result = daq_import(store, path)
    assert result.returncode == 0, result.stderr
    (note,) = [n for n in notes(result) if "radians" in n]
    assert note.startswith("note: column 3 'H11 phase' has no unit and all its values lie within ±π (")
    assert note.endswith(
        "read as degrees, but it looks like radians; if it is, write the unit in the header, "
        "'H11 phase [rad]' ('H11 phase [deg]' says degrees)"
    )
    (run_id,) = runs_in(store)
    stored = Store(store).open(run_id).measured_frfs.frf[0]
    np.testing.assert_allclose(np.angle(stored), np.deg2rad([float(r[2]) for r in rows]), atol=1e-12)
    # Told, the reader takes radians.
    said = write_rows(tmp_path / "f_rad.csv", "Frequency (Hz),H11 mag,H11 phase [rad]", rows)
    again = daq_import(tmp_path / "runs2", said)
    assert not [n for n in notes(again) if "radians" in n]
    (run_id,) = runs_in(tmp_path / "runs2")
    np.testing.assert_allclose(Store(tmp_path / "runs2").open(run_id).measured_frfs.frf[0], h, rtol=1e-5)


# --- 7: G, g's and m/s/s for acceleration ------------------------------------------------------


def test_g_gs_and_m_s_s_headers_are_read(tmp_path):
    rows = hit_rows()
    cases = [
        ("q_sec_G.csv", "Time [sec],Force [lbf],Acceleration [G]", "response G (header, read as g)", 9.80665),
        ("q_gs.csv", "Time (s),Force (N),Accel (g's)", "response g's (header, read as g)", 9.80665),
        ("q_ms_sq.csv", "Time (s),Force (N),Accel (m/s/s)", "response m/s/s (header, read as m/s^2)", 1.0),
    ]
    for name, header, said, factor in cases:
        store = tmp_path / f"runs-{name}"
        result = daq_import(store, write_rows(tmp_path / name, header, rows))
        assert result.returncode == 0, result.stderr
        assert said in result.stdout
        (run_id,) = runs_in(store)
        hits = Store(store).open(run_id).hits
        np.testing.assert_array_equal(hits.response_m_s2[0], [float(r[2]) * factor for r in rows])


# --- 8: an ASCII UFF 58 time record at 4096 Hz ----------------------------------------------


def test_an_ascii_uff_at_4096_hz_comes_back_at_4096_hz(tmp_path):
    import pyuff

    n = 4096
    rows = hit_rows(n)
    force = np.array([float(r[1]) for r in rows])
    accel = np.array([float(r[2]) for r in rows]) * 9.80665
    sets = []
    for k in range(3):  # hit k: force (node 1), then acceleration (node 2), as the user's file
        for what, node, kind, unit, data in (
            ("force", 1, 13, "N", force * (1 + 0.01 * k)),  # hits that differ: no copies
            ("accel", 2, 12, "m/s^2", accel),
        ):
            dset = pyuff.prepare_58(
                binary=0, id1=f"hit {k} {what}", func_type=1, rsp_node=node, rsp_dir=3, ref_node=1, ref_dir=3,
                abscissa_spacing=1, abscissa_spec_data_type=17, ordinate_spec_data_type=kind,
                orddenom_spec_data_type=0, z_axis_spec_data_type=0, data=data, x=np.arange(n) / RATE_HZ,
            )  # fmt: skip
            dset.update(ordinate_axis_units_lab=unit, abscissa_axis_units_lab="s")
            sets.append(dset)
    path = tmp_path / "U1_time.uff"
    pyuff.UFF(str(path)).write_sets(sets, mode="add")
    assert "  2.44141e-04  " in path.read_text()  # the increment as the header prints it
    store = tmp_path / "runs"
    result = daq_import(store, path)
    assert result.returncode == 0, result.stderr
    assert "(uff: 3 hits of 4096 samples at 4096 Hz)" in result.stdout
    assert notes(result) == [
        "note: sample rate 4096 Hz: the abscissa increment 2.44141e-04 s, printed to 6 significant digits, "
        "gives 4095.994 Hz, and any rate from 4095.985 to 4096.002 Hz lies within half a unit of its last "
        "digit; 4096 Hz, the one whole number of hertz among them, is stored"
    ]
    (run_id,) = runs_in(store)
    assert Store(store).open(run_id).hits.sample_rate_hz == 4096.0
