"""SDF spectra as a run's spectra, through the CLI as a user runs it: the real HP 35670A
file (one auto-power spectrum) imports as a run of one power spectrum in V^2 whose
values are the analyzer's own, goes out as SDF and comes back the same, and every
command that cannot use spectra says so in one line instead of failing."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from daq.formats.sdf import read_sdf_run, write_sdf_run
from daq.store import MeasuredFrf, Run, Spectra, Store, new_run_id
from tests.cli_helpers import assert_one_line_error, invoke_daq

DATA = Path(__file__).resolve().parents[1] / "data" / "sdf"
REAL = DATA / "SDF3KHZ.DAT"


@pytest.fixture(scope="module")
def imported(tmp_path_factory):
    """(store folder, run id, the import's stdout) of `daq import SDF3KHZ.DAT`."""
    tmp = tmp_path_factory.mktemp("spectra")
    store = tmp / "store"
    copy = tmp / "SDF3KHZ.DAT"
    shutil.copyfile(REAL, copy)
    result = invoke_daq("import", str(copy), "--format", "sdf", "--store", str(store))
    assert result.returncode == 0, result.stderr
    (summary,) = Store(store).list()
    return store, summary.run_id, result.stdout


def test_the_import_line_names_the_spectrum(imported):
    _store, run_id, stdout = imported
    assert stdout.startswith(f"Imported SDF3KHZ.DAT (sdf: 1 spectra of 1601 points) as run {run_id}: ")
    assert stdout.count("\n") == 1


def test_the_run_holds_one_power_spectrum_in_volts_squared(imported):
    store, run_id, _ = imported
    run = Store(store).open(run_id)
    assert (run.hits, run.analyzer, run.measured_frfs) == (None, None, None)
    spectra = run.spectra
    assert (spectra.n_traces, spectra.n_lines) == (1, 1601)
    assert (spectra.kinds, spectra.units, spectra.labels) == (["power"], ["V^2"], ["Pwr Spec"])
    assert spectra.values.dtype == np.float64
    # The alias-protected lines 0..1600 of the 2,049 stored: 0 to 12.8 kHz in 8 Hz steps.
    np.testing.assert_array_equal(spectra.frequency_hz, np.arange(1601) * 8.0)
    source = run.provenance["imported_from"]
    assert (source["format"], source["instrument"], source["sdf_revision"]) == ("sdf", "HP 35670A", 2)
    assert (source["n_spectra"], source["spectrum_lines"], source["spectrum_units"]) == (1, 1601, ["V^2"])
    assert source["data_headers"][0]["data_type"] == "auto-power spectrum"


def test_its_values_are_the_analyzers_to_the_printed_precision(imported):
    store, run_id, _ = imported
    spectra = Store(store).open(run_id).spectra
    hz = np.loadtxt(DATA / "ASCII3KH.X")
    shown = np.loadtxt(DATA / "ASCII3KH.TXT")  # V rms, as the analyzer's screen showed it
    index = np.searchsorted(spectra.frequency_hz, hz)
    assert np.array_equal(spectra.frequency_hz[index], hz)
    # V^2 (peak) -> V rms: sqrt(P / 2), as tests/formats/test_sdf_real_file.py does.
    ours = np.sqrt(spectra.values[0, index] / 2)
    nonzero = shown != 0
    assert np.array_equal(ours[~nonzero], shown[~nonzero])
    unit = 10.0 ** (np.floor(np.log10(np.abs(shown[nonzero]))) - 6)  # one unit of the 7th digit
    error = np.abs(ours[nonzero] - shown[nonzero]) / unit
    assert error.max() <= 1.0, f"worst: {error.max():.3f} units of the last printed digit"
    assert np.mean(error <= 0.5) > 0.9
    assert ours[375] == pytest.approx(0.0100988, abs=1e-7)  # the 3 kHz, 10 mV rms source


def test_export_as_sdf_then_import_gives_the_same_spectrum(imported, tmp_path):
    store, run_id, _ = imported
    out = tmp_path / "again.sdf"
    result = invoke_daq("export", run_id, "--format", "sdf", "-o", str(out), "--store", str(store))
    assert result.returncode == 0, result.stderr
    other = tmp_path / "other-store"
    result = invoke_daq("import", str(out), "--store", str(other))
    assert result.returncode == 0, result.stderr
    assert "(sdf: 1 spectra of 1601 points)" in result.stdout
    first = Store(store).open(run_id).spectra
    (summary,) = Store(other).list()
    again = Store(other).open(summary.run_id).spectra
    assert again.values.tobytes() == first.values.tobytes()
    assert again.frequency_hz.tobytes() == first.frequency_hz.tobytes()
    assert (again.kinds, again.units, again.labels) == (first.kinds, first.units, first.labels)


def test_analyze_says_in_one_line_there_is_nothing_to_identify(imported):
    store, run_id, _ = imported
    result = invoke_daq("analyze", run_id, "--store", str(store))
    assert_one_line_error(result, run_id, "spectra but no time records or FRF", "nothing to identify modes")
    assert result.returncode == 1
    assert not (store / f"{run_id}.analysis.h5").exists()


@pytest.mark.parametrize("command", ["analyze", "fit"])
def test_all_runs_skip_it_with_a_line(imported, command):
    store, run_id, _ = imported
    result = invoke_daq(command, "--all", "--jobs", "1", "--store", str(store))
    assert result.returncode == 0, result.stderr
    assert result.stderr == (
        f"daq {command}: run {run_id}: skipped: the run holds spectra but no time records or FRF: "
        "nothing to identify modes from\n"
    )


@pytest.mark.parametrize("args", [("fit",), ("report", "-o", "REPORT")], ids=["fit", "report"])
def test_fit_and_report_say_why_in_one_line(imported, tmp_path, args):
    store, run_id, _ = imported
    args = tuple(str(tmp_path / a) if a == "REPORT" else a for a in args)
    result = invoke_daq(args[0], run_id, *args[1:], "--store", str(store))
    assert_one_line_error(result, run_id, "nothing to identify modes from")
    assert result.returncode == 1


def test_the_services_background_analysis_gets_a_reason_not_a_crash(imported):
    from daq.service.jobs import analyse_in_worker, fit_in_worker

    store, run_id, _ = imported
    for worker in (analyse_in_worker, fit_in_worker):
        outcome = worker(store, run_id)
        assert isinstance(outcome, str)
        assert "\n" not in outcome
        assert outcome.endswith("nothing to identify modes from")


@pytest.mark.parametrize(("fmt", "holds"), [("csv", "CSV holds time records"), ("uff", "UFF export holds")])
def test_csv_and_uff_say_what_they_hold(imported, tmp_path, fmt, holds):
    store, run_id, _ = imported
    out = tmp_path / f"x.{fmt}"
    result = invoke_daq("export", run_id, "--format", fmt, "-o", str(out), "--store", str(store))
    assert_one_line_error(result, run_id, "holds only spectra (1)", holds, "--format sdf")
    assert not out.exists()


def test_runs_show_and_list(imported):
    store, run_id, _ = imported
    result = invoke_daq("runs", "show", run_id, "--json", "--store", str(store))
    assert result.returncode == 0, result.stderr
    shown = json.loads(result.stdout)
    assert shown["spectra"] == {
        "n_traces": 1,
        "n_lines": 1601,
        "f_min_hz": 0.0,
        "f_max_hz": 12800.0,
        "complex": False,
        "kinds": ["power"],
        "units": ["V^2"],
        "labels": ["Pwr Spec"],
    }
    assert (shown["hits"], shown["measured_frf"], shown["n_hits"]) == (None, None, 0)
    text = invoke_daq("runs", "show", run_id, "--store", str(store))
    assert text.returncode == 0, text.stderr
    assert "spectra       1 x 1601 points, 0-12800 Hz: Pwr Spec (power, V^2)" in text.stdout
    listed = invoke_daq("runs", "list", "--store", str(store))
    assert listed.returncode == 0
    assert run_id in listed.stdout
    verified = invoke_daq("runs", "verify", run_id, "--store", str(store))
    assert verified.returncode == 0
    assert f"OK       {run_id}" in verified.stdout


def test_every_kind_of_spectrum_and_the_other_parts_round_trip_through_sdf(tmp_path):
    """A run with FRFs and complex spectra of every kind, on an uneven axis, with a unit
    longer than SDF's field and non-ASCII labels: export, import, the same values."""
    rng = np.random.default_rng(3)
    freq = np.array([0.5, 1.0, 2.5, 4.0, 8.0])
    values = rng.normal(size=(5, freq.size)) + 1j * rng.normal(size=(5, freq.size))
    spectra = Spectra(
        frequency_hz=freq,
        values=values,
        kinds=["power", "linear", "cross", "coherence", "other"],
        units=["(m/s^2)^2", "N", "N*(m/s^2)", "", "furlongs per fortnight"],
        labels=["Pwr Spec — accel", "Lin Spec force", "Cross Spec", "Coh", "an unusually long label"],
    )
    frfs = MeasuredFrf(np.arange(1.0, 5.0), rng.normal(size=(1, 4)) + 0j, None, ["H21"])
    run = Run(
        run_id=new_run_id(), kind="imported", complete=True,
        start_time="2026-11-23T10:15:03.123Z", end_time="2026-11-23T10:15:03.123Z",
        measured_frfs=frfs, spectra=spectra,
    )  # fmt: skip
    path = tmp_path / "all.sdf"
    write_sdf_run(run, path)
    back = read_sdf_run(path)
    np.testing.assert_array_equal(back.measured_frfs.frf, frfs.frf)
    assert back.spectra.values.tobytes() == values.tobytes()
    assert back.spectra.frequency_hz.tobytes() == freq.tobytes()
    assert back.spectra.kinds == spectra.kinds
    assert back.spectra.units == spectra.units
    assert back.spectra.labels == spectra.labels
