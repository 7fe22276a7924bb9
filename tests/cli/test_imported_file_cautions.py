"""What an imported file did not say is said wherever its analysis is shown: an FRF form
only assumed, windows unknown (both `caution:` lines and `cautions` in --json), points
never recorded; a table that is neither an FRF table nor a vibration record is refused;
a test whose points were read in different forms says so. Found by a new user's trial
of the tool holder's files (tests/data/README.md)."""

from __future__ import annotations

import json

import numpy as np

from tests.cli_helpers import assert_one_line_error, invoke_daq


def receptance_table(path, scale: float = 1.0) -> None:
    """A headerless frequency, Re, Im table of one 3 %-damped mode at 1070 Hz, in m/N (the
    layout of the tool holder's Point_N_Channel_1_CH1.txt); nothing in it says m/N."""
    f = np.arange(0.0, 3001.0)
    h = scale * 1e-7 / (1 - (f / 1070.0) ** 2 + 0.06j * f / 1070.0)
    path.write_text("".join(f"{x:.6e}\t{v.real:.6e}\t{v.imag:.6e}\n" for x, v in zip(f, h, strict=True)))


def daq_ok(*args: str):
    result = invoke_daq(*args)
    assert result.returncode == 0, result.stderr
    return result


def test_an_assumed_form_and_unknown_windows_are_cautions_everywhere(tmp_path):
    table, store = tmp_path / "Point_1.txt", str(tmp_path / "runs")
    receptance_table(table)
    daq_ok("import", str(table), "--store", store)
    text = daq_ok("analyze", "latest", "--store", store).stdout
    (info,) = json.loads(daq_ok("analyze", "latest", "--json", "--store", store).stdout)
    assumed = [c for c in info["cautions"] if c.startswith("FRF form assumed")]
    assert len(assumed) == 1
    assert "--frf-form" in assumed[0]
    assert "windows unknown: the damping includes any window the source applied" in info["cautions"]
    for caution in info["cautions"]:
        assert text.count(f"caution: {caution}") == 1, (caution, text)
    shown = daq_ok("runs", "show", "latest", "--store", store).stdout
    assert "not recorded (the imported file says nothing of the structure)" in shown
    assert "seed's beam" not in shown
    # Told the form, the import says nothing is assumed, and so does the analysis.
    daq_ok("import", str(table), "--frf-form", "receptance", "--store", store)
    (told,) = json.loads(daq_ok("analyze", "latest", "--json", "--store", store).stdout)
    assert not [c for c in told["cautions"] if c.startswith("FRF form assumed")]


def test_points_read_in_different_forms_are_said(tmp_path):
    store = str(tmp_path / "runs")
    daq_ok("test", "new", "t2", "--points", "p1=0.7,p2=0.5", "--store", store)
    for k, form in enumerate((["--frf-form", "receptance"], []), start=1):
        table = tmp_path / f"Point_{k}.txt"
        receptance_table(table, scale=1.0 / k)
        daq_ok("import", str(table), "--test", "t2", "--point", f"p{k}", *form, "--store", store)
    printed = daq_ok("test", "analyze", "t2", "--store", store).stdout
    assert "caution: FRF form assumed at p2" in printed
    assert "the points hold accelerance and receptance, so their shapes cannot be compared" in printed


def test_a_headerless_table_that_is_neither_is_refused_and_nothing_is_stored(tmp_path):
    path, store = tmp_path / "even.txt", tmp_path / "runs"
    path.write_text("".join(f"{k}\t1\t0\t1\n" for k in range(100)))
    result = invoke_daq("import", str(path), "--store", str(store))
    assert_one_line_error(result, "cannot tell its format", "needs an odd number of columns", "not 4")
    assert not store.exists() or not any(store.glob("*.h5"))


def test_a_record_whose_force_is_never_nonzero_says_why_it_has_no_frf(tmp_path):
    path, store = tmp_path / "flat.csv", str(tmp_path / "runs")
    path.write_text("time,force,response\n" + "".join(f"{k / 1000},1,{np.sin(k)}\n" for k in range(256)))
    daq_ok("import", str(path), "--store", store)
    result = invoke_daq("analyze", "latest", "--store", store)
    assert_one_line_error(result, "hold a finite FRF")
