"""UFF 58 import and export: exact round trips, pyuff reads our files, foreign units, refusals."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
import pyuff

from daq.formats.errors import FormatError
from daq.formats.uff58 import read_uff
from daq.formats.uff58_export import write_uff
from daq.store.ids import new_run_id
from daq.store.model import Hits, MeasuredFrf, Run


def make_hits(zoom: bool = False, n_hits: int = 3, n: int = 1024, rate: float = 256.0, seed: int = 3) -> Hits:
    rng = np.random.default_rng(seed)
    force = rng.normal(size=(n_hits, n)) * 50
    response = rng.normal(size=(n_hits, n))
    if zoom:
        force = force + 1j * rng.normal(size=(n_hits, n))
        response = response + 1j * rng.normal(size=(n_hits, n))
    return Hits(
        force_n=force,
        response_m_s2=response,
        sample_rate_hz=rate,
        start_s=-0.125,
        center_hz=1234.5 if zoom else 0.0,
        accepted=np.array([True, False, True][:n_hits]),
        reject_reason=["", "double hit", ""][:n_hits],
        overload=np.zeros((n_hits, 2), dtype=bool),
        peak_force_n=np.abs(force).max(axis=1),
        timestamp_utc=["2026-11-23T10:15:03.123Z"] * n_hits,
        checks=[{} for _ in range(n_hits)],
    )


def make_frfs(freq: np.ndarray, n_frf: int = 2, coherence: bool = True, seed: int = 4) -> MeasuredFrf:
    rng = np.random.default_rng(seed)
    frf = rng.normal(size=(n_frf, freq.size)) + 1j * rng.normal(size=(n_frf, freq.size))
    coh = rng.uniform(size=(n_frf, freq.size)) if coherence else None
    return MeasuredFrf(freq, frf, coh, [f"H21 set {i}" for i in range(n_frf)])


def make_run(**parts) -> Run:
    return Run(new_run_id(), "captured", True, "2026-11-23T10:15:03Z", "2026-11-23T10:16:03Z", **parts)


def refused(path: Path, **kwargs) -> str:
    with pytest.raises(FormatError) as info:
        read_uff(path, **kwargs)
    message = str(info.value)
    assert "\n" not in message
    assert str(path) in message
    return message


def same_bits(a: np.ndarray, b: np.ndarray) -> bool:
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


# --- round trips -----------------------------------------------------------------------


@pytest.mark.parametrize("zoom", [False, True])
def test_round_trip_hits_and_frfs_exact(tmp_path, zoom):
    freq = np.linspace(0.0, 200.0, 801)  # even 0.25 Hz lines
    run = make_run(hits=make_hits(zoom=zoom), analyzer=make_frfs(freq))
    path = tmp_path / "run.uff"
    write_uff(run, path)
    got = read_uff(path)
    assert got.format == "uff"
    assert same_bits(got.hits.force_n, run.hits.force_n)
    assert same_bits(got.hits.response_m_s2, run.hits.response_m_s2)
    assert got.hits.sample_rate_hz == 256.0
    assert got.hits.start_s == -0.125
    assert got.hits.center_hz == (1234.5 if zoom else 0.0)
    # the verdicts come back from ID line 1 of each force record
    assert got.hits.accepted.tolist() == run.hits.accepted.tolist()
    assert list(got.hits.reject_reason) == list(run.hits.reject_reason)
    assert got.hits.peak_force_n.tolist() == np.abs(run.hits.force_n).max(axis=1).tolist()
    assert same_bits(got.measured_frfs.frequency_hz, freq)
    assert same_bits(got.measured_frfs.frf, run.analyzer.frf)
    assert same_bits(got.measured_frfs.coherence, run.analyzer.coherence)
    assert list(got.measured_frfs.labels) == ["H21 set 0", "H21 set 1"]
    assert os.listdir(tmp_path) == ["run.uff"]


def test_round_trip_rate_and_axis_that_text_headers_cannot_hold(tmp_path):
    # 1/3000 s and 1/3 Hz steps lose digits in pyuff's %13.5e header fields
    freq = 1.0 + np.arange(50) / 3.0
    hits = make_hits(n=64, rate=3000.0)
    run = make_run(hits=hits, measured_frfs=make_frfs(freq, coherence=False))
    path = tmp_path / "run.uff"
    write_uff(run, path)
    got = read_uff(path)
    assert got.hits.sample_rate_hz == 3000.0
    assert got.hits.start_s == -0.125
    assert same_bits(got.hits.force_n, hits.force_n)
    assert same_bits(got.measured_frfs.frequency_hz, freq)
    assert got.measured_frfs.coherence is None


def test_frf_only_run(tmp_path):
    freq = np.arange(1, 101) * 0.5
    run = make_run(measured_frfs=make_frfs(freq, n_frf=1))
    path = tmp_path / "frf.uff"
    write_uff(run, path)
    got = read_uff(path)
    assert got.hits is None
    assert same_bits(got.measured_frfs.frf, run.measured_frfs.frf)


def test_plain_pyuff_reads_our_file_unchanged(tmp_path):
    freq = np.linspace(0.0, 100.0, 401)
    run = make_run(hits=make_hits(n_hits=2, n=256), analyzer=make_frfs(freq, n_frf=1))
    path = tmp_path / "run.uff"
    write_uff(run, path)
    sets = pyuff.UFF(str(path)).read_sets()
    assert [s["type"] for s in sets] == [58] * 6
    # FRFs first: sdypy-EMA takes the FRF's form from the file's first dataset 58
    assert [s["func_type"] for s in sets] == [4, 6, 1, 1, 1, 1]
    assert [s["ordinate_spec_data_type"] for s in sets[2:]] == [13, 12, 13, 12]
    for k in range(2):
        assert same_bits(sets[2 + 2 * k]["data"], run.hits.force_n[k])
        assert same_bits(sets[3 + 2 * k]["data"], run.hits.response_m_s2[k])
        # the time axis from the %13.5e header: -0.125 and 1/256 happen to be exact
        assert np.allclose(sets[2 + 2 * k]["x"], run.hits.time_s(), rtol=0, atol=1e-12)
    assert same_bits(sets[0]["data"], run.analyzer.frf[0])
    assert same_bits(sets[0]["x"], freq)
    assert same_bits(sets[1]["data"], run.analyzer.coherence[0])
    assert sets[2]["ordinate_axis_units_lab"] == "N"
    assert sets[3]["ordinate_axis_units_lab"] == "m/s^2"
    assert run.run_id in sets[2]["id2"]
    # a run that records no points was measured at the tip, hammer and sensor: one node
    assert {(s["ref_node"], s["ref_dir"], s["rsp_node"], s["rsp_dir"]) for s in sets} == {(1, 3, 1, 3)}


def test_export_refuses_non_finite(tmp_path):
    hits = make_hits(n_hits=1, n=8)
    hits.force_n[0, 3] = np.nan
    with pytest.raises(FormatError, match="non-finite"):
        write_uff(make_run(hits=hits), tmp_path / "x.uff")
    assert list(tmp_path.iterdir()) == []


# --- files written by other tools (pyuff directly) -------------------------------------------


def time_set(data, kind, unit, x, id4="NONE", binary=0):
    dset = pyuff.prepare_58(
        binary=binary,
        id1="foreign",
        id4=id4,
        func_type=1,
        rsp_node=1,
        rsp_dir=3,
        ref_node=1,
        ref_dir=3,
        abscissa_spacing=1,
        abscissa_spec_data_type=17,
        ordinate_spec_data_type=kind,
        orddenom_spec_data_type=0,
        z_axis_spec_data_type=0,
        data=np.asarray(data),
        x=np.asarray(x, dtype=float),
    )
    dset["ordinate_axis_units_lab"] = unit
    return dset


def frf_set(data, x, func=4, num="m/s^2", den="N", id1="NONE"):
    dset = pyuff.prepare_58(
        binary=0,
        id1=id1,
        func_type=func,
        rsp_node=7,
        rsp_dir=3,
        ref_node=5,
        ref_dir=-3,
        abscissa_spacing=1,
        abscissa_spec_data_type=18,
        ordinate_spec_data_type=12,
        orddenom_spec_data_type=13,
        z_axis_spec_data_type=0,
        data=np.asarray(data),
        x=np.asarray(x, dtype=float),
    )
    dset.update(ordinate_axis_units_lab=num, orddenom_axis_units_lab=den)
    return dset


def write_sets(path: Path, sets: list[dict]) -> Path:
    pyuff.UFF(str(path)).write_sets(sets, mode="add")
    return path


def test_foreign_ascii_units_g_and_lbf_converted(tmp_path):
    x = np.arange(4) * 0.5
    path = write_sets(
        tmp_path / "f.uff",
        [time_set([1.0, 2.0, 0.5, -1.0], 13, "lbf", x), time_set([1.0, -2.0, 0.25, 0.0], 12, "g", x)],
    )
    got = read_uff(path)
    assert got.hits.force_n[0] == pytest.approx(
        [4.4482216152605, 8.896443230521, 2.22411080763025, -4.4482216152605]
    )
    assert got.hits.response_m_s2[0] == pytest.approx([9.80665, -19.6133, 2.4516625, 0.0])
    assert got.hits.sample_rate_hz == 2.0
    assert got.hits.start_s == 0.0


def test_foreign_frf_units_and_default_label(tmp_path):
    freq = np.array([1.0, 2.0, 3.0])
    path = write_sets(tmp_path / "f.uff", [frf_set([1 + 1j, 2 + 0j, 0 - 1j], freq, num="g", den="lbf")])
    got = read_uff(path).measured_frfs
    factor = 9.80665 / 4.4482216152605  # (m/s^2 per g) / (N per lbf)
    assert got.frf[0] == pytest.approx(np.array([1 + 1j, 2, -1j]) * factor)
    assert list(got.labels) == ["ref5-3->rsp73"]


def test_unknown_unit_label_is_refused_in_one_line(tmp_path):
    # Kept before with one import warning, a force in furlong was stored as newtons and
    # nothing said so after; the CSV reader refuses such a unit, and so does this one.
    x = np.arange(3.0)
    path = write_sets(
        tmp_path / "f.uff", [time_set([1.0, 2, 3], 13, "furlong", x), time_set([1.0, 2, 3], 12, "", x)]
    )
    with pytest.raises(FormatError) as excinfo:
        read_uff(path)
    message = str(excinfo.value)
    assert "\n" not in message
    assert "'furlong'" in message
    assert "not known" in message


def test_coherence_count_mismatch_ignored_and_noted(tmp_path):
    freq = np.array([1.0, 2.0, 3.0])
    sets = [frf_set([1 + 1j] * 3, freq), frf_set([2 + 1j] * 3, freq), frf_set([0.5, 0.6, 0.7], freq, func=6)]
    got = read_uff(write_sets(tmp_path / "f.uff", sets))
    assert got.measured_frfs.coherence is None
    assert any("coherence ignored" in note for note in got.details["notes"])


# --- refusals -------------------------------------------------------------------------------


def test_only_dataset_15_or_151(tmp_path):
    nodes = pyuff.prepare_15(
        node_nums=[1, 2],
        def_cs=[0, 0],
        disp_cs=[0, 0],
        color=[1, 1],
        x=[0.0, 1.0],
        y=[0.0, 0.0],
        z=[0.0, 0.0],
    )
    path = write_sets(tmp_path / "nodes.uff", [nodes])
    assert pyuff.UFF(str(path)).get_set_types().tolist() == [15]
    assert "no dataset 58 in" in refused(path)
    header = pyuff.prepare_151(
        model_name="beam",
        description="d",
        db_app="app",
        date_db_created="01-Jan-26",
        time_db_created="00:00:00",
        version_db1=1,
        version_db2=1,
        file_type=0,
        date_db_saved="01-Jan-26",
        time_db_saved="00:00:00",
        program="p",
        date_db_written="01-Jan-26",
        time_db_written="00:00:00",
    )
    path = write_sets(tmp_path / "h.uff", [header])
    assert pyuff.UFF(str(path)).get_set_types().tolist() == [151]
    assert "no dataset 58 in" in refused(path)


@pytest.mark.parametrize(
    "content",
    [b"\x00\xff garbage \x13" * 50, b"hello\n", b"    -1\n    58\nshort\n    -1\n", os.urandom(4096)],
)
def test_garbage_refused(tmp_path, content):
    path = tmp_path / "g.uff"
    path.write_bytes(content)
    refused(path)


def test_truncated_export_refused(tmp_path):
    path = tmp_path / "run.uff"
    write_uff(make_run(hits=make_hits(n_hits=1, n=64)), path)
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    refused(path)


def test_unpaired_records(tmp_path):
    x = np.arange(3.0)
    path = write_sets(
        tmp_path / "f.uff", [time_set([1.0, 2, 3], 13, "N", x)] * 2 + [time_set([1.0, 2, 3], 12, "", x)]
    )
    assert "2 force and 1 acceleration time records" in refused(path)


def test_unequal_lengths(tmp_path):
    sets = [time_set([1.0, 2, 3], 13, "N", np.arange(3.0)), time_set([1.0, 2], 12, "m/s^2", np.arange(2.0))]
    assert "has 2 samples" in refused(write_sets(tmp_path / "f.uff", sets))


def test_different_time_axes(tmp_path):
    sets = [
        time_set([1.0, 2, 3], 13, "N", np.arange(3.0)),
        time_set([1.0, 2, 3], 12, "g", np.arange(3.0) * 2),
    ]
    assert "different time axis" in refused(write_sets(tmp_path / "f.uff", sets))


def test_complex_time_without_center_refused(tmp_path):
    x = np.arange(3.0)
    sets = [time_set(np.ones(3) + 1j, 13, "N", x), time_set(np.ones(3) + 2j, 12, "m/s^2", x)]
    assert "center_hz" in refused(write_sets(tmp_path / "f.uff", sets))
    sets = [time_set(np.ones(3) + 1j, 13, "N", x, "center_hz=80"), time_set(np.ones(3) + 2j, 12, "", x, "x")]
    assert read_uff(write_sets(tmp_path / "g.uff", sets)).hits.center_hz == 80.0


def test_frfs_on_different_axes(tmp_path):
    sets = [frf_set([1j] * 3, [1.0, 2, 3]), frf_set([1j] * 3, [2.0, 3, 4])]
    assert "different frequency axis" in refused(write_sets(tmp_path / "f.uff", sets))


def test_not_regular_files(tmp_path):
    assert "is a directory" in refused(tmp_path)
    fifo = tmp_path / "pipe.uff"
    os.mkfifo(fifo)
    assert "is a FIFO" in refused(fifo)
    empty = tmp_path / "e.uff"
    empty.write_bytes(b"")
    assert "is empty" in refused(empty)
    big = tmp_path / "big.uff"
    write_uff(make_run(hits=make_hits(n_hits=1, n=64)), big)
    assert "more than the import limit" in refused(big, max_bytes=100)


def test_a_file_with_no_force_acceleration_record_and_no_frf_says_what_it_holds(tmp_path):
    """A microphone's pressure record and a PSD: refused, naming what the datasets are
    (a new user could not tell why their file was refused)."""
    x = np.arange(64) / 1024.0
    pressure = time_set(np.sin(x), 15, "Pa", x)
    psd = frf_set(np.abs(np.sin(x)) + 0.0j, np.arange(64.0), func=9, num="g^2/Hz", den="NONE")
    path = write_sets(tmp_path / "mic.uff", [pressure, pressure, psd])
    with pytest.raises(
        FormatError, match=r"it holds 2 × time record of pressure \(Pa\), 1 × PSD of acceleration"
    ):
        read_uff(path)
