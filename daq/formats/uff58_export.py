"""UFF dataset 58 export through pyuff (the reader is daq/formats/uff58.py, whose
docstring gives the records written and why binary 58 is used).

Records are written FRFs first (function type 4), then their coherence (6), then the
hits' time records (1): readers that take the FRF's form from the file's first
dataset 58 (sdypy-EMA does) find an FRF there.

Nodes follow the run's points (Run.resolved_points): the force point is node 1 and
every response point at the same place (same name, position or article node) is node 1
too, so a driving point is ONE node for reference and response; a response point
elsewhere is node 2, 3, ... Directions are the points' (``+z`` -> +Z, code 3). An
imported run that records no points keeps reference node 1, response node 2 (where it
was measured is not known). The FRF records' ID line 5 names the two points
(``ref_name=... rsp_name=...``), ID line 4 states the windows the FRF went through
(``response_window=exponential exp_decay_s=... pulse_s=...`` or
``response_window=uniform``): UFF 58 has no field for a window.

The file is written to a temporary in the target's folder, read back with pyuff and
compared record by record before it replaces the target: a file pyuff cannot read
back unchanged is never left at ``path``.
"""

from __future__ import annotations

import gc
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pyuff

from daq.formats.errors import FormatError
from daq.formats.imported import atomic_temp, commit_temp, discard_temp, one_line, show_path
from daq.formats.uff58 import FUNC_COHERENCE, FUNC_FRF, FUNC_TIME, read_uff_sets
from daq.store.model import POSITION_TOLERANCE_M, MeasuredFrf, Point, Run

#: UFF direction codes of the points' directions.
DIRECTION_CODES = {"+x": 1, "-x": -1, "+y": 2, "-y": -2, "+z": 3, "-z": -3}


@dataclass(frozen=True)
class ExportFrfs:
    """FRFs to write in place of the run's stored ones (daq/workflows/export.py makes
    them: the H1 of the accepted hits without the response window). ``windows``: the
    text of the records' ID line 4, the windows the FRFs went through as ``key=value``
    words (at most 80 characters); ``tag``: what ID line 2 calls them after the run id."""

    frfs: MeasuredFrf
    windows: str
    tag: str = "h1"


@dataclass(frozen=True)
class _Dof:
    node: int
    direction: int
    name: str


def write_uff(run: Run, path: Path, frfs: ExportFrfs | None = None) -> None:
    """Write ``run``'s FRFs and hits as binary UFF 58, atomically.

    The FRFs are ``frfs`` when given, else the run's analyzer FRF and measured FRFs as
    stored (with the windows they went through stated in ID line 4).
    The written file is read back with pyuff before it replaces ``path``: every value
    must come back bit for bit, else FormatError and ``path`` is left untouched.
    """
    path = Path(path)
    name = show_path(path)
    force, responses = _dofs(run)
    sets = _frf_sets(run, force, responses, frfs) + _time_sets(run, force, responses)
    for dset in sets:
        if dset["data"].size < 2:
            raise FormatError(f"cannot write {name}: UFF 58 records need at least 2 points")
        if not np.all(np.isfinite(dset["data"])):
            # pyuff would silently write NaN and inf as numbers (nan_to_num).
            raise FormatError(f"cannot write {name}: run {run.run_id} holds non-finite values")
    expected = [(d["data"].copy(), d["x"].copy(), d["abscissa_spacing"]) for d in sets]
    temp = atomic_temp(path)
    try:
        failure = ""
        with warnings.catch_warnings():
            # pyuff's binary writer leaves a file object for the garbage collector.
            warnings.simplefilter("ignore", ResourceWarning)
            try:
                pyuff.UFF(str(temp)).write_sets(sets, mode="add")  # "overwrite" + binary truncates
            except Exception as exc:  # pyuff raises bare Exception on any write problem
                failure = one_line(str(exc))[:100] or type(exc).__name__
                del exc
            gc.collect()  # close what pyuff left open while its warning is silenced
        if failure:
            raise FormatError(f"cannot write {name}: {failure}")
        back = read_uff_sets(temp, name)
        if len(back) != len(expected) or not all(
            _equal(b.get("data"), data) and (not _exact_x(spacing, b) or _equal(b.get("x"), x))
            for b, (data, x, spacing) in zip(back, expected, strict=False)
        ):
            raise FormatError(f"cannot write {name} exactly: pyuff read back different values")
        commit_temp(temp, path)
    except BaseException:
        discard_temp(temp)
        raise


def _exact_x(spacing: int, back: dict) -> bool:
    # Even time axes come back from the %13.5e header (the exact values are in the ID
    # lines); every other abscissa was chosen so that pyuff rebuilds it exactly.
    return not (spacing == 1 and back.get("func_type") == FUNC_TIME)


def _equal(a: Any, b: np.ndarray) -> bool:
    """Same shape, dtype and values. Value equality, not bytes: pyuff builds complex
    values as re + 1j * im, which turns a -0.0 part into +0.0 (equal, but other bits)."""
    a = np.asarray(a)
    return a.shape == b.shape and a.dtype == b.dtype and bool(np.array_equal(a, b))


def _dofs(run: Run) -> tuple[_Dof, list[_Dof]]:
    """The force point's DOF (node 1) and the response points' (module docstring)."""
    if run.points is None and run.kind == "imported":
        return _Dof(1, 3, ""), [_Dof(2, 3, "")]
    points = run.resolved_points()
    force = points.force_point
    numbers: dict[str, int] = {}
    responses = []
    for point in points.response_points:
        node = 1 if _same_place(point, force) else numbers.setdefault(point.name, 2 + len(numbers))
        responses.append(_Dof(node, DIRECTION_CODES[point.direction], point.name))
    return _Dof(1, DIRECTION_CODES[force.direction], force.name), responses


def _same_place(a: Point, b: Point) -> bool:
    if a.name == b.name:
        return True
    if a.position_m is not None and b.position_m is not None:
        return abs(a.position_m - b.position_m) <= POSITION_TOLERANCE_M
    return a.node is not None and a.node == b.node


def _time_sets(run: Run, force: _Dof, responses: list[_Dof]) -> list[dict]:
    hits = run.hits
    if hits is None:
        return []
    # ID line 3: the start time and how the titles count hits (from 1, as people read
    # them; the records' own numbers and the API's indices count from 0).
    ids = (_id_text(f"{run.start_time} hit numbers count from 1"), f"center_hz={float(hits.center_hz)!r}")
    ids += (f"sample_rate_hz={float(hits.sample_rate_hz)!r} start_s={float(hits.start_s)!r}",)
    sets = []
    for k in range(hits.n_hits):
        for what, data, dof, kind, unit in (
            ("force", hits.force_n[k], force, 13, "N"),
            ("response", hits.response_m_s2[k], responses[0], 12, "m/s^2"),
        ):
            title = f"{run.run_id} hit {k + 1} {what}"
            if not hits.accepted[k]:
                # The verdict travels in ID line 1 (80 characters), read back by read_uff.
                title = f"{title} rejected: {one_line(str(hits.reject_reason[k]))}"[:80]
            head = (title, run.run_id, *ids)
            kinds = ((kind, unit), (0, "NONE"))
            sets.append(_dset(FUNC_TIME, k, head, force, dof, True, (17, "s"), *kinds, data, hits.time_s()))
    return sets


def _frf_sets(run: Run, force: _Dof, responses: list[_Dof], given: ExportFrfs | None) -> list[dict]:
    if given is not None:
        groups = [(given.tag, given.frfs, given.windows)]
    else:
        groups = [
            (tag, frfs, _frf_windows(run, tag))
            for tag, frfs in (("analyzer", run.analyzer), ("measured", run.measured_frfs))
            if frfs is not None
        ]
    frf_sets, coh_sets = [], []
    for tag, frfs, windows in groups:
        even = _even_axis(frfs.frequency_hz)
        numerator = {"receptance": (8, "m"), "mobility": (11, "m/s"), "accelerance": (12, "m/s^2")}[frfs.form]
        axis, frf_kinds, coh_kinds = frfs.frequency_hz, (numerator, (13, "N")), ((0, "NONE"), (0, "NONE"))
        for i in range(frfs.n_frf):
            # The i-th FRF is the i-th response point's when the run has one per FRF.
            rsp = responses[i] if len(responses) == frfs.n_frf else responses[0]
            names = f"ref_name={force.name} rsp_name={rsp.name}" if force.name and rsp.name else ""
            head = (
                _id_text(frfs.labels[i]), f"{run.run_id} {tag}", run.start_time, windows,
                names if len(names) <= 80 else "NONE",
            )  # fmt: skip
            frf_sets.append(
                _dset(FUNC_FRF, i, head, force, rsp, even, (18, "Hz"), *frf_kinds, frfs.frf[i], axis)
            )
            if frfs.coherence is not None:
                coh = frfs.coherence[i]
                coh_sets.append(
                    _dset(FUNC_COHERENCE, i, head, force, rsp, even, (18, "Hz"), *coh_kinds, coh, axis)
                )
    return frf_sets + coh_sets


def _frf_windows(run: Run, tag: str) -> str:
    """ID line 4 of a stored FRF's records: the exponential window the FRF went through
    (``response_window=exponential exp_decay_s=... pulse_s=...``), read back by read_uff
    so that the analysis can take the window's damping out; "NONE" when it is not known."""
    decay = pulse = None
    if tag == "analyzer" and run.instrument is not None:
        setup = run.instrument.settings.get("accelerometer", {})
        if isinstance(setup, dict) and setup.get("window") == "EXPO" and setup.get("exp_decay_s"):
            decay = float(setup["exp_decay_s"])
            pulse = max(0.0, -run.hits.start_s) if run.hits is not None else 0.0
    elif tag == "measured":
        source = run.provenance.get("imported_from", {})
        if isinstance(source, dict) and source.get("exp_decay_s"):
            decay, pulse = float(source["exp_decay_s"]), float(source.get("pulse_s") or 0.0)
    if decay is None:
        return "NONE"
    return f"response_window=exponential exp_decay_s={decay!r} pulse_s={pulse!r}"


def _dset(func, number, ids, ref, rsp, even, abscissa, ordinate, denominator, data, x) -> dict:
    """One binary dataset 58 dict; ref, rsp: the reference and response _Dof; abscissa,
    ordinate, denominator: (specific data type, units label)."""
    dset = pyuff.prepare_58(
        binary=1,
        **{f"id{i + 1}": text for i, text in enumerate(ids)},
        func_type=func,
        ver_num=number,
        load_case_id=0,
        rsp_node=rsp.node,
        rsp_dir=rsp.direction,
        ref_node=ref.node,
        ref_dir=ref.direction,
        abscissa_spacing=1 if even else 0,
        abscissa_spec_data_type=abscissa[0],
        ordinate_spec_data_type=ordinate[0],
        orddenom_spec_data_type=denominator[0],
        z_axis_spec_data_type=0,
        data=np.array(data),
        x=np.array(x, dtype=np.float64),
    )
    dset.update(
        abscissa_axis_units_lab=abscissa[1],
        ordinate_axis_units_lab=ordinate[1],
        orddenom_axis_units_lab=denominator[1],
    )
    return dset


def _even_axis(freq: np.ndarray) -> bool:
    """Whether pyuff's even-spacing header (%13.5e min and step) rebuilds ``freq`` exactly."""
    if freq.size < 2:
        return False
    # The same text round trip pyuff does: write min and x[1]-x[0] as %13.5e, read them,
    # rebuild min + arange(n) * step.
    lo, step = float(f"{freq[0]:13.5e}"), float(f"{freq[1] - freq[0]:13.5e}")
    return _same(lo + np.arange(freq.size) * step, freq)


def _id_text(text: str) -> str:
    # An ID line is one 80-character record: no line breaks, and no run of 4 spaces that
    # could form pyuff's "    -1" block marker; "NONE" when blank, as the format asks.
    clean = " ".join("".join(ch if ch.isprintable() else " " for ch in text).split())[:80]
    return clean or "NONE"


def _same(a: Any, b: np.ndarray) -> bool:
    """Bit-for-bit equality (so -0.0 and 0.0 differ) of two arrays of the same dtype."""
    a = np.asarray(a)
    return a.shape == b.shape and a.dtype == b.dtype and a.tobytes() == b.tobytes()
