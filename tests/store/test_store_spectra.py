"""A run's spectra (/entry/spectra) through the real store: sealed and read back bit for
bit, checked by verify(), refused when damaged, and absent from older runs."""

from __future__ import annotations

import h5py
import numpy as np
import pytest

from daq.store import (
    SCHEMA_VERSION,
    Run,
    Spectra,
    StoreError,
    new_run_id,
    open_run,
    read_summary,
    seal,
    verify,
)
from tests.store.store_helpers import make_hits, make_run

N_LINES = 1601


def make_spectra(complex_values: bool = False) -> Spectra:
    rng = np.random.default_rng(7)
    values = rng.uniform(0, 1e-4, (3, N_LINES))
    if complex_values:
        values = values + 1j * rng.normal(size=values.shape)
    return Spectra(
        frequency_hz=np.arange(N_LINES) * 8.0,
        values=values,
        kinds=["power", "cross" if complex_values else "linear", "coherence"],
        units=["V^2", "N*(m/s^2)", ""],
        labels=["Pwr Spec", "Spectrum — ch 2", "Coherence"],  # non-ASCII on purpose
    )


def spectra_run(spectra: Spectra | None = None, **parts) -> Run:
    return Run(
        run_id=new_run_id(),
        kind="imported",
        complete=True,
        start_time="2026-11-23T10:15:03.123Z",
        end_time="2026-11-23T10:15:04.000Z",
        provenance={"imported_from": {"file": "SDF3KHZ.DAT", "format": "sdf"}},
        spectra=spectra if spectra is not None else make_spectra(),
        **parts,
    )


def assert_same_spectra(a: Spectra, b: Spectra) -> None:
    assert a.values.dtype == b.values.dtype
    assert a.values.tobytes() == b.values.tobytes()
    assert a.frequency_hz.tobytes() == b.frequency_hz.tobytes()
    assert (a.kinds, a.units, a.labels) == (b.kinds, b.units, b.labels)


@pytest.mark.parametrize("complex_values", [False, True])
def test_a_run_of_spectra_alone_round_trips_bit_for_bit(tmp_path, complex_values):
    run = spectra_run(make_spectra(complex_values))
    path = seal(run, tmp_path / "store")
    assert verify(path) == []
    back = open_run(path)
    assert (back.hits, back.analyzer, back.measured_frfs) == (None, None, None)
    assert_same_spectra(back.spectra, run.spectra)
    summary = read_summary(path)
    assert (summary.n_hits, summary.error) == (0, None)
    with h5py.File(path, "r") as f:
        assert int(f.attrs["schema_version"]) == SCHEMA_VERSION == 1  # an optional group: no bump
        group = f["entry/spectra"]
        assert f["entry"].attrs["default"] == b"spectra"  # what a viewer plots
        assert group.attrs["NX_class"] == b"NXdata"
        assert group.attrs["signal"] == b"spectrum"
        assert "units" not in group["spectrum"].attrs  # the traces' units differ
        assert [u.decode() for u in group["unit"][()]] == ["V^2", "N*(m/s^2)", ""]
        for name in ("frequency", "spectrum", "kind", "unit", "label", "spectrum_index"):
            assert group[name].fletcher32
            assert group[name].compression == "gzip"


def test_spectra_beside_hits_keep_both(tmp_path):
    run = make_run(hits=make_hits(3, 128))
    run.spectra = make_spectra()
    back = open_run(seal(run, tmp_path / "store"))
    assert back.hits.n_hits == 3
    assert_same_spectra(back.spectra, run.spectra)


def test_one_shared_unit_is_also_the_datasets_units_attribute(tmp_path):
    spectra = make_spectra()
    spectra = Spectra(spectra.frequency_hz, spectra.values[:1], ["power"], ["V^2"], ["Pwr Spec"])
    path = seal(spectra_run(spectra), tmp_path / "store")
    with h5py.File(path, "r") as f:
        assert f["entry/spectra/spectrum"].attrs["units"] == b"V^2"


def test_verify_names_a_corrupted_spectra_dataset(tmp_path):
    path = seal(spectra_run(), tmp_path / "store")
    with h5py.File(path, "r") as f:
        info = f["entry/spectra/spectrum"].id.get_chunk_info(0)
    data = bytearray(path.read_bytes())
    data[info.byte_offset + info.size // 2] ^= 0x01
    broken = tmp_path / "store" / "20991231T235959.999Z-0badf11e.h5"
    broken.write_bytes(bytes(data))
    problems = verify(broken)
    assert len(problems) == 1, problems
    assert "/entry/spectra/spectrum" in problems[0], problems
    with pytest.raises(StoreError):
        open_run(broken)


@pytest.mark.parametrize(
    ("dataset", "value", "words"),
    [
        ("kind", np.array([b"power", b"phase", b"coherence"]), "not one of"),
        ("label", np.array([b"one", b"two"]), "spectra.labels must hold 3"),
    ],
)
def test_inconsistent_spectra_are_refused(tmp_path, dataset, value, words):
    path = seal(spectra_run(), tmp_path / "store")
    edited = tmp_path / "store" / "20991231T235959.999Z-0badf11e.h5"
    edited.write_bytes(path.read_bytes())
    with h5py.File(edited, "r+") as f:
        group = f["entry/spectra"]
        del group[dataset]
        group.create_dataset(dataset, data=value, fletcher32=True, compression="gzip", shuffle=True)
    problems = verify(edited)
    assert len(problems) == 1, problems
    assert words in problems[0], problems
    with pytest.raises(StoreError, match=words):
        open_run(edited)


def test_an_older_run_without_the_group_still_reads(tmp_path):
    # Every run written before spectra existed is a run without /entry/spectra.
    run = make_run(hits=make_hits(2, 64))
    path = seal(run, tmp_path / "store")
    with h5py.File(path, "r") as f:
        assert "spectra" not in f["entry"]
    assert verify(path) == []
    back = open_run(path)
    assert back.spectra is None
    assert back.hits.n_hits == 2


@pytest.mark.parametrize(
    ("change", "words"),
    [
        ({"kinds": ["power", "phase", "coherence"]}, "not one of"),
        ({"units": ["V^2"]}, "spectra.units must hold 3"),
        ({"values": np.zeros((3, 5))}, "must have shape"),
        ({"values": np.zeros((3, N_LINES), dtype=np.float32)}, "float64 or complex128"),
        ({"frequency_hz": np.zeros(N_LINES)}, "strictly increasing"),
    ],
)
def test_the_model_refuses_inconsistent_spectra(change, words):
    spectra = make_spectra()
    fields = {
        "frequency_hz": spectra.frequency_hz,
        "values": spectra.values,
        "kinds": spectra.kinds,
        "units": spectra.units,
        "labels": spectra.labels,
    }
    with pytest.raises(ValueError, match=words):
        Spectra(**{**fields, **change})


def test_a_run_needs_a_data_part_and_spectra_count_as_one():
    with pytest.raises(ValueError, match="or spectra: it has none"):
        Run(
            run_id=new_run_id(),
            kind="imported",
            complete=True,
            start_time="2026-11-23T10:15:03.123Z",
            end_time="2026-11-23T10:15:03.123Z",
        )
    assert spectra_run().spectra.n_traces == 3
