"""The analysis of a whole multi-point test: one set of poles from every point's FRF,
the mode shapes at the points, MAC against the beam, and the damping matrix fitted to
every point at once (docs/modal-tests.md).

Each point's counted run (the newest accepted) gives its H1 FRF (daq/workflows/point_frf.py);
the FRFs are analysed together (analysis.run_analysis.analyze_frfs: the band and the
orders chosen as for one run); the residues of every point give the complex shapes
(analysis.modal_id.shapes), scaled to unit modal mass through the driving point when the
test has one; analysis.beam_shapes gives the exact and Ritz shapes at the same points.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from analysis.band_choice import choose_band
from analysis.beam_shapes import exact_shapes
from analysis.mac import align, auto_mac
from analysis.modal_id.shapes import ModeShapes, mode_shapes
from analysis.pretrigger import Screen, moved, screen
from analysis.run_analysis import AnalysisOptions, RunAnalysis, analyze_frfs, set_aside
from analysis.table2 import ModalTestTable2, modal_test_table2
from daq.store import ModalTest, Point, Store, StoreError
from daq.workflows.analysis import form_assumed
from daq.workflows.article import article_beam
from daq.workflows.errors import WorkflowError
from daq.workflows.point_frf import PointFrf, point_frf, stack_points
from daq.workflows.test import open_test

#: Exact-beam modes the measured ones are compared with (more than a band usually holds).
EXACT_MODES = 8
#: Below this MAC a measured mode does not look like any beam mode at these points.
POOR_MAC = 0.8
#: Above this auto-MAC two measured modes cannot be told apart at the test's points.
AUTO_MAC_ALIKE = 0.5
#: Below this MPC a shape is markedly complex (non-proportional damping, or noise).
COMPLEX_MPC = 0.8
#: Two windows' added decay rates differing by more than this (1/s) are not one setup.
DECAY_TOLERANCE_1_S = 1e-6


@dataclass
class TestData:
    """The measured points of a test, on one frequency axis.

    points: the points measured (the roving ones with a counted run), in the test's order.
    run_ids: their counted runs. positions_m (n_points,) where the roving end sat, m
    (NaN on a free structure). frequency_hz (n_lines,); frf (n_points, n_lines) complex
    accelerance (m/s^2)/N; coherence (n_points, n_lines) or None; per_hit: per point
    (n_hits, n_lines) or None. driving_index: the point whose force and response share
    a place, or None. added_decay_1_s: the response window's decay in the poles, 1/s.
    """

    test: ModalTest
    points: list[Point]
    run_ids: list[str]
    point_frfs: list[PointFrf]
    positions_m: np.ndarray
    frequency_hz: np.ndarray
    frf: np.ndarray
    coherence: np.ndarray | None
    driving_index: int | None
    added_decay_1_s: float
    cautions: list[str] = field(default_factory=list)


def gather(store_dir: Path, name: str, n_keep: int | None = None) -> TestData:
    """Every measured point of test ``name``: its counted run's FRF (hits without windows
    cut at their impacts to ``n_keep`` samples when given: point_frf). WorkflowError when
    no point is measured or the points do not share one frequency axis."""
    test = open_test(store_dir, name)
    store = Store(store_dir)
    counted = test.counted_runs()
    points, run_ids, frfs = [], [], []
    forms: dict[str, tuple[str, bool]] = {}
    missing = [p for p, run_id in counted.items() if run_id is None]
    for point in test.points:
        run_id = counted[point.name]
        if run_id is None:
            continue
        try:
            run = store.open(run_id)
            measured = point_frf(run, n_keep)
        except (StoreError, ValueError, OSError) as exc:
            raise WorkflowError(f"test {name}, point {point.name}: run {run_id}: {exc}") from None
        forms[point.name] = _stored_form(run)
        frfs.append(_along_axes(measured, test.run_points(point.name)))
        points.append(point)
        run_ids.append(run_id)
    if not points:
        raise WorkflowError(
            f"test {name} has no measured point yet: daq capture --test {name} --next (or daq import "
            f"FILE --test {name} --point P)"
        )
    try:
        f, frf, coherence = stack_points([p.name for p in points], frfs)
    except ValueError as exc:
        raise WorkflowError(f"test {name}: {exc}") from None
    cautions = _form_cautions(forms)
    if missing:
        cautions.append(
            f"{len(missing)} of {len(test.points)} points not measured ({', '.join(missing)}): the shapes "
            "hold only the measured ones"
        )
    decays = np.array([p.added_decay_1_s for p in frfs])
    if np.ptp(decays) > DECAY_TOLERANCE_1_S:
        cautions.append(
            "the points' runs used different exponential windows: one set of poles from them mixes "
            "dampings; the median window's decay is taken out"
        )
    roving_end = [test.run_points(p.name).force_point if test.roving == "hammer" else p for p in points]
    positions = np.array([np.nan if p.position_m is None else p.position_m for p in roving_end])
    driving = [i for i, p in enumerate(points) if p.same_place(test.fixed_point)]
    return TestData(
        test, points, run_ids, frfs, positions, f, frf, coherence,
        driving[0] if driving else None, float(np.median(decays)), cautions,
    )  # fmt: skip


def _stored_form(run: Any) -> tuple[str, bool]:
    """(the form of the run's FRFs as stored, whether that form was assumed at import
    because the file did not say); time records are measured as accelerance."""
    frfs = run.measured_frfs if run.measured_frfs is not None else run.analyzer
    if (run.hits is not None and run.hits.accepted.any()) or frfs is None:
        return "accelerance", False
    return str(getattr(frfs, "form", "accelerance")), form_assumed(run)


def _form_cautions(forms: dict[str, tuple[str, bool]]) -> list[str]:
    """A caution when some points' FRF form was assumed at import: read as the wrong form,
    a point's FRF is off by omega^2 and its shape values with it."""
    assumed = [p for p, (_, guessed) in forms.items() if guessed]
    if not assumed:
        return []
    kinds = sorted({form for form, _ in forms.values()})
    mixed = (
        f"; the points hold {' and '.join(kinds)}, so their shapes cannot be compared"
        if len(kinds) > 1
        else ""
    )
    return [
        f"FRF form assumed at {', '.join(assumed)}: their files do not say what their FRFs are and "
        f"they were read as accelerance{mixed}; import them again with --frf-form if they are not"
    ]


def _along_axes(measured: PointFrf, points: Any) -> PointFrf:
    """The FRF with force and response along their axes' positive sense: a force along
    -x and a response along +x (a driving point measured with the accelerometer facing
    the hammer) turn the FRF's sign, which the shapes would otherwise carry."""
    sign = 1.0
    for point in (points.force_point, *points.response_points[:1]):
        if point.direction.startswith("-"):
            sign = -sign
    if sign > 0:
        return measured
    per_hit = None if measured.per_hit is None else -measured.per_hit
    return replace(measured, frf=-measured.frf, per_hit=per_hit)


@dataclass
class TestAnalysis:
    """What `daq test analyze` reports: the run-style analysis of all FRFs together,
    the shapes at the points and their comparison with the beam (arrays, units in
    analysis.modal_id.shapes and analysis.beam_shapes)."""

    data: TestData
    result: RunAnalysis
    shapes: ModeShapes
    table2: ModalTestTable2 | None
    exact_at_points: np.ndarray | None
    auto_mac: np.ndarray
    cautions: list[str]

    @property
    def mac_exact(self) -> np.ndarray | None:
        return None if self.table2 is None else self.table2.mac_exact_matrix

    @property
    def mac_ritz(self) -> np.ndarray | None:
        return None if self.table2 is None else self.table2.mac_ritz_matrix


def analyze_test(store_dir: Path, name: str, options: AnalysisOptions | None = None) -> TestAnalysis:
    """Analyse every measured point of test ``name`` together. WorkflowError (one line).

    Points measured as hits without windows, whose pre-trigger may bias a mode that has
    not died away by the record's end, are analysed again cut at their impacts, all to
    one length, as one run's hits are (analysis.run_analysis.analyze_hits): that result is
    kept where a mode moved by more than MOVED_BY_U of its u (analysis.pretrigger)."""
    options = options or AnalysisOptions()
    data = gather(store_dir, name)
    result, band = _analyze_points(data, name, options)
    pre_cautions: list[str] = []
    found = _pretrigger_screen(data, result)
    if found is not None and found.too_short:
        first = data.point_frfs[0]
        pre_cautions.append(found.caution_text(first.n_samples / first.sample_rate_hz))
    elif found is not None:
        cut_data = gather(store_dir, name, n_keep=found.kept_samples)
        cut_result, cut_band = _analyze_points(cut_data, name, options)
        if moved(found.suspects, cut_result.modes, cut_result.frequency_hz):
            data, result, band = cut_data, cut_result, cut_band
            result.pretrigger_cut_s = found.pretrigger_s
            result.pretrigger_range_s = found.range_s
            result.record_after_cut_s = found.kept_samples / data.point_frfs[0].sample_rate_hz
    if band is not None:
        result.band = band
    cautions = list(data.cautions) + pre_cautions + list(result.cautions)
    if not result.modes:
        aside = ",".join(f"{f:.6g}" for f, _ in set_aside(result))
        raise WorkflowError(
            f"test {name}: no mode found in {result.band.low_hz:g}-{result.band.high_hz:g} Hz over "
            f"{len(data.points)} points; "
            + (
                f"possible modes left out as too weak at {aside} Hz: keep them with --frequencies {aside}"
                if aside
                else "give --band or --frequencies"
            )
        )
    poles = _poles_seen(result)
    band = (result.band.low_hz, result.band.high_hz)
    per_hit = [p.per_hit for p in data.point_frfs]
    try:
        shapes = mode_shapes(
            data.frequency_hz, data.frf, poles, "accelerance", data.driving_index,
            per_hit if all(h is not None for h in per_hit) else None, rng=0, band=band,
        )  # fmt: skip
    except ValueError as exc:
        raise WorkflowError(f"test {name}: mode shapes: {exc}") from None
    cautions += shapes.cautions
    beam = article_beam(data.test.article)
    table = exact_at = None
    if beam is not None and np.all(np.isfinite(data.positions_m)) and len(data.points) >= 2:
        modes = result.modes
        table = modal_test_table2(
            np.array([m.frequency_hz for m in modes]), np.array([m.damping_ratio for m in modes]),
            shapes.shapes, data.positions_m, beam, 3, n_exact_modes=EXACT_MODES,
            frequency_std_hz=np.array([m.frequency_u_hz for m in modes]),
            damping_std=np.array([m.damping_u for m in modes]), mpc=shapes.mpc,
        )  # fmt: skip
        exact_at = exact_shapes(data.positions_m, EXACT_MODES, beam).shapes
    if len(data.points) < 2:
        cautions.append("one point: a mode shape needs two points or more; MAC not computed")
    auto = auto_mac(shapes.shapes)
    if data.driving_index is None:
        cautions.append(
            "no driving point (no point at the fixed point's place): the shapes are scaled to a unit largest "
            "component, not to unit modal mass; measure a point where the "
            + ("accelerometer" if data.test.roving == "hammer" else "hammer")
            + " is"
        )
    close = np.argwhere(np.triu(auto, 1) > AUTO_MAC_ALIKE)
    n_points, n_modes = len(data.points), len(result.modes)
    if close.size and n_points < n_modes:
        # n points span at most n independent shapes: with more modes than points many pairs
        # look alike whatever the data, and one line says why better than one per pair.
        pairs = auto[np.triu_indices(n_modes, 1)]
        cautions.append(
            f"{n_points} point{'s' * (n_points != 1)} cannot tell {n_modes} modes apart (auto-MAC above "
            f"{AUTO_MAC_ALIKE:g} for {len(close)} of the {pairs.size} pairs of modes, up to "
            f"{pairs.max():.2f}): measure more points than there are modes, or name the modes wanted "
            "with --frequencies"
        )
    else:
        for i, j in close:
            cautions.append(
                f"modes at {result.modes[i].frequency_hz:.4g} and {result.modes[j].frequency_hz:.4g} Hz look "
                f"alike at these {n_points} points (auto-MAC {auto[i, j]:.2f}): too few points, or "
                "badly placed"
            )
    for k, mode in enumerate(result.modes):
        if table is not None and table.exact_mode[k] < 0:
            cautions.append(
                f"mode at {mode.frequency_hz:.4g} Hz: no exact-beam mode within 25 % of it: not a mode of "
                "this beam (a local mode, the fixture, noise), or the article is wrong"
            )
        elif table is not None and not table.mac_exact[k] >= POOR_MAC:
            cautions.append(
                f"mode at {mode.frequency_hz:.4g} Hz: MAC {table.mac_exact[k]:.2f} against its exact-beam "
                "mode at these points: a local mode, noise, or too few points"
            )
        if shapes.mpc[k] < COMPLEX_MPC:
            cautions.append(
                f"mode at {mode.frequency_hz:.4g} Hz: its shape is complex (MPC {shapes.mpc[k]:.2f}): "
                "non-proportional damping, or noise"
            )
    return TestAnalysis(data, result, shapes, table, exact_at, auto, cautions)


def _analyze_points(data: TestData, name: str, options: AnalysisOptions) -> tuple[RunAnalysis, Any]:
    """The points' FRFs analysed together, and the band chosen from their hits (or None)."""
    band = None
    forces = [p.force_autospectrum for p in data.point_frfs]
    try:
        if options.band_hz is None and all(g is not None for g in forces):
            # Where every hit put energy and the coherence is usable, as for one run: the
            # points' force spectra (their median) instead of the FRFs alone.
            band = choose_band(data.frequency_hz, np.median(np.stack(forces), axis=0), data.coherence)
            options = replace(options, band_hz=(band.low_hz, band.high_hz))
        result = analyze_frfs(
            data.frequency_hz, data.frf, data.coherence, "hits", options, data.added_decay_1_s
        )
    except ValueError as exc:
        raise WorkflowError(f"test {name}: {exc}") from None
    return result, band


def _pretrigger_screen(data: TestData, result: RunAnalysis) -> Screen | None:
    """The pre-trigger screen (analysis.pretrigger.screen) over the modes read from every
    point's whole records, when every point is hits without windows of one length and
    rate; else None."""
    points = data.point_frfs
    if not result.modes or any(p.impact_starts is None for p in points):
        return None
    if len({(p.n_samples, p.sample_rate_hz) for p in points}) != 1:
        return None
    starts = np.concatenate([p.impact_starts for p in points])
    return screen(result.modes, starts, points[0].n_samples, points[0].sample_rate_hz)


def _poles_seen(result: RunAnalysis) -> np.ndarray:
    """The poles of the reported modes as the FRFs show them (window decay included),
    rad/s: the identification's pole nearest each reported mode."""
    modal = result.modal.modes
    freqs = np.array([m.frequency_hz for m in modal])
    return np.array([modal[int(np.argmin(np.abs(freqs - m.frequency_hz)))].pole for m in result.modes])


def pairs(analysis: TestAnalysis, model: str = "exact") -> list[int | None]:
    """Per measured mode, the paired beam mode (0-based; nearest in frequency, Table 2 of
    a test) of the exact beam or the Ritz model, None when none; [] without a Table 2."""
    if analysis.table2 is None:
        return []
    index = analysis.table2.exact_mode if model == "exact" else analysis.table2.ritz_mode
    return [int(j) if j >= 0 else None for j in index]


def test_analysis_json(analysis: TestAnalysis) -> dict[str, Any]:
    """The JSON of `daq test analyze --json`: band, modes (frequency, damping, their
    standard uncertainties, MPC, MPD, the shape at every point with its standard
    uncertainty, the paired exact and Ritz modes and MAC), the MAC matrices, cautions."""
    data, result, shapes = analysis.data, analysis.result, analysis.shapes
    table = analysis.table2
    modes = []
    for k, mode in enumerate(result.modes):
        row: dict[str, Any] = {
            "frequency_hz": mode.frequency_hz,
            "frequency_u_hz": _finite(mode.frequency_u_hz),
            "damping_ratio": mode.damping_ratio,
            "damping_u": _finite(mode.damping_u),
            "uncertainty_from": mode.uncertainty_from,
            "mpc": float(shapes.mpc[k]),
            "mpd_deg": float(shapes.mpd_deg[k]),
            "shape": {
                "real": shapes.shapes[k].real.tolist(),
                "imag": shapes.shapes[k].imag.tolist(),
                "real_u": shapes.shape_std[k].tolist(),
                "imag_u": shapes.shape_std_imag[k].tolist(),
            },
        }
        if table is not None:
            row["exact"] = _pair(int(table.exact_mode[k]), table.exact_hz[k], table.mac_exact[k])
            row["ritz"] = _pair(int(table.ritz_mode[k]), table.ritz_hz[k], table.mac_ritz[k])
        modes.append(row)
    return {
        "test": data.test.name,
        "points": [p.to_dict() | {"run_id": r} for p, r in zip(data.points, data.run_ids, strict=True)],
        "positions_m": [_finite(x) for x in data.positions_m],
        "driving_point": None if data.driving_index is None else data.points[data.driving_index].name,
        "band_hz": [result.band.low_hz, result.band.high_hz],
        "band_reason": for_a_test(result.band.reason),
        "n_lines": int(data.frequency_hz.size),
        "pretrigger_cut_s": result.pretrigger_cut_s,
        "pretrigger_range_s": list(result.pretrigger_range_s),
        "record_after_cut_s": result.record_after_cut_s,
        "synthesis_error": _finite(result.modal.synthesis_error),
        "set_aside": [{"frequency_hz": f, "damping_ratio": _finite(z)} for f, z in set_aside(result)],
        "shape_scaling": _scaling_text(shapes.scaling, data),
        "shape_uncertainty_from": shapes.uncertainty_from,
        "modes": modes,
        "mac_exact": _matrix(analysis.mac_exact),
        "mac_ritz": _matrix(analysis.mac_ritz),
        "auto_mac": _matrix(analysis.auto_mac),
        "cautions": analysis.cautions,
    }


def _pair(j: int, frequency_hz: float, mac_value: float) -> dict[str, Any] | None:
    """The paired model mode (1-based) with its frequency and MAC; None when unpaired."""
    if j < 0:
        return None
    return {"mode": j + 1, "frequency_hz": float(frequency_hz), "mac": _finite(mac_value)}


def _scaling_text(text: str, data: TestData) -> str:
    """The shapes' scaling as a person reads it: the driving point by its name."""
    if data.driving_index is None:
        return text
    return text.replace(f"(FRF {data.driving_index})", f"(point {data.points[data.driving_index].name})")


def _finite(value: float) -> float | None:
    value = float(value)
    return value if np.isfinite(value) else None


def _matrix(values: np.ndarray | None) -> list[list[float | None]] | None:
    if values is None:
        return None
    return [[_finite(v) for v in row] for row in np.asarray(values)]


def aligned_shapes(analysis: TestAnalysis) -> np.ndarray:
    """The measured shapes turned (phase or sign) towards their paired exact shape, for
    drawing and for comparing value by value; (n_modes, n_points) complex."""
    paired = pairs(analysis)
    if not paired or analysis.exact_at_points is None:
        return analysis.shapes.shapes
    reference = np.array(
        [
            analysis.exact_at_points[j] if j is not None else s
            for j, s in zip(paired, analysis.shapes.shapes, strict=True)
        ]
    )
    return align(analysis.shapes.shapes, reference)


def for_a_test(reason: str) -> str:
    """The band's reason (analysis/band_choice.py, written for one run) as said of a
    test, whose band comes from all its points' runs: the same words in the terminal, the
    JSON and the page."""
    return reason.replace("in the run limits", "in the test's runs limits").replace(
        "the run's lines", "the points' lines"
    )
