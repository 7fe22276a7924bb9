"""A whole multi-point modal test as one UFF file, through pyuff: geometry, FRFs, mode shapes.

Plain data (:class:`MultiPointExchange`) in and out; no store and no command line here.

Datasets written by :func:`write_multipoint_uff`, in this order:

- 15 (nodes): every node that has coordinates (x, y, z in m, global system 0), printed
  by the format as %13.5E (6 significant digits). UFF 15 has no name field.
- 82 (trace lines): one dataset per line, its two node numbers.
- 58b (function at nodal DOF): every FRF, function type 4, in the form's type and SI
  unit (8 m, 11 m/s or 12 m/s^2 over 13 N, as daq/formats/uff58_export.py writes
  them), with its reference and response node and direction; a driving point is ONE
  node (reference node = response node). ID line 4 carries the two nodes' names
  (``ref_name=... rsp_name=...``). Then the coherence, function type 6, in the same
  order and with the same DOFs. Binary 58, so every float64 comes back exactly.
- 55 (data at nodes): one dataset per mode, complex eigenvalue (analysis type 3),
  3 DOF global translation (data characteristic 2), complex values; a node's value is
  written in the global component of its axis (X, Y or Z). The eigenvalue
  lambda = 2 pi f (-zeta + i sqrt(1 - zeta^2)) is %13.5e text, so ID line 4 carries the
  exact ``freq_hz=... damping_ratio=...``; the shape values are %13.5e (6 significant
  digits), as the format defines them.

:func:`read_multipoint_uff` reads such a file, or any UFF file holding the FRFs of
several points (datasets 58 with node numbers; 15 if present), and refuses with one
line (FormatError) what cannot be one test. The FRF type and unit logic is the UFF 58
reader's (daq/formats/uff58.py), imported, not copied.
"""

from __future__ import annotations

import gc
import itertools
import math
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pyuff

from daq.formats.errors import FormatError
from daq.formats.imported import (
    MAX_IMPORT_BYTES,
    atomic_temp,
    check_regular_file,
    commit_temp,
    discard_temp,
    one_line,
    show_path,
)
from daq.formats.uff58 import (
    FRF_TYPE_OF_FORM,
    FUNC_COHERENCE,
    FUNC_FRF,
    _check_ends_whole,
    _check_starts_as_uff,
    _frf_factor,
    _frf_form,
    _Record,
    _record,
    _records_text,
    check_complex,
    coherence_values,
    conversion_notes,
    decode_texts,
    frequency_axis,
    skipped_datasets_note,
)

#: UFF direction codes (58 reference / response direction) and their names.
DIRECTION_CODES = {
    "scalar": 0,
    "+X": 1,
    "-X": -1,
    "+Y": 2,
    "-Y": -2,
    "+Z": 3,
    "-Z": -3,
    "+RX": 4,
    "-RX": -4,
    "+RY": 5,
    "-RY": -5,
    "+RZ": 6,
    "-RZ": -6,
}
DIRECTION_NAMES = {code: name for name, code in DIRECTION_CODES.items()}
FORMS = ("receptance", "mobility", "accelerance")
AXES = ("X", "Y", "Z")
MAX_NODE = 999_999_999  # 9 digits: pyuff's readers of 15 and 82 split on spaces between %10i fields
MAX_NAME = 30  # two names and their keys fit one 80-character ID line
_UNIT_OF_FORM = {"receptance": "m", "mobility": "m/s", "accelerance": "m/s^2"}
_GEOMETRY, _LINES, _SHAPES, _FUNCTIONS = 15, 82, 55, 58
_SHAPE_TOLERANCE = 1e-4  # the %13.5e eigenvalue against the ID line's exact frequency and damping


@dataclass(frozen=True, eq=False)
class Node:
    """A measurement point: UFF node number (1 to 999,999,999), name (one word of at most
    30 printable ASCII characters; the number as text when the file gives none), position in m (NaN
    when unknown: such a node is not written to dataset 15)."""

    number: int
    name: str
    x: float = math.nan
    y: float = math.nan
    z: float = math.nan

    @property
    def has_position(self) -> bool:
        return all(math.isfinite(v) for v in (self.x, self.y, self.z))

    def _key(self) -> tuple:
        # NaN (no position) equals NaN here: two nodes without coordinates are the same node.
        return (
            int(self.number),
            self.name,
            *(None if math.isnan(v) else float(v) for v in (self.x, self.y, self.z)),
        )

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Node) and self._key() == other._key()

    def __hash__(self) -> int:
        return hash(self._key())


@dataclass(frozen=True)
class Dof:
    """A node and a direction: one of :data:`DIRECTION_CODES` ("+X", "-Z", "+RY", "scalar")."""

    node: int
    direction: str

    @property
    def code(self) -> int:
        return DIRECTION_CODES[self.direction]


@dataclass(eq=False)
class ModeShapes:
    """Complex mode shapes, one value per node of the exchange (its ``nodes`` order).

    shapes (n_modes, n_nodes) complex128; frequency_hz, damping_ratio (n_modes,)
    (f = |lambda| / 2 pi, zeta = -Re(lambda) / |lambda|); axes (n_nodes,): the global
    axis, "X", "Y" or "Z", each node's value lies along (positive sense).
    """

    frequency_hz: np.ndarray
    damping_ratio: np.ndarray
    shapes: np.ndarray
    axes: tuple[str, ...]

    def __post_init__(self) -> None:
        self.frequency_hz = np.asarray(self.frequency_hz, dtype=np.float64)
        self.damping_ratio = np.asarray(self.damping_ratio, dtype=np.float64)
        self.shapes = np.asarray(self.shapes, dtype=np.complex128)
        self.axes = tuple(self.axes)

    @property
    def n_modes(self) -> int:
        return int(self.frequency_hz.size)


@dataclass(eq=False)
class MultiPointExchange:
    """A multi-point modal test as exchanged in one UFF file.

    frf (n_frf, n_lines) complex128 in the SI unit of ``form`` (m/N, (m/s)/N or
    (m/s^2)/N) on frequency_hz (n_lines,); references[i] and responses[i] are FRF i's
    force and response DOFs; coherence (n_frf, n_lines) or None; lines: trace lines as
    pairs of node numbers; modes: mode shapes or None. ``notes`` says what a reader
    skipped (not compared, not written).
    """

    nodes: tuple[Node, ...]
    lines: tuple[tuple[int, int], ...]
    frequency_hz: np.ndarray
    frf: np.ndarray
    references: tuple[Dof, ...]
    responses: tuple[Dof, ...]
    form: str = "accelerance"
    coherence: np.ndarray | None = None
    modes: ModeShapes | None = None
    notes: tuple[str, ...] = field(default=())
    window_decay_1_s: float = 0.0

    def __post_init__(self) -> None:
        self.nodes = tuple(self.nodes)
        self.lines = tuple((int(a), int(b)) for a, b in self.lines)
        self.frequency_hz = np.asarray(self.frequency_hz, dtype=np.float64)
        self.frf = np.asarray(self.frf, dtype=np.complex128)
        self.references = tuple(self.references)
        self.responses = tuple(self.responses)
        if self.coherence is not None:
            self.coherence = np.asarray(self.coherence, dtype=np.float64)
        self.notes = tuple(self.notes)

    @property
    def n_frf(self) -> int:
        return int(self.frf.shape[0]) if self.frf.ndim == 2 else 0

    def node(self, number: int) -> Node:
        return next(n for n in self.nodes if n.number == number)


# ---------------------------------------------------------------------------------------------
# Checks shared by the writer and the reader


def check_exchange(ex: MultiPointExchange, where: str) -> None:
    """Refuse (FormatError ``where: ...``) an exchange that is no consistent test."""
    numbers = [n.number for n in ex.nodes]
    for node in ex.nodes:
        if isinstance(node.number, bool) or not isinstance(node.number, int | np.integer):
            raise FormatError(f"{where}: node number {node.number!r} is not a whole number")
        if not 1 <= node.number <= MAX_NODE:
            raise FormatError(f"{where}: node number {node.number} is outside 1 to {MAX_NODE:,}")
        _check_name(node, where)
        finite = [math.isfinite(v) for v in (node.x, node.y, node.z)]
        if any(finite) and not all(finite):
            raise FormatError(f"{where}: node {node.number} has some coordinates but not all three")
    if len(set(numbers)) != len(numbers):
        twice = next(n for n in numbers if numbers.count(n) > 1)
        raise FormatError(f"{where}: node {twice} is listed twice")
    known = set(numbers)
    seen: set[frozenset[int]] = set()
    for a, b in ex.lines:
        for end in (a, b):
            if end not in known:
                raise FormatError(f"{where}: trace line {a}-{b} names node {end}, which is not a node")
        if a == b or frozenset((a, b)) in seen:
            raise FormatError(f"{where}: trace line {a}-{b} is a loop or listed twice")
        seen.add(frozenset((a, b)))
    if ex.form not in FORMS:
        raise FormatError(f"{where}: FRF form {ex.form!r} is none of {', '.join(FORMS)}")
    freq = ex.frequency_hz
    if freq.ndim != 1 or freq.size < 2 or not np.all(np.isfinite(freq)) or np.any(np.diff(freq) <= 0):
        raise FormatError(f"{where}: the frequency axis needs at least 2 finite, increasing values")
    if ex.frf.ndim != 2 or ex.frf.shape[1] != freq.size or ex.frf.shape[0] == 0:
        raise FormatError(
            f"{where}: FRFs of shape {ex.frf.shape} for {freq.size} frequency lines (want (n_frf, n_lines))"
        )
    if not np.all(np.isfinite(ex.frf)):
        raise FormatError(f"{where}: the FRFs hold NaN or infinite values")
    if len(ex.references) != ex.n_frf or len(ex.responses) != ex.n_frf:
        raise FormatError(
            f"{where}: {ex.n_frf} FRFs but {len(ex.references)} references and {len(ex.responses)} responses"
        )
    pairs: dict[tuple, int] = {}
    for i, (ref, rsp) in enumerate(zip(ex.references, ex.responses, strict=True)):
        for dof in (ref, rsp):
            if dof.direction not in DIRECTION_CODES:
                raise FormatError(f"{where}: FRF {i} has direction {dof.direction!r}, no UFF direction")
            if dof.node not in known:
                raise FormatError(f"{where}: FRF {i} names node {dof.node}, which is not a node")
        key = (ref.node, ref.code, rsp.node, rsp.code)
        if key in pairs:
            raise FormatError(
                f"{where}: FRFs {pairs[key]} and {i} are both {_dof_text(ref, rsp)}; "
                "a test holds one FRF per DOF pair"
            )
        pairs[key] = i
    if ex.coherence is not None and (
        ex.coherence.shape != ex.frf.shape or not np.all(np.isfinite(ex.coherence))
    ):
        raise FormatError(
            f"{where}: coherence of shape {ex.coherence.shape} for FRFs of shape {ex.frf.shape}"
        )
    if ex.modes is not None:
        _check_modes(ex.modes, len(ex.nodes), where)


def _check_name(node: Node, where: str) -> None:
    name = node.name
    if (
        not isinstance(name, str)
        or not name
        or len(name) > MAX_NAME
        or not (name.isascii() and name.isprintable())
        or name != "".join(name.split())
    ):
        raise FormatError(
            f"{where}: node {node.number}'s name {name!r} is not one word of 1 to {MAX_NAME} "
            "printable ASCII characters"
        )


def _check_modes(modes: ModeShapes, n_nodes: int, where: str) -> None:
    n = modes.n_modes
    if (
        modes.frequency_hz.ndim != 1
        or modes.damping_ratio.shape != (n,)
        or modes.shapes.shape != (n, n_nodes)
    ):
        raise FormatError(
            f"{where}: mode shapes of shape {modes.shapes.shape} with {modes.frequency_hz.size} "
            f"frequencies and {modes.damping_ratio.size} dampings for {n_nodes} nodes"
        )
    if len(modes.axes) != n_nodes or any(a not in AXES for a in modes.axes):
        raise FormatError(f"{where}: mode shape axes must be one of X, Y, Z per node ({n_nodes} nodes)")
    if not (np.all(np.isfinite(modes.shapes)) and np.all(modes.frequency_hz > 0)):
        raise FormatError(f"{where}: mode shapes need finite values and frequencies above 0 Hz")
    if not np.all(np.isfinite(modes.frequency_hz)) or not np.all(np.abs(modes.damping_ratio) < 1):
        raise FormatError(f"{where}: a mode's damping ratio must lie between -1 and 1 (exclusive)")


def _dof_text(ref: Dof, rsp: Dof) -> str:
    return f"reference {ref.node} {ref.direction}, response {rsp.node} {rsp.direction}"


# ---------------------------------------------------------------------------------------------
# Writer


def write_multipoint_uff(path: Path | str, exchange: MultiPointExchange) -> None:
    """Write ``exchange`` as UFF 15, 82, 58b and 55 (see the module docstring), atomically.

    The file is read back with :func:`read_multipoint_uff` before it replaces ``path``;
    it must give back the FRFs, coherence, frequencies and DOFs exactly and the rest as
    the format prints it, else FormatError and ``path`` is left untouched.
    """
    path = Path(path)
    name = show_path(path)
    check_exchange(exchange, f"cannot write {name}")
    sets = _node_sets(exchange) + _line_sets(exchange) + _frf_sets(exchange) + _mode_sets(exchange)
    temp = atomic_temp(path)
    try:
        failure = ""
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # pyuff leaves file objects for the collector
            try:
                pyuff.UFF(str(temp)).write_sets(sets, mode="add")
            except Exception as exc:  # pyuff raises bare Exception on any write problem
                failure = one_line(str(exc))[:100] or type(exc).__name__
                del exc
            gc.collect()
        if failure:
            raise FormatError(f"cannot write {name}: {failure}")
        back = read_multipoint_uff(temp)
        difference = _difference(as_written(exchange), back)
        if difference:
            raise FormatError(f"cannot write {name} exactly: read back, {difference}")
        commit_temp(temp, path)
    except BaseException:
        discard_temp(temp)
        raise


def _node_sets(ex: MultiPointExchange) -> list[dict]:
    placed = [n for n in ex.nodes if n.has_position]
    if not placed:
        return []
    zeros = np.zeros(len(placed), dtype=int)
    return [
        {
            "type": _GEOMETRY,
            "node_nums": np.array([n.number for n in placed], dtype=int),
            "def_cs": zeros,
            "disp_cs": zeros,
            "color": zeros,
            "x": np.array([n.x for n in placed], dtype=np.float64),
            "y": np.array([n.y for n in placed], dtype=np.float64),
            "z": np.array([n.z for n in placed], dtype=np.float64),
        }
    ]


def _line_sets(ex: MultiPointExchange) -> list[dict]:
    return [
        {"type": _LINES, "trace_num": k + 1, "color": 0, "id": f"line {a}-{b}", "nodes": np.array([a, b])}
        for k, (a, b) in enumerate(ex.lines)
    ]


def _frf_sets(ex: MultiPointExchange) -> list[dict]:
    even = _even_axis(ex.frequency_hz)
    names = {n.number: n.name for n in ex.nodes}
    unit = _UNIT_OF_FORM[ex.form]
    frf_sets, coh_sets = [], []
    for i, (ref, rsp) in enumerate(zip(ex.references, ex.responses, strict=True)):
        ids = (
            f"FRF {i} {_dof_text(ref, rsp)}"[:80],
            f"multi-point test {ex.form}",
            "NONE",
            f"ref_name={names[ref.node]} rsp_name={names[rsp.node]}",
            f"{WINDOW_TAG}{ex.window_decay_1_s!r} 1/s from record start" if ex.window_decay_1_s else "NONE",
        )
        kinds = ((FRF_TYPE_OF_FORM[ex.form], unit), (13, "N"))
        frf_sets.append(_dset(FUNC_FRF, i, ids, ref, rsp, even, *kinds, ex.frf[i], ex.frequency_hz))
        if ex.coherence is not None:
            kinds = ((0, "NONE"), (0, "NONE"))
            coh_sets.append(
                _dset(FUNC_COHERENCE, i, ids, ref, rsp, even, *kinds, ex.coherence[i], ex.frequency_hz)
            )
    return frf_sets + coh_sets


def _dset(func, index, ids, ref: Dof, rsp: Dof, even, ordinate, denominator, data, x) -> dict:
    """One binary dataset 58; ordinate, denominator: (specific data type, units label)."""
    dset = pyuff.prepare_58(
        binary=1,
        **{f"id{k + 1}": text for k, text in enumerate(ids)},
        func_type=func,
        ver_num=0,
        load_case_id=0,
        rsp_node=int(rsp.node),
        rsp_dir=rsp.code,
        ref_node=int(ref.node),
        ref_dir=ref.code,
        abscissa_spacing=1 if even else 0,
        abscissa_spec_data_type=18,
        ordinate_spec_data_type=ordinate[0],
        orddenom_spec_data_type=denominator[0],
        z_axis_spec_data_type=0,
        data=np.array(data),
        x=np.array(x, dtype=np.float64),
    )
    dset.update(
        func_id=index + 1,
        abscissa_axis_units_lab="Hz",
        ordinate_axis_units_lab=ordinate[1],
        orddenom_axis_units_lab=denominator[1],
    )
    return dset


def _mode_sets(ex: MultiPointExchange) -> list[dict]:
    modes = ex.modes
    if modes is None:
        return []
    numbers = np.array([n.number for n in ex.nodes], dtype=int)
    sets = []
    for k in range(modes.n_modes):
        f, zeta = float(modes.frequency_hz[k]), float(modes.damping_ratio[k])
        omega = 2 * math.pi * f
        r = {axis: np.zeros(numbers.size, dtype=np.complex128) for axis in AXES}
        for j, axis in enumerate(modes.axes):
            r[axis][j] = modes.shapes[k, j]
        sets.append(
            {
                "type": _SHAPES,
                "id1": f"mode {k + 1}",
                "id2": "multi-point test",
                "id3": "NONE",
                "id4": f"freq_hz={f!r} damping_ratio={zeta!r}",
                "id5": "NONE",
                "model_type": 1,
                "analysis_type": 3,
                "data_ch": 2,
                "spec_data_type": 8,
                "load_case": 1,
                "mode_n": k + 1,
                "eig": complex(-zeta * omega, omega * math.sqrt(1 - zeta * zeta)),
                "modal_a": 0j,
                "modal_b": 0j,
                "node_nums": numbers,
                "r1": r["X"],
                "r2": r["Y"],
                "r3": r["Z"],
            }
        )
    return sets


def _even_axis(freq: np.ndarray) -> bool:
    """Whether pyuff's even-spacing header (%13.5e minimum and step) rebuilds ``freq`` exactly
    (the rule of daq/formats/uff58_export.py); otherwise x is stored as doubles."""
    lo, step = float(f"{freq[0]:13.5e}"), float(f"{freq[1] - freq[0]:13.5e}")
    rebuilt = lo + np.arange(freq.size) * step
    return rebuilt.tobytes() == freq.tobytes()


def as_written(ex: MultiPointExchange) -> MultiPointExchange:
    """``ex`` as the file holds it: coordinates and shape values at the format's 6
    significant digits, names only of nodes that are in an FRF (others: their number),
    the nodes with coordinates first (dataset 15, in their order), then the others by number."""
    in_frf = {d.node for d in ex.references + ex.responses}

    def printed(v: float, fmt: str) -> float:
        return float(format(v, fmt)) if math.isfinite(v) else v

    nodes = {
        n.number: Node(
            n.number,
            n.name if n.number in in_frf else str(n.number),
            printed(n.x, "13.5E"),
            printed(n.y, "13.5E"),
            printed(n.z, "13.5E"),
        )
        for n in ex.nodes
    }
    order = [n.number for n in ex.nodes if n.has_position]
    order += sorted(n.number for n in ex.nodes if not n.has_position)
    modes = None
    if ex.modes is not None:
        column = {n.number: j for j, n in enumerate(ex.nodes)}
        cols = [column[number] for number in order]
        rounded = np.vectorize(lambda v: complex(printed(v.real, "13.5e"), printed(v.imag, "13.5e")))
        shapes = (
            rounded(ex.modes.shapes[:, cols]).astype(np.complex128) if ex.modes.n_modes else ex.modes.shapes
        )
        axes = [ex.modes.axes[c] for c in cols]
        dofs = _dof_axes(ex.references, ex.responses)
        for j, number in enumerate(order):
            if not np.any(shapes[:, j]):
                axes[j] = dofs.get(number, "Z")
        modes = ModeShapes(ex.modes.frequency_hz, ex.modes.damping_ratio, shapes, tuple(axes))
    return MultiPointExchange(
        nodes=tuple(nodes[number] for number in order),
        lines=ex.lines,
        frequency_hz=ex.frequency_hz,
        frf=ex.frf,
        references=ex.references,
        responses=ex.responses,
        form=ex.form,
        coherence=ex.coherence,
        modes=modes,
    )


def _dof_axes(references, responses) -> dict[int, str]:
    """The translational axis each node is measured along in the FRFs (first seen)."""
    found: dict[int, str] = {}
    for dof in (*references, *responses):
        code = abs(dof.code)
        if 1 <= code <= 3:
            found.setdefault(dof.node, AXES[code - 1])
    return found


def _difference(want: MultiPointExchange, got: MultiPointExchange) -> str:
    """What differs between two exchanges (exact comparison), or "" if nothing."""
    if want.nodes != got.nodes:
        return "other nodes"
    if want.lines != got.lines:
        return "other trace lines"
    if want.references != got.references or want.responses != got.responses:
        return "other DOFs"
    if want.form != got.form:
        return "another FRF form"
    if not (_equal(want.frequency_hz, got.frequency_hz) and _equal(want.frf, got.frf)):
        return "other FRF values"
    if (want.coherence is None) != (got.coherence is None) or (
        want.coherence is not None and not _equal(want.coherence, got.coherence)
    ):
        return "other coherence values"
    if (want.modes is None) != (got.modes is None):
        return "other mode shapes"
    if want.modes is not None and got.modes is not None:
        a, b = want.modes, got.modes
        if not (
            _equal(a.frequency_hz, b.frequency_hz)
            and _equal(a.damping_ratio, b.damping_ratio)
            and _equal(a.shapes, b.shapes)
            and a.axes == b.axes
        ):
            return "other mode shapes"
    return ""


def _equal(a: np.ndarray, b: np.ndarray) -> bool:
    # Value equality: pyuff forms complex values as re + 1j * im, which may turn a -0.0
    # part into +0.0 (equal, but other bits).
    return a.shape == b.shape and a.dtype == b.dtype and bool(np.array_equal(a, b))


# ---------------------------------------------------------------------------------------------
# Reader


def read_multipoint_uff(path: Path | str, max_bytes: int = MAX_IMPORT_BYTES) -> MultiPointExchange:
    """Read a UFF file holding the FRFs of several points as one test.

    Datasets 58 of function type 4 are the FRFs (type 6 their coherence, matched by
    DOFs), 15 the nodes' coordinates (else the nodes come without), 82 the trace lines,
    55 the mode shapes. Any problem: one-line FormatError naming the file.
    """
    path = Path(path)
    name = show_path(path)
    check_regular_file(path, max_bytes)
    _check_starts_as_uff(path, name)
    _check_ends_whole(path, name)
    sets, skipped = _read_sets(path, name)
    why = "a test holds nodes (15), trace lines (82), functions (58) and mode shapes (55)"
    notes = [skipped_datasets_note(skipped, why)] if skipped else []
    records = [_record(d, k, name) for k, d in enumerate(s for s in sets if s.get("type") == _FUNCTIONS)]
    if not records:
        raise FormatError(f"no dataset 58 in {name}: a multi-point test needs its FRFs (function type 4)")
    frf_recs = [r for r in records if r.func == FUNC_FRF]
    coh_recs = [r for r in records if r.func == FUNC_COHERENCE]
    other = [r for r in records if r.func not in (FUNC_FRF, FUNC_COHERENCE)]
    if other:
        notes.append(
            f"skipped {_records_text(other)}: a test holds FRFs (function type 4) and their coherence (6)"
        )
    if not frf_recs:
        raise FormatError(f"{name}: no FRFs (function type 4) among its datasets 58")
    for rec in frf_recs:
        check_complex(name, rec)
    axis = frequency_axis(name, frf_recs, notes, tuple(coh_recs))
    freq = axis.hz
    for rec in frf_recs:
        if not np.array_equal(rec.x, frf_recs[0].x):
            raise FormatError(
                f"{name}: FRF record #{rec.index} has a different frequency axis from #{frf_recs[0].index}; "
                "one test has one frequency axis"
            )
    forms = [_frf_form(name, rec) for rec in frf_recs]
    mixed = next((k for k, form in enumerate(forms) if form != forms[0]), None)
    if mixed is not None:
        raise FormatError(
            f"{name}: FRF records #{frf_recs[0].index} ({forms[0]}) and #{frf_recs[mixed].index} "
            f"({forms[mixed]}) are of different forms; one test holds FRFs of one form"
        )
    units: list[str] = []
    factors = [_frf_factor(rec, units, name) for rec in frf_recs]
    frf = np.stack(
        [_scaled(rec.data.astype(np.complex128), f) for rec, f in zip(frf_recs, factors, strict=True)]
    )
    doubtful = sorted({u for u in units if u.startswith(("unknown", "none"))})
    if doubtful:
        notes.append(f"FRF units: {'; '.join(doubtful)}")
    notes.extend(conversion_notes(frf_recs, factors, forms[0]))
    dofs = [_dofs(name, rec) for rec in frf_recs]
    coherence = _coherence(frf_recs, coh_recs, dofs, name, notes)
    if axis.order is not None:  # frequencies given falling: every array in rising order
        frf = frf[:, axis.order]
        coherence = coherence[:, axis.order] if coherence is not None else None
    names = _names(frf_recs, dofs, notes)
    geometry = [s for s in sets if s.get("type") == _GEOMETRY]
    nodes = _geometry(name, geometry, notes)
    if not geometry:
        notes.append("no dataset 15: nodes without coordinates")
    lines = _lines(name, [s for s in sets if s.get("type") == _LINES], notes)
    refs = tuple(ref for ref, _ in dofs)
    rsps = tuple(rsp for _, rsp in dofs)
    # Nodes named by FRFs, trace lines or shapes but not by dataset 15: no coordinates,
    # after those of dataset 15, by number.
    unplaced = {d.node for d in refs + rsps} | {n for line in lines for n in line}
    shape_sets = [s for s in sets if s.get("type") == _SHAPES]
    for dset in shape_sets:
        unplaced |= {_whole(v) for v in np.asarray(dset.get("node_nums", []), dtype=np.float64).ravel()}
    for number in sorted(n for n in unplaced - set(nodes) if n is not None):
        nodes[number] = (math.nan, math.nan, math.nan)
    modes = _modes(name, shape_sets, nodes, _dof_axes(refs, rsps), notes)
    decay = _window_decay(frf_recs)
    if decay:
        notes.append(f"the FRFs went through an exponential window adding {decay:g} 1/s of decay (ID line 5)")
    exchange = MultiPointExchange(
        window_decay_1_s=decay,
        nodes=tuple(Node(n, names.get(n, str(n)), *xyz) for n, xyz in nodes.items()),
        lines=tuple(lines),
        frequency_hz=freq,
        frf=frf,
        references=refs,
        responses=rsps,
        form=forms[0],
        coherence=coherence,
        modes=modes,
        notes=tuple(notes),
    )
    check_exchange(exchange, name)
    return exchange


def _read_sets(path: Path, name: str) -> tuple[list[dict], list[int]]:
    """The datasets 15, 55, 58 and 82 as pyuff reads them, and the other types skipped."""
    # pyuff raises bare Exception, IndexError, struct.error, ValueError... on damaged
    # input: every failure inside pyuff means "this file cannot be read" (one line).
    failure = ""
    sets: Any = []
    skipped: list[int] = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            uff = pyuff.UFF(str(path))
            types = [int(t) for t in uff.get_set_types()]
            wanted = [i for i, t in enumerate(types) if t in (_GEOMETRY, _LINES, _SHAPES, _FUNCTIONS)]
            skipped = sorted(set(types) - {_GEOMETRY, _LINES, _SHAPES, _FUNCTIONS})
            sets = uff.read_sets(wanted) if wanted else []
            sets = [sets] if isinstance(sets, dict) else list(sets)
            # Latin-1 ID lines and unit labels ('m/s²' from Windows tools), read as a run's import does.
            functions = [k for k, i in enumerate(wanted) if types[i] == _FUNCTIONS]
            decode_texts(path, uff, [wanted[k] for k in functions], [sets[k] for k in functions])
        except Exception as exc:
            failure = one_line(str(exc))[:100] or type(exc).__name__
            del exc
        if failure:
            gc.collect()  # pyuff's open file sits in the traceback's frames
    if failure:
        raise FormatError(f"{name}: not a readable UFF file ({failure})")
    if not all(isinstance(s, dict) for s in sets):
        raise FormatError(f"{name}: a dataset could not be read")
    return sets, skipped


def _scaled(values: np.ndarray, factor: float) -> np.ndarray:
    return values * factor if factor != 1.0 else values  # * 1.0 could flip a zero's sign


def _dofs(name: str, rec: _Record) -> tuple[Dof, Dof]:
    ref_node, ref_dir, rsp_node, rsp_dir = (_whole(v) for v in rec.nodes)
    out = []
    for what, node, code in (("reference", ref_node, ref_dir), ("response", rsp_node, rsp_dir)):
        if node is None or not 1 <= node <= MAX_NODE:
            raise FormatError(
                f"{name}: record #{rec.index} has a {what} node that is no node number 1 to {MAX_NODE:,}"
            )
        if code not in DIRECTION_NAMES:
            raise FormatError(
                f"{name}: record #{rec.index} has {what} direction {code!r}, no UFF direction (-6 to 6)"
            )
        out.append(Dof(node, DIRECTION_NAMES[code]))
    return out[0], out[1]


def _whole(value: Any) -> int | None:
    try:
        number = float(value)
    except (TypeError, ValueError, OverflowError):
        return None
    return int(number) if math.isfinite(number) and number == int(number) else None


#: How an exported FRF's ID line 5 states the response's exponential window (its decay rate).
WINDOW_TAG = "exp_window_decay_1_s="


def _window_decay(frf_recs) -> float:
    """The exponential window's decay (1/s) every FRF record states in ID line 5 as
    written by write_multipoint_uff; 0 when they do not all state the same one."""
    values = set()
    for rec in frf_recs:
        text = rec.ids[4] if len(rec.ids) > 4 else ""
        if not text.startswith(WINDOW_TAG):
            return 0.0
        try:
            values.add(float(text[len(WINDOW_TAG) :].split()[0]))
        except (ValueError, IndexError):
            return 0.0
    value = values.pop() if len(values) == 1 else 0.0
    return value if math.isfinite(value) and value > 0 else 0.0


def _coherence(frf_recs, coh_recs, dofs, name: str, notes: list[str]) -> np.ndarray | None:
    if not coh_recs:
        return None
    by_dofs: dict[tuple, _Record] = {}
    for rec in coh_recs:
        ref, rsp = _dofs(name, rec)
        key = (ref, rsp)
        if key in by_dofs:
            notes.append(f"two coherence records for {_dof_text(ref, rsp)}: coherence ignored")
            return None
        by_dofs[key] = rec
    found = [by_dofs.get(key) for key in dofs]
    freq = frf_recs[0].x
    if any(rec is None for rec in found) or len(by_dofs) != len(dofs):
        notes.append(
            f"{len(coh_recs)} coherence records do not match the {len(dofs)} FRFs one to one: ignored"
        )
        return None
    return coherence_values(found, freq, notes)  # type: ignore[arg-type]


def _names(frf_recs, dofs, notes: list[str]) -> dict[int, str]:
    """Node names from the FRF records' ID lines (ref_name=..., rsp_name=...), first wins."""
    names: dict[int, str] = {}
    for rec, (ref, rsp) in zip(frf_recs, dofs, strict=True):
        for key, node in (("ref_name", ref.node), ("rsp_name", rsp.node)):
            text = rec.keys.get(key)
            if text is None or len(text) > MAX_NAME or not text.isprintable():
                continue
            if names.setdefault(node, text) != text:
                notes.append(f"node {node} is named both {names[node]!r} and {text!r}: the first kept")
    return names


def _geometry(name: str, sets: list[dict], notes: list[str]) -> dict[int, tuple[float, float, float]]:
    nodes: dict[int, tuple[float, float, float]] = {}
    for dset in sets:
        columns = [
            np.asarray(dset.get(key, []), dtype=np.float64).ravel() for key in ("node_nums", "x", "y", "z")
        ]
        systems = np.asarray(dset.get("def_cs", []), dtype=np.float64)
        if len({c.size for c in columns}) != 1:
            raise FormatError(f"{name}: dataset 15 has rows of fewer than 7 fields: damaged")
        if np.any(systems != 0) and "coordinate systems" not in " ".join(notes):
            notes.append("dataset 15 names coordinate systems other than 0: coordinates taken as global")
        for number, x, y, z in zip(*columns, strict=True):
            node = _whole(number)
            if node is None or not 1 <= node <= MAX_NODE:
                raise FormatError(
                    f"{name}: dataset 15 has node number {number!r}, no node number 1 to {MAX_NODE:,}"
                )
            if node in nodes:
                raise FormatError(f"{name}: node {node} is defined twice in dataset 15")
            if not all(math.isfinite(v) for v in (x, y, z)):
                raise FormatError(f"{name}: node {node} has NaN or infinite coordinates")
            nodes[node] = (float(x), float(y), float(z))
    return nodes


def _lines(name: str, sets: list[dict], notes: list[str]) -> list[tuple[int, int]]:
    """Trace lines as node pairs: consecutive non-zero nodes of each dataset 82 (0: move)."""
    pairs: list[tuple[int, int]] = []
    seen: set[frozenset[int]] = set()
    for dset in sets:
        nodes = [_whole(v) for v in np.asarray(dset.get("nodes", []), dtype=np.float64).ravel()]
        if any(n is None or not 0 <= n <= MAX_NODE for n in nodes):
            raise FormatError(
                f"{name}: trace line {dset.get('trace_num')!r} has a node that is no node number"
            )
        for a, b in itertools.pairwise(nodes):
            if not a or not b or a == b:
                continue
            if frozenset((a, b)) in seen:
                notes.append(f"trace line {a}-{b} given twice: kept once")
                continue
            seen.add(frozenset((a, b)))
            pairs.append((a, b))
    return pairs


def _modes(
    name: str, sets: list[dict], nodes: dict, dof_axes: dict[int, str], notes: list[str]
) -> ModeShapes | None:
    """Mode shapes from datasets 55 of analysis type 2 (normal modes) or 3, 7 (complex)."""
    modes = [s for s in sets if _whole(s.get("analysis_type")) in (2, 3, 7)]
    if len(modes) != len(sets):
        notes.append("skipped datasets 55 that hold no modes (analysis type other than 2, 3, 7)")
    if not modes:
        return None
    values: list[dict[int, np.ndarray]] = []
    freqs, damps = [], []
    for k, dset in enumerate(modes):
        where = f"{name}: dataset 55 #{k + 1} (mode {dset.get('mode_n', k + 1)})"
        numbers = [_whole(v) for v in np.asarray(dset.get("node_nums", []), dtype=np.float64).ravel()]
        present = [f"r{i}" for i in range(1, 7) if i <= 3 or f"r{i}" in dset]
        components = [np.asarray(dset.get(key, []), dtype=np.complex128).ravel() for key in present]
        if any(c.size != len(numbers) for c in components):
            raise FormatError(f"{where} has {len(numbers)} nodes but other numbers of values: damaged")
        if any(np.any(c) for c in components[3:]):
            raise FormatError(f"{where} has rotations; a test's shapes hold translations only")
        shape: dict[int, np.ndarray] = {}
        for j, number in enumerate(numbers):
            if number is None or not 1 <= number <= MAX_NODE:
                raise FormatError(f"{where} has node number {number!r}, no node number 1 to {MAX_NODE:,}")
            if number in shape:
                raise FormatError(f"{where} gives node {number} twice")
            shape[number] = np.array([components[i][j] for i in range(3)])
            nodes.setdefault(number, (math.nan, math.nan, math.nan))
        if not all(np.all(np.isfinite(v)) for v in shape.values()):
            raise FormatError(f"{where} holds NaN or infinite values")
        f, zeta = _frequency_damping(where, dset)
        freqs.append(f)
        damps.append(zeta)
        values.append(shape)
    order = list(nodes)
    axes = []
    for number in order:
        used = sorted({i for shape in values if number in shape for i in np.flatnonzero(shape[number])})
        if len(used) > 1:
            raise FormatError(
                f"{name}: the mode shapes move node {number} along {' and '.join(AXES[i] for i in used)}; "
                "a test's shapes hold one direction per node"
            )
        axes.append(AXES[used[0]] if used else dof_axes.get(number, "Z"))
    shapes = np.zeros((len(modes), len(order)), dtype=np.complex128)
    for k, shape in enumerate(values):
        for j, number in enumerate(order):
            if number in shape:
                shapes[k, j] = shape[number][AXES.index(axes[j])]
    return ModeShapes(np.array(freqs), np.array(damps), shapes, tuple(axes))


def _frequency_damping(where: str, dset: dict) -> tuple[float, float]:
    """Frequency (Hz) and damping ratio of one dataset 55: from the eigenvalue (complex
    modes) or the frequency and viscous damping fields (normal modes); the ID lines'
    exact ``freq_hz=... damping_ratio=...`` when they agree with those."""
    if _whole(dset.get("analysis_type")) == 2:
        f, zeta = _number(dset.get("freq")), _number(dset.get("modal_damp_vis"))
    else:
        try:
            eig = complex(dset.get("eig"))
        except (TypeError, ValueError):
            eig = complex(math.nan)
        w = abs(eig)
        f, zeta = w / (2 * math.pi), (-eig.real / w if w > 0 else math.nan)
    if not (math.isfinite(f) and f > 0 and math.isfinite(zeta) and abs(zeta) < 1):
        raise FormatError(f"{where} has no usable frequency and damping (f {f!r} Hz, damping {zeta!r})")
    text = " ".join(str(dset.get(f"id{i}", "")) for i in range(1, 6))
    keys = dict(part.split("=", 1) for part in text.split() if "=" in part)
    exact_f, exact_z = _number(keys.get("freq_hz")), _number(keys.get("damping_ratio"))
    if (
        math.isfinite(exact_f)
        and math.isfinite(exact_z)
        and abs(exact_f - f) <= _SHAPE_TOLERANCE * f
        and abs(exact_z - zeta) <= _SHAPE_TOLERANCE * max(abs(zeta), 1e-3)
    ):
        return exact_f, exact_z
    return f, zeta


def _number(value: Any) -> float:
    try:
        return float(value)
    except (TypeError, ValueError, OverflowError):
        return math.nan
