"""Damaged, foreign or booby-trapped files: verify() says what is wrong, open_run()
raises StoreError and nothing else, and undetected damage never changes the data."""

from __future__ import annotations

import os
import random
import shutil
from pathlib import Path

import h5py
import numpy as np
import pytest

from daq.store import Store, StoreError, open_run, read_summary, seal, verify
from tests.store.store_helpers import NOTE_MARKER, assert_same_run, make_frf, make_hits, make_run


@pytest.fixture
def sealed(tmp_path):
    run = make_run(hits=make_hits(6, 512), analyzer=make_frf(1, 201))
    return run, seal(run, tmp_path / "store")


def damaged_copy(path: Path, tmp_path: Path, edit) -> Path:
    data = bytearray(path.read_bytes())
    edit(data)
    out = tmp_path / "store" / ("20991231T235959.999Z-0badf11e.h5")
    out.write_bytes(bytes(data))
    return out


def writable_copy(path: Path, tmp_path: Path) -> Path:
    out = tmp_path / "store" / "20991231T235959.999Z-0badf11e.h5"
    shutil.copyfile(path, out)
    os.chmod(out, 0o644)
    return out


def assert_refused(path: Path, *words: str) -> list[str]:
    problems = verify(path)
    assert problems, "damage went unnoticed by verify()"
    for problem in problems:
        assert "\n" not in problem
    with pytest.raises(StoreError) as caught:
        open_run(path)
    assert "\n" not in str(caught.value)
    assert path.name in str(caught.value)
    text = " ".join(problems).lower()
    for word in words:
        assert word.lower() in text, problems
    return problems


@pytest.mark.parametrize("fraction", [0.0, 0.001, 0.05, 0.25, 0.5, 0.9, 0.999])
def test_truncated_file(sealed, tmp_path, fraction):
    _, path = sealed
    size = path.stat().st_size
    keep = int(size * fraction) if fraction < 0.999 else size - 1
    broken = damaged_copy(path, tmp_path, lambda d: d.__delitem__(slice(keep, None)))
    assert broken.stat().st_size == keep
    assert_refused(broken)
    with pytest.raises(StoreError):
        read_summary(broken)


def _chunk_span(path: Path, dataset: str) -> tuple[int, int]:
    with h5py.File(path, "r") as f:
        info = f[dataset].id.get_chunk_info(0)
        return info.byte_offset, info.size


@pytest.mark.parametrize(
    "dataset",
    [
        "entry/hits/force",
        "entry/hits/response",
        "entry/hits/checks_json",
        "entry/analyzer/frf",
        "entry/hits/accepted",
    ],
)
def test_flipped_byte_in_data(sealed, tmp_path, dataset):
    _, path = sealed
    offset, size = _chunk_span(path, dataset)

    def flip(data: bytearray) -> None:
        data[offset + size // 2] ^= 0x01

    broken = damaged_copy(path, tmp_path, flip)
    problems = assert_refused(broken, f"/{dataset}")
    assert len(problems) == 1  # only that dataset is named


@pytest.mark.parametrize(
    "needle", [NOTE_MARKER, "Ada Lovelace", "HP 35660A", "cantilever-daq.run", "NXentry"]
)
def test_flipped_byte_in_metadata(sealed, tmp_path, needle):
    _, path = sealed
    raw = path.read_bytes()
    # The note and the operator are in the root's summary attribute too: every copy counts.
    places = [at for at in range(len(raw)) if raw.startswith(needle.encode(), at)]
    assert places
    assert len(places) <= 2

    for at in places:

        def flip(data: bytearray, at=at) -> None:
            data[at + 2] ^= 0x20  # e.g. "Ada" -> "AdA": still valid text, so only a checksum can tell

        assert_refused(damaged_copy(path, tmp_path, flip), "checksum")


def test_random_flips_are_detected_or_harmless(sealed, tmp_path):
    run, path = sealed
    original = path.read_bytes()
    rng = random.Random(20261123)
    detected = 0
    for _ in range(60):
        position = rng.randrange(len(original))

        def flip(data: bytearray, position=position) -> None:
            data[position] ^= 1 << rng.randrange(8)

        broken = damaged_copy(path, tmp_path, flip)
        problems = verify(broken)
        try:
            got = open_run(broken)
        except StoreError:
            assert problems, f"open_run refused a flip at {position} that verify() passed"
            detected += 1
        else:
            # Unnoticed damage is allowed only where it changes nothing we read back.
            assert_same_run(got, run)
        broken.unlink()
    assert detected >= 30  # the file is mostly checksummed data, so most flips must be caught


def test_not_hdf5_at_all(tmp_path):
    store = tmp_path / "store"
    store.mkdir()
    for content in (b"", b"hello", b"\x89HDF\r\n\x1a\n" + b"\0" * 100):
        path = store / "20261123T101503.123Z-3f9c1a2b.h5"
        path.write_bytes(content)
        assert_refused(path, "cannot open")
        path.unlink()


def test_missing_file(tmp_path):
    assert verify(tmp_path / "nothing.h5") == [f"{tmp_path / 'nothing.h5'}: no such file"]
    with pytest.raises(StoreError, match="no such run file"):
        open_run(tmp_path / "nothing.h5")


def test_foreign_hdf5_file(tmp_path):
    path = tmp_path / "foreign.h5"
    with h5py.File(path, "w") as f:
        f["data"] = np.arange(3)
    assert_refused(path, "not a run file")


def test_newer_schema_version_is_refused(sealed, tmp_path):
    _, path = sealed
    copy = writable_copy(path, tmp_path)
    with h5py.File(copy, "a") as f:
        f.attrs["schema_version"] = np.int64(3)  # 2 is read: FRF forms
    assert_refused(copy, "newer")


@pytest.mark.parametrize(
    ("edit", "words"),
    [
        (lambda f: f["entry/hits"].__delitem__("peak_force"), ["peak_force", "missing"]),
        (lambda f: f["entry"].attrs.__delitem__("kind"), ["kind", "missing"]),
        (lambda f: f["entry"].__delitem__("hits") or f["entry"].__delitem__("analyzer"), ["none"]),
        (lambda f: f["entry/hits"].attrs.__setitem__("sample_rate_hz", np.float64(1.0)), ["time"]),
        (lambda f: _replace(f, "entry/hits/accepted", np.ones(5, bool)), ["shape"]),
        (lambda f: _replace(f, "entry/hits/force", np.zeros((6, 512), np.float32)), ["float64"]),
        (lambda f: _replace(f, "entry/hits/overload", np.zeros((6, 2), bool), filters=False), ["fletcher32"]),
    ],
    ids=["no-dataset", "no-attribute", "no-data", "time-axis", "n-hits", "dtype", "no-checksum"],
)
def test_inconsistent_content(sealed, tmp_path, edit, words):
    _, path = sealed
    copy = writable_copy(path, tmp_path)
    with h5py.File(copy, "a") as f:
        edit(f)
    assert_refused(copy, *words)


def _replace(f: h5py.File, name: str, data: np.ndarray, filters: bool = True) -> None:
    del f[name]
    if filters:
        f.create_dataset(name, data=data, chunks=True, compression="gzip", shuffle=True, fletcher32=True)
    else:
        f.create_dataset(name, data=data)


def test_external_link_is_refused(sealed, tmp_path):
    _, path = sealed
    outside = tmp_path / "outside.h5"
    with h5py.File(outside, "w") as f:
        f["force"] = np.ones((6, 512))
    copy = writable_copy(path, tmp_path)
    with h5py.File(copy, "a") as f:
        del f["entry/hits/force"]
        f["entry/hits/force"] = h5py.ExternalLink(str(outside), "/force")
    assert_refused(copy, "external link")


def test_virtual_dataset_is_refused(sealed, tmp_path):
    _, path = sealed
    outside = tmp_path / "outside.h5"
    with h5py.File(outside, "w") as f:
        f["force"] = np.ones((6, 512))
    copy = writable_copy(path, tmp_path)
    with h5py.File(copy, "a") as f:
        layout = h5py.VirtualLayout(shape=(6, 512), dtype=np.float64)
        layout[:] = h5py.VirtualSource(str(outside), "force", shape=(6, 512))
        del f["entry/hits/force"]
        f["entry/hits"].create_virtual_dataset("force", layout)
    assert_refused(copy, "virtual")


def test_external_raw_storage_is_refused(sealed, tmp_path):
    _, path = sealed
    raw = tmp_path / "raw.bin"
    raw.write_bytes(np.ones(12).tobytes())
    copy = writable_copy(path, tmp_path)
    with h5py.File(copy, "a") as f:
        f["entry"].create_dataset("extra", shape=(12,), dtype="<f8", external=[(str(raw), 0, 96)])
    assert_refused(copy, "external raw")


def test_soft_link_is_refused(sealed, tmp_path):
    _, path = sealed
    copy = writable_copy(path, tmp_path)
    with h5py.File(copy, "a") as f:
        f["entry/loop"] = h5py.SoftLink("/entry")
    assert_refused(copy, "soft link")


def test_listing_shows_damaged_runs_with_their_error(sealed, tmp_path):
    run, path = sealed
    broken = damaged_copy(path, tmp_path, lambda d: d.__delitem__(slice(len(d) // 2, None)))
    listing = Store(tmp_path / "store").list()
    assert [s.run_id for s in listing] == sorted([run.run_id, broken.stem])
    by_id = {s.run_id: s for s in listing}
    assert by_id[run.run_id].error is None
    assert by_id[broken.stem].error
    assert "damaged" in by_id[broken.stem].error


@pytest.mark.parametrize("target", ["entry/hits/accepted", "entry/hits"])
def test_listing_never_follows_links_out(sealed, tmp_path, target):
    # The listing reads only a few objects; those must be checked just as strictly.
    _, path = sealed
    outside = tmp_path / "outside.h5"
    with h5py.File(outside, "w") as f:
        f.create_group("g")["accepted"] = np.ones(6, bool)
        f["accepted"] = np.ones(6, bool)
    copy = writable_copy(path, tmp_path)
    with h5py.File(copy, "a") as f:
        del f[target]
        f[target] = h5py.ExternalLink(str(outside), "/accepted" if target.endswith("accepted") else "/g")
    with pytest.raises(StoreError, match=r"ExternalLink|linked"):
        read_summary(copy)
    listed = {s.run_id: s for s in Store(tmp_path / "store").list()}
    assert "refused" in listed[copy.stem].error
