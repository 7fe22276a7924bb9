"""Sealing a run and opening it again gives back exactly what went in, in a file that
generic HDF5/NeXus viewers can show: filters on every dataset, NX attributes, units."""

from __future__ import annotations

import h5py
import numpy as np
import pytest

from daq import __version__
from daq.store import SCHEMA_NAME, SCHEMA_VERSION, open_run, read_summary, seal, verify
from tests.store.store_helpers import assert_same_run, make_frf, make_hits, make_run


@pytest.mark.parametrize(
    "parts",
    [
        {"hits": "baseband"},
        {"hits": "baseband", "analyzer": True},
        {"hits": "zoom"},
        {"measured": True},
        {"measured": "no coherence", "analyzer": True},
    ],
    ids=["baseband", "baseband+analyzer", "zoom", "frf-only", "frf-no-coherence"],
)
def test_round_trip_is_exact(tmp_path, parts):
    hits = None
    if parts.get("hits") == "baseband":
        hits = make_hits(5, 300)
    elif parts.get("hits") == "zoom":
        hits = make_hits(3, 200, zoom=True)
    analyzer = make_frf(1, 401, seed=5) if parts.get("analyzer") else None
    measured = None
    if parts.get("measured"):
        measured = make_frf(3, 129, coherence=parts["measured"] is True, seed=9)
    kind = "imported" if measured is not None else "captured"
    run = make_run(kind=kind, hits=hits, analyzer=analyzer, measured=measured)
    if hits is None:
        assert run.hits is None
    path = seal(run, tmp_path)
    assert path == tmp_path / f"{run.run_id}.h5"
    got = open_run(path)
    assert_same_run(got, run)
    assert verify(path) == []
    if hits is not None and hits.is_zoom:
        assert got.hits.force_n.dtype == np.complex128
        assert got.hits.center_hz == 1234.5


def test_special_values_survive(tmp_path):
    hits = make_hits(2, 8)
    hits.force_n[0, 0] = np.nan  # a dropout in the record must come back as NaN, not 0
    hits.force_n[0, 1] = -0.0
    hits.response_m_s2[1, 2] = np.inf
    run = make_run(hits=hits, note="Zeilen\nmit Ümlauten und 'Anführung' ✓")
    run.sample.sensor_position_m = None
    run.sample.force_position_m = 0.0
    got = open_run(seal(run, tmp_path))
    assert_same_run(got, run)
    assert np.signbit(got.hits.force_n[0, 1])
    assert got.sample.sensor_position_m is None
    assert got.sample.force_position_m == 0.0


def test_software_and_schema_recorded(tmp_path):
    path = seal(make_run(), tmp_path)
    with h5py.File(path, "r") as f:
        assert f.attrs["schema"].decode() == SCHEMA_NAME == "cantilever-daq.run"
        assert int(f.attrs["schema_version"]) == SCHEMA_VERSION == 1
        assert f.attrs["creator"].decode() == f"cantilever-daq {__version__}"
    assert open_run(path).software == f"cantilever-daq {__version__}"


def test_summary_counts(tmp_path):
    path = seal(make_run(hits=make_hits(7, 16)), tmp_path)
    summary = read_summary(path)
    # make_hits rejects exactly its last hit
    assert (summary.n_hits, summary.n_accepted, summary.kind, summary.complete) == (7, 6, "simulated", True)
    assert summary.size_bytes == path.stat().st_size
    frf_only = read_summary(seal(make_run(kind="imported", measured=make_frf()), tmp_path))
    assert (frf_only.n_hits, frf_only.n_accepted) == (0, 0)


def _datasets(f: h5py.File) -> list[h5py.Dataset]:
    found: list[h5py.Dataset] = []
    f.visititems(lambda _, obj: found.append(obj) if isinstance(obj, h5py.Dataset) else None)
    return found


def test_every_dataset_is_compressed_and_checksummed(tmp_path):
    run = make_run(hits=make_hits(3, 64), analyzer=make_frf(1, 33), measured=make_frf(2, 17))
    with h5py.File(seal(run, tmp_path), "r") as f:
        datasets = _datasets(f)
        assert len(datasets) >= 20
        for dset in datasets:
            assert dset.chunks is not None, dset.name
            assert dset.compression == "gzip", dset.name
            assert dset.shuffle, dset.name
            assert dset.fletcher32, dset.name
            assert dset.dtype.kind != "O", f"{dset.name}: variable-length data escapes the checksums"


def _text(value) -> str:
    return value.decode() if isinstance(value, bytes) else str(value)


@pytest.mark.parametrize("content", ["hits", "frf-only"])
def test_nexus_attributes_lead_a_viewer_to_plottable_data(tmp_path, content):
    if content == "hits":
        run = make_run(hits=make_hits(3, 64))
    else:
        run = make_run(kind="imported", measured=make_frf(2, 17))
    with h5py.File(seal(run, tmp_path), "r") as f:
        entry = f[_text(f.attrs["default"])]
        assert _text(entry.attrs["NX_class"]) == "NXentry"
        data = entry[_text(entry.attrs["default"])]
        assert _text(data.attrs["NX_class"]) == "NXdata"
        signal = data[_text(data.attrs["signal"])]
        axes = [_text(a) for a in data.attrs["axes"]]
        assert len(axes) == signal.ndim
        for dim, axis_name in enumerate(axes):
            assert data[axis_name].shape == (signal.shape[dim],)
        assert "units" in signal.attrs
        assert "long_name" in signal.attrs
        assert _text(data[axes[-1]].attrs["units"]) == ("s" if content == "hits" else "Hz")
        if content == "hits":
            assert _text(f["entry/instrument"].attrs["NX_class"]) == "NXinstrument"
            assert _text(f["entry/sample"].attrs["NX_class"]) == "NXsample"
            assert _text(data["force"].attrs["units"]) == "N"
            assert _text(data["response"].attrs["units"]) == "m/s^2"
            # The stored time axis: first sample at start_s, one sample period apart.
            time_s = data["time"][()]
            assert time_s[0] == pytest.approx(-0.0125)
            assert time_s[1] - time_s[0] == pytest.approx(1 / 2560.0)
        else:
            assert _text(signal.attrs["units"]) == "(m/s^2)/N"


def test_sealed_file_is_read_only_and_alone(tmp_path):
    path = seal(make_run(), tmp_path)
    assert path.stat().st_mode & 0o777 == 0o444
    assert sorted(p.name for p in tmp_path.iterdir()) == [path.name]  # no temporary left
