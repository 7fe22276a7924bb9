"""Modal tests in the store (daq/store/modal_tests.py) and the points a run records
(Run.points): real files in temporary folders, real processes for the kill and the race."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
import tomllib
from pathlib import Path

import h5py
import pytest

from daq.store import (
    Point,
    RunPoints,
    Sample,
    StoreError,
    create_test,
    join_run,
    list_tests,
    load_test,
    next_point,
    open_run,
    seal,
)
from daq.store.layout import POINTS_ATTRS
from daq.store.modal_tests import modal_test_path
from daq.store.model import SEED_BEAM
from tests.store.store_helpers import make_run

ROOT = Path(__file__).resolve().parents[2]
BEAM = {
    "kind": "cantilever",
    "name": "steel bar",
    "material": {"youngs_modulus_pa": 2.1e11, "density_kg_m3": 7850, "name": "S235"},
    "length_m": 0.5,
    "width_m": 0.03,
    "thickness_m": 0.004,
}
POINTS = [Point("p1", 0.1), Point("p2", 0.25), Point("p3", 0.4), Point("tip", 0.5)]
FREE = {
    "kind": "free",
    "nodes": [
        {"name": "n1", "x_m": 0.0, "y_m": 0.0, "z_m": 0.0, "direction": "+z"},
        {"name": "n2", "x_m": 0.3, "y_m": 0.0, "z_m": 0.0, "direction": "-y"},
    ],
}


def files(folder: Path) -> dict[str, bytes]:
    """Every file below ``folder`` (hidden ones included) and its bytes."""
    if not folder.exists():
        return {}
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def sample_of(points: RunPoints) -> Sample | None:
    values = {
        "seed-beam": SEED_BEAM,
        "cantilever": {
            **{k: BEAM["material"][k] for k in ("density_kg_m3", "youngs_modulus_pa")},
            "width_m": 0.03,
            "height_m": 0.004,
            "length_m": 0.5,
            "area_m2": 0.03 * 0.004,
            "second_moment_m4": 0.03 * 0.004**3 / 12,
        },
    }.get(points.article["kind"])
    if values is None:
        return None
    return Sample(
        **values,
        force_position_m=points.force_point.position_m,
        sensor_position_m=points.response_points[0].position_m,
    )


def seal_at(store: Path, points: RunPoints | None, seed: int = 0) -> str:
    """A run sealed into ``store`` measured at ``points`` (None: a run that does not say)."""
    run = make_run(seed=seed, n_hits=2, n_samples=16)
    run.sample = sample_of(points) if points is not None else None
    run.points = points
    seal(run, store)
    return run.run_id


# --- the test file -----------------------------------------------------------------------


def test_create_load_list_and_the_file_is_toml(tmp_path):
    test = create_test(tmp_path, "bar-1", BEAM, POINTS, "tip")
    assert load_test(tmp_path, "bar-1") == test
    assert list_tests(tmp_path) == ["bar-1"]
    assert (test.roving, test.fixed_point, test.points) == ("hammer", POINTS[-1], tuple(POINTS))
    doc = tomllib.loads(modal_test_path(tmp_path, "bar-1").read_text())
    assert doc["schema"] == "cantilever-daq.test"
    assert doc["article"]["material"] == {
        "name": "S235",
        "youngs_modulus_pa": 2.1e11,
        "density_kg_m3": 7850.0,
    }
    assert [p["position_m"] for p in doc["points"]] == [0.1, 0.25, 0.4, 0.5]
    assert next_point(test) == "p1"
    assert test.run_points("p2") == RunPoints(BEAM, POINTS[1], (POINTS[-1],), test="bar-1")

    sensor = create_test(tmp_path, "bar-2", {"kind": "seed-beam"}, POINTS[:2], Point("f", 0.7), "sensor")
    assert sensor.run_points("p1") == RunPoints({"kind": "seed-beam"}, Point("f", 0.7), (POINTS[0],), "bar-2")
    free = create_test(tmp_path, "frame", FREE, [Point("a", node="n1"), Point("b", node="n2")], "a")
    assert load_test(tmp_path, "frame").article["nodes"][1]["direction"] == "-y"
    assert list_tests(tmp_path) == ["bar-1", "bar-2", "frame"]
    assert free.fixed_point.node == "n1"


def test_join_counts_the_newest_accepted_run(tmp_path):
    test = create_test(tmp_path, "bar", BEAM, POINTS, "tip")
    first = seal_at(tmp_path, test.run_points("p1"), seed=1)
    second = seal_at(tmp_path, test.run_points("p1"), seed=2)
    join_run(tmp_path, "bar", "p1", first)
    test = join_run(tmp_path, "bar", "p1", second)
    assert test.counted_run("p1") == second
    assert next_point(test) == "p2"
    test = join_run(tmp_path, "bar", "p1", second, accepted=False)  # rejected later
    assert test.counted_run("p1") == first
    assert [r.accepted for r in test.runs_at("p1")] == [True, False]
    assert load_test(tmp_path, "bar") == test
    tip = seal_at(tmp_path, test.run_points("tip"), seed=3)
    test = join_run(tmp_path, "bar", "tip", tip)  # the driving point
    assert test.counted_runs() == {"p1": first, "p2": None, "p3": None, "tip": tip}


def test_a_run_that_records_no_points_joins_a_seed_beam_test_at_the_tip(tmp_path):
    create_test(tmp_path, "seed", {"kind": "seed-beam"}, [Point("mid", 0.35), Point("tip", 0.7)], "tip")
    old = seal_at(tmp_path, None)
    assert join_run(tmp_path, "seed", "tip", old).counted_run("tip") == old
    with pytest.raises(StoreError, match=r"has its force at 0\.7 m, but test seed puts it at 0\.35 m"):
        join_run(tmp_path, "seed", "mid", seal_at(tmp_path, None, seed=1))


def test_every_point_measured_leaves_no_next(tmp_path):
    test = create_test(tmp_path, "one", {"kind": "seed-beam"}, [Point("tip", 0.7)], "tip")
    test = join_run(tmp_path, "one", "tip", seal_at(tmp_path, test.run_points("tip")))
    assert next_point(test) is None


# --- atomic, and safe with two writers ------------------------------------------------------

KILLED_WRITER = """
import os, sys, time
from pathlib import Path
import daq.store.writer as writer
from daq.store import join_run

store, run_id, ready = sys.argv[1], sys.argv[2], Path(sys.argv[3])

def half_then_hang(path, data):
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    os.write(fd, data[: len(data) // 2])
    os.fsync(fd)
    ready.write_text("half written")
    time.sleep(120)

writer._write_new_file = half_then_hang
join_run(store, "bar", "p1", run_id)
"""


def test_a_killed_writer_leaves_the_old_file(tmp_path):
    test = create_test(tmp_path, "bar", BEAM, POINTS, "tip")
    run_id = seal_at(tmp_path, test.run_points("p1"))
    before = modal_test_path(tmp_path, "bar").read_bytes()
    ready = tmp_path / "ready"
    child = subprocess.Popen(
        [sys.executable, "-c", KILLED_WRITER, str(tmp_path), run_id, str(ready)],
        cwd=ROOT,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
    )
    try:
        deadline = time.monotonic() + 60
        while not ready.exists():
            assert child.poll() is None, "the writer ended before writing"
            assert time.monotonic() < deadline, "the writer never started writing"
            time.sleep(0.02)
    finally:
        child.send_signal(signal.SIGKILL)
        child.wait()
    assert modal_test_path(tmp_path, "bar").read_bytes() == before
    assert load_test(tmp_path, "bar") == test
    leftovers = [p.name for p in modal_test_path(tmp_path, "bar").parent.iterdir()]
    assert any(".tmp-" in name and name.startswith(".") for name in leftovers)
    assert list_tests(tmp_path) == ["bar"]
    # The dead writer's lock went with it: the next join lands.
    assert join_run(tmp_path, "bar", "p1", run_id).counted_run("p1") == run_id


RACING_JOINER = """
import sys, time
from pathlib import Path
from daq.store import join_run

store, point, go = sys.argv[1], sys.argv[2], Path(sys.argv[3])
run_ids = sys.argv[4:]
while not go.exists():
    time.sleep(0.001)
for run_id in run_ids:
    join_run(store, "bar", point, run_id)
"""


def test_two_processes_joining_at_once_both_land(tmp_path):
    test = create_test(tmp_path, "bar", BEAM, POINTS, "tip")
    runs = {p: [seal_at(tmp_path, test.run_points(p), seed=i) for i in range(8)] for p in ("p1", "p2")}
    go = tmp_path / "go"
    children = [
        subprocess.Popen(
            [sys.executable, "-c", RACING_JOINER, str(tmp_path), point, str(go), *ids],
            cwd=ROOT,
            env={**os.environ, "PYTHONPATH": str(ROOT)},
            stderr=subprocess.PIPE,
            text=True,
        )
        for point, ids in runs.items()
    ]
    time.sleep(1.0)  # both started and waiting (imports done)
    go.write_text("go")
    for child in children:
        _, err = child.communicate(timeout=100)
        assert child.returncode == 0, err
    test = load_test(tmp_path, "bar")
    for point, ids in runs.items():
        assert sorted(r.run_id for r in test.runs_at(point)) == sorted(ids)
    assert len(test.runs) == 16


# --- bad input: one line, nothing written ----------------------------------------------------


@pytest.mark.parametrize(
    ("name", "article", "points", "fixed", "roving", "says"),
    [
        ("Bar", BEAM, POINTS, "tip", "hammer", "invalid test name 'Bar'"),
        ("../x", BEAM, POINTS, "tip", "hammer", "invalid test name"),
        ("", BEAM, POINTS, "tip", "hammer", "invalid test name"),
        ("bar", BEAM, [*POINTS, Point("p1", 0.3)], "tip", "hammer", "point name 'p1' is used twice"),
        (
            "bar",
            BEAM,
            [Point("far", 0.6)],
            "far",
            "hammer",
            "point far at 0.6 m lies outside the beam (0 < x <= 0.5 m)",
        ),
        (
            "bar",
            {"kind": "seed-beam"},
            [Point("far", 0.71)],
            "far",
            "hammer",
            "outside the beam (0 < x <= 0.7 m)",
        ),
        (
            "clamp",
            {"kind": "seed-beam"},
            [Point("root", 0.0)],
            "root",
            "hammer",
            "outside the beam (0 < x <= 0.7 m)",
        ),
        ("bar", BEAM, [], "tip", "hammer", "a test needs at least one point"),
        ("bar", BEAM, POINTS, "nowhere", "hammer", "fixed point 'nowhere' is none of the points"),
        ("bar", BEAM, POINTS, Point("s", 0.9), "hammer", "fixed point s at 0.9 m lies outside the beam"),
        ("bar", BEAM, POINTS, Point("p1", 0.3), "hammer", "fixed point p1 has the name of a point elsewhere"),
        ("bar", BEAM, POINTS, "tip", "both", "roving must be one of hammer, sensor"),
        ("bar", {"kind": "plate"}, POINTS, "tip", "hammer", "article.kind is 'plate'"),
        ("bar", {**BEAM, "length_m": -1.0}, POINTS, "tip", "hammer", "article.length_m must be positive"),
        ("bar", {**BEAM, "colour": "red"}, POINTS, "tip", "hammer", "unknown key(s) colour"),
        (
            "bar",
            {k: v for k, v in BEAM.items() if k != "width_m"},
            POINTS,
            "tip",
            "hammer",
            "article.width_m is",
        ),
        (
            "bar",
            {**BEAM, "material": {"density_kg_m3": 1.0}},
            POINTS,
            "tip",
            "hammer",
            "youngs_modulus_pa is",
        ),
        ("bar", FREE, [Point("a", node="n9")], "a", "hammer", "the article has no node 'n9'"),
        (
            "bar",
            FREE,
            [Point("a", 0.1)],
            "a",
            "hammer",
            "has a position, but the article is a free structure",
        ),
        ("bar", BEAM, [Point("a", node="n1")], "a", "hammer", "names node 'n1', but the article is a beam"),
        (
            "bar",
            {"kind": "free", "nodes": [{"name": "n1", "x_m": 0, "y_m": 0, "z_m": 0, "direction": "up"}]},
            [Point("a", node="n1")],
            "a",
            "hammer",
            "article.nodes[0].direction 'up' is not one of",
        ),
    ],
)
def test_bad_tests_are_refused_in_one_line_and_nothing_is_written(
    tmp_path, name, article, points, fixed, roving, says
):
    with pytest.raises(StoreError) as caught:
        create_test(tmp_path, name, article, points, fixed, roving)
    assert says in str(caught.value)
    assert "\n" not in str(caught.value)
    assert files(tmp_path) == {}


def test_an_existing_test_is_never_replaced(tmp_path):
    create_test(tmp_path, "bar", BEAM, POINTS, "tip")
    before = files(tmp_path)
    with pytest.raises(StoreError, match="test bar already exists"):
        create_test(tmp_path, "bar", {"kind": "seed-beam"}, [Point("x", 0.1)], "x")
    assert files(tmp_path) == before


def test_bad_joins_are_refused_in_one_line_and_nothing_is_written(tmp_path):
    test = create_test(tmp_path, "bar", BEAM, POINTS, "tip")
    create_test(tmp_path, "other", BEAM, POINTS, "tip")
    at_p1 = seal_at(tmp_path, test.run_points("p1"), seed=1)
    old_style = seal_at(tmp_path, None, seed=2)  # reads as the seed's beam at the tip
    other_test = seal_at(tmp_path, load_test(tmp_path, "other").run_points("p2"), seed=3)
    join_run(tmp_path, "bar", "p1", at_p1)
    cases = [
        ("nope", "p1", at_p1, "no test nope in"),
        ("bar", "p9", at_p1, "test bar has no point 'p9'"),
        ("bar", "p2", at_p1, "already joined test bar at point p1"),
        ("bar", "p2", "20261124T101010.000Z-00000000", "no run 20261124T101010.000Z-00000000 in"),
        ("bar", "p2", "not-a-run", "invalid run id"),
        ("bar", "tip", old_style, "was measured on another article (seed-beam)"),
        ("bar", "p2", other_test, "was measured for test other, not bar"),
        ("bar", "Bad Name", at_p1, "no point"),
        ("Bad", "p1", at_p1, "invalid test name"),
    ]
    wrong_place = seal_at(tmp_path, test.run_points("p3"), seed=4)
    cases.append(
        ("bar", "p2", wrong_place, "has its force at 0.4 m, but test bar puts it at 0.25 m for point p2")
    )
    before = files(tmp_path)
    for name, point, run_id, says in cases:
        with pytest.raises(StoreError) as caught:
            join_run(tmp_path, name, point, run_id)
        assert says in str(caught.value), (name, point, str(caught.value))
        assert "\n" not in str(caught.value)
        assert files(tmp_path) == before, (name, point)


def test_a_damaged_test_file_is_refused_in_one_line(tmp_path):
    create_test(tmp_path, "bar", BEAM, POINTS, "tip")
    path = modal_test_path(tmp_path, "bar")
    text = path.read_text()
    for damaged, says in [
        (text[: len(text) // 2] + "[[", "not valid TOML"),
        (text.replace('roving = "hammer"', 'roving = "drone"'), "roving must be one of"),
        (text.replace("schema_version = 1", "schema_version = 9"), "newer than this software reads"),
        (text.replace("position_m = 0.4", "position_m = 4.0"), "p3 at 4.0 m lies outside the beam"),
        (text.replace('name = "bar"', 'name = "baz"'), "names test 'baz', not 'bar'"),
    ]:
        path.write_text(damaged)
        with pytest.raises(StoreError) as caught:
            load_test(tmp_path, "bar")
        assert says in str(caught.value)
        assert "\n" not in str(caught.value)


def test_listing_skips_what_is_no_test(tmp_path):
    create_test(tmp_path, "bar", BEAM, POINTS, "tip")
    folder = modal_test_path(tmp_path, "bar").parent
    (folder / ".bar.toml.tmp-1-abcd").write_text("x")
    (folder / "Not A Test.toml").write_text("x")
    (folder / "notes.txt").write_text("x")
    assert list_tests(tmp_path) == ["bar"]
    assert list_tests(tmp_path / "empty") == []


# --- the points a run records ---------------------------------------------------------------


def test_points_round_trip_through_the_run_file(tmp_path):
    test = create_test(tmp_path, "bar", BEAM, POINTS, "tip")
    points = test.run_points("p2")
    got = open_run(tmp_path / f"{seal_at(tmp_path, points)}.h5")
    assert got.points == points
    assert got.resolved_points() == points
    assert got.sample.force_position_m == 0.25
    two = RunPoints(
        FREE, Point("a", node="n1"), (Point("b", node="n2"), Point("c", node="n1", direction="+x"))
    )
    got = open_run(tmp_path / f"{seal_at(tmp_path, two, seed=5)}.h5")
    assert got.points == two
    assert got.sample is None


def test_runs_without_points_read_as_the_seed_beam_at_the_tip(tmp_path):
    """A run file without the point attributes, as every run written before them: the
    seed's beam (Table 1, 0.7 m) with hammer and sensor at the tip."""
    run = make_run(n_hits=2, n_samples=16)
    run.sample = Sample(**SEED_BEAM, force_position_m=0.7, sensor_position_m=0.7)  # what capture wrote
    run.points = None
    path = seal(run, tmp_path)
    with h5py.File(path, "r") as f:
        assert not set(POINTS_ATTRS) & set(f["entry"].attrs)
    got = open_run(path)
    assert got.points is None
    tip = Point("tip", 0.7, "+z")
    assert got.resolved_points() == RunPoints({"kind": "seed-beam"}, tip, (tip,))
    # No sample at all (an import): the seed's beam at the tip too.
    bare = make_run(n_hits=2, n_samples=16, seed=1)
    bare.sample = None
    assert open_run(seal(bare, tmp_path)).resolved_points() == RunPoints({"kind": "seed-beam"}, tip, (tip,))
    # Another beam with its positions (store_helpers' sample): that beam, where it says.
    other = open_run(seal(make_run(n_hits=2, n_samples=16, seed=2), tmp_path)).resolved_points()
    assert other.article["kind"] == "cantilever"
    assert other.article["length_m"] == 0.3
    assert other.force_point == Point("force", 0.29)
    assert other.response_points == (Point("tip", 0.3),)


def test_a_run_whose_points_disagree_with_its_sample_is_refused(tmp_path):
    points = RunPoints({"kind": "seed-beam"}, Point("p3", 0.3), (Point("tip", 0.7),))
    run = make_run(n_hits=2, n_samples=16)
    with pytest.raises(ValueError, match=r"the article's beam is 0\.7 m long, sample\.length_m is 0\.3 m"):
        type(run)(**{**vars(run), "points": points})
    at_tip = Sample(**SEED_BEAM, force_position_m=0.7, sensor_position_m=0.7)
    with pytest.raises(ValueError, match=r"p3 is at 0.3 m but sample.force_position_m is 0.7 m"):
        type(run)(**{**vars(run), "sample": at_tip, "points": points})


def test_a_run_file_with_part_of_the_points_is_refused(tmp_path):
    test = create_test(tmp_path, "bar", BEAM, POINTS, "tip")
    path = tmp_path / f"{seal_at(tmp_path, test.run_points('p1'))}.h5"
    os.chmod(path, 0o644)
    with h5py.File(path, "r+") as f:
        del f["entry"].attrs["force_point_json"]
    with pytest.raises(StoreError, match="force_point_json is missing") as caught:
        open_run(path)
    assert "\n" not in str(caught.value)
