"""The JSON of the store's multi-point tests as the lab service serves them
(``GET /api/tests``, ``GET /api/tests/{name}``): each test with its points, whether each
is measured, the runs joined there, and the point a capture with ``"point": "next"``
would measure. The test files are the store's (daq/store/modal_tests.py); choosing a
point and joining a run are daq/workflows/test.py's.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from daq.store import ModalTest, next_point
from daq.workflows.test import open_test, test_names, test_view


def test_summary(test: ModalTest) -> dict[str, Any]:
    """One test without opening its runs: ``{"name", "roving", "fixed_point", "points":
    [{"name", "position_m" | "node", "direction", "measured", "counted_run", "runs"}],
    "measured", "next"}``; ``next`` is the first point without an accepted run (None when
    every point has one)."""
    points = []
    for point in test.points:
        counted = test.counted_run(point.name)
        runs = [
            {"run_id": joined.run_id, "accepted": joined.accepted, "joined": joined.joined}
            for joined in test.runs_at(point.name)
        ]
        points.append(
            {**point.to_dict(), "measured": counted is not None, "counted_run": counted, "runs": runs}
        )
    return {
        "name": test.name,
        "created": test.created,
        "roving": test.roving,
        "fixed_point": test.fixed_point.to_dict(),
        "points": points,
        "measured": sum(p["measured"] for p in points),
        "next": next_point(test),
    }


def tests_listing(store_dir: Path) -> dict[str, Any]:
    """``{"tests": [test_summary(...) ...]}`` of every test in the store, by name.
    A test file that cannot be read is listed as ``{"name", "error"}``."""
    from daq.workflows.errors import WorkflowError

    out = []
    for name in test_names(store_dir):
        try:
            out.append(test_summary(open_test(store_dir, name)))
        except WorkflowError as exc:
            out.append({"name": name, "error": str(exc)})
    return {"tests": out}


def test_detail(store_dir: Path, name: str) -> dict[str, Any]:
    """One test as ``daq test show --json`` gives it (daq/workflows/test.py ``test_view``:
    the article, each point's counted run and mean coherence), with ``next`` as in the
    listing. WorkflowError when the store has no such test."""
    view = test_view(store_dir, name)
    view["next"] = view.get("next_point")
    return view
