"""Hostile run files: small on disk, ruinous to read naively; every command must refuse them
with one line, in bounded time and memory (issue items 8, 9 and 13, store part).

Each builder seals a sound run into ``store`` and then edits it with h5py, so the
file carries a valid schema, ids and checksums: only the hostile part is wrong.
Also the real CLI under an address-space limit, so that a regression fails the
test with a MemoryError or a timeout instead of taking the machine down.
"""

from __future__ import annotations

import json
import os
import resource
import shutil
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

from daq.store import Store, open_run, seal, verify
from daq.store.h5io import refuse_outside_references
from tests.store.store_helpers import add_hard_link_bomb, make_run

DAQ = Path(sys.executable).with_name("daq")
#: Address-space limit of the CLI under test: the sound run needs well under half of it.
LIMIT_BYTES = 1536 * 2**20


def sound_run(store: Path, n_hits: int = 3, n_samples: int = 64) -> Path:
    return seal(make_run(n_hits=n_hits, n_samples=n_samples), store)


def hard_link_bomb(store: Path, fan_out: int = 30, depth: int = 7) -> Path:
    """A sound run turned into the hard-link bomb (store_helpers.add_hard_link_bomb)."""
    return add_hard_link_bomb(sound_run(store), fan_out, depth)


def _filtered(group: h5py.Group, name: str, shape: tuple[int, ...], dtype, chunks: tuple[int, ...]):
    if name in group:
        del group[name]
    return group.create_dataset(
        name, shape=shape, dtype=dtype, chunks=chunks, compression="gzip", shuffle=True, fletcher32=True
    )


def declared_bool_bomb(store: Path, count: int = 2_000_000_000) -> Path:
    """/entry/hits/accepted declares ``count`` booleans and holds none (fill value)."""
    path = sound_run(store)
    with h5py.File(path, "r+") as f:
        _filtered(f["entry/hits"], "accepted", (count,), bool, (1_000_000,))
    return path


def gzip_bomb(store: Path, n_bytes: int = 1700 * 2**20) -> Path:
    """/entry/hits/force replaced by ~``n_bytes`` of zeros really written (compressed
    to a few MB), shaped (3, n): every chunk is there and every checksum is right."""
    path = sound_run(store)
    row = 2**20  # float64 per chunk: 8 MiB
    per_hit = max(1, n_bytes // (3 * 8 * row)) * row
    with h5py.File(path, "r+") as f:
        dset = _filtered(f["entry/hits"], "force", (3, per_hit), np.float64, (1, row))
        dset[0, :row] = np.zeros(row)
        raw = dset.id.read_direct_chunk((0, 0))[1]
        for i in range(3):
            for j in range(0, per_hit, row):
                if (i, j) != (0, 0):
                    dset.id.write_direct_chunk((i, j), raw)
    return path


def nan_run(store: Path) -> Path:
    """A sound file whose records hold NaN and infinity (sealed as is: the model allows them)."""
    run = make_run(n_hits=3, n_samples=64)
    run.hits.force_n[1, 5] = np.nan
    run.hits.response_m_s2[2, 7] = np.inf
    return seal(run, store)


def run_limited(*args: str, timeout: float = 60, limit: int = LIMIT_BYTES, **kwargs):
    """The real `daq` console script under RLIMIT_AS = ``limit``, with a timeout."""

    def cap() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))

    env = {**os.environ, "COLUMNS": "200", "NO_COLOR": "1"}
    env.pop("DAQ_DEBUG", None)
    return subprocess.run(
        [str(DAQ), *args],
        capture_output=True,
        text=True,
        timeout=timeout,
        env=env,
        preexec_fn=cap,
        **kwargs,
    )


BOMBS = {
    "hard links": (hard_link_bomb, "30 names (hard links)"),
    "declared booleans": (declared_bool_bomb, "declares 2000000000 bytes"),
    "gzip bomb": (gzip_bomb, "/entry/hits/force declares"),
}


@pytest.fixture(params=list(BOMBS), ids=list(BOMBS))
def bomb(request, tmp_path):
    build, words = BOMBS[request.param]
    store = tmp_path / "store"
    store.mkdir()
    return store, build(store), words


def _one_line(result, *fragments):
    lines = result.stderr.splitlines()
    assert result.returncode not in (0, 70), result
    assert len(lines) == 1, result.stderr[-2000:]
    assert lines[0].startswith("daq: error: "), lines[0]
    for fragment in fragments:
        assert fragment in lines[0], lines[0]


@pytest.mark.timeout(30)  # "at once": a walk of the 30^7 paths, or a 2 GB inflate, never ends in time
def test_the_library_refuses_each_bomb_at_once(bomb):
    store, path, words = bomb
    problems = verify(path)
    assert len(problems) == 1, problems
    assert words in problems[0], problems
    with pytest.raises(Exception, match="refused"):
        open_run(path)
    [summary] = Store(store).list()
    assert words in (summary.error or "")


def test_runs_verify_and_show_refuse_each_bomb_in_bounded_memory(bomb):
    store, path, words = bomb
    result = run_limited("runs", "verify", "--store", str(store))
    assert result.returncode == 1, result.stderr
    assert f"PROBLEM  {path.stem}: " in result.stdout, result.stdout
    assert words in result.stdout, result.stdout
    _one_line(run_limited("runs", "show", path.stem, "--store", str(store)), path.name, words)


def test_runs_list_names_each_bomb_damaged_in_bounded_memory(bomb):
    store, path, words = bomb
    result = run_limited("runs", "list", "--json", "--store", str(store))
    assert result.returncode == 0, result.stderr[-2000:]
    [row] = json.loads(result.stdout)
    assert row["file"] == path.name, row
    assert words in (row["error"] or ""), row


def test_import_and_analyze_refuse_each_bomb_in_bounded_memory(bomb, tmp_path):
    store, path, words = bomb
    other = tmp_path / "other"
    _one_line(run_limited("import", str(path), "--format", "run", "--store", str(other)), words)
    assert not other.exists() or not list(other.glob("*.h5"))
    _one_line(run_limited("analyze", path.stem, "--store", str(store)), words)


def test_the_link_walk_visits_each_object_once_and_refuses_second_names(tmp_path):
    path = tmp_path / "links.h5"
    with h5py.File(path, "w") as f:
        f.create_group("a/b")
        f["c"] = f["a/b"]  # one group, two names
    with h5py.File(path, "r") as f, pytest.raises(Exception, match="2 names"):
        refuse_outside_references(f)


def test_counts_must_agree_before_anything_is_read(tmp_path):
    path = sound_run(tmp_path)
    with h5py.File(path, "r+") as f:
        _filtered(f["entry/hits"], "accepted", (4,), bool, (4,))[...] = True  # the run has 3 hits
    [summary] = Store(tmp_path).list()
    assert "accepted has shape (4,), the run's counts say (3,)" in summary.error
    assert "accepted has shape (4,)" in verify(path)[0]


def test_nan_and_infinity_are_verify_problems_and_refused_at_import(tmp_path):
    path = nan_run(tmp_path)
    problems = verify(path)
    assert len(problems) == 2, problems
    assert "/entry/hits/force holds 1 NaN or infinite value(s), first at index (1, 5)" in problems[0]
    assert "/entry/hits/response" in problems[1]
    assert np.isnan(open_run(path).hits.force_n[1, 5])  # still readable, for a look at it
    with pytest.raises(Exception, match="NaN or infinite"):
        open_run(path, require_finite=True)


def test_a_run_under_another_file_name_is_listed_as_misnamed(tmp_path):
    store = tmp_path / "store"
    store.mkdir()
    path = sound_run(store)
    other = store / "20200101T000000.000Z-00000000.h5"
    shutil.move(path, other)
    [summary] = Store(store).list()
    assert summary.file_name == other.name
    assert f"holds run {path.stem!r}" in (summary.error or "")
    assert "misnamed" in verify(other)[0]


def test_leftover_temporaries_are_reported_and_repair_removes_them(tmp_path):
    from daq.store.verify import leftover_temporaries, remove_temporaries

    run = sound_run(tmp_path)
    crashed = [tmp_path / f".{run.name}.tmp-123-abcd1234", tmp_path / ".export.csv.k3j2.tmp"]
    fresh = tmp_path / f".{run.name}.tmp-456-00000000"  # a seal in progress
    for path in [*crashed, fresh]:
        path.write_bytes(b"partial")
    for path in crashed:
        os.utime(path, (time.time() - 7200,) * 2)
    assert leftover_temporaries(tmp_path) == sorted(crashed)
    assert remove_temporaries(tmp_path) == sorted(crashed)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([run.name, fresh.name])
    assert leftover_temporaries(tmp_path) == []
