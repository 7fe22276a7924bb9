"""A test's analysis as other programs and people read it: a UFF file (15, 82, 58, 55:
daq/formats/uff_multipoint.py) and the report's inputs (daq/report/modal_test_report.py).

A beam's points lie along X (their distance from the clamp), their direction along Z;
node numbers follow the test's points, 1, 2, ...; the fixed point is the node of the
point at its place (the driving point) or a node of its own after them.
"""

from __future__ import annotations

import itertools
from pathlib import Path
from typing import Any

import numpy as np

from analysis.beam_shapes import exact_shapes, ritz_shapes
from analysis.run_analysis import set_aside
from daq.formats.errors import FormatError
from daq.formats.uff_multipoint import Dof, ModeShapes, MultiPointExchange, Node, write_multipoint_uff
from daq.report.modal_test_report import ModalTestReport
from daq.workflows.article import article_beam, article_nodes
from daq.workflows.errors import WorkflowError
from daq.workflows.run_views import pretrigger_text
from daq.workflows.test_analysis import EXACT_MODES, TestAnalysis, aligned_shapes, pairs
from daq.workflows.test_fit import TestFit

#: Positions the beam's shapes are drawn at, along the beam.
GRID_POINTS = 101


def _direction(text: str) -> str:
    return text[0] + text[1:].upper()


def export_test(analysis: TestAnalysis, path: Path) -> tuple[int, int]:
    """Write ``analysis``'s test to ``path`` as UFF; (FRFs written, mode shapes written).
    Mode shapes are written only when the fixed point is one of the points (a shape
    needs a value at every node). WorkflowError (one line) when the file cannot be written."""
    data, result = analysis.data, analysis.result
    # A free structure's points sit on its nodes, whose coordinates the article holds; a
    # beam's lie along x.
    at_node = {n.name: (n.x_m, n.y_m, n.z_m) for n in article_nodes(data.test.article)}

    def place(point: Any) -> tuple[float, float, float]:
        if point.node is not None:
            return at_node.get(point.node, (np.nan, np.nan, np.nan))
        return (float(point.position_m), 0.0, 0.0) if point.position_m is not None else (np.nan,) * 3

    nodes = [Node(k, point.name, *place(point)) for k, point in enumerate(data.points, start=1)]
    if data.driving_index is not None:
        fixed_node = data.driving_index + 1
    else:
        fixed = data.test.fixed_point
        fixed_node = len(nodes) + 1
        nodes.append(Node(fixed_node, fixed.name, *place(fixed)))
    fixed_dof = Dof(fixed_node, _direction(data.test.fixed_point.direction))
    roving = [Dof(k, _direction(p.direction)) for k, p in enumerate(data.points, start=1)]
    if data.test.roving == "hammer":
        references, responses = tuple(roving), (fixed_dof,) * len(roving)
    else:
        references, responses = (fixed_dof,) * len(roving), tuple(roving)
    order = np.argsort([n.x for n in nodes])
    lines = tuple((nodes[i].number, nodes[j].number) for i, j in itertools.pairwise(order))
    modes = None
    if data.driving_index is not None:
        shapes = aligned_shapes(analysis)
        modes = ModeShapes(
            np.array([m.frequency_hz for m in result.modes]),
            np.array([m.damping_ratio for m in result.modes]),
            shapes,
            tuple("Z" for _ in nodes),
        )
    coherence = data.coherence
    if coherence is not None and not np.all(np.isfinite(coherence)):
        coherence = np.nan_to_num(coherence, nan=0.0)
    frf = data.frf
    keep = np.all(np.isfinite(frf), axis=0)
    if coherence is not None:
        coherence = coherence[:, keep]
    exchange = MultiPointExchange(
        tuple(nodes), lines, data.frequency_hz[keep], frf[:, keep], references, responses,
        "accelerance", coherence, modes, window_decay_1_s=data.added_decay_1_s,
    )  # fmt: skip
    try:
        write_multipoint_uff(path, exchange)
    except FormatError as exc:
        raise WorkflowError(str(exc)) from None  # it names the file already
    except OSError as exc:
        raise WorkflowError(f"cannot write {path}: {exc.strerror or exc}") from None
    return frf.shape[0], 0 if modes is None else modes.n_modes


def _stability(analysis: TestAnalysis) -> dict[str, np.ndarray]:
    diagram = analysis.result.modal.stability
    orders, freqs, status = [], [], []
    for order, poles, codes in zip(diagram.orders, diagram.poles, diagram.status, strict=True):
        for pole, code in zip(np.asarray(poles), np.asarray(codes), strict=True):
            orders.append(int(order))
            freqs.append(abs(complex(pole)) / (2 * np.pi))
            status.append("frequency" if str(code) == "damping" else str(code))
    out = {"order": np.array(orders), "frequency_hz": np.array(freqs), "status": np.array(status)}
    if diagram.normalisation:  # which of the zone's two LSCF fits each pole is from
        out["normalisation"] = np.concatenate([np.asarray(n, dtype=str) for n in diagram.normalisation])
    return out


def report_inputs(analysis: TestAnalysis, fit: TestFit | None = None) -> ModalTestReport:
    """The report's data of ``analysis`` (and ``fit``, when R was fitted)."""
    data, result, shapes = analysis.data, analysis.result, analysis.shapes
    beam = article_beam(data.test.article)
    if beam is None or analysis.mac_exact is None:
        raise WorkflowError(
            f"test {data.test.name}: the report draws shapes along a beam; it needs a beam article and "
            "two measured points or more"
        )
    lines = np.isin(data.frequency_hz, result.modal.frequency_hz)
    grid = np.linspace(0.0, beam.length_m, GRID_POINTS)
    exact = exact_shapes(grid, EXACT_MODES, beam).shapes
    ritz = ritz_shapes(grid, 3, beam).shapes
    exact_pairs, ritz_pairs = pairs(analysis, "exact"), pairs(analysis, "ritz")
    nan_row = np.full(grid.size, np.nan)
    modes = result.modes
    role = "sensor" if data.test.roving == "hammer" else "hammer"
    labels = [
        f"force {p.name} -> sensor {data.test.fixed_point.name}"
        if data.test.roving == "hammer"
        else f"force {data.test.fixed_point.name} -> sensor {p.name}"
        for p in data.points
    ]
    notes = []
    if fit is not None:
        notes = [f"{len(fit.determined)} of 6 terms determined: {', '.join(fit.determined) or 'none'}"]
        notes += [
            "not determined: "
            + " + ".join(f"{v:.2g} {k}" for k, v in combo.get("combination", {}).items())
            + f" (relative standard uncertainty {100 * combo.get('relative_std', float('nan')):.3g} %)"
            for combo in fit.undetermined
        ]
    drawn_exact = np.array([exact[j] if j is not None else nan_row for j in exact_pairs])
    drawn_ritz = np.array([ritz[j] if j is not None else nan_row for j in ritz_pairs])
    if data.driving_index is None and analysis.exact_at_points is not None:
        # Shapes scaled to a unit largest component: the beam's curves drawn at the
        # measured scale (least squares at the points) so that they overlay.
        measured = aligned_shapes(analysis).real
        for k, j in enumerate(exact_pairs):
            if j is not None:
                at = analysis.exact_at_points[j]
                factor = float(measured[k] @ at / (at @ at)) if at @ at > 0 else np.nan
                drawn_exact[k] *= factor
                drawn_ritz[k] *= factor
    return ModalTestReport(
        test_name=data.test.name,
        article=f"{data.test.article.get('kind')}, roving {data.test.roving}, {role} fixed",
        point_names=np.array([p.name for p in data.points]),
        point_positions_m=data.positions_m,
        beam_length_m=float(beam.length_m),
        fixed_point=data.test.fixed_point.name,
        frequency_hz=result.modal.frequency_hz,
        measured_frf=data.frf[:, lines],
        synthesized_frf=result.modal.synthesized,
        frf_labels=np.array(labels),
        frf_unit="(m/s²)/N",
        stability=_stability(analysis),
        mode_frequency_hz=np.array([m.frequency_hz for m in modes]),
        mode_frequency_std_hz=np.array([m.frequency_u_hz for m in modes]),
        damping_ratio=np.array([m.damping_ratio for m in modes]),
        damping_std=np.array([m.damping_u for m in modes]),
        mpc=shapes.mpc,
        shapes=aligned_shapes(analysis),
        shape_std=shapes.shape_std,
        shape_scaling=shapes.scaling,
        grid_m=grid,
        exact_shapes=drawn_exact,
        mac_exact=analysis.mac_exact,
        auto_mac=analysis.auto_mac,
        ritz_shapes=drawn_ritz,
        mac_ritz=analysis.mac_ritz,
        fit_method=None if fit is None else fit.method,
        damping_matrix=None if fit is None else fit.damping_matrix,
        damping_matrix_std=None if fit is None else fit.damping_std,
        fit_notes=notes,
        cautions=list(analysis.cautions) + ([] if fit is None else list(fit.cautions)),
        paired_exact_mode=np.array([-1 if j is None else j for j in exact_pairs]),
        set_aside_hz=np.array([f for f, _ in set_aside(result)]),
        records_note=pretrigger_text(
            {
                "pretrigger_cut_s": result.pretrigger_cut_s,
                "pretrigger_range_s": result.pretrigger_range_s,
                "record_after_cut_s": result.record_after_cut_s,
            }
        ),
    )
