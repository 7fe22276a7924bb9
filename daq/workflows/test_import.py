"""A UFF file holding the FRFs of several points imported as a whole test: the test
file, one imported run per FRF, each joined at its point (docs/modal-tests.md).

The file must be a roving test: every FRF shares its response DOF (roving hammer) or
its reference DOF (roving sensor). On a beam article the points' positions are the
nodes' X coordinates (UFF 15); otherwise the article is the file's nodes as a free
structure.
"""

from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Any

from daq.formats.errors import FormatError
from daq.formats.uff_multipoint import MultiPointExchange, Node, read_multipoint_uff
from daq.store import MeasuredFrf, ModalTest, Point, Run, Store, StoreError, create_test, join_run, new_run_id
from daq.workflows.article import article_beam, read_article
from daq.workflows.capture import utc_now
from daq.workflows.errors import WorkflowError


def _direction(text: str, where: str) -> str:
    direction = text.lower()
    if direction not in ("+x", "-x", "+y", "-y", "+z", "-z"):
        raise WorkflowError(
            f"{where}: direction {text} is not a translation (+x ... -z); cannot make a test of it"
        )
    return direction


def _name(node: Node) -> str:
    text = "".join(c if c.isalnum() or c in "_-" else "_" for c in node.name) or f"n{node.number}"
    return text if text[0].isalnum() else f"n{text}"


def import_uff_test(
    store_dir: Path,
    path: Path,
    name: str,
    article_spec: str | None = None,
    operator: str = "",
    note: str = "",
) -> tuple[ModalTest, list[str], list[str]]:
    """Import ``path`` as test ``name``: (the test, the run ids, notes on what was
    assumed). Nothing is written unless the whole file reads and makes a test.
    WorkflowError (one line)."""
    try:
        ex = read_multipoint_uff(path)
    except FormatError as exc:
        raise WorkflowError(str(exc)) from None
    roving, fixed_dof, roving_dofs = _roving(ex, path)
    nodes = {n.number: n for n in ex.nodes}
    notes = list(ex.notes)
    beam = None
    if article_spec is not None:
        article = read_article(article_spec)
        beam = article_beam(article)
    if beam is not None:

        def point_of(number: int, direction: str) -> Point:
            node = nodes[number]
            if not node.has_position:
                raise WorkflowError(
                    f"{path}: node {number} has no coordinates (no UFF 15): its place on the beam is unknown"
                )
            return Point(_name(node), float(node.x), direction)
    else:
        missing = [n.number for n in ex.nodes if not n.has_position]
        if missing:
            notes.append(
                f"nodes {', '.join(map(str, missing))} have no coordinates in the file: placed at 0, 0, 0"
            )
        article = {
            "kind": "free",
            "name": f"nodes of {path.name}",
            "nodes": [
                {
                    "name": _name(n),
                    "x_m": float(n.x) if n.has_position else 0.0,
                    "y_m": float(n.y) if n.has_position else 0.0,
                    "z_m": float(n.z) if n.has_position else 0.0,
                    "direction": _node_direction(n.number, ex, path),
                }
                for n in ex.nodes
            ],
        }

        def point_of(number: int, direction: str) -> Point:
            return Point(_name(nodes[number]), None, direction, node=_name(nodes[number]))

    try:
        points = [point_of(d.node, _direction(d.direction, str(path))) for d in roving_dofs]
        fixed = point_of(fixed_dof.node, _direction(fixed_dof.direction, str(path)))
    except ValueError as exc:
        raise WorkflowError(f"{path}: {exc}") from None
    if len({p.name for p in points}) != len(points):
        raise WorkflowError(f"{path}: two FRFs at the same roving node: keep one per point")
    fixed_arg: Point | str = fixed
    twin = [p for p in points if p.name == fixed.name]
    if twin and twin[0].direction == fixed.direction:
        fixed_arg = fixed.name  # the driving point, measured along one direction
    elif twin:
        # The same node measured along the opposite sense (accelerometer facing the
        # hammer): a point of its own name, at the same place.
        fixed_arg = Point(f"{fixed.name}_fixed", fixed.position_m, fixed.direction, node=fixed.node)
    runs = []
    started = utc_now()
    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    store = Store(store_dir)
    try:
        test = create_test(store_dir, name, article, points, fixed_arg, roving)
        for k, point in enumerate(points):
            coherence = None if ex.coherence is None else ex.coherence[k : k + 1]
            frfs = MeasuredFrf(ex.frequency_hz, ex.frf[k : k + 1], coherence, [point.name], ex.form)
            imported: dict[str, Any] = {"file": path.name, "sha256": digest, "format": "uff", "frf_index": k}
            if ex.window_decay_1_s > 0:
                # As a run's analysis reads windows an importer found (daq/workflows/analysis.py).
                window = {"window": "EXPO", "exp_decay_s": 1.0 / ex.window_decay_1_s}
                imported["windows"] = {"accelerometer": window, "hammer": {"window": "UNIF"}}
            provenance: dict[str, Any] = {
                "imported_from": {**imported, "format_from": "daq import --as-test"}
            }
            run = Run(
                run_id=new_run_id(), kind="imported", complete=True, start_time=started, end_time=utc_now(),
                operator=operator, note=note, provenance=provenance, measured_frfs=frfs,
                points=test.run_points(point.name),
            )  # fmt: skip
            store.seal(run)
            test = join_run(store_dir, name, point.name, run.run_id)
            runs.append(run.run_id)
    except (StoreError, ValueError) as exc:
        raise WorkflowError(f"{path}: {exc}") from None
    return test, runs, notes


def _node_direction(number: int, ex: MultiPointExchange, path: Path) -> str:
    for dof in (*ex.references, *ex.responses):
        if dof.node == number:
            return _direction(dof.direction, str(path))
    return "+z"


def _roving(ex: MultiPointExchange, path: Path):
    """("hammer" or "sensor", the fixed DOF, the roving DOFs in FRF order)."""
    if len(set(ex.responses)) == 1:
        return "hammer", ex.responses[0], list(ex.references)
    if len(set(ex.references)) == 1:
        return "sensor", ex.references[0], list(ex.responses)
    raise WorkflowError(
        f"{path}: its FRFs have {len(set(ex.references))} references and {len(set(ex.responses))} responses: "
        "a test here roves the hammer (one response) or the sensor (one reference)"
    )
