"""Sealing never overwrites, never leaves a half-written file visible, and fails with
one StoreError (full disk included); results are sealed beside their run the same way."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from daq.cli.errors import UserError, exit_code_and_message
from daq.store import Store, StoreError, open_run, read_result, seal, write_result
from tests.store.store_helpers import make_hits, make_run

HERE = Path(__file__).parent


def child_env() -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(HERE), env.get("PYTHONPATH", "")])
    return env


def test_store_error_is_the_stores_own_with_one_line():
    error = StoreError("first line\nsecond line")
    # The store's own error, which the command line maps (daq/cli/errors.py).
    assert not isinstance(error, UserError)
    assert exit_code_and_message(error) == (1, "first line second line")
    assert str(error) == "first line second line"


def test_sealing_twice_refuses_and_keeps_the_first(tmp_path):
    run = make_run(note="the first")
    path = seal(run, tmp_path)
    before = path.read_bytes()
    again = make_run(run_id=run.run_id, note="the second", seed=3)
    with pytest.raises(StoreError, match="already exists"):
        seal(again, tmp_path)
    assert path.read_bytes() == before
    assert open_run(path).note == "the first"
    assert sorted(p.name for p in tmp_path.iterdir()) == [path.name]


def test_sealing_refuses_even_when_the_name_appears_during_the_write(tmp_path, monkeypatch):
    # The pre-check passes, then another process publishes the same id while we write:
    # the link() step must still refuse rather than replace.
    import daq.store.writer as writer

    run = make_run(note="ours")
    final = tmp_path / f"{run.run_id}.h5"
    original_fill = writer.encode_run

    def fill_then_race(f, r):
        original_fill(f, r)
        final.write_bytes(b"theirs")

    monkeypatch.setattr(writer, "encode_run", fill_then_race)
    with pytest.raises(StoreError, match="already exists"):
        seal(run, tmp_path)
    assert final.read_bytes() == b"theirs"
    assert sorted(p.name for p in tmp_path.iterdir()) == [final.name]  # temporary removed


RACE_CHILD = textwrap.dedent(
    """
    import sys, time
    from store_helpers import make_run
    from daq.store import StoreError, seal
    store, run_id, me, start_at = sys.argv[1], sys.argv[2], sys.argv[3], float(sys.argv[4])
    run = make_run(run_id=run_id, note=me, n_hits=20, n_samples=2048)
    while time.time() < start_at:
        pass
    try:
        seal(run, store)
        print("sealed")
    except StoreError as exc:
        print("refused", exc)
    """
)


def test_racing_processes_with_one_id_exactly_one_wins(tmp_path):
    import time

    run_id = "20261123T101503.123Z-3f9c1a2b"
    start_at = time.time() + 1.5
    children = [
        subprocess.Popen(
            [sys.executable, "-c", RACE_CHILD, str(tmp_path), run_id, f"proc{k}", str(start_at)],
            stdout=subprocess.PIPE,
            text=True,
            env=child_env(),
        )
        for k in range(4)
    ]
    outputs = [c.communicate(timeout=60)[0] for c in children]
    assert all(c.returncode == 0 for c in children), outputs
    winners = [k for k, out in enumerate(outputs) if out.startswith("sealed")]
    assert len(winners) == 1, outputs
    assert all("already exists" in out for k, out in enumerate(outputs) if k != winners[0])
    assert open_run(tmp_path / f"{run_id}.h5").note == f"proc{winners[0]}"
    assert [p.name for p in tmp_path.iterdir()] == [f"{run_id}.h5"]


def test_seal_creates_the_store_folder(tmp_path):
    path = seal(make_run(), tmp_path / "a" / "b")
    assert path.parent == tmp_path / "a" / "b"
    assert path.is_file()


def test_seal_into_a_file_is_one_error(tmp_path):
    blocker = tmp_path / "not-a-folder"
    blocker.write_text("x")
    with pytest.raises(StoreError, match="not-a-folder"):
        seal(make_run(), blocker)


def test_seal_refuses_what_is_not_a_run(tmp_path):
    with pytest.raises(StoreError, match="needs a Run"):
        seal({"run_id": "x"}, tmp_path)


FULL_DISK_CHILD = textwrap.dedent(
    """
    import resource, signal, sys
    from store_helpers import make_run
    from daq.store import StoreError, seal
    run = make_run(n_hits=50, n_samples=4096)
    # A file-size limit makes every write past 64 KiB fail with EFBIG, as a full
    # disk fails with ENOSPC: same code path, no special filesystem needed.
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (65536, 65536))
    try:
        seal(run, sys.argv[1])
    except StoreError as exc:
        print("StoreError:", exc)
    """
)


def test_a_full_disk_gives_one_error_and_leaves_nothing(tmp_path):
    result = subprocess.run(
        [sys.executable, "-c", FULL_DISK_CHILD, str(tmp_path)],
        capture_output=True,
        text=True,
        env=child_env(),
        timeout=60,
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith("StoreError: cannot write run ")
    assert len(result.stdout.strip().splitlines()) == 1
    assert list(tmp_path.iterdir()) == []  # neither a run nor a temporary


# --- results ---------------------------------------------------------------------


def test_result_round_trip(tmp_path):
    run = make_run()
    seal(run, tmp_path)
    payload = {
        "natural_frequency_hz": np.array([27.1, 170.2, 476.5]),
        "damping_ratio": np.array([0.0021, 0.0018, 0.0011]),
        "residues": np.array([1 + 2j, 3 - 4j]),
        "mask": np.array([[True, False], [False, True]]),
        "counts": np.arange(5, dtype=np.int32),
        "method": "circle fit",
        "settings": {"bands_hz": [[20, 35], [150, 190]], "window": None},
        "n_modes": 3,
    }
    path = write_result(tmp_path, run.run_id, "modal-fit", payload)
    assert path.name == f"{run.run_id}.modal-fit.h5"
    assert path.stat().st_mode & 0o777 == 0o444
    got = read_result(tmp_path, run.run_id, "modal-fit")
    assert set(got) == set(payload)
    for key, value in payload.items():
        if isinstance(value, np.ndarray):
            assert got[key].dtype == value.dtype
            assert got[key].tobytes() == value.tobytes()
        else:
            assert got[key] == value
    # The result file is not a run: listing still shows one run.
    assert [s.run_id for s in Store(tmp_path).list()] == [run.run_id]


def test_result_overwrite_policy(tmp_path):
    run = make_run()
    seal(run, tmp_path)
    write_result(tmp_path, run.run_id, "fit", {"a": 1})
    with pytest.raises(StoreError, match="already exists"):
        write_result(tmp_path, run.run_id, "fit", {"a": 2})
    assert read_result(tmp_path, run.run_id, "fit") == {"a": 1}
    write_result(tmp_path, run.run_id, "fit", {"a": 3}, overwrite=True)
    assert read_result(tmp_path, run.run_id, "fit") == {"a": 3}
    assert len(list(tmp_path.iterdir())) == 2


@pytest.mark.parametrize(
    ("name", "payload", "message"),
    [
        ("Fit", {}, "invalid result name"),
        ("a.b", {}, "invalid result name"),
        ("../x", {}, "invalid result name"),
        ("fit", {"a/b": 1}, "invalid result key"),
        ("fit", {"x": np.array([])}, "non-empty"),
        ("fit", {"x": np.array(["a"])}, "numbers"),
        ("fit", {"x": [np.float32(1)]}, "JSON"),
        ("fit", [1, 2], "dict"),
    ],
)
def test_result_refuses_bad_input(tmp_path, name, payload, message):
    run = make_run()
    seal(run, tmp_path)
    with pytest.raises(StoreError, match=message):
        write_result(tmp_path, run.run_id, name, payload)


def test_result_needs_its_run(tmp_path):
    with pytest.raises(StoreError, match="needs its run"):
        write_result(tmp_path, "20261123T101503.123Z-3f9c1a2b", "fit", {"a": 1})
    with pytest.raises(StoreError, match="no result"):
        read_result(tmp_path, "20261123T101503.123Z-3f9c1a2b", "fit")


def test_large_run_round_trips(tmp_path):
    # Big enough that records are chunked hit by hit.
    run = make_run(hits=make_hits(40, 8192))
    got = open_run(seal(run, tmp_path))
    assert got.hits.force_n.tobytes() == run.hits.force_n.tobytes()
