"""`daq import` and `daq export` from the command line: round trips through CSV and
UFF 58 from a real simulated capture, provenance of imported runs, bad files refused
with one line and nothing written, odd names stored safely.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

import h5py
import numpy as np
import pytest
import pyuff

from daq.store import Store, open_run, seal
from daq.workflows.export import uff_frfs
from tests.cli_helpers import assert_one_line_error, invoke_daq
from tests.store.store_helpers import make_run


@pytest.fixture(scope="module")
def captured(tmp_path_factory) -> tuple[Path, str]:
    """A store holding one run of 3 simulated hits, one of them rejected (double hit)."""
    store = tmp_path_factory.mktemp("captured")
    result = invoke_daq(
        "capture", "--sim", "--yes", "--hits", "2", "--seed", "7",
        "--hammer", "double_hit_probability=0.5", "--store", str(store),
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    (run,) = Store(store).list()
    return store, run.run_id


def daq_in(store: Path, *args: str):
    return invoke_daq(*args, "--store", str(store))


def only_new(store: Path, known: set[str]) -> str:
    (new,) = [s.run_id for s in Store(store).list() if s.run_id not in known]
    return new


def assert_same_hits(got, want) -> None:
    for name in ("force_n", "response_m_s2"):
        a, b = getattr(got, name), getattr(want, name)
        assert a.dtype == b.dtype
        assert a.shape == b.shape
        assert a.tobytes() == b.tobytes(), name
    assert got.sample_rate_hz == want.sample_rate_hz
    assert got.start_s == want.start_s


@pytest.mark.parametrize("fmt", ["csv", "uff"])
def test_capture_export_import_gives_the_same_records(captured, tmp_path, fmt):
    source_store, run_id = captured
    store = tmp_path / "store"
    out = tmp_path / f"out.{fmt}"
    result = daq_in(source_store, "export", run_id[:10], "--format", fmt, "-o", str(out))
    assert result.returncode == 0, result.stderr
    result = daq_in(store, "import", str(out))
    assert result.returncode == 0, result.stderr
    original = open_run(source_store / f"{run_id}.h5")
    imported = Store(store).open(only_new(store, set()))
    # repr() text and binary 58 both carry float64 exactly: bit for bit, not "close".
    assert_same_hits(imported.hits, original.hits)
    # Rejected hits stay rejected, with their reasons: an average of the "accepted"
    # hits of the imported run must not take in a double impact.
    assert not original.hits.accepted.all()
    assert imported.hits.accepted.tolist() == original.hits.accepted.tolist()
    assert list(imported.hits.reject_reason) == list(original.hits.reject_reason)
    assert imported.kind == "imported"
    source = imported.provenance["imported_from"]
    assert source["file"] == out.name
    assert source["sha256"] == hashlib.sha256(out.read_bytes()).hexdigest()
    assert source["format"] == fmt
    if fmt == "uff":
        # The FRF written is the accepted hits' H1 without the response window (uff_frfs).
        written = uff_frfs(original).frfs
        np.testing.assert_array_equal(imported.measured_frfs.frf, written.frf)
        np.testing.assert_array_equal(imported.measured_frfs.coherence, written.coherence)


def test_a_uff_export_reads_back_with_pyuff(captured, tmp_path):
    source_store, run_id = captured
    out = tmp_path / "run.uff"
    assert daq_in(source_store, "export", run_id, "-f", "uff", "-o", str(out)).returncode == 0
    original = open_run(source_store / f"{run_id}.h5")
    sets = pyuff.UFF(str(out)).read_sets()
    sets = sets if isinstance(sets, list) else [sets]
    time_sets = [s for s in sets if s["type"] == 58 and s["func_type"] == 1]
    assert len(time_sets) == 2 * original.hits.n_hits
    forces = [s for s in time_sets if s["ordinate_spec_data_type"] == 13]
    for i, record in enumerate(forces):
        np.testing.assert_array_equal(record["data"], original.hits.force_n[i])
    frf_sets = [s for s in sets if s["type"] == 58 and s["func_type"] == 4]
    np.testing.assert_array_equal(frf_sets[0]["data"], uff_frfs(original).frfs.frf[0])


def test_an_imported_csv_replays_bit_for_bit(captured, tmp_path):
    source_store, run_id = captured
    out = tmp_path / "hits.csv"
    assert daq_in(source_store, "export", run_id, "-f", "csv", "-o", str(out)).returncode == 0
    store = tmp_path / "store"
    assert daq_in(store, "import", str(out)).returncode == 0
    imported = only_new(store, set())
    result = daq_in(store, "replay", imported)
    assert result.returncode == 0, result.stderr
    assert "bit for bit" in result.stdout


def test_export_never_overwrites_without_force(captured, tmp_path):
    source_store, run_id = captured
    out = tmp_path / "x.csv"
    out.write_text("precious\n")
    assert_one_line_error(daq_in(source_store, "export", run_id, "-f", "csv", "-o", str(out)), "--force")
    assert out.read_text() == "precious\n"
    assert daq_in(source_store, "export", run_id, "-f", "csv", "-o", str(out), "--force").returncode == 0
    assert out.read_text().startswith("# ")


def test_export_of_a_frf_only_run_to_csv_is_one_line(tmp_path):
    from tests.store.store_helpers import make_frf

    run = make_run(kind="imported", measured=make_frf())
    seal(run, tmp_path)
    result = daq_in(tmp_path, "export", run.run_id, "-f", "csv", "-o", str(tmp_path / "x.csv"))
    assert_one_line_error(result, "no time records")
    assert not (tmp_path / "x.csv").exists()


def _text(content: str):
    def make(path: Path) -> Path:
        path.write_text(content)
        return path

    return make


def _fifo(path: Path) -> Path:
    os.mkfifo(path)
    return path


BAD_FILES = {
    "empty": (_text(""), "csv", "empty"),
    "two columns": (_text("0,1\n1,2\n2,3\n"), "csv", "column"),
    "non-numeric": (_text("0,1,2\n0.1,x,3\n0.2,1,2\n"), "csv", "line"),
    "uneven steps": (_text("0,1,2\n0.1,1,2\n0.25,1,2\n0.3,1,2\n"), "csv", "time"),
    "NaN": (_text("0,1,2\n0.1,nan,2\n0.2,1,2\n"), "csv", ""),
    "uff without 58": (_text("    -1\n   151\n\n    -1\n"), "uff", ""),
    "directory": (lambda p: p.mkdir() or p, "csv", "not a regular file"),
    "fifo": (_fifo, "csv", ""),
    "garbage hdf5": (lambda p: p.write_bytes(b"\x89HDF\r\n\x1a\n" + b"\0" * 100) or p, "run", ""),
}


@pytest.mark.timeout(30)
@pytest.mark.parametrize("case", list(BAD_FILES))
def test_a_bad_file_is_one_line_and_nothing_is_written(tmp_path, case):
    make, fmt, fragment = BAD_FILES[case]
    path = make(tmp_path / f"bad-{case.replace(' ', '-')}")
    store = tmp_path / "store"
    result = daq_in(store, "import", str(path), "--format", fmt)
    assert_one_line_error(result, fragment)
    assert result.returncode == 1
    assert not store.exists() or Store(store).list() == []


def test_an_unknown_format_is_asked_for(tmp_path):
    path = tmp_path / "mystery.bin"
    path.write_bytes(b"\x01\x02")
    assert_one_line_error(daq_in(tmp_path / "s", "import", str(path)), "--format")


def test_csv_options_on_a_uff_file_are_a_usage_error(tmp_path):
    path = tmp_path / "a.uff"
    path.write_text("    -1\n")
    result = daq_in(tmp_path / "s", "import", str(path), "--columns", "0,1,2")
    assert_one_line_error(result, "CSV and LVM files only")
    assert result.returncode == 2


def test_csv_with_units_columns_and_odd_names(tmp_path):
    # A file name, operator and note with spaces, quotes, unicode, a path separator
    # look-alike and shell characters: stored as given, never used as a path.
    name = "hit 'ü' $(x) ;.txt"
    path = tmp_path / name
    rows = ["a_mV,t,F"] + [f"{10.0 * (i % 3)},{i / 1000},{(i % 2) * 0.5}" for i in range(8)]
    path.write_text("\n".join(rows) + "\n")
    store = tmp_path / "store"
    odd = 'Zoë ../etc/passwd "quoted" ; rm -rf /'
    result = invoke_daq(
        "import", str(path), "--columns", "t,F,a_mV", "--force-unit", "kN",
        "--response-unit", "mV@10mV/g", "--operator", odd, "--note", "line one\tand a tab",
        "--store", str(store),
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    (only,) = Store(store).list()
    run = Store(store).open(only.run_id)
    assert run.operator == odd
    assert run.note == "line one\tand a tab"
    assert run.provenance["imported_from"]["file"] == name
    np.testing.assert_array_equal(run.hits.force_n[0], [(i % 2) * 500.0 for i in range(8)])
    # 10 mV per g: x mV is x / 10 g = x / 10 * 9.80665 m/s^2.
    np.testing.assert_allclose(run.hits.response_m_s2[0], [(i % 3) * 9.80665 for i in range(8)], rtol=1e-15)
    assert run.hits.sample_rate_hz == pytest.approx(1000.0, rel=1e-12)
    assert sorted(p.name for p in store.iterdir() if not p.name.startswith(".")) == [f"{only.run_id}.h5"]


def test_a_run_file_from_another_store_is_imported_with_its_origin(tmp_path):
    other = make_run(kind="captured")
    path = seal(other, tmp_path / "other")
    store = tmp_path / "store"
    assert daq_in(store, "import", str(path)).returncode == 0
    run = Store(store).open(only_new(store, set()))
    assert run.run_id != other.run_id
    assert run.provenance["imported_from"]["run_id"] == other.run_id
    assert_same_hits(run.hits, other.hits)


def test_a_run_file_holding_nan_is_refused_on_import(tmp_path):
    # Analysis and replay would fail on it later ("non-finite value"): refused at the door.
    path = seal(make_run(kind="captured"), tmp_path / "other")
    with h5py.File(path, "r+") as f:
        data = f["entry/hits/force"]
        values = data[...]
        values[0, 0] = np.nan
        data[...] = values
    result = daq_in(tmp_path / "store", "import", str(path))
    assert_one_line_error(result)
    assert "finite" in result.stderr or "NaN" in result.stderr
    assert Store(tmp_path / "store").list() == []


def test_a_run_file_with_an_external_link_is_refused_on_import(tmp_path):
    path = seal(make_run(), tmp_path / "other")
    outside = tmp_path / "outside.h5"
    with h5py.File(outside, "w") as f:
        f["x"] = np.zeros(3)
    with h5py.File(path, "r+") as f:
        f["entry/extra"] = h5py.ExternalLink(str(outside), "/x")
    result = daq_in(tmp_path / "store", "import", str(path))
    assert_one_line_error(result, "external link")
    assert Store(tmp_path / "store").list() == []


def test_import_json_free_provenance_is_valid_json(captured, tmp_path):
    # The provenance is stored as JSON text: a reader with h5py and json alone gets it.
    source_store, run_id = captured
    out = tmp_path / "r.csv"
    daq_in(source_store, "export", run_id, "-f", "csv", "-o", str(out))
    store = tmp_path / "s"
    daq_in(store, "import", str(out))
    with h5py.File(store / f"{only_new(store, set())}.h5", "r") as f:
        provenance = json.loads(f["entry"].attrs["provenance_json"])
    assert provenance["imported_from"]["size_bytes"] == out.stat().st_size


def test_a_uff_file_cut_short_anywhere_is_refused(captured, tmp_path):
    source_store, run_id = captured
    out = tmp_path / "whole.uff"
    assert daq_in(source_store, "export", run_id, "-f", "uff", "-o", str(out)).returncode == 0
    data = out.read_bytes()
    store = tmp_path / "store"
    for fraction in (0.05, 0.3, 0.5, 0.7, 0.9, 0.99, 0.9999):
        cut = tmp_path / f"cut-{fraction}.uff"
        cut.write_bytes(data[: int(len(data) * fraction)])
        assert_one_line_error(daq_in(store, "import", str(cut)), "truncated")
    assert not store.exists() or Store(store).list() == []


def test_export_never_writes_over_a_device_or_fifo_even_with_force(captured, tmp_path):
    source_store, run_id = captured
    fifo = tmp_path / "pipe.csv"
    os.mkfifo(fifo)
    result = daq_in(source_store, "export", run_id, "-f", "csv", "-o", str(fifo), "--force")
    assert_one_line_error(result, "not a regular file")
    assert fifo.is_fifo()
    assert_one_line_error(daq_in(source_store, "export", run_id, "-f", "csv", "-o", "-"), "stdout")
    missing = f"{tmp_path}/missing/"
    assert_one_line_error(
        daq_in(source_store, "export", run_id, "-f", "csv", "-o", missing), "no such folder"
    )
    assert not (tmp_path / "missing").exists()


def test_exported_files_get_the_umask_mode_not_0600(captured, tmp_path):
    source_store, run_id = captured
    out = tmp_path / "shared.csv"
    old = os.umask(0o022)
    try:
        assert daq_in(source_store, "export", run_id, "-f", "csv", "-o", str(out)).returncode == 0
    finally:
        os.umask(old)
    assert out.stat().st_mode & 0o777 == 0o644


def test_a_store_that_is_a_file_fails_before_any_hit(tmp_path):
    not_a_folder = tmp_path / "store.csv"
    not_a_folder.write_text("x\n")
    result = invoke_daq("capture", "--sim", "--yes", "--hits", "2", "--store", str(not_a_folder))
    assert_one_line_error(result, "is a file, not a folder")
    assert "Hit 1" not in result.stdout


# --- what instruments and programs really write ----------------------------------------------


def test_a_frequency_table_imports_as_frfs_and_says_why(tmp_path):
    path = tmp_path / "frf.csv"
    path.write_text("Frequency (Hz);Re [m/N];Im [m/N]\n0,5;1,0;0,0\n1,0;0,5;-0,5\n")
    store = tmp_path / "store"
    result = daq_in(store, "import", str(path))
    assert result.returncode == 0, result.stderr
    assert (
        "format frf-text: detected: the header's first column 'Frequency (Hz)' is a frequency"
        in result.stdout
    )
    assert "form: receptance (header (m/N))" in result.stdout
    (only,) = Store(store).list()
    run = Store(store).open(only.run_id)
    assert run.hits is None
    assert run.measured_frfs.form == "receptance"
    assert run.measured_frfs.frf[0].tolist() == [1.0, 0.5 - 0.5j]


def test_a_frequency_table_forced_as_csv_is_refused_not_a_1_hz_record(tmp_path):
    path = tmp_path / "frf.csv"
    path.write_text("frequency,Re,Im\n1,1,0\n2,0.5,-0.5\n3,0.1,0\n")
    store = tmp_path / "store"
    result = daq_in(store, "import", str(path), "--format", "csv")
    assert_one_line_error(result, "--format frf-text")
    assert not store.exists() or Store(store).list() == []


def test_header_units_are_used_and_said(tmp_path):
    path = tmp_path / "impact.txt"
    rows = ["Time (s)\tForce [kN]\tacc (g)"] + [f"{i / 51200:.7g}\t0,5\t1,0" for i in range(64)]
    path.write_text("\n".join(rows) + "\n")
    store = tmp_path / "store"
    result = daq_in(store, "import", str(path))
    assert result.returncode == 0, result.stderr
    assert "units: time s, force kN (header), response g (header)" in result.stdout
    (only,) = Store(store).list()
    hits = Store(store).open(only.run_id).hits
    assert hits.force_n[0, 0] == 500.0
    assert hits.sample_rate_hz == pytest.approx(51200.0, rel=1e-6)


@pytest.mark.parametrize(
    ("content", "fragment"),
    [
        (
            "t;F;a\n" + "".join(f"0,00{i};1;2\n" for i in (0, 1, 2, 3, 5, 6, 7)),
            "line 6: uneven time step",
        ),
        ("t (s);F (N);a (mV)\n0;1;2\n0,001;1;2\n", "--response-unit mV@10.2mV/g"),
        ("t (fortnight),F,a\n0,1,2\n1,1,2\n", "unknown time unit"),
        ("freq,Re\n1,2\n2,3\n", "starts no FRF"),
        ("Frequency,Magnitude\n1,2\n2,3\n", "a magnitude without its phase"),
    ],
)
def test_bad_real_world_files_are_one_line_and_nothing_is_written(tmp_path, content, fragment):
    path = tmp_path / "bad.csv"
    path.write_text(content)
    store = tmp_path / "store"
    result = daq_in(store, "import", str(path))
    assert_one_line_error(result, fragment)
    assert result.returncode == 1
    assert str(path) in result.stderr
    assert not store.exists() or Store(store).list() == []
