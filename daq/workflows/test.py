"""Multi-point modal tests: create one, choose the point a capture or an import measures,
join the run, and say what the test holds (docs/modal-tests.md).

The test file itself is the store's (daq/store/modal_tests.py); the article and the
--points text are parsed by daq/workflows/article.py. The analysis and the damping fit
of a whole test live in daq/workflows/test_analysis.py.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from daq.store import (
    ModalTest,
    Point,
    RunPoints,
    Store,
    StoreError,
    create_test,
    join_run,
    list_tests,
    load_test,
    next_point,
)
from daq.workflows.article import parse_fixed_point, parse_points, read_article
from daq.workflows.errors import WorkflowError


def new_test(
    store_dir: Path,
    name: str,
    article_spec: str | None,
    points_text: str,
    fixed_text: str,
    roving: str = "hammer",
) -> ModalTest:
    """Create test ``name`` in the store: ``article_spec`` (None / "seed-beam" or a TOML
    file), ``points_text`` (``p1=0.1,p2=0.2,...``, m from the clamp on a beam), the fixed
    point (``tip``, a point's name, or ``name=where``) and which of hammer or sensor
    roves. WorkflowError (one line) on bad input or an existing test."""
    if roving not in ("hammer", "sensor"):
        raise WorkflowError(f"--roving must be hammer or sensor, got {roving!r}", exit_code=2)
    article = read_article(article_spec)
    points = parse_points(points_text, article)
    fixed = parse_fixed_point(fixed_text, points, article)
    try:
        return create_test(store_dir, name, article, points, fixed, roving)
    except (StoreError, ValueError) as exc:
        raise WorkflowError(str(exc)) from None


def open_test(store_dir: Path, name: str) -> ModalTest:
    """The test ``name``; WorkflowError naming the tests the store has when it has no such test."""
    try:
        return load_test(store_dir, name)
    except (StoreError, ValueError) as exc:
        raise WorkflowError(str(exc)) from None


def test_names(store_dir: Path) -> list[str]:
    """The names of the store's tests, sorted."""
    try:
        return list_tests(store_dir)
    except (StoreError, ValueError) as exc:
        raise WorkflowError(str(exc)) from None


@dataclass(frozen=True)
class TestPoint:
    """What a capture or an import into a test needs: the test's name, the point's name
    and where the run is measured (force point, response point, article)."""

    test: str
    point: str
    points: RunPoints

    @property
    def force_at_m(self) -> float | None:
        return self.points.force_point.position_m

    @property
    def sensor_at_m(self) -> float | None:
        return self.points.response_points[0].position_m


def point_to_measure(store_dir: Path, name: str, point: str | None, next_one: bool) -> TestPoint:
    """The point of test ``name`` a run will measure: ``point`` by name, or with
    ``next_one`` the first point without an accepted run. WorkflowError (exit 2) when
    both or neither are given, the point is unknown, or every point is measured."""
    if (point is None) == (not next_one):
        raise WorkflowError("with --test, give --point NAME or --next", exit_code=2)
    test = open_test(store_dir, name)
    if next_one:
        point = next_point(test)
        if point is None:
            raise WorkflowError(
                f"every point of test {name} has an accepted run: nothing left for --next "
                f"(daq test show {name}; --point NAME measures one again)",
                exit_code=2,
            )
    names = [p.name for p in test.points]
    if point not in names:
        raise WorkflowError(
            f"test {name} has no point {point!r}; its points: {', '.join(names)}", exit_code=2
        )
    points = test.run_points(point)
    return TestPoint(name, point, RunPoints(points.article, points.force_point, points.response_points, name))


def join(store_dir: Path, where: TestPoint, run_id: str, accepted: bool = True) -> ModalTest:
    """Join sealed run ``run_id`` to its test at its point. WorkflowError (one line)."""
    try:
        return join_run(store_dir, where.test, where.point, run_id, accepted)
    except (StoreError, ValueError) as exc:
        raise WorkflowError(f"run {run_id} was sealed but not joined to test {where.test}: {exc}") from None


def describe_point(point: Point) -> str:
    """``p3 (0.3 m, +z)``: a point as a person reads it."""
    where = f"{point.position_m:g} m" if point.position_m is not None else f"node {point.node}"
    return f"{point.name} ({where}, {point.direction})"


def test_view(store_dir: Path, name: str) -> dict[str, Any]:
    """The JSON of test ``name``: article, roving, fixed point, and per point whether it is
    measured, by which runs, and the counted run's mean coherence in 0..1 over its lines
    (None when the run holds no coherence)."""
    from daq.workflows.point_frf import point_frf

    test = open_test(store_dir, name)
    store = Store(store_dir)
    points = []
    for point in test.points:
        runs = [
            {"run_id": joined.run_id, "accepted": joined.accepted, "joined": joined.joined}
            for joined in test.runs_at(point.name)
        ]
        counted = test.counted_run(point.name)
        coherence = None
        problem = ""
        if counted is not None:
            try:
                measured = point_frf(store.open(counted))
                if measured.coherence is not None:
                    valid = measured.coherence[np.isfinite(measured.coherence)]
                    coherence = float(np.mean(valid)) if valid.size else None
            except (StoreError, ValueError, OSError) as exc:
                problem = str(exc)
        points.append(
            {
                **point.to_dict(),
                "measured": counted is not None,
                "counted_run": counted,
                "mean_coherence": coherence,
                "runs": runs,
                **({"problem": problem} if problem else {}),
            }
        )
    return {
        "name": test.name,
        "created": test.created,
        "article": test.article,
        "roving": test.roving,
        "fixed_point": test.fixed_point.to_dict(),
        "points": points,
        "measured": sum(p["measured"] for p in points),
        "next_point": next_point(test),
    }


def set_run_accepted(store_dir: Path, name: str, run: str, accepted: bool) -> tuple[ModalTest, str, str]:
    """Accept or reject a run already joined to test ``name`` (by id or a unique prefix);
    (the test after, the run's point, the run id). WorkflowError (one line)."""
    test = open_test(store_dir, name)
    matches = sorted({r.run_id for r in test.runs if r.run_id.startswith(run)})
    if len(matches) != 1:
        what = "no run" if not matches else f"{len(matches)} runs"
        raise WorkflowError(
            f"test {name} has {what} starting with {run!r} (daq test show {name})", exit_code=2
        )
    run_id = matches[0]
    point = next(r.point for r in test.runs if r.run_id == run_id)
    try:
        test = join_run(store_dir, name, point, run_id, accepted)
    except (StoreError, ValueError) as exc:
        raise WorkflowError(str(exc)) from None
    return test, point, run_id
