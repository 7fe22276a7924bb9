"""The summary attribute (/@summary_json) that listings read alone, and decoding a run
from bytes or only its hits (open_run_bytes, read_hits).

A listing trusts the attribute only when it is well-formed, names the file's run and
gives the file's size; anything else falls back to reading the run's data, as for
runs sealed before the attribute existed."""

from __future__ import annotations

import json
import os
import re
from dataclasses import replace
from pathlib import Path

import h5py
import numpy as np
import pytest

from daq.store import (
    NotARunError,
    Spectra,
    Store,
    StoreError,
    open_run,
    open_run_bytes,
    read_hits,
    read_summary,
    reader,
    seal,
    verify,
    writer,
)
from daq.store.layout import ATTR_SUMMARY
from daq.store.summary import SUMMARY_TYPES, parse_summary
from tests.store.store_helpers import add_hard_link_bomb, assert_same_run, make_frf, make_hits, make_run


def _attribute(path: Path) -> dict:
    with h5py.File(path, "r") as f:
        return json.loads(f.attrs[ATTR_SUMMARY].decode("utf-8"))


def _from_data(path: Path):
    return reader._summary_from_data(path, path.stat().st_size)


def _older_run(run, store: Path, monkeypatch) -> Path:
    """``run`` sealed as software from before the summary attribute sealed it."""
    with monkeypatch.context() as patch:
        patch.setattr(writer, "write_summary", lambda f, run: None)
        return seal(run, store)


def _rewrite(path: Path, text: str | bytes, width: int = 1024) -> None:
    """Replace the summary by ``text`` (the string "SIZE" in it becomes the file's final
    size, so that only the other checks can catch it)."""
    os.chmod(path, 0o644)
    dtype = h5py.string_dtype("utf-8", width)
    data = text if isinstance(text, bytes) else text.encode()
    with h5py.File(path, "r+") as f:
        f.attrs.create(ATTR_SUMMARY, np.array(data.replace(b"SIZE", b"0"), dtype=dtype))
    size = path.stat().st_size
    with h5py.File(path, "r+") as f:  # in place, same type: the size stays
        f.attrs.get_id(ATTR_SUMMARY).write(np.array(data.replace(b"SIZE", str(size).encode()), dtype=dtype))
    assert path.stat().st_size == size


def _fields_text(path: Path, **change) -> str:
    fields = {**_attribute(path), **change, "size_bytes": 123456789}
    return json.dumps(fields).replace("123456789", "SIZE")


RUNS = {
    "hits": lambda: make_run(hits=make_hits(5, 64)),
    "zoom hits": lambda: make_run(hits=make_hits(3, 32, zoom=True), note="ünïcødé — and a\nnewline"),
    "frf only": lambda: make_run(kind="imported", measured=make_frf()),
    "long note": lambda: make_run(hits=make_hits(2, 16), note="n" * 100_000),
    "spectra": lambda: replace(
        make_run(kind="imported", measured=make_frf()),
        spectra=Spectra(np.arange(1.0, 6.0), np.ones((1, 5)), ["power"], ["V^2"], ["p"]),
    ),
}


@pytest.mark.parametrize("name", list(RUNS))
def test_seal_writes_the_listing_line_and_the_final_size(tmp_path, name):
    path = seal(RUNS[name](), tmp_path)
    stored = _attribute(path)
    assert set(stored) == set(SUMMARY_TYPES)
    assert stored["size_bytes"] == path.stat().st_size
    assert read_summary(path) == _from_data(path)  # the same line either way
    assert verify(path) == []


def test_listing_reads_only_the_attribute(tmp_path, monkeypatch):
    store = Store(tmp_path)
    for k in range(3):
        store.seal(make_run(hits=make_hits(k + 2, 16), note=f"run {k}"))
    want = [_from_data(p) for p in sorted(tmp_path.glob("*.h5"))]
    monkeypatch.setattr(reader, "_summary_from_data", lambda path, size: pytest.fail("read the data"))
    assert store.list() == want


def test_older_runs_without_the_attribute_list_and_verify_as_before(tmp_path, monkeypatch):
    run = make_run(hits=make_hits(4, 32))
    path = _older_run(run, tmp_path / "store", monkeypatch)
    with h5py.File(path, "r") as f:
        assert ATTR_SUMMARY not in f.attrs
    [listed] = Store(tmp_path / "store").list()
    assert listed == _from_data(path)
    assert (listed.n_hits, listed.n_accepted, listed.error) == (4, 3, None)
    assert verify(path) == []
    assert_same_run(open_run(path), run)


FORGERIES = {
    "not JSON": "{not json SIZE",
    "a list": '["SIZE"]',
    "a key missing": lambda p: _fields_text(p, note=None).replace(', "note": null', ""),
    "a key more": lambda p: _fields_text(p, extra=1),
    "a bool for a count": lambda p: _fields_text(p, n_hits=True),
    "a float for a count": lambda p: _fields_text(p, n_hits=4.0),
    "a text for a bool": lambda p: _fields_text(p, complete="yes"),
    "more accepted than hits": lambda p: _fields_text(p, n_accepted=99),
    "negative counts": lambda p: _fields_text(p, n_hits=-1, n_accepted=-2),
    "counts beyond the limit": lambda p: _fields_text(p, n_hits=10**9, n_accepted=0),
    "another run": lambda p: _fields_text(p, run_id="20200101T000000.000Z-00000000"),
    "not a run id": lambda p: _fields_text(p, run_id="../../etc/passwd"),
    "an unknown kind": lambda p: _fields_text(p, kind="forged"),
    "a time that is no time": lambda p: _fields_text(p, start_time="yesterday"),
    "NaN": lambda p: _fields_text(p, n_hits=1234321).replace("1234321", "NaN"),
    "not UTF-8": b'{"note": "\xff\xfe" SIZE}',
}


@pytest.mark.parametrize("forgery", list(FORGERIES))
def test_a_malformed_summary_is_never_trusted(tmp_path, forgery):
    path = seal(make_run(hits=make_hits(4, 32), note="the real note"), tmp_path)
    text = FORGERIES[forgery]
    _rewrite(path, text(path) if callable(text) else text)
    assert read_summary(path) == _from_data(path)
    [listed] = Store(tmp_path).list()
    assert (listed.note, listed.n_hits, listed.error) == ("the real note", 4, None)
    [problem] = verify(path)
    assert ATTR_SUMMARY in problem
    assert "\n" not in problem


def test_a_summary_of_another_size_is_not_trusted(tmp_path):
    """An edit after sealing (here: the note rewritten by hand) changes the size."""
    path = seal(make_run(hits=make_hits(4, 32)), tmp_path)
    text = _fields_text(path, note="forged").replace("SIZE", "1000")
    _rewrite(path, text)
    assert read_summary(path).note != "forged"
    assert "size_bytes 1000 there" in verify(path)[0]


@pytest.mark.parametrize("kind", ["variable-length", "array", "number", "too long"])
def test_a_summary_of_another_type_is_not_read(tmp_path, kind):
    path = seal(make_run(hits=make_hits(4, 32), note="the real note"), tmp_path)
    text = _fields_text(path, note="forged").replace("SIZE", str(path.stat().st_size))
    os.chmod(path, 0o644)
    with h5py.File(path, "r+") as f:
        del f.attrs[ATTR_SUMMARY]
        if kind == "variable-length":
            f.attrs.create(ATTR_SUMMARY, text, dtype=h5py.string_dtype())
        elif kind == "array":
            f.attrs.create(ATTR_SUMMARY, np.array([text.encode()] * 2))
        elif kind == "number":
            f.attrs.create(ATTR_SUMMARY, 7)
        else:
            f.attrs.create(ATTR_SUMMARY, np.array(b"x", dtype=h5py.string_dtype("utf-8", 2 * 2**20)))
    assert read_summary(path).note == "the real note"
    assert ATTR_SUMMARY in verify(path)[0]


def test_a_consistent_summary_that_disagrees_with_the_data_is_a_verify_problem(tmp_path):
    path = seal(make_run(hits=make_hits(4, 32), note="the real note"), tmp_path)
    _rewrite(path, _fields_text(path, note="forged", n_accepted=1))
    # Well-formed, this run's, this size: a listing shows it; verify finds it out.
    assert read_summary(path).note == "forged"
    [problem] = verify(path)
    assert "disagrees with the run" in problem
    assert "n_accepted 1 there, 3 in the file" in problem
    assert "note 'forged' there, 'the real note' in the file" in problem


def test_the_summary_does_not_hide_a_newer_schema(tmp_path):
    path = seal(make_run(hits=make_hits(2, 16)), tmp_path)
    os.chmod(path, 0o644)
    with h5py.File(path, "r+") as f:
        f.attrs["schema_version"] = np.int64(99)
    with pytest.raises(StoreError, match="newer than this software reads"):
        read_summary(path)


def test_parse_summary_checks_names_and_sizes():
    fields = {
        "run_id": "20261123T101503.123Z-3f9c1a2b",
        "start_time": "2026-11-23T10:15:03.123Z",
        "kind": "captured",
        "complete": False,
        "n_hits": 3,
        "n_accepted": 2,
        "operator": "",
        "note": "",
        "size_bytes": 4096,
    }
    text = json.dumps(fields)
    assert parse_summary(text, run_id=fields["run_id"], size_bytes=4096) == fields
    with pytest.raises(ValueError, match="the file is"):
        parse_summary(text, run_id="20261123T101503.123Z-3f9c1a2c")
    with pytest.raises(ValueError, match="it has 4097"):
        parse_summary(text, size_bytes=4097)


# --- open_run_bytes and read_hits -------------------------------------------------------


def test_open_run_bytes_decodes_as_open_run(tmp_path):
    run = make_run(hits=make_hits(3, 64), analyzer=make_frf())
    path = seal(run, tmp_path)
    data = path.read_bytes()
    for form in (data, bytearray(data), memoryview(data)):
        assert_same_run(open_run_bytes(form, str(path)), run)


def test_damaged_bytes_are_refused_in_one_line(tmp_path):
    data = seal(make_run(), tmp_path).read_bytes()
    for broken in (data[: len(data) // 2], b"not HDF5 at all", b""):
        with pytest.raises(StoreError) as caught:
            open_run_bytes(broken, "sent.h5")
        assert "\n" not in str(caught.value)
        assert str(caught.value).startswith("sent.h5: damaged or not an HDF5 run file (")
    with pytest.raises(StoreError, match="a run's bytes are needed"):
        open_run_bytes("a path, not bytes", "x")  # type: ignore[arg-type]


def test_open_run_bytes_keeps_the_refusals_of_open_run(tmp_path):
    bomb = add_hard_link_bomb(seal(make_run(), tmp_path / "a"))
    with pytest.raises(StoreError, match=r"30 names \(hard links\); refused"):
        open_run_bytes(bomb.read_bytes(), "bomb.h5")
    linked = seal(make_run(), tmp_path / "b")
    os.chmod(linked, 0o644)
    with h5py.File(linked, "r+") as f:
        f["entry/elsewhere"] = h5py.ExternalLink("/etc/hostname", "/")
    with pytest.raises(StoreError, match="external link"):
        open_run_bytes(linked.read_bytes(), "linked.h5")
    run = make_run(hits=make_hits(2, 16))
    run.hits.force_n[0, 0] = np.nan
    nan = seal(run, tmp_path / "c").read_bytes()
    assert np.isnan(open_run_bytes(nan, "nan.h5").hits.force_n[0, 0])
    with pytest.raises(StoreError, match=r"^nan\.h5: dataset /entry/hits/force holds 1 NaN"):
        open_run_bytes(nan, "nan.h5", require_finite=True)


def test_read_hits_reads_the_records_checked_as_a_whole_run(tmp_path):
    run = make_run(hits=make_hits(4, 64, zoom=True))
    path = seal(run, tmp_path)
    hits = read_hits(path)
    assert np.array_equal(hits.force_n, run.hits.force_n)
    assert np.array_equal(hits.accepted, run.hits.accepted)
    assert (hits.sample_rate_hz, hits.start_s, hits.center_hz) == (400.0, -0.0125, 1234.5)

    frf_only = seal(make_run(kind="imported", measured=make_frf()), tmp_path)
    with pytest.raises(StoreError, match="holds no time records to replay") as caught:
        read_hits(frf_only)
    assert not isinstance(caught.value, NotARunError)
    assert str(caught.value).startswith(f"{frf_only}: run {frf_only.stem} ")


def test_read_hits_tells_other_hdf5_files_from_damaged_runs(tmp_path):
    minimal = tmp_path / "minimal.h5"
    with h5py.File(minimal, "w") as f:
        f["entry/hits/force"] = np.zeros((1, 1024))
    with pytest.raises(NotARunError, match=f"^{re.escape(str(minimal))}: not a run file"):
        read_hits(minimal)
    with h5py.File(minimal, "a") as f:
        f["entry/outside"] = h5py.ExternalLink("/etc/hostname", "/")
    with pytest.raises(StoreError, match="external link") as caught:
        read_hits(minimal)  # refused before anything else is looked at
    assert not isinstance(caught.value, NotARunError)
    garbage = tmp_path / "garbage.h5"
    garbage.write_bytes(b"nothing like HDF5")
    with pytest.raises(StoreError, match="damaged or not an HDF5 run file") as caught:
        read_hits(garbage)
    assert not isinstance(caught.value, NotARunError)
    with pytest.raises(StoreError, match="no such run file"):
        read_hits(tmp_path / "absent.h5")


def test_a_file_without_the_hdf5_signature_is_said_so_in_plain_words(tmp_path):
    path = tmp_path / "table.csv"
    path.write_text("t,F,a\n0,1,2\n")
    with pytest.raises(StoreError) as caught:
        open_run(path)
    assert str(caught.value).endswith("damaged or not an HDF5 run file (no HDF5 signature at its start)")
