"""Store.list() and Store.resolve(): right with or without the index cache, with
vanished, touched and damaged files, and with four processes sealing at once."""

from __future__ import annotations

import os
import sqlite3
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from daq.store import Store, StoreError, open_run, seal, verify
from tests.store.store_helpers import make_hits, make_run

HERE = Path(__file__).parent
EXAMPLE_IDS = [
    "20261123T101503.123Z-3f9c1a2b",
    "20261123T101503.123Z-3f9c1a2c",
    "20261123T111503.000Z-00000000",
    "20261124T080000.500Z-abcdef01",
]


@pytest.fixture
def four_runs(tmp_path):
    store = Store(tmp_path / "store")
    for k, run_id in enumerate(EXAMPLE_IDS):
        store.seal(make_run(run_id=run_id, hits=make_hits(k + 1, 32), note=f"run {k}"))
    return store


def _expected(store: Store) -> list[tuple]:
    # What the files say, read one by one without the store's listing code.
    out = []
    for path in sorted(store.path.glob("*.h5")):
        if path.name.count(".") != 2:
            continue  # result files
        run = open_run(path)
        out.append((run.run_id, run.note, run.hits.n_hits, int(run.hits.accepted.sum()), path.stat().st_size))
    return out


def _listed(store: Store) -> list[tuple]:
    return [(s.run_id, s.note, s.n_hits, s.n_accepted, s.size_bytes) for s in store.list()]


def test_listing_matches_the_files(four_runs):
    listing = four_runs.list()
    assert [s.run_id for s in listing] == EXAMPLE_IDS
    assert [s.n_hits for s in listing] == [1, 2, 3, 4]
    assert [s.n_accepted for s in listing] == [1, 1, 2, 3]  # make_hits rejects the last of several
    assert _listed(four_runs) == _expected(four_runs)
    assert all(s.kind == "simulated" and s.complete and s.operator == "Ada Lovelace" for s in listing)


def test_empty_and_missing_store(tmp_path):
    assert Store(tmp_path / "never-created").list() == []
    assert Store(tmp_path).list() == []


def test_listing_ignores_everything_but_run_files(four_runs):
    folder = four_runs.path
    for name in [
        ".20261123T101503.123Z-3f9c1a2b.h5.tmp-123-abcd",
        "20261123T101503.123Z-3f9c1a2b.fit.h5",
        "notes.txt",
        "20261123T101503.123Z-3F9C1A2B.h5",
        "x.h5",
    ]:
        (folder / name).write_bytes(b"junk")
    (folder / "20261125T000000.000Z-11111111.h5").mkdir()  # a folder named like a run: not a file...
    listing = four_runs.list()
    assert [s.run_id for s in listing if s.error is None] == EXAMPLE_IDS
    assert [s.run_id for s in listing if s.error] == ["20261125T000000.000Z-11111111"]  # ...so an error


def test_index_is_only_a_cache(four_runs):
    index = four_runs.path / ".index.sqlite"
    expected = _expected(four_runs)
    assert _listed(four_runs) == expected
    assert index.is_file()
    index.unlink()
    assert _listed(four_runs) == expected
    index.write_bytes(b"this is not a database at all" * 100)
    assert _listed(four_runs) == expected
    assert index.read_bytes()[:15] == b"SQLite format 3"  # rebuilt
    # Rows of the right shape but wrong types are refused too.
    with sqlite3.connect(index) as db:
        db.execute("UPDATE runs SET n_hits = 'many'")
    assert _listed(four_runs) == expected


def test_index_follows_file_changes(four_runs):
    four_runs.list()
    vanished = four_runs.path / f"{EXAMPLE_IDS[0]}.h5"
    vanished.unlink()
    # A run replaced under the same name (size and mtime change): re-read, not trusted.
    replaced = four_runs.path / f"{EXAMPLE_IDS[1]}.h5"
    replaced.unlink()
    seal(make_run(run_id=EXAMPLE_IDS[1], hits=make_hits(9, 64), note="replaced"), four_runs.path)
    os.utime(replaced, ns=(1, 1))
    listing = four_runs.list()
    assert [s.run_id for s in listing] == EXAMPLE_IDS[1:]
    assert (listing[0].note, listing[0].n_hits) == ("replaced", 9)
    with sqlite3.connect(four_runs.path / ".index.sqlite") as db:
        names = sorted(row[0] for row in db.execute("SELECT file_name FROM runs"))
    assert names == [f"{i}.h5" for i in EXAMPLE_IDS[1:]]


def test_locked_index_is_bypassed(four_runs, monkeypatch):
    import daq.store.index as index_module

    monkeypatch.setattr(index_module, "_BUSY_TIMEOUT_S", 0.2)
    expected = _expected(four_runs)
    four_runs.list()
    inode = (four_runs.path / ".index.sqlite").stat().st_ino
    holder = sqlite3.connect(four_runs.path / ".index.sqlite", isolation_level=None)
    holder.execute("PRAGMA locking_mode=EXCLUSIVE")
    holder.execute("BEGIN EXCLUSIVE")
    holder.execute("DELETE FROM runs")
    try:
        assert _listed(four_runs) == expected
    finally:
        holder.execute("ROLLBACK")
        holder.close()
    assert (four_runs.path / ".index.sqlite").stat().st_ino == inode  # locked is not corrupt: kept
    assert _listed(four_runs) == expected


def test_read_only_store_lists_without_index(four_runs):
    os.chmod(four_runs.path, 0o555)
    try:
        if os.access(four_runs.path, os.W_OK):
            pytest.skip("running as root: permissions are not enforced")
        assert _listed(four_runs) == _expected(four_runs)
    finally:
        os.chmod(four_runs.path, 0o755)


def test_resolve_by_id_and_prefix(four_runs):
    folder = four_runs.path
    assert four_runs.resolve(EXAMPLE_IDS[2]) == folder / f"{EXAMPLE_IDS[2]}.h5"
    assert four_runs.resolve(EXAMPLE_IDS[2] + ".h5") == folder / f"{EXAMPLE_IDS[2]}.h5"
    assert four_runs.resolve("20261124") == folder / f"{EXAMPLE_IDS[3]}.h5"
    assert four_runs.resolve("20261123T1115") == folder / f"{EXAMPLE_IDS[2]}.h5"
    assert four_runs.open("20261124").note == "run 3"
    assert four_runs.verify("20261124") == []
    with pytest.raises(StoreError, match="matches 2 runs"):
        four_runs.resolve("20261123T101503.123Z-3f9c1a2")
    with pytest.raises(StoreError, match="no run matches"):
        four_runs.resolve("2027")
    for bad in ("../20261124", "", "2026/11", "*"):
        with pytest.raises(StoreError, match="invalid run id"):
            four_runs.resolve(bad)


CONCURRENT_CHILD = textwrap.dedent(
    """
    import sys, time
    from store_helpers import make_run
    from daq.store import Store
    store, me, start_at = Store(sys.argv[1]), sys.argv[2], float(sys.argv[3])
    while time.time() < start_at:
        time.sleep(0.001)
    for i in range(25):
        run = make_run(note=f"{me} run {i}", seed=i, n_hits=3, n_samples=512)
        store.seal(run)
        print(run.run_id, flush=True)
        store.list()  # listing while the others seal: the index must cope
    """
)


@pytest.mark.slow
def test_four_processes_sealing_into_one_store(tmp_path):
    folder = tmp_path / "store"
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(HERE), env.get("PYTHONPATH", "")])
    start_at = time.time() + 2.0
    children = [
        subprocess.Popen(
            [sys.executable, "-c", CONCURRENT_CHILD, str(folder), f"proc{k}", str(start_at)],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=env,
        )
        for k in range(4)
    ]
    sealed: dict[str, str] = {}
    for k, child in enumerate(children):
        out, err = child.communicate(timeout=100)
        assert child.returncode == 0, err
        assert err == ""
        for i, run_id in enumerate(out.split()):
            sealed[run_id] = f"proc{k} run {i}"
    assert len(sealed) == 100
    listing = Store(folder).list()
    assert [s.run_id for s in listing] == sorted(sealed)
    for summary in listing:
        assert summary.note == sealed[summary.run_id]  # nobody's run was replaced by another's
        assert verify(folder / summary.file_name) == []


def test_thousand_runs_listed_correctly(tmp_path):
    folder = tmp_path / "store"
    ids = []
    for i in range(1000):
        run = make_run(hits=make_hits(1 + i % 3, 8, seed=i), note=f"n{i}")
        seal(run, folder)
        ids.append(run.run_id)
    store = Store(folder)
    for _ in range(2):  # cold (building the index), then warm (from the index)
        listing = store.list()
        assert [s.run_id for s in listing] == sorted(ids)
        by_id = {s.run_id: s for s in listing}
        for i, run_id in enumerate(ids):
            assert by_id[run_id].note == f"n{i}"
            assert by_id[run_id].n_hits == 1 + i % 3
