"""CSV / text import and export: exact round trips, hand-written files, every refusal."""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np
import pytest

from daq.formats.csv_text import read_csv, write_csv
from daq.formats.errors import FormatError
from daq.store.ids import new_run_id
from daq.store.model import Hits, MeasuredFrf, Run


def make_run(zoom: bool = False, rate: float = 256.0, n_hits: int = 3, n: int = 1024, seed: int = 7) -> Run:
    rng = np.random.default_rng(seed)
    force = rng.normal(size=(n_hits, n)) * 100
    response = rng.normal(size=(n_hits, n)) * 3
    if zoom:
        force = force + 1j * rng.normal(size=(n_hits, n))
        response = response + 1j * rng.normal(size=(n_hits, n))
    accepted = np.ones(n_hits, dtype=bool)
    accepted[1] = False
    hits = Hits(
        force_n=force,
        response_m_s2=response,
        sample_rate_hz=rate,
        start_s=-0.125,
        center_hz=1234.5 if zoom else 0.0,
        accepted=accepted,
        reject_reason=["" if ok else "double hit" for ok in accepted],
        overload=np.zeros((n_hits, 2), dtype=bool),
        peak_force_n=np.abs(force).max(axis=1),
        timestamp_utc=["2026-11-23T10:15:03.123Z"] * n_hits,
        checks=[{} for _ in range(n_hits)],
    )
    return Run(new_run_id(), "captured", True, "2026-11-23T10:15:03Z", "2026-11-23T10:16:03Z", hits=hits)


def write(tmp_path: Path, text: str, name: str = "data.csv") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def refused(path: Path, **kwargs) -> str:
    """The FormatError message of read_csv(path); it must be one line naming the file."""
    with pytest.raises(FormatError) as info:
        read_csv(path, **kwargs)
    message = str(info.value)
    assert "\n" not in message
    assert "\r" not in message
    assert str(path) in message
    return message


# --- round trips ---------------------------------------------------------------------


@pytest.mark.parametrize("zoom", [False, True])
def test_round_trip_is_bit_exact(tmp_path, zoom):
    run = make_run(zoom=zoom)
    path = tmp_path / "run.csv"
    write_csv(run, path)
    got = read_csv(path)
    assert got.format == "csv"
    assert got.measured_frfs is None
    hits = got.hits
    assert hits.force_n.dtype == run.hits.force_n.dtype
    assert hits.force_n.tobytes() == run.hits.force_n.tobytes()
    assert hits.response_m_s2.tobytes() == run.hits.response_m_s2.tobytes()
    assert hits.sample_rate_hz == 256.0
    assert hits.start_s == -0.125
    assert hits.center_hz == (1234.5 if zoom else 0.0)
    # the verdicts come back from the "# rejected hit k: reason" comments
    assert hits.accepted.tolist() == run.hits.accepted.tolist()
    assert list(hits.reject_reason) == list(run.hits.reject_reason)
    assert not hits.overload.any()
    assert hits.peak_force_n.tolist() == np.abs(run.hits.force_n).max(axis=1).tolist()
    assert all(str(s).endswith("Z") for s in hits.timestamp_utc)
    assert got.details["n_records"] == 3


def test_round_trip_keeps_a_rate_that_is_not_a_binary_fraction(tmp_path):
    # 1/3000 s steps are not exact in binary: the rate comes from the exact comment
    run = make_run(rate=3000.0, n=100)
    path = tmp_path / "run.csv"
    write_csv(run, path)
    got = read_csv(path).hits
    assert got.sample_rate_hz == 3000.0
    assert got.start_s == -0.125
    assert got.force_n.tobytes() == run.hits.force_n.tobytes()


def test_export_layout(tmp_path):
    path = tmp_path / "run.csv"
    run = make_run(n=4)
    write_csv(run, path)
    lines = path.read_text().splitlines()
    assert f"# run_id: {run.run_id}" in lines
    assert "# rejected hit 1: double hit" in lines
    assert "# units: time s, force N, response m/s^2" in lines
    header = lines.index("hit,time,force,response")
    assert lines[header + 1].startswith("0,-0.125,")
    assert lines[header + 2].startswith("0,-0.12109375,")  # -0.125 + 1/256
    assert len(lines) == header + 1 + 3 * 4
    assert os.listdir(tmp_path) == ["run.csv"]  # no temporary file left behind


def test_export_replaces_existing_file(tmp_path):
    path = write(tmp_path, "old", "run.csv")
    write_csv(make_run(n=8), path)
    assert read_csv(path).hits.n_samples == 8
    assert sorted(os.listdir(tmp_path)) == ["run.csv"]


def test_export_without_hits_refused(tmp_path):
    frf = MeasuredFrf(np.array([1.0, 2.0]), np.array([[1 + 1j, 2 + 0j]]), None, ["H21"])
    run = Run(
        new_run_id(), "imported", True, "2026-11-23T10:15:03Z", "2026-11-23T10:15:03Z", measured_frfs=frf
    )
    with pytest.raises(FormatError, match=r"has no time records; export FRFs as UFF"):
        write_csv(run, tmp_path / "x.csv")
    assert not (tmp_path / "x.csv").exists()


def test_export_into_missing_folder_is_user_error(tmp_path):
    with pytest.raises(FormatError, match="cannot write"):
        write_csv(make_run(n=4), tmp_path / "nope" / "x.csv")


# --- hand-written files ----------------------------------------------------------------


def test_comma_with_header(tmp_path):
    path = write(tmp_path, "# a note\ntime,force,response\n0,1.5,-2\n0.001,2.5,-3\n0.002,3.5,-4\n")
    hits = read_csv(path).hits
    assert hits.force_n.tolist() == [[1.5, 2.5, 3.5]]
    assert hits.response_m_s2.tolist() == [[-2.0, -3.0, -4.0]]
    assert hits.sample_rate_hz == pytest.approx(1000.0, rel=1e-12)
    assert hits.start_s == 0.0
    assert hits.peak_force_n.tolist() == [3.5]


def test_semicolons_and_crlf(tmp_path):
    path = write(tmp_path, "t;F;a\r\n-0.5;1;10\r\n0;2;20\r\n0.5;3;30\r\n")
    hits = read_csv(path).hits
    assert hits.force_n.tolist() == [[1.0, 2.0, 3.0]]
    assert hits.response_m_s2.tolist() == [[10.0, 20.0, 30.0]]
    assert hits.sample_rate_hz == 2.0
    assert hits.start_s == -0.5


def test_whitespace_without_header_and_time_drop_starts_a_hit(tmp_path):
    path = write(tmp_path, "0  1 7\n0.25\t2 8\n0.5 3 9\n0 4 10\n0.25 5 11\n0.5 6 12\n")
    got = read_csv(path)
    assert got.hits.force_n.tolist() == [[1, 2, 3], [4, 5, 6]]
    assert got.hits.response_m_s2.tolist() == [[7, 8, 9], [10, 11, 12]]
    assert got.hits.sample_rate_hz == 4.0
    assert got.details["header"] is False


def test_tab_delimited(tmp_path):
    path = write(tmp_path, "time\tforce\tresponse\n0\t1\t2\n1\t3\t4\n")
    assert read_csv(path).hits.response_m_s2.tolist() == [[2.0, 4.0]]


def test_hit_column_groups_rows_in_order_of_first_appearance(tmp_path):
    text = "hit,time,force,response\n5,0,1,1\n2,0,10,10\n5,1,2,2\n2,1,20,20\n"
    hits = read_csv(write(tmp_path, text)).hits
    assert hits.force_n.tolist() == [[1, 2], [10, 20]]


def test_columns_by_name_and_index(tmp_path):
    text = "a,t,F,other\n3,0,1,9\n4,0.5,2,9\n5,1,3,9\n"
    path = write(tmp_path, text)
    by_name = read_csv(path, columns="t,F,a").hits
    assert by_name.force_n.tolist() == [[1, 2, 3]]
    assert by_name.response_m_s2.tolist() == [[3, 4, 5]]
    by_index = read_csv(path, columns="1, 0, 2").hits
    assert by_index.force_n.tolist() == [[3, 4, 5]]
    assert by_index.response_m_s2.tolist() == [[1, 2, 3]]


def test_units_g_and_millivolts(tmp_path):
    path = write(tmp_path, "t F a\n0 0.5 1\n1 2 -2\n")
    g = read_csv(path, force_unit="kN", response_unit="g").hits
    assert g.force_n.tolist() == [[500.0, 2000.0]]
    assert g.response_m_s2.tolist() == [[9.80665, -19.6133]]
    # 10.2 mV per g; the column in mV
    path = write(tmp_path, "t F a\n0 2.25 10.2\n1 4.5 20.4\n", "mv.csv")
    mv = read_csv(path, force_unit="mV@2.25mV/N", response_unit="mV@10.2mV/g").hits
    assert mv.force_n[0] == pytest.approx([1.0, 2.0], rel=1e-14)
    assert mv.response_m_s2[0] == pytest.approx([9.80665, 19.6133], rel=1e-14)


def test_lbf(tmp_path):
    path = write(tmp_path, "0 1 0.5\n1 2 0.25\n")
    assert read_csv(path, force_unit="lbf").hits.force_n[0] == pytest.approx(
        [4.4482216152605, 8.896443230521]
    )


def test_hand_written_zoom_file(tmp_path):
    text = "# center_hz: 500\ntime,force_re,force_im,response_re,response_im\n0,1,2,3,4\n0.01,5,6,7,8\n"
    hits = read_csv(write(tmp_path, text)).hits
    assert hits.center_hz == 500.0
    assert hits.force_n.tolist() == [[1 + 2j, 5 + 6j]]
    assert hits.response_m_s2.tolist() == [[3 + 4j, 7 + 8j]]


# --- refusals -------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("text", "kwargs", "expected"),
    [
        ("0,1,2\n1,2\n", {}, "line 2: 2 columns, expected 3"),
        ("0,1,2\n1\n", {}, "line 2: 1 column, expected 3"),
        ("# c\n0,1,2\n1,2,x\n", {}, "line 3 column 3: 'x' is not a number"),
        ("0,1,2\n1,nan,3\n", {}, "line 2 column 2"),
        ("0,1,2\n1,2,inf\n", {}, "not finite"),
        ("0,1,2\n", {}, "fewer than 2 samples"),
        ("t,F,a\n", {}, "no data rows"),
        ("# only comments\n\n", {}, "no data rows"),
        ("0,1,2\n1,2,3\n1,3,4\n", {}, "line 3: the first column (time or frequency) does not increase"),
        ("0,1,2\n1,2,3\n2,3,4\n3.5,4,5\n", {}, "line 4: the first column (time or frequency) steps unevenly"),
        ("0,1,2\n1,2,3\n0,1,2\n1,2,3\n2,3,4\n", {}, "hit 2 (line 3) has 3 samples, hit 1 has 2"),
        ("0,1,2\n1,2,3\n0.5,1,2\n1.5,2,3\n", {}, "hit 2 (line 3) has a different time axis from hit 1"),
        ("0,1,2\n1,2,3\n0,1,2\n2,2,3\n", {}, "different time axis"),
        ("t,F,a\n0,1,2\n1,2,3\n", {"columns": "t,F,x"}, "no column 'x' in the header (t, F, a)"),
        ("0,1,2\n1,2,3\n", {"columns": "t,F,a"}, "no header row"),
        ("0,1,2\n1,2,3\n", {"columns": "0,1,3"}, "column index 3 is out of range"),
        ("0,1,2\n1,2,3\n", {"columns": "0,1"}, "must name three columns"),
        ("0,1,2\n1,2,3\n", {"columns": "0,1,1"}, "must be different columns"),
        ("0,1\n1,2\n", {}, "need time, force and response"),
        ("hit,t,F,a\n0.5,0,1,2\n0.5,1,2,3\n", {}, "line 2: hit 0.5 is not a whole number"),
        ("time,force_re,force_im,response_re,response_im\n0,1,2,3,4\n1,1,2,3,4\n", {}, "no '# center_hz"),
        ("# center_hz = 5\n0,1,2\n1,2,3\n", {}, "center_hz = 5.0 but the records are real"),
        ("# center_hz = abc\n0,1,2\n1,2,3\n", {}, "center_hz 'abc' is not a number"),
        ("0,1,2\n1,2,3\n", {"force_unit": "furlong"}, "unknown force unit 'furlong'"),
        ("0,1,2\n1,2,3\n", {"response_unit": "mV@0mV/g"}, "sensitivity must be positive"),
        # A decimal comma is read (";" separates); a thousands mark as well is not.
        ("t;F;a\n1.234,5;2;3\n", {}, "line 2 column 1: '1.234,5' is not a number"),
    ],
)
def test_bad_input_refused(tmp_path, text, kwargs, expected):
    message = refused(write(tmp_path, text), **kwargs)
    assert expected in message


def test_not_utf8_bytes_in_a_number_are_refused_with_their_line(tmp_path):
    path = tmp_path / "bin.csv"
    path.write_bytes(b"0,1,2\n\xff\xfe,1,2\n")
    assert "line 2" in refused(path)


def test_a_windows_1252_header_reads_as_its_utf8_twin(tmp_path):
    # Excel on Windows saves "Accel (m/s²)" as cp1252: it used to be refused as "not UTF-8".
    rows = "".join(f"{k / 1000!r},{float(k == 3)!r},{0.5 * k!r}\n" for k in range(64))
    header = "Time (s),Force (N),Accel (m/s²)\n"
    (tmp_path / "cp1252.csv").write_bytes((header + rows).encode("cp1252"))
    (tmp_path / "utf8.csv").write_bytes((header + rows).encode("utf-8"))
    cp1252, utf8 = read_csv(tmp_path / "cp1252.csv"), read_csv(tmp_path / "utf8.csv")
    np.testing.assert_array_equal(cp1252.hits.response_m_s2, utf8.hits.response_m_s2)
    assert cp1252.details["response_unit"] == utf8.details["response_unit"] == "m/s^2"


def test_missing_empty_and_too_large(tmp_path):
    assert "no such file" in refused(tmp_path / "missing.csv")
    assert "is empty" in refused(write(tmp_path, "", "empty.csv"))
    big = write(tmp_path, "0,1,2\n1,2,3\n" * 10, "big.csv")
    assert "more than the import limit of 50 bytes" in refused(big, max_bytes=50)
    assert read_csv(big, max_bytes=120).hits.n_hits == 10


def test_directory_refused(tmp_path):
    assert "is a directory, not a regular file" in refused(tmp_path)


def test_fifo_refused_without_blocking(tmp_path):
    # Opening a FIFO without a writer blocks forever: the pytest timeout would catch it.
    fifo = tmp_path / "pipe.csv"
    os.mkfifo(fifo)
    assert "is a FIFO, not a regular file" in refused(fifo)


def test_device_refused():
    assert "not a regular file" in refused(Path("/dev/null"))


def test_newline_in_file_name_stays_one_line(tmp_path):
    path = tmp_path / "bad\nname.csv"
    path.write_text("0,1,2\n1,2,x\n")
    with pytest.raises(FormatError) as info:
        read_csv(path)
    assert "\n" not in str(info.value)
    assert "bad\\nname.csv" in str(info.value)


@pytest.mark.parametrize(
    ("text", "said"),
    [
        (
            "hit,t,F,a\n0,0,1,2\n0,1,1,2\n1,0,1,2\n1,1,1,2\n1,2,1,2\n",
            "hit 1 (line 4) has 3 samples, hit 0 has 2",
        ),
        (
            "hit,t,F,a\n7,0,1,2\n7,0.001,1,2\n9,0.0005,1,2\n9,0.0015,1,2\n",
            "hit 9 (line 4) has a different time axis from hit 7",
        ),
    ],
)
def test_a_hit_column_names_its_hits_by_the_files_own_numbers(tmp_path, text, said):
    path = tmp_path / "hits.csv"
    path.write_text(text)
    with pytest.raises(FormatError, match=re.escape(said)):
        read_csv(path)


def test_an_empty_cell_among_a_whitespace_header_s_cells_is_no_unit(tmp_path):
    # Hypothesis found b'\x0b\x0b"': an empty cell read as the start of a "(unit)" and an
    # IndexError came out instead of a refusal.
    path = tmp_path / "vt.csv"
    path.write_bytes(b'\x0b\x0b"')
    refused(path)
