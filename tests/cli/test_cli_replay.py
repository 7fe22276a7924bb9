"""`daq replay`: stored runs served by the simulator's replay mode and captured again
through the driver over a real TCP socket, into new runs equal bit for bit.

The originals come from `daq capture --sim` (baseband and zoom) or are built by hand
(an imported run with no instrument settings, an incomplete run whose last hits were
rejected); the comparison reads both files here with h5py, not through our reader.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import h5py
import numpy as np
import pytest

from daq.store import Hits, Store, seal
from tests.cli_helpers import assert_one_line_error, invoke_daq
from tests.store.store_helpers import make_frf, make_run

RAW = ("force", "response", "time", "accepted", "reject_reason", "overload")


def capture(store: Path, *extra: str) -> str:
    result = invoke_daq("capture", "--sim", "--yes", "--store", str(store), *extra)
    assert result.returncode == 0, result.stderr
    (run,) = Store(store).list()
    return run.run_id


def replay(store: Path, *names: str):
    return invoke_daq("replay", "--store", str(store), *names)


def new_runs(store: Path, known: set[str]) -> list[str]:
    return [s.run_id for s in Store(store).list() if s.run_id not in known]


def raw(path: Path) -> dict[str, bytes | tuple]:
    """The bytes and shape of every raw-data dataset of a run file, read with h5py."""
    with h5py.File(path, "r") as f:
        out = {}
        for name in RAW:
            data = f[f"entry/hits/{name}"][()]
            out[name] = (data.dtype.str, data.shape, np.asarray(data).tobytes())
        for name in ("sample_rate_hz", "start_s", "center_hz"):
            out[name] = np.float64(f["entry/hits"].attrs[name]).tobytes()
        return out


def entry(path: Path) -> dict:
    with h5py.File(path, "r") as f:
        attrs = {k: v.decode() if isinstance(v, bytes) else v for k, v in f["entry"].attrs.items()}
    attrs["provenance"] = json.loads(attrs.pop("provenance_json"))
    return attrs


def assert_replayed(store: Path, original_id: str, new_id: str) -> None:
    a, b = store / f"{original_id}.h5", store / f"{new_id}.h5"
    assert raw(b) == raw(a)
    info = entry(b)
    assert info["kind"] == "replayed"
    source = info["provenance"]["replayed_from"]
    assert source["run_id"] == original_id
    assert source["sha256"] == hashlib.sha256(a.read_bytes()).hexdigest()


@pytest.mark.timeout(60)
def test_a_simulated_run_with_rejected_hits_replays_bit_for_bit(tmp_path):
    # A hammer that double-hits half the time: the run holds rejected hits too.
    original = capture(tmp_path, "--hits", "3", "--seed", "7", "--hammer", "double_hit_probability=0.5")
    with h5py.File(tmp_path / f"{original}.h5", "r") as f:
        accepted = f["entry/hits/accepted"][()]
        analyzer_frf = f["entry/analyzer/frf"][()]
    assert not accepted.all(), "the seed should give at least one rejected hit"
    result = replay(tmp_path, original[:12])
    assert result.returncode == 0, result.stderr
    (new,) = new_runs(tmp_path, {original})
    assert "bit for bit" in result.stdout
    assert_replayed(tmp_path, original, new)
    # The analyzer averaged the same accepted hits with the same settings; the window
    # parameters travel as the analyzer's decimal text, hence not bit for bit (2e-10 seen).
    with h5py.File(tmp_path / f"{new}.h5", "r") as f:
        np.testing.assert_allclose(f["entry/analyzer/frf"][()], analyzer_frf, rtol=1e-8, atol=0)


@pytest.mark.timeout(60)
def test_a_zoom_run_replays_bit_for_bit(tmp_path):
    setup = tmp_path / "zoom.toml"
    setup.write_text("span_hz = 50.0\ncenter_hz = 45.0\naverages = 2\n")
    original = capture(tmp_path / "s", "--setup", str(setup))
    with h5py.File(tmp_path / "s" / f"{original}.h5", "r") as f:
        assert f["entry/hits/force"].dtype.kind == "c"
        assert f["entry/hits"].attrs["center_hz"] == 45.0
    result = replay(tmp_path / "s", original)
    assert result.returncode == 0, result.stderr
    (new,) = new_runs(tmp_path / "s", {original})
    assert_replayed(tmp_path / "s", original, new)


def sim_like_hits(n_hits: int, accepted: list[bool], reasons: list[str]) -> Hits:
    """Records shaped as the 35660A takes them at a 200 Hz span (1024 samples at 512 Hz)."""
    rng = np.random.default_rng(5)
    t = np.arange(1024) / 512.0
    force = rng.normal(0, 0.1, (n_hits, 1024))
    force[:, 16:20] += 100.0
    response = rng.normal(0, 1.0, (n_hits, 1024)) + 50 * np.exp(-3 * t) * np.sin(2 * np.pi * 20 * t)
    return Hits(
        force_n=force, response_m_s2=response, sample_rate_hz=512.0, start_s=-16 / 512.0, center_hz=0.0,
        accepted=np.array(accepted), reject_reason=reasons, overload=np.zeros((n_hits, 2), bool),
        peak_force_n=np.abs(force).max(axis=1), timestamp_utc=["2026-11-23T10:00:00Z"] * n_hits,
        checks=[{}] * n_hits,
    )  # fmt: skip


@pytest.mark.timeout(60)
def test_an_imported_run_without_settings_replays_from_its_record_geometry(tmp_path):
    run = make_run(kind="imported", hits=sim_like_hits(2, [True, True], ["", ""]))
    run.instrument = None
    seal(run, tmp_path)
    result = replay(tmp_path, run.run_id)
    assert result.returncode == 0, result.stderr
    (new,) = new_runs(tmp_path, {run.run_id})
    assert_replayed(tmp_path, run.run_id, new)
    assert entry(tmp_path / f"{new}.h5")["provenance"]["replayed_from"]["kind"] == "imported"


@pytest.mark.timeout(60)
def test_an_incomplete_run_replays_into_an_incomplete_run_with_its_verdicts(tmp_path):
    reasons = ["", "double impact", "", "interrupted before a decision"]
    run = make_run(hits=sim_like_hits(4, [True, False, True, False], reasons))
    run.complete = False
    seal(run, tmp_path)
    result = replay(tmp_path, run.run_id)
    assert result.returncode == 0, result.stderr
    (new,) = new_runs(tmp_path, {run.run_id})
    assert_replayed(tmp_path, run.run_id, new)
    assert entry(tmp_path / f"{new}.h5")["complete"] == 0


@pytest.mark.timeout(60)
def test_a_replay_of_a_run_file_given_by_path_lands_in_the_store(tmp_path):
    elsewhere = tmp_path / "colleague"
    run = make_run(kind="imported", hits=sim_like_hits(1, [True], [""]))
    path = seal(run, elsewhere)
    result = replay(tmp_path / "store", str(path))
    assert result.returncode == 0, result.stderr
    (new,) = new_runs(tmp_path / "store", set())
    assert raw(tmp_path / "store" / f"{new}.h5") == raw(path)


def test_records_no_35660a_takes_are_refused_and_nothing_is_written(tmp_path):
    run = make_run(kind="imported", n_samples=256)  # 256 samples at 2.56 kHz
    seal(run, tmp_path)
    result = replay(tmp_path, run.run_id)
    assert_one_line_error(result, run.run_id, "256 real samples", "replay cannot serve them")
    assert new_runs(tmp_path, {run.run_id}) == []


def test_a_run_of_frfs_only_is_refused(tmp_path):
    run = make_run(kind="imported", measured=make_frf())
    seal(run, tmp_path)
    assert_one_line_error(replay(tmp_path, run.run_id), "FRFs only")


def test_an_unknown_run_is_one_line(tmp_path):
    assert_one_line_error(replay(tmp_path, "2031"), "no run matches")
    assert_one_line_error(replay(tmp_path, "../etc/passwd"))


def test_a_run_file_linking_outside_itself_is_refused(tmp_path):
    run = make_run(kind="imported", hits=sim_like_hits(1, [True], [""]))
    path = seal(run, tmp_path / "a")
    outside = tmp_path / "outside.h5"
    with h5py.File(outside, "w") as f:
        f["force"] = np.zeros((1, 1024))
    linked = tmp_path / "linked.h5"
    linked.write_bytes(path.read_bytes())
    with h5py.File(linked, "r+") as f:
        del f["entry/hits/force"]
        f["entry/hits/force"] = h5py.ExternalLink(str(outside), "/force")
    assert_one_line_error(replay(tmp_path / "store", str(linked)), "external link")
    assert Store(tmp_path / "store").list() == []


@pytest.mark.timeout(60)
def test_several_runs_replay_and_a_bad_one_is_named(tmp_path):
    good = make_run(kind="imported", hits=sim_like_hits(1, [True], [""]))
    bad = make_run(kind="imported", n_samples=256)
    seal(good, tmp_path)
    seal(bad, tmp_path)
    result = replay(tmp_path, good.run_id, bad.run_id)
    assert result.returncode == 1
    assert f"daq replay: run {bad.run_id}" in result.stderr
    assert "1 of 2 replays failed" in result.stderr
    assert len(new_runs(tmp_path, {good.run_id, bad.run_id})) == 1


def test_an_unknown_name_among_several_replays_nothing(tmp_path):
    good = make_run(kind="imported", hits=sim_like_hits(1, [True], [""]))
    seal(good, tmp_path)
    assert_one_line_error(replay(tmp_path, good.run_id, "2031"), "no run matches")
    assert_one_line_error(replay(tmp_path, good.run_id, f"{tmp_path}/nope.h5"), "no such run file")
    assert_one_line_error(replay(tmp_path, good.run_id, f"{tmp_path}/"), "not a regular file")
    assert new_runs(tmp_path, {good.run_id}) == []


def test_a_replayed_import_keeps_its_missing_windows_and_article_and_analyses_alike(tmp_path):
    """An imported file records no windows and no test article: its replay records
    uniform windows and no article (not the simulator's windows and beam), so `daq
    analyze` gives both runs the same modes and neither a Table 2."""
    captured = capture(tmp_path / "sim", "--hits", "3")
    exported = tmp_path / "sim.csv"
    done = invoke_daq("export", captured, "-f", "csv", "-o", str(exported), "--store", str(tmp_path / "sim"))
    assert done.returncode == 0, done.stderr
    store = tmp_path / "runs"
    assert invoke_daq("import", str(exported), "--store", str(store)).returncode == 0
    (imported,) = [s.run_id for s in Store(store).list()]
    result = replay(store, imported)
    assert result.returncode == 0, result.stderr
    (new,) = new_runs(store, {imported})
    replayed = Store(store).open(new)
    assert replayed.sample is None
    settings = replayed.instrument.settings
    assert settings["hammer"]["window"] == settings["accelerometer"]["window"] == "UNIF"
    modes = {}
    for run_id in (imported, new):
        out = invoke_daq("analyze", run_id, "--json", "--store", str(store))
        assert out.returncode == 0, out.stderr
        (info,) = json.loads(out.stdout)
        modes[run_id] = [(m["frequency_hz"], m["damping_ratio"]) for m in info["modes"]]
        assert info["table2"]["beam"].startswith("no beam model for this run")
    assert modes[imported] == modes[new]
