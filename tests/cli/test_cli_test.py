"""`daq test ...` and `daq capture --test` as a user runs them: through daq.cli.app.main,
the real simulator over a socket, a real HDF5 store (issue 23). The real console script
in subprocesses where processes are the point: two captures into one test at the same
time (the test's lock) and a capture killed mid-test.

The seven-point roving-hammer test of the `seed` scenario (the paper's Ritz N = 3 beam
with the eq (18) damping matrix) is captured once for the module; the damping matrix
`daq test fit` finds is checked against the paper's matrix, written out here.
"""

from __future__ import annotations

import contextlib
import json
import os
import signal
import subprocess
from pathlib import Path

import numpy as np
import pytest

from tests.cli_helpers import DAQ, ENV, assert_one_line_error, invoke_daq
from tests.workflows.capture_processes import capture_env, wait_for_accepted

#: Seed paper, eq (18): the damping matrix of the Ritz N = 3 beam, N s/m.
EQ18 = np.array(
    [
        [4.9582, 4.1824, 2.9015],
        [4.1824, 4.0732, 1.9945],
        [2.9015, 1.9945, 2.7482],
    ]
)
POSITIONS_M = (0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7)
POINTS = ",".join(f"p{k}={x}" for k, x in enumerate(POSITIONS_M, start=1))
HITS = 5


def run_daq(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    """`daq ARGS` in this process (tests/cli_helpers.py), from ``cwd`` if given: a
    subprocess would add a second of start-up to every call and prove nothing more."""
    with contextlib.chdir(cwd) if cwd is not None else contextlib.nullcontext():
        return invoke_daq(*args)


def daq_ok(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    result = run_daq(*args, cwd=cwd)
    assert result.returncode == 0, result.stderr
    return result


def snapshot(*folders: Path) -> dict[str, tuple[int, int]]:
    """Every file under ``folders``: (size, mtime_ns), to show nothing was written."""
    files = {}
    for folder in folders:
        for path in sorted(folder.rglob("*")):
            if path.is_file():
                stat = path.stat()
                files[str(path)] = (stat.st_size, stat.st_mtime_ns)
    return files


def capture(store: Path, *args: str, seed: int) -> subprocess.CompletedProcess[str]:
    return daq_ok(
        "capture", "--sim", "--scenario", "seed", "--yes", "--hits", str(HITS), "--time-scale", "0",
        "--seed", str(seed), "--store", str(store), *args,
    )  # fmt: skip


def capture_command(store: Path, *args: str, seed: int) -> list[str]:
    return [
        str(DAQ), "capture", "--sim", "--scenario", "seed", "--yes", "--hits", str(HITS), "--time-scale", "0",
        "--seed", str(seed), "--store", str(store), *args,
    ]  # fmt: skip


@pytest.fixture(scope="module")
def seed_test(tmp_path_factory):
    """(store, `daq test show s7 --json` after 3 of the 7 points): test s7, roving hammer,
    accelerometer at the tip, 5 hits a point. p1..p3 one after the other with --next;
    then p4..p7 by name, two captures at a time into the one test (its lock)."""
    store = tmp_path_factory.mktemp("cli-test") / "runs"
    daq_ok("test", "new", "s7", "--points", POINTS, "--store", str(store))
    for seed in (1, 2, 3):
        result = capture(store, "--test", "s7", "--next", seed=seed)
        assert f"joined test s7 at point p{seed}" in result.stdout
    partial = json.loads(daq_ok("test", "show", "s7", "--json", "--store", str(store)).stdout)
    env = {**os.environ, **ENV}
    env.pop("DAQ_DEBUG", None)
    for pair in ((4, 5), (6, 7)):
        procs = [
            subprocess.Popen(
                capture_command(store, "--test", "s7", "--point", f"p{k}", seed=k),
                stdout=subprocess.PIPE,
                stderr=subprocess.PIPE,
                stdin=subprocess.DEVNULL,
                text=True,
                env=env,
            )
            for k in pair
        ]
        for k, proc in zip(pair, procs, strict=True):
            out, err = proc.communicate(timeout=120)
            assert proc.returncode == 0, err
            assert f"joined test s7 at point p{k}" in out
    return store, partial


@pytest.fixture(scope="module")
def seed_store(seed_test):
    return seed_test[0]


def test_show_json_counts_points_names_the_next_and_the_counted_runs(seed_test):
    store, partial = seed_test
    assert partial["measured"] == 3
    assert partial["next_point"] == "p4"
    assert [p["measured"] for p in partial["points"]] == [True] * 3 + [False] * 4
    assert all(p["counted_run"] is None and p["runs"] == [] for p in partial["points"][3:])

    view = json.loads(daq_ok("test", "show", "s7", "--json", "--store", str(store)).stdout)
    assert view["name"] == "s7"
    assert view["roving"] == "hammer"
    assert view["fixed_point"]["position_m"] == pytest.approx(0.7)
    assert view["measured"] == 7
    assert view["next_point"] is None
    from daq.store import Store

    run_ids = {r.run_id for r in Store(store).list()}
    assert len(run_ids) == 7
    counted = []
    for point, x in zip(view["points"], POSITIONS_M, strict=True):
        assert point["position_m"] == pytest.approx(x)
        assert point["measured"] is True
        assert [r["run_id"] for r in point["runs"]] == [point["counted_run"]]
        assert point["runs"][0]["accepted"] is True
        assert 0.0 <= point["mean_coherence"] <= 1.0
        counted.append(point["counted_run"])
    # The first three points were counted by the same runs before and after.
    assert counted[:3] == [p["counted_run"] for p in partial["points"][:3]]
    assert set(counted) == run_ids

    (listed,) = json.loads(daq_ok("test", "list", "--json", "--store", str(store)).stdout)
    assert listed["name"] == "s7"
    assert listed["measured"] == 7
    assert len(listed["points"]) == 7
    assert listed["next_point"] is None


def test_next_after_every_point_is_measured_is_one_line_exit_2(seed_store):
    before = snapshot(seed_store)
    result = run_daq(
        "capture", "--sim", "--test", "s7", "--next", "--yes", "--hits", "1", "--time-scale", "0",
        "--store", str(seed_store),
    )  # fmt: skip
    assert_one_line_error(result, "every point of test s7")
    assert result.returncode == 2
    assert snapshot(seed_store) == before


def test_fit_recovers_eq18_within_three_stated_uncertainties(seed_store):
    from analysis.seed import eq18_damping_matrix

    np.testing.assert_allclose(eq18_damping_matrix(), EQ18, rtol=1e-4)
    result = daq_ok("test", "fit", "s7", "--json", "--store", str(seed_store))
    fit = json.loads(result.stdout)
    assert fit["n_points"] == 7
    assert fit["ritz_functions"] == 3
    r = np.array(fit["damping_matrix"])
    u = np.array(fit["damping_matrix_u"])
    assert r.shape == u.shape == (3, 3)
    assert np.all(u > 0)
    np.testing.assert_allclose(r, r.T)
    misses = np.abs(r - EQ18) / u
    assert np.all(misses <= 3.0), np.round(misses, 2)
    # The terms it calls determined are the well-measured ones: within 10 % of eq (18).
    for term in fit["determined_terms"]:
        i, j = int(term[1]) - 1, int(term[2]) - 1
        assert r[i, j] == pytest.approx(EQ18[i, j], rel=0.10), term


def test_export_is_read_back_by_pyuff_and_by_the_test_reader(seed_store, tmp_path):
    import pyuff

    from daq.formats.uff_multipoint import read_multipoint_uff

    path = tmp_path / "s7.uff"
    result = daq_ok("test", "export", "s7", "-o", str(path), "--store", str(seed_store), cwd=tmp_path)
    assert "7 FRFs" in result.stdout
    sets = pyuff.UFF(str(path)).read_sets()
    kinds = [s["type"] for s in sets]
    (nodes,) = [s for s in sets if s["type"] == 15]
    assert sorted(int(n) for n in nodes["node_nums"]) == list(range(1, 8))  # the tip is p7's node
    np.testing.assert_allclose(sorted(nodes["x"]), POSITIONS_M, atol=1e-9)
    assert 82 in kinds
    frfs = [s for s in sets if s["type"] == 58 and int(s["func_type"]) == 4]
    assert len(frfs) == 7
    assert {int(s["rsp_node"]) for s in frfs} == {7}
    shapes = [s for s in sets if s["type"] == 55]
    assert len(shapes) >= 2
    back = read_multipoint_uff(path)
    for s in frfs:
        k = int(s["ref_node"]) - 1
        np.testing.assert_allclose(back.frequency_hz, s["x"], rtol=1e-9)
        np.testing.assert_allclose(back.frf[k], s["data"], rtol=1e-9, atol=0)

    # Again without --force: one line, the file untouched.
    before = snapshot(tmp_path, seed_store)
    again = run_daq("test", "export", "s7", "-o", str(path), "--store", str(seed_store), cwd=tmp_path)
    assert_one_line_error(again, "exists", "--force")
    assert snapshot(tmp_path, seed_store) == before


def test_report_of_the_test(seed_store, tmp_path):
    folder = tmp_path / "rep"
    result = daq_ok("test", "report", "s7", "-o", str(folder), "--store", str(seed_store))
    assert "index.html" in result.stdout
    html = (folder / "index.html").read_text(encoding="utf-8")
    assert "s7" in html
    assert list(folder.glob("*.png"))


# Each: the arguments (STORE is the module's store, FILE an existing file), the exit
# status (None: any non-zero) and a fragment of the one line.
BAD = {
    "unknown test": (["test", "show", "nope"], None, "no test nope"),
    "unknown point": (
        ["capture", "--sim", "--test", "s7", "--point", "p9", "--yes", "--time-scale", "0"],
        2,
        "no point 'p9'",
    ),
    "point without test": (["capture", "--sim", "--point", "p1", "--yes", "--time-scale", "0"], 2, "--test"),
    "test with force-at": (
        [
            "capture",
            "--sim",
            "--test",
            "s7",
            "--point",
            "p1",
            "--force-at",
            "0.3",
            "--yes",
            "--time-scale",
            "0",
        ],
        2,
        "--force-at",
    ),
    "point off the beam": (["test", "new", "off", "--points", "p=0.9"], 2, "outside the beam"),
    "duplicate point names": (["test", "new", "dup", "--points", "a=0.1,a=0.2"], 2, "twice"),
    "name with a slash": (["test", "new", "a/b", "--points", "a=0.1"], None, "invalid test name"),
    "existing test name": (["test", "new", "s7", "--points", "a=0.1"], None, "already exists"),
    "roving sensor with --sensor": (
        ["test", "new", "rs", "--points", "a=0.1", "--roving", "sensor", "--sensor", "tip"],
        2,
        "--sensor",
    ),
    "export onto an existing file": (["test", "export", "s7", "-o", "FILE"], 2, "--force"),
    "report into a file": (["test", "report", "s7", "-o", "FILE"], None, "not a folder"),
}


@pytest.mark.parametrize("case", list(BAD), ids=list(BAD))
def test_bad_input_is_one_line_and_writes_nothing(seed_store, tmp_path, case):
    args, status, fragment = BAD[case]
    existing = tmp_path / "existing.uff"
    existing.write_text("not ours\n")
    args = [str(existing) if a == "FILE" else a for a in args]
    before = snapshot(seed_store, tmp_path)
    result = run_daq(*args, "--store", str(seed_store), cwd=tmp_path)
    assert_one_line_error(result, fragment)
    if status is not None:
        assert result.returncode == status
    assert snapshot(seed_store, tmp_path) == before
    assert existing.read_text() == "not ours\n"


@pytest.fixture(scope="module")
def empty_test(tmp_path_factory):
    """(store, `daq test analyze empty` of a test with no measured point, cwd) and
    whether anything was written."""
    root = tmp_path_factory.mktemp("empty-test")
    store = root / "runs"
    daq_ok("test", "new", "empty", "--points", "a=0.1,b=0.7", "--store", str(store))
    before = snapshot(root)
    result = run_daq("test", "analyze", "empty", "--store", str(store), cwd=root)
    return result, snapshot(root) == before


def test_analyze_with_no_measured_point_refuses_and_writes_nothing(empty_test):
    result, unchanged = empty_test
    assert result.returncode != 0
    assert "Traceback" not in result.stderr
    assert result.stderr.splitlines()[-1].startswith("daq: error: test empty has no measured point")
    assert unchanged


def test_analyze_with_no_measured_point_is_one_line(empty_test):
    assert_one_line_error(empty_test[0], "no measured point")


@pytest.mark.timeout(90)
def test_a_capture_killed_mid_test_keeps_its_hits_and_its_point(tmp_path):
    """SIGTERM to a real `daq capture --test T --point p1` after two accepted hits: the hits
    are sealed as an incomplete run that records the test and where hammer and sensor were;
    an incomplete run does not count as the point's measurement."""
    from daq.store import Store

    store = tmp_path / "runs"
    env = capture_env(tmp_path)
    daq_ok("test", "new", "t", "--points", "p1=0.3,p2=0.7", "--store", str(store))
    proc = subprocess.Popen(
        [str(DAQ), "capture", "--sim", "--scenario", "seed", "--test", "t", "--point", "p1", "--hits", "50",
         "--yes", "--time-scale", "0.1", "--store", str(store)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, stdin=subprocess.DEVNULL, env=env, text=True,
        bufsize=1, start_new_session=True,
    )  # fmt: skip
    try:
        wait_for_accepted(proc, 2)
        os.kill(proc.pid, signal.SIGTERM)
        _, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()
    assert proc.returncode == 143, err
    assert "hits kept as incomplete run" in err
    (summary,) = Store(store).list()
    run = Store(store).open(summary.run_id)
    assert not run.complete
    assert int(run.hits.accepted.sum()) >= 2
    assert run.points is not None
    assert run.points.test == "t"
    assert run.points.force_point.position_m == pytest.approx(0.3)
    assert run.points.response_points[0].position_m == pytest.approx(0.7)
    view = json.loads(daq_ok("test", "show", "t", "--json", "--store", str(store)).stdout)
    assert view["measured"] == 0
    assert view["next_point"] == "p1"
    p1 = next(p for p in view["points"] if p["name"] == "p1")
    assert p1["runs"] == [{"run_id": run.run_id, "accepted": False, "joined": p1["runs"][0]["joined"]}]


def test_reject_and_accept_a_run_of_the_test(seed_store):
    """`daq test reject` stops counting a run at its point (the point is next again) and
    `daq test accept` counts it again; an unknown run is one line, exit 2."""
    store = str(seed_store)
    view = json.loads(daq_ok("test", "show", "s7", "--json", "--store", store).stdout)
    p3 = next(p for p in view["points"] if p["name"] == "p3")
    run_id = p3["counted_run"]
    try:
        out = daq_ok("test", "reject", "s7", run_id[:24], "--store", store).stdout
        assert f"Run {run_id} rejected at point p3" in out
        after = json.loads(daq_ok("test", "show", "s7", "--json", "--store", store).stdout)
        assert after["next_point"] == "p3"
        assert after["measured"] == view["measured"] - 1
    finally:
        daq_ok("test", "accept", "s7", run_id, "--store", store)
    again = json.loads(daq_ok("test", "show", "s7", "--json", "--store", store).stdout)
    assert again["measured"] == view["measured"]
    bad = run_daq("test", "reject", "s7", "nosuchrun", "--store", store)
    assert bad.returncode == 2
    assert bad.stderr.count("\n") == 1
    assert "no run starting with" in bad.stderr


def test_two_points_without_a_driving_point_say_so(tmp_path):
    """Two points, the accelerometer at the tip, neither at the tip: the shapes cannot be
    scaled to unit modal mass; the caution says so in the JSON, a pair of modes whose
    auto-MAC exceeds 0.5 is named, and nothing says a MAC of 'nan'."""
    store = tmp_path / "runs"
    daq_ok("test", "new", "two", "--points", "a=0.3,b=0.5", "--store", str(store))
    for seed in (5, 6):
        capture(store, "--test", "two", "--next", seed=seed)
    info = json.loads(daq_ok("test", "analyze", "two", "--json", "--store", str(store)).stdout)
    cautions = " ".join(info["cautions"])
    assert info["driving_point"] is None
    assert "no driving point" in cautions
    assert "unit largest component" in info["shape_scaling"]
    auto = np.array(info["auto_mac"])
    alike = np.triu(auto, 1) > 0.5
    assert cautions.count("look alike") == int(alike.sum())
    assert "nan" not in cautions
    # The possible modes left out are listed as in daq analyze --json, each named by a caution.
    for chain in info["set_aside"]:
        assert f"{chain['frequency_hz']:.6g}" in cautions
