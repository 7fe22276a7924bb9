"""FRF tables after a preamble, as analyzer software exports them (DataPhysics SignalCalc
ASCII: CRLF, tabs, Latin-1 "m/s²", a units row of its own), and the one-line messages of
files given the wrong --format. The SignalCalc file is written here in its layout: the real
ones (ModeLAB's example) are GPL data and stay out of the repository."""

from __future__ import annotations

import json

import h5py
import numpy as np
import pytest

from daq.cli.commands.import_file import detect_format
from daq.formats.errors import FormatError
from daq.formats.frf_text import read_frf_text, scan_layout
from daq.store import Store
from tests.cli_helpers import assert_one_line_error, invoke_daq

FREQ = np.arange(6) * 0.01953125
FRF = np.array([-0.1504349, -0.1366724 + 0.007331555j, -0.1397468 - 0.006409508j, 0.5 + 0.25j, 1e-3, -2j])


def signalcalc(unit: bytes = "(m/s²)(N)".encode("latin-1"), preamble_units: bytes = b"Ratio") -> bytes:
    """A SignalCalc ASCII export of FRF in its own bytes: CRLF, tabs, padded cells."""
    lines = [
        b"Units: " + preamble_units,
        b"Ref Chan:Resp Chan\t0-Z:0-Z",
        b"Channel Name\t : ",
        b"Channel Comment\t : ",
        b"",
        b"Frequency\t Real\t Imaginary",
        b"",
        b"Units:",
        b"Hz\t" + unit + b"\t ",
    ]
    for f, h in zip(FREQ, FRF, strict=True):
        lines.append(f"{f:.13e}\t{h.real:16.7g}\t{h.imag:16.10g}".encode())
    return b"\r\n".join(lines) + b"\r\n"


def stored(store):
    (only,) = Store(store).list()
    return Store(store).open(only.run_id), only.run_id


def test_a_signalcalc_export_is_detected_and_imported_as_accelerance(tmp_path):
    path = tmp_path / "Hxysv00001.txt"
    path.write_bytes(signalcalc())
    assert detect_format(path)[0] == "frf-text"
    store = tmp_path / "store"
    result = invoke_daq("import", str(path), "--store", str(store))
    assert result.returncode == 0, result.stderr
    out = result.stdout.splitlines()
    assert "(frf-text: 1 FRF of 6 points, accelerance)" in out[0]
    assert out[1] == (
        "format frf-text: detected: 4 preamble lines, then the column names 'Frequency', 'Real', "
        "'Imaginary', a frequency first"
    )
    assert out[2] == "form: accelerance (units row ((m/s^2)/N))"
    run, run_id = stored(store)
    np.testing.assert_array_equal(run.measured_frfs.frequency_hz, FREQ)
    np.testing.assert_allclose(run.measured_frfs.frf[0], FRF, rtol=1e-9)
    assert run.measured_frfs.form == "accelerance"
    with h5py.File(store / f"{run_id}.h5", "r") as f:
        provenance = json.loads(f["entry"].attrs["provenance_json"])["imported_from"]
    assert provenance["preamble"] == {
        "Units": "Ratio",
        "Ref Chan:Resp Chan": "0-Z:0-Z",
        "Channel Name": "",
        "Channel Comment": "",
    }
    assert provenance["units_row"] == ["Hz", "(m/s²)(N)", ""]


@pytest.mark.parametrize(
    ("unit", "form", "factor", "said"),
    [
        ("(m/s)(N)", "mobility", 1.0, "units row ((m/s)/N)"),
        ("m/N", "receptance", 1.0, "units row (m/N)"),
        ("(mm)(N)", "receptance", 1e-3, "units row (mm/N)"),
        ("g/N", "accelerance", 9.80665, "units row (g/N)"),
        ("Ratio", "accelerance", 1.0, "default: the units row says 'Ratio', no FRF unit; (m/s^2)/N assumed"),
        ("EU", "accelerance", 1.0, "default: the units row says 'EU', no FRF unit; (m/s^2)/N assumed"),
    ],
)
def test_the_units_row_sets_the_form(tmp_path, unit, form, factor, said):
    path = tmp_path / "h.txt"
    path.write_bytes(signalcalc(unit.encode("latin-1")))
    got = read_frf_text(path)
    assert got.measured_frfs.form == form
    assert got.details["form_from"] == said
    np.testing.assert_allclose(got.measured_frfs.frf[0], FRF * factor, rtol=1e-9)


def test_frf_form_option_wins_over_the_units_row(tmp_path):
    path = tmp_path / "h.txt"
    path.write_bytes(signalcalc())
    got = read_frf_text(path, frf_form="mobility")
    assert got.measured_frfs.form == "mobility"
    assert got.details["form_from"] == "option; the units row says (m/s^2)/N"


def test_a_utf8_export_with_lf_and_magnitude_phase_reads_too(tmp_path):
    rows = ["Title: beam", "Date\t2021-01-16", "", "Freq\tMagnitude\tPhase", "Hz\tm/N\tdeg"]
    rows += [
        f"{float(f)!r}\t{float(abs(h))!r}\t{float(np.degrees(np.angle(h)))!r}"
        for f, h in zip(FREQ, FRF, strict=True)
    ]
    path = tmp_path / "mp.txt"
    path.write_text("\n".join(rows) + "\n", encoding="utf-8")
    assert detect_format(path)[0] == "frf-text"
    got = read_frf_text(path)
    assert got.measured_frfs.form == "receptance"
    np.testing.assert_allclose(got.measured_frfs.frf[0], FRF, rtol=1e-12, atol=1e-15)
    assert got.details["preamble"] == {"Title": "beam", "Date": "2021-01-16"}


def test_the_provenance_keeps_a_bounded_preamble(tmp_path):
    rows = [f"key {k}: " + "v" * 1000 for k in range(60)] + ["Frequency\tRe\tIm", "1\t1\t0", "2\t0\t1"]
    path = tmp_path / "long.txt"
    path.write_text("\n".join(rows) + "\n")
    kept = read_frf_text(path).details["preamble"]
    assert len(kept) == 60
    assert all(len(v) == 203 for v in kept.values())


def test_a_preamble_before_a_time_record_header_stays_csv(tmp_path):
    path = tmp_path / "t.txt"
    path.write_text("Operator: me\nTime (s)\tForce (N)\tAcc (g)\n0\t1\t2\n0.001\t1\t2\n")
    assert detect_format(path)[0] == "csv"
    assert scan_layout(path.read_text().splitlines()).header is None


def test_a_first_row_of_numbers_is_data_never_a_header(tmp_path):
    path = tmp_path / "plain.txt"
    path.write_text("1\t1\t0\n2\t0.5\t-0.5\n3\t0.25\t0\n")
    got = read_frf_text(path)
    assert got.details["header"] is False
    assert got.measured_frfs.frequency_hz.tolist() == [1.0, 2.0, 3.0]
    # Quoted numbers are numbers (RFC 4180): the row is data.
    quoted = tmp_path / "quoted.txt"
    quoted.write_text('"1","1","0"\n"2","0.5","-0.5"\n')
    assert read_frf_text(quoted).measured_frfs.frequency_hz.tolist() == [1.0, 2.0]
    # A delimiter at the end of every line makes no column (and no header).
    trail = tmp_path / "trail.txt"
    trail.write_text("1;1;0;\n2;0,5;0;\n")
    got = read_frf_text(trail)
    assert got.measured_frfs.frf[0].tolist() == [1.0, 0.5]
    assert got.details["notes"] == [
        "column 4 is empty on every line (a delimiter at the end of every line): read without it"
    ]
    store = tmp_path / "store"
    for name, text in [
        ("fortran.txt", "1;1D0;0\n2;5D-1;0\n"),  # a number, but not as float() reads it
    ]:
        path = tmp_path / name
        path.write_text(text)
        with pytest.raises(FormatError, match="line 1: a row of numbers, so data, not a header"):
            read_frf_text(path)
        result = invoke_daq("import", str(path), "--format", "frf-text", "--store", str(store))
        assert_one_line_error(result, "a row of numbers, so data, not a header")
    assert not store.exists() or Store(store).list() == []


def test_a_csv_given_as_uff_is_not_called_truncated(tmp_path):
    path = tmp_path / "a.csv"
    path.write_text("time,force,response\n0,1,2\n0.001,1,2\n")
    store = tmp_path / "store"
    result = invoke_daq("import", str(path), "--format", "uff", "--store", str(store))
    assert_one_line_error(
        result, "does not look like a UFF file: its first line is not a UFF -1 delimiter line"
    )
    assert "truncated" not in result.stderr
    assert not store.exists() or Store(store).list() == []


@pytest.mark.parametrize("given", ["csv", "frf-text"])
def test_a_uff_given_as_text_says_it_looks_like_uff(tmp_path, given):
    path = tmp_path / "h.uff"
    path.write_text("    -1\n    58\nH11\n")
    store = tmp_path / "store"
    result = invoke_daq("import", str(path), "--format", given, "--store", str(store))
    assert_one_line_error(result, "looks like a UFF file")
    assert "--format uff" in result.stderr
    assert "data column" not in result.stderr
    assert not store.exists() or Store(store).list() == []


def test_import_line_plurals_and_balanced_form_parentheses(tmp_path):
    path = tmp_path / "frf.csv"
    path.write_text("Frequency (Hz);H11 Re [(m/s^2)/N];H11 Im [(m/s^2)/N]\n1;1;0\n2;0;1\n")
    store = tmp_path / "store"
    result = invoke_daq("import", str(path), "--store", str(store))
    assert result.returncode == 0, result.stderr
    assert "1 FRF of 2 points" in result.stdout
    form = next(line for line in result.stdout.splitlines() if line.startswith("form:"))
    assert form == "form: accelerance (header ((m/s^2)/N))"
    assert form.count("(") == form.count(")")
    hits = tmp_path / "one.csv"
    hits.write_text("time,force,response\n0,1,2\n0.001,1,2\n0.002,1,2\n")
    result = invoke_daq("import", str(hits), "--store", str(store))
    assert result.returncode == 0, result.stderr
    assert "(csv: 1 hit of 3 samples" in result.stdout
