"""A run in memory: plain dataclasses holding numpy arrays, checked on construction.

Units are SI unless a name says otherwise. Every constructor raises ValueError with
a one-line message when shapes, dtypes or values do not fit together, so a Run that
exists is a Run that can be sealed.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass, field
from datetime import datetime
from typing import Any

import numpy as np

from daq import __version__
from daq.store.ids import is_run_id
from daq.store.layout import SAMPLE_ATTRS

RUN_KINDS = ("simulated", "captured", "replayed", "imported")
SOFTWARE = f"cantilever-daq {__version__}"


@dataclass(eq=False)
class Hits:
    """The time records of a run's hits, both channels, and what was decided about each.

    force_n, response_m_s2: (n_hits, n_samples), N and m/s^2; float64 at baseband,
        complex128 for zoom records (complex envelope around ``center_hz``).
    sample_rate_hz: samples per second of each record, Hz.
    start_s: time of the first sample relative to the trigger, s (negative = pre-trigger).
    center_hz: 0 at baseband, the zoom centre frequency otherwise, Hz.
    accepted: (n_hits,) bool. reject_reason: (n_hits,) str, "" exactly when accepted.
    overload: (n_hits, 2) bool, [force channel, response channel].
    peak_force_n: (n_hits,) N. timestamp_utc: (n_hits,) ISO 8601 UTC strings.
    checks: n_hits JSON-able dicts, the per-hit check results.
    """

    force_n: np.ndarray
    response_m_s2: np.ndarray
    sample_rate_hz: float
    start_s: float
    center_hz: float
    accepted: np.ndarray
    reject_reason: np.ndarray
    overload: np.ndarray
    peak_force_n: np.ndarray
    timestamp_utc: np.ndarray
    checks: list[dict[str, Any]]

    def __post_init__(self) -> None:
        self.force_n = _record_array(self.force_n, "force_n")
        self.response_m_s2 = _record_array(self.response_m_s2, "response_m_s2")
        if self.force_n.shape != self.response_m_s2.shape:
            raise ValueError(
                f"hits: force_n {self.force_n.shape} and response_m_s2 "
                f"{self.response_m_s2.shape} differ in shape"
            )
        if self.force_n.dtype != self.response_m_s2.dtype:
            raise ValueError("hits: force_n and response_m_s2 must both be float64 or both complex128")
        n_hits = self.force_n.shape[0]
        self.sample_rate_hz = _finite_float(self.sample_rate_hz, "hits.sample_rate_hz", positive=True)
        self.start_s = _finite_float(self.start_s, "hits.start_s")
        self.center_hz = _finite_float(self.center_hz, "hits.center_hz")
        if self.center_hz < 0:
            raise ValueError(f"hits.center_hz must be >= 0, got {self.center_hz}")
        if self.force_n.dtype == np.float64 and self.center_hz != 0:
            raise ValueError("hits: real (baseband) records need center_hz = 0; zoom records are complex128")
        self.accepted = _array(self.accepted, "hits.accepted", "b", (n_hits,), np.bool_)
        self.reject_reason = _text_array(self.reject_reason, "hits.reject_reason", n_hits)
        for i, (ok, reason) in enumerate(zip(self.accepted, self.reject_reason, strict=True)):
            if bool(ok) == bool(reason):
                raise ValueError(
                    f"hits: hit {i + 1} (index {i}) is {'accepted' if ok else 'rejected'} but its "
                    f"reject_reason is {reason!r} (must be empty exactly when accepted)"
                )
        self.overload = _array(self.overload, "hits.overload", "b", (n_hits, 2), np.bool_)
        self.peak_force_n = _array(self.peak_force_n, "hits.peak_force_n", "fiu", (n_hits,), np.float64)
        self.timestamp_utc = _text_array(self.timestamp_utc, "hits.timestamp_utc", n_hits)
        for stamp in self.timestamp_utc:
            check_iso_utc(str(stamp), "hits.timestamp_utc")
        if not isinstance(self.checks, (list, tuple)) or len(self.checks) != n_hits:
            raise ValueError(f"hits.checks must be a list of {n_hits} dicts (one per hit)")
        self.checks = [_json_dict(c, f"hits.checks[{i}]") for i, c in enumerate(self.checks)]

    @property
    def n_hits(self) -> int:
        return int(self.force_n.shape[0])

    @property
    def n_samples(self) -> int:
        return int(self.force_n.shape[1])

    @property
    def is_zoom(self) -> bool:
        return bool(self.force_n.dtype == np.complex128)

    def time_s(self) -> np.ndarray:
        """(n_samples,) time of each sample relative to the trigger, s."""
        return self.start_s + np.arange(self.n_samples) / self.sample_rate_hz


# What an FRF is, and its SI unit: displacement, velocity or acceleration over force.
FRF_FORMS = ("receptance", "mobility", "accelerance")
FRF_FORM_UNITS = {"receptance": "m/N", "mobility": "(m/s)/N", "accelerance": "(m/s^2)/N"}


@dataclass(eq=False)
class MeasuredFrf:
    """Frequency response functions in SI units, with coherence when known.

    frequency_hz: (n_lines,) Hz, strictly increasing.
    frf: (n_frf, n_lines) complex128 in the unit of ``form``.
    coherence: (n_frf, n_lines) float64 (dimensionless, 0..1) or None.
    labels: n_frf names, e.g. "H21" or the UFF record's description.
    form: what the FRFs are: "receptance" (displacement over force, m/N), "mobility"
        (velocity over force, (m/s)/N) or "accelerance" (acceleration over force,
        (m/s^2)/N, what an impact test measures). The data stay in the form they came in;
        analysis.spectra.convert_form turns one form into another.
    """

    frequency_hz: np.ndarray
    frf: np.ndarray
    coherence: np.ndarray | None
    labels: list[str]
    form: str = "accelerance"

    def __post_init__(self) -> None:
        if self.form not in FRF_FORMS:
            raise ValueError(f"frf.form {self.form!r} is not one of {', '.join(FRF_FORMS)}")
        self.form = str(self.form)
        self.frequency_hz = freq = _frequency_axis(self.frequency_hz, "frf.frequency_hz")
        frf = _array(self.frf, "frf.frf", "fiuc", None, np.complex128)
        if frf.ndim != 2 or frf.shape[0] == 0 or frf.shape[1] != freq.size:
            raise ValueError(f"frf.frf must have shape (n_frf >= 1, {freq.size}), got {frf.shape}")
        self.frf = frf
        if self.coherence is not None:
            self.coherence = _array(self.coherence, "frf.coherence", "fiu", frf.shape, np.float64)
        self.labels = list(_text_array(self.labels, "frf.labels", frf.shape[0]))

    @property
    def n_frf(self) -> int:
        return int(self.frf.shape[0])

    @property
    def n_lines(self) -> int:
        return int(self.frf.shape[1])


SPECTRUM_KINDS = ("power", "linear", "cross", "coherence", "other")


@dataclass(eq=False)
class Spectra:
    """Spectra that are not FRFs: auto-power, linear and cross spectra, coherence alone.

    frequency_hz: (n_lines,) Hz, strictly increasing.
    values: (n_traces, n_lines) float64, or complex128 (e.g. when a cross spectrum is
        among them; every trace then has the same dtype).
    kinds: n_traces of SPECTRUM_KINDS ("power", "linear", "cross", "coherence", "other").
    units: n_traces unit texts: SI where the source's unit is known ("V^2", "N^2",
        "(m/s^2)^2", "V", "N", "m/s^2"; "" for coherence), else the source's label verbatim.
    labels: n_traces names, e.g. the SDF trace title "Pwr Spec".
    """

    frequency_hz: np.ndarray
    values: np.ndarray
    kinds: list[str]
    units: list[str]
    labels: list[str]

    def __post_init__(self) -> None:
        self.frequency_hz = _frequency_axis(self.frequency_hz, "spectra.frequency_hz")
        values = np.asarray(self.values)
        if values.dtype not in (np.float64, np.complex128):
            raise ValueError(f"spectra.values must be float64 or complex128, got {values.dtype}")
        if values.ndim != 2 or values.shape[0] == 0 or values.shape[1] != self.frequency_hz.size:
            n_lines = self.frequency_hz.size
            raise ValueError(f"spectra.values must have shape (n_traces >= 1, {n_lines}), got {values.shape}")
        self.values = np.ascontiguousarray(values)
        n = values.shape[0]
        self.kinds = [str(k) for k in _text_array(self.kinds, "spectra.kinds", n)]
        for kind in self.kinds:
            if kind not in SPECTRUM_KINDS:
                raise ValueError(f"spectra.kinds: {kind!r} is not one of {', '.join(SPECTRUM_KINDS)}")
        self.units = [str(u) for u in _text_array(self.units, "spectra.units", n)]
        self.labels = [str(x) for x in _text_array(self.labels, "spectra.labels", n)]

    @property
    def n_traces(self) -> int:
        return int(self.values.shape[0])

    @property
    def n_lines(self) -> int:
        return int(self.values.shape[1])


@dataclass(eq=False)
class Instrument:
    """The analyzer as it identified itself and the settings it reported back.

    settings: JSON-able dict, e.g. span_hz, lines, record points, windows, ranges.
    """

    model: str
    identification: str
    resource: str
    transport: str
    dialect: str
    settings: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for name in ("model", "identification", "resource", "transport", "dialect"):
            _text(getattr(self, name), f"instrument.{name}")
        self.settings = _json_dict(self.settings, "instrument.settings")


@dataclass(eq=False)
class Sample:
    """The test article: a uniform cantilever beam, SI units as the names say.

    force_position_m, sensor_position_m: distance from the clamp, m (None if unknown).
    """

    density_kg_m3: float
    youngs_modulus_pa: float
    width_m: float
    height_m: float
    length_m: float
    area_m2: float
    second_moment_m4: float
    force_position_m: float | None = None
    sensor_position_m: float | None = None

    def __post_init__(self) -> None:
        for name in SAMPLE_ATTRS:
            setattr(self, name, _finite_float(getattr(self, name), f"sample.{name}", positive=True))
        for name in ("force_position_m", "sensor_position_m"):
            value = getattr(self, name)
            if value is not None:
                value = _finite_float(value, f"sample.{name}")
                if not 0 <= value <= self.length_m:
                    raise ValueError(
                        f"sample.{name} = {value} m lies outside the beam (0..{self.length_m} m)"
                    )
                setattr(self, name, value)


@dataclass(eq=False)
class Run:
    """One impact test (or one imported FRF or spectrum set) as stored on disk.

    complete: False when the run was sealed after an interruption (listed as incomplete).
    start_time, end_time: ISO 8601 UTC, e.g. "2026-11-23T10:15:03.123Z".
    provenance: JSON-able dict: replayed_from run id, imported file name and SHA-256,
        simulator scenario and seed...
    hits: None for a run without time records (e.g. imported FRFs).
    analyzer: the averaged FRF/coherence the analyzer itself computed, if read.
    measured_frfs: FRFs imported from elsewhere (UFF 58, SDF), if any.
    spectra: spectra that are not FRFs (power, linear, cross, coherence alone), if any;
        kept, shown and exported, but nothing to identify modes from.
    points: the test article, force point and response point(s), and the modal test the
        run belongs to (RunPoints), or None when the run does not say (every run written
        before points existed). :meth:`resolved_points` gives them either way: for None,
        :func:`default_points` of ``sample`` (the seed's beam, or the beam of ``sample``;
        hammer and sensor where ``sample`` puts them, else at the tip).
    """

    run_id: str
    kind: str
    complete: bool
    start_time: str
    end_time: str
    operator: str = ""
    note: str = ""
    software: str = SOFTWARE
    provenance: dict[str, Any] = field(default_factory=dict)
    instrument: Instrument | None = None
    sample: Sample | None = None
    hits: Hits | None = None
    analyzer: MeasuredFrf | None = None
    measured_frfs: MeasuredFrf | None = None
    spectra: Spectra | None = None
    points: RunPoints | None = None

    def __post_init__(self) -> None:
        if not is_run_id(self.run_id):
            raise ValueError(
                f"run_id {self.run_id!r} is not a valid run id (e.g. 20261123T101503.123Z-3f9c1a2b)"
            )
        if self.kind not in RUN_KINDS:
            raise ValueError(f"run kind {self.kind!r} is not one of {', '.join(RUN_KINDS)}")
        if not isinstance(self.complete, (bool, np.bool_)):
            raise ValueError(f"run.complete must be a bool, got {type(self.complete).__name__}")
        self.complete = bool(self.complete)
        check_iso_utc(self.start_time, "run.start_time")
        check_iso_utc(self.end_time, "run.end_time")
        for name in ("operator", "note", "software"):
            _text(getattr(self, name), f"run.{name}")
        self.provenance = _json_dict(self.provenance, "run.provenance")
        for name, cls in (
            ("instrument", Instrument),
            ("sample", Sample),
            ("hits", Hits),
            ("analyzer", MeasuredFrf),
            ("measured_frfs", MeasuredFrf),
            ("spectra", Spectra),
        ):
            value = getattr(self, name)
            if value is not None and not isinstance(value, cls):
                raise ValueError(f"run.{name} must be a {cls.__name__} or None, got {type(value).__name__}")
        if all(getattr(self, n) is None for n in ("hits", "analyzer", "measured_frfs", "spectra")):
            raise ValueError("a run needs hits, an analyzer FRF, measured FRFs or spectra: it has none")
        if self.points is not None:
            if not isinstance(self.points, RunPoints):
                raise ValueError(f"run.points must be a RunPoints or None, got {type(self.points).__name__}")
            check_points_against_sample(self.points, self.sample)

    def resolved_points(self) -> RunPoints:
        """Where the run was measured: ``points``, or for a run that does not say,
        default_points(sample) (the seed's beam with hammer and sensor at the tip)."""
        return self.points if self.points is not None else default_points(self.sample)


# --- test articles and measurement points -----------------------------------------

#: The seed paper's Table 1 beam, SI (analysis.beam.TABLE_1 holds the same numbers; the
#: store imports nothing of analysis, and a test checks the two agree).
SEED_BEAM = {
    "density_kg_m3": 2710.0,
    "youngs_modulus_pa": 7.1e10,
    "width_m": 31.7e-3,
    "height_m": 3.3e-3,
    "length_m": 0.7,
    "area_m2": 10.46e-5,
    "second_moment_m4": 9.493e-11,
}
ARTICLE_KINDS = ("seed-beam", "cantilever", "free")
DIRECTIONS = ("+x", "-x", "+y", "-y", "+z", "-z")
#: Point and node names: letters, digits, _ and -, starting with a letter or digit, at
#: most 64 (no "=", ",", ":" or dot, so that `--points p1=0.1,p2=0.2:-z` parses).
POINT_NAME_PATTERN = re.compile(r"[A-Za-z0-9][A-Za-z0-9_-]{0,63}")
#: Modal test names: the rule of result names (lower-case letters, digits, _ and -, at
#: most 64): a plain file name on every filesystem, case-insensitive ones included.
TEST_NAME_PATTERN = re.compile(r"[a-z0-9][a-z0-9_-]{0,63}")
#: Two positions closer than this are the same point, m.
POSITION_TOLERANCE_M = 1e-9
_CANTILEVER_KEYS = ("length_m", "width_m", "thickness_m")
_CANTILEVER_OPTIONAL = ("area_m2", "second_moment_m4")
_MATERIAL_KEYS = ("youngs_modulus_pa", "density_kg_m3")


def check_test_name(name: object) -> str:
    """``name`` if it is a valid modal test name, else ValueError (one line)."""
    if not isinstance(name, str) or TEST_NAME_PATTERN.fullmatch(name) is None:
        shown = repr(name if not isinstance(name, str) or len(name) <= 40 else name[:40] + "...")
        raise ValueError(
            f"invalid test name {shown}: use lower-case letters, digits, _ and - (at most 64, "
            "starting with a letter or digit)"
        )
    return name


def check_point_name(name: object, what: str = "point name") -> str:
    """``name`` if it is a valid point (or node) name, else ValueError (one line)."""
    if not isinstance(name, str) or POINT_NAME_PATTERN.fullmatch(name) is None:
        shown = repr(name if not isinstance(name, str) or len(name) <= 40 else name[:40] + "...")
        raise ValueError(
            f"invalid {what} {shown}: use letters, digits, _ and - (at most 64, starting with a "
            "letter or digit)"
        )
    return name


@dataclass(frozen=True)
class Point:
    """A named measurement point: where the hammer strikes or a sensor sits.

    name: letters, digits, _ and - (POINT_NAME_PATTERN).
    position_m: on a beam, the distance from the clamp, m (None on a free structure).
    direction: of the force or the measured response, one of DIRECTIONS ("+z"...).
    node: on a free structure, the article's node the point sits on (None on a beam).
    Exactly one of ``position_m`` and ``node`` is given.
    """

    name: str
    position_m: float | None = None
    direction: str = "+z"
    node: str | None = None

    def __post_init__(self) -> None:
        check_point_name(self.name)
        if self.direction not in DIRECTIONS:
            raise ValueError(
                f"point {self.name}: direction {self.direction!r} is not one of {', '.join(DIRECTIONS)}"
            )
        if (self.position_m is None) == (self.node is None):
            raise ValueError(f"point {self.name}: give either position_m (a beam) or node (a free structure)")
        if self.position_m is not None:
            position = _finite_float(self.position_m, f"point {self.name}: position_m")
            if position < 0:
                raise ValueError(f"point {self.name}: position_m must be >= 0 m, got {position}")
            object.__setattr__(self, "position_m", position)
        else:
            check_point_name(self.node, f"point {self.name}: node name")

    def to_dict(self) -> dict[str, Any]:
        """{name, position_m | node, direction}: what the run and the test files hold."""
        where = {"position_m": self.position_m} if self.node is None else {"node": self.node}
        return {"name": self.name, **where, "direction": self.direction}

    @classmethod
    def from_dict(cls, value: object, what: str = "point") -> Point:
        """The point of a dict as to_dict makes it; ValueError (one line) naming ``what``."""
        if not isinstance(value, dict):
            raise ValueError(f"{what} must be a table, got {type(value).__name__}")
        unknown = sorted(set(value) - {"name", "position_m", "node", "direction"})
        if unknown:
            raise ValueError(f"{what}: unknown key(s) {', '.join(map(str, unknown))}")
        if "name" not in value:
            raise ValueError(f"{what}: name is missing")
        if "direction" not in value:
            raise ValueError(f"{what} {value['name']}: direction is missing")
        try:
            return cls(
                name=value["name"],
                position_m=value.get("position_m"),
                direction=value["direction"],
                node=value.get("node"),
            )
        except ValueError as exc:
            raise ValueError(f"{what}: {exc}") from None

    def same_place(self, other: Point) -> bool:
        """Whether ``other`` sits where this point does (positions within
        POSITION_TOLERANCE_M, or the same node); names and directions are not compared."""
        if self.node is not None or other.node is not None:
            return self.node == other.node
        return abs(self.position_m - other.position_m) <= POSITION_TOLERANCE_M


def check_article(value: object) -> dict[str, Any]:
    """The test article ``value`` checked and normalised (floats, sorted node list kept in
    order); ValueError with one line naming the field.

    Kinds (SI units in the key names):

    - ``{"kind": "seed-beam"}``: the seed paper's Table 1 beam (SEED_BEAM), clamped;
    - ``{"kind": "cantilever", "material": {"youngs_modulus_pa", "density_kg_m3"[, "name"]},
      "length_m", "width_m", "thickness_m"[, "area_m2", "second_moment_m4"]}``: a uniform
      clamped beam of rectangular section (A = b*h, I = b*h^3/12 unless given);
    - ``{"kind": "free", "nodes": [{"name", "x_m", "y_m", "z_m", "direction"}, ...]}``: a
      structure given as nodes (coordinates in m, a direction each).

    Every kind may carry ``"name"``, free text describing the article.
    """
    if not isinstance(value, dict):
        raise ValueError(f"article must be a table, got {type(value).__name__}")
    kind = value.get("kind")
    if kind not in ARTICLE_KINDS:
        shown = "missing" if kind is None else repr(kind)
        raise ValueError(f"article.kind is {shown}: use one of {', '.join(ARTICLE_KINDS)}")
    out: dict[str, Any] = {"kind": kind}
    known = {"kind", "name"} | {
        "seed-beam": set(),
        "cantilever": {"material", *_CANTILEVER_KEYS, *_CANTILEVER_OPTIONAL},
        "free": {"nodes"},
    }[kind]
    unknown = sorted(set(value) - known)
    if unknown:  # first: a misspelt key is named as such, not as a missing one
        raise ValueError(f"article ({kind}): unknown key(s) {', '.join(map(str, unknown))}")
    if "name" in value:
        out["name"] = _text(value["name"], "article.name")
    if kind == "cantilever":
        material = value.get("material")
        if not isinstance(material, dict):
            raise ValueError("article.material must be a table (youngs_modulus_pa, density_kg_m3)")
        unknown = sorted(set(material) - {*_MATERIAL_KEYS, "name"})
        if unknown:
            raise ValueError(f"article.material: unknown key(s) {', '.join(map(str, unknown))}")
        out["material"] = {}
        if "name" in material:
            out["material"]["name"] = _text(material["name"], "article.material.name")
        for key in _MATERIAL_KEYS:
            if key not in material:
                raise ValueError(f"article.material.{key} is missing")
            out["material"][key] = _finite_float(material[key], f"article.material.{key}", positive=True)
        for key in _CANTILEVER_KEYS:
            if key not in value:
                raise ValueError(f"article.{key} is missing")
            out[key] = _finite_float(value[key], f"article.{key}", positive=True)
        for key in _CANTILEVER_OPTIONAL:
            if key in value:
                out[key] = _finite_float(value[key], f"article.{key}", positive=True)
    elif kind == "free":
        nodes = value.get("nodes")
        if not isinstance(nodes, (list, tuple)) or not nodes:
            raise ValueError(
                "article.nodes must be a non-empty list of nodes (name, x_m, y_m, z_m, direction)"
            )
        out["nodes"] = []
        seen: set[str] = set()
        for i, node in enumerate(nodes):
            what = f"article.nodes[{i}]"
            if not isinstance(node, dict):
                raise ValueError(f"{what} must be a table, got {type(node).__name__}")
            unknown = sorted(set(node) - {"name", "x_m", "y_m", "z_m", "direction"})
            if unknown:
                raise ValueError(f"{what}: unknown key(s) {', '.join(map(str, unknown))}")
            for key in ("name", "x_m", "y_m", "z_m", "direction"):
                if key not in node:
                    raise ValueError(f"{what}.{key} is missing")
            name = check_point_name(node["name"], f"{what}.name")
            if name in seen:
                raise ValueError(f"{what}.name {name!r} is used by an earlier node")
            seen.add(name)
            if node["direction"] not in DIRECTIONS:
                raise ValueError(
                    f"{what}.direction {node['direction']!r} is not one of {', '.join(DIRECTIONS)}"
                )
            out["nodes"].append(
                {
                    "name": name,
                    **{k: _finite_float(node[k], f"{what}.{k}") for k in ("x_m", "y_m", "z_m")},
                    "direction": node["direction"],
                }
            )
    return out


def article_length_m(article: dict[str, Any]) -> float | None:
    """The beam's length of a checked article, m; None for a free structure."""
    if article["kind"] == "seed-beam":
        return SEED_BEAM["length_m"]
    if article["kind"] == "cantilever":
        return article["length_m"]
    return None


def article_sample_values(article: dict[str, Any]) -> dict[str, float] | None:
    """The Sample attributes (SAMPLE_ATTRS, SI) of a checked beam article; None for a
    free structure. A cantilever's A and I are b*h and b*h^3/12 unless it gives them."""
    if article["kind"] == "seed-beam":
        return dict(SEED_BEAM)
    if article["kind"] != "cantilever":
        return None
    b, h = article["width_m"], article["thickness_m"]
    return {
        "density_kg_m3": article["material"]["density_kg_m3"],
        "youngs_modulus_pa": article["material"]["youngs_modulus_pa"],
        "width_m": b,
        "height_m": h,
        "length_m": article["length_m"],
        "area_m2": article.get("area_m2", b * h),
        "second_moment_m4": article.get("second_moment_m4", b * h**3 / 12.0),
    }


def check_point_on_article(point: Point, article: dict[str, Any], what: str = "point") -> Point:
    """``point`` if it lies on the checked ``article`` (a beam position between the clamp
    and the tip, or a node the free structure has), else ValueError naming it."""
    length = article_length_m(article)
    if length is not None:
        if point.position_m is None:
            raise ValueError(f"{what} {point.name} names node {point.node!r}, but the article is a beam")
        if point.position_m > length + POSITION_TOLERANCE_M or point.position_m <= POSITION_TOLERANCE_M:
            # At the clamp nothing moves: no hammer or sensor can measure there.
            raise ValueError(
                f"{what} {point.name} at {point.position_m} m lies outside the beam (0 < x <= {length} m)"
            )
    else:
        if point.node is None:
            raise ValueError(f"{what} {point.name} has a position, but the article is a free structure")
        names = [node["name"] for node in article["nodes"]]
        if point.node not in names:
            raise ValueError(f"{what} {point.name}: the article has no node {point.node!r}")
    return point


@dataclass(frozen=True)
class RunPoints:
    """Where a run was measured: its article, force point and response point(s).

    article: a test article as check_article accepts it (normalised on construction).
    force_point: where the force went in (Point).
    response_points: the points whose responses the run holds, in the order of its
        response channels (tuple of Point, at least one, distinct names).
    test: the modal test the run was measured for, "" when none.
    """

    article: dict[str, Any]
    force_point: Point
    response_points: tuple[Point, ...]
    test: str = ""

    def __post_init__(self) -> None:
        object.__setattr__(self, "article", check_article(self.article))
        if not isinstance(self.force_point, Point):
            raise ValueError(f"points.force_point must be a Point, got {type(self.force_point).__name__}")
        responses = self.response_points
        if isinstance(responses, Point) or not isinstance(responses, (list, tuple)) or not responses:
            raise ValueError("points.response_points must be a non-empty list of Point")
        responses = tuple(responses)
        for point in responses:
            if not isinstance(point, Point):
                raise ValueError(f"points.response_points holds a {type(point).__name__}, not a Point")
        names = [p.name for p in responses]
        if len(set(names)) != len(names):
            raise ValueError(f"points.response_points: a name is used twice ({', '.join(names)})")
        object.__setattr__(self, "response_points", responses)
        check_point_on_article(self.force_point, self.article, "force point")
        for point in responses:
            check_point_on_article(point, self.article, "response point")
        if self.test != "":
            check_test_name(self.test)

    def to_dicts(self) -> dict[str, Any]:
        """{test, article, force_point, response_points} as plain JSON-able values."""
        return {
            "test": self.test,
            "article": self.article,
            "force_point": self.force_point.to_dict(),
            "response_points": [p.to_dict() for p in self.response_points],
        }


def default_points(sample: Sample | None) -> RunPoints:
    """Where a run that does not say was measured: the seed's beam (or the beam of
    ``sample`` when it is another one), force at ``sample.force_position_m`` and the
    response at ``sample.sensor_position_m``, each at the tip when not given; both "+z".

    Points at the tip are named "tip", others "force" and "response".
    """
    if sample is None or all(
        math.isclose(getattr(sample, k), v, rel_tol=1e-12) for k, v in SEED_BEAM.items()
    ):
        article: dict[str, Any] = {"kind": "seed-beam"}
    else:
        article = {
            "kind": "cantilever",
            "material": {
                "youngs_modulus_pa": sample.youngs_modulus_pa,
                "density_kg_m3": sample.density_kg_m3,
            },
            "length_m": sample.length_m,
            "width_m": sample.width_m,
            "thickness_m": sample.height_m,
            "area_m2": sample.area_m2,
            "second_moment_m4": sample.second_moment_m4,
        }
    length = article_length_m(check_article(article))

    def at(position: float | None, other: str) -> Point:
        position = length if position is None else position
        name = "tip" if abs(position - length) <= POSITION_TOLERANCE_M else other
        return Point(name, position, "+z")

    force = at(None if sample is None else sample.force_position_m, "force")
    response = at(None if sample is None else sample.sensor_position_m, "response")
    return RunPoints(article=article, force_point=force, response_points=(response,))


def check_points_against_sample(points: RunPoints, sample: Sample | None) -> None:
    """ValueError when ``sample`` and ``points`` disagree on the beam or the positions
    (the sample's positions are what software before points reads)."""
    if sample is None:
        return
    values = article_sample_values(points.article)
    if values is not None and not math.isclose(values["length_m"], sample.length_m, rel_tol=1e-9):
        raise ValueError(
            f"run.points: the article's beam is {values['length_m']} m long, "
            f"sample.length_m is {sample.length_m} m"
        )
    pairs = [("force_position_m", points.force_point)]
    if len(points.response_points) == 1:
        pairs.append(("sensor_position_m", points.response_points[0]))
    for name, point in pairs:
        stated = getattr(sample, name)
        if stated is not None and point.position_m is not None and abs(stated - point.position_m) > 1e-9:
            raise ValueError(
                f"run.points: {point.name} is at {point.position_m} m but sample.{name} is {stated} m"
            )


def check_iso_utc(text: object, what: str) -> str:
    """``text`` if it is an ISO 8601 time in UTC ("...Z" or "...+00:00"), else ValueError."""
    if not isinstance(text, str):
        raise ValueError(f"{what} must be an ISO 8601 UTC string, got {type(text).__name__}")
    try:
        stamp = datetime.fromisoformat(text)
    except ValueError:
        raise ValueError(f"{what} {text!r} is not an ISO 8601 time") from None
    if stamp.utcoffset() is None or stamp.utcoffset().total_seconds() != 0:
        raise ValueError(f"{what} {text!r} must be in UTC (end in Z or +00:00)")
    return text


def _text(value: object, what: str) -> str:
    if not isinstance(value, str):
        raise ValueError(f"{what} must be a str, got {type(value).__name__}")
    # NUL cannot survive HDF5's fixed-length strings (it is the padding character).
    if "\x00" in value:
        raise ValueError(f"{what} contains a NUL character")
    return value


def _text_array(values: object, what: str, n: int) -> np.ndarray:
    items = list(values) if not isinstance(values, str) else None
    if items is None or len(items) != n:
        raise ValueError(f"{what} must hold {n} strings")
    for i, item in enumerate(items):
        _text(item, f"{what}[{i}]")  # np.str_ is a str too
    return np.array([str(item) for item in items], dtype=str) if n else np.array([], dtype=str)


def _frequency_axis(value: object, what: str) -> np.ndarray:
    """(n_lines,) float64 Hz, non-empty, finite and strictly increasing, else ValueError."""
    freq = _array(value, what, "fiu", None, np.float64)
    if freq.ndim != 1 or freq.size == 0:
        raise ValueError(f"{what} must be a non-empty 1-D array, got shape {freq.shape}")
    if not np.all(np.isfinite(freq)) or np.any(np.diff(freq) <= 0):
        raise ValueError(f"{what} must be finite and strictly increasing")
    return freq


def _finite_float(value: object, what: str, positive: bool = False) -> float:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ValueError(f"{what} must be a number, got {type(value).__name__}")
    number = float(value)
    if not math.isfinite(number) or (positive and number <= 0):
        raise ValueError(f"{what} must be {'positive and ' if positive else ''}finite, got {number}")
    return number


def _array(value: object, what: str, kinds: str, shape: tuple[int, ...] | None, dtype: type) -> np.ndarray:
    array = np.asarray(value)
    if array.dtype.kind not in kinds:
        raise ValueError(f"{what} must have dtype kind {kinds!r} ({np.dtype(dtype).name}), got {array.dtype}")
    if shape is not None and array.shape != shape:
        raise ValueError(f"{what} must have shape {shape}, got {array.shape}")
    return np.ascontiguousarray(array, dtype=dtype)


def _record_array(value: object, what: str) -> np.ndarray:
    array = np.asarray(value)
    if array.dtype not in (np.float64, np.complex128):
        raise ValueError(f"hits.{what} must be float64 (baseband) or complex128 (zoom), got {array.dtype}")
    if array.ndim != 2 or array.shape[0] == 0 or array.shape[1] == 0:
        raise ValueError(f"hits.{what} must have shape (n_hits >= 1, n_samples >= 1), got {array.shape}")
    return np.ascontiguousarray(array)


def _json_dict(value: object, what: str) -> dict[str, Any]:
    if not isinstance(value, dict):
        raise ValueError(f"{what} must be a dict, got {type(value).__name__}")
    try:
        # Round trip so the in-memory value equals what a reader will get back
        # (tuples become lists, numpy scalars are refused rather than mangled).
        return json.loads(json.dumps(value, allow_nan=False))
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{what} is not JSON-able: {exc}") from None
