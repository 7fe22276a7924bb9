"""Test articles and measurement points from what a user types: an article file or a
built-in name, ``--points p1=0.1,p2=0.2``, ``--sensor tip``.

The article is kept as the store keeps it (a plain table, daq.store.model.check_article)
and turned into analysis objects here: a beam into analysis.beam.BeamProperties, a free
structure into a list of Node. Every refusal is one WorkflowError line naming the field.
docs/modal-tests.md describes the article file.
"""

from __future__ import annotations

import errno
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from analysis.beam import TABLE_1, BeamProperties
from daq.store.errors import StoreError
from daq.store.model import (
    DIRECTIONS,
    Point,
    RunPoints,
    Sample,
    article_length_m,
    article_sample_values,
    check_article,
    check_point_on_article,
)
from daq.store.text_files import parse_toml, read_bounded
from daq.workflows.errors import WorkflowError

#: The built-in articles, by the name ``--article`` takes.
BUILT_IN_ARTICLES = {"seed-beam": {"kind": "seed-beam"}}
DEFAULT_ARTICLE = "seed-beam"
#: An article file larger than this is refused unread.
MAX_ARTICLE_FILE_BYTES = 1 * 2**20
#: Points one --points option may name.
MAX_POINTS = 10_000


@dataclass(frozen=True)
class Node:
    """A node of a free structure: name, coordinates x_m, y_m, z_m (m) and the
    direction measured there (one of daq.store.model.DIRECTIONS)."""

    name: str
    x_m: float
    y_m: float
    z_m: float
    direction: str


def read_article(spec: str | Path | None = None) -> dict[str, Any]:
    """The article ``spec`` names, checked: None or "seed-beam" (the seed's Table 1 beam),
    or the path of a TOML article file (docs/modal-tests.md: its keys at the top level or
    under ``[article]``). WorkflowError (one line, naming the file and the field)."""
    if spec is None:
        spec = DEFAULT_ARTICLE
    if isinstance(spec, str) and spec in BUILT_IN_ARTICLES:
        return check_article(BUILT_IN_ARTICLES[spec])
    path = Path(spec)
    if isinstance(spec, str) and path.suffix.lower() != ".toml" and not path.exists():
        raise WorkflowError(
            f"unknown article {spec!r}: give a built-in ({', '.join(BUILT_IN_ARTICLES)}) "
            "or an article file (.toml)",
            exit_code=2,
        )
    what = f"article file {path}"
    try:
        doc = parse_toml(read_bounded(path, MAX_ARTICLE_FILE_BYTES, what), what)
    except FileNotFoundError:
        raise WorkflowError(f"cannot read {what}: {os.strerror(errno.ENOENT)}") from None
    except StoreError as exc:
        raise WorkflowError(str(exc)) from None
    return parse_article(doc, str(path))


def parse_article(doc: dict[str, Any], where: str = "article") -> dict[str, Any]:
    """The article in the TOML table ``doc`` (its keys, or an ``article`` table holding
    them), checked and normalised; WorkflowError naming ``where`` and the field."""
    if isinstance(doc, dict) and set(doc) == {"article"}:
        doc = doc["article"]
    try:
        return check_article(doc)
    except ValueError as exc:
        raise WorkflowError(f"{where}: {exc}") from None


def cantilever_article(
    youngs_modulus_pa: float,
    density_kg_m3: float,
    length_m: float,
    width_m: float,
    thickness_m: float,
    name: str = "",
) -> dict[str, Any]:
    """A clamped uniform beam of rectangular section (SI: Pa, kg/m^3, m), checked."""
    article: dict[str, Any] = {
        "kind": "cantilever",
        "material": {"youngs_modulus_pa": youngs_modulus_pa, "density_kg_m3": density_kg_m3},
        "length_m": length_m,
        "width_m": width_m,
        "thickness_m": thickness_m,
    }
    if name:
        article["name"] = name
    return parse_article(article)


def article_beam(article: dict[str, Any]) -> BeamProperties | None:
    """The beam of ``article`` for the analysis (None for a free structure): the seed's
    Table 1 for "seed-beam"; for "cantilever", E, rho, L, b, h of the article with
    A = b*h and I = b*h^3/12 unless the article gives them."""
    article = parse_article(article)
    if article["kind"] == "seed-beam":
        return TABLE_1
    values = article_sample_values(article)
    if values is None:
        return None
    try:
        return BeamProperties(**values)
    except ValueError as exc:
        raise WorkflowError(f"article: {exc}") from None


def article_nodes(article: dict[str, Any]) -> list[Node]:
    """The nodes of a free structure, in the article's order ([] for a beam)."""
    article = parse_article(article)
    return [Node(**node) for node in article.get("nodes", [])]


def sample_for(points: RunPoints) -> Sample | None:
    """The run's /entry/sample for a run measured at ``points``: the beam's properties of
    ``points.article`` (SI) with force_position_m at the force point and
    sensor_position_m at the response point (when there is one response point); None
    for a free structure. What software before points reads, and what Run checks
    points against."""
    values = article_sample_values(points.article)
    if values is None:
        return None
    sensor = points.response_points[0].position_m if len(points.response_points) == 1 else None
    return Sample(**values, force_position_m=points.force_point.position_m, sensor_position_m=sensor)


def parse_points(text: str, article: dict[str, Any] | None = None) -> list[Point]:
    """The points of ``--points`` text: ``name=where[:direction]`` separated by commas.

    where: on a beam, the distance from the clamp in m (``p1=0.1``); on a free structure,
        a node's name (``p1=n7``).
    direction: one of +x, -x, +y, -y, +z, -z; default "+z" on a beam, the node's own on
        a free structure.
    article: the checked article the points lie on (default: the seed's beam); each
        point is checked against it (inside the beam, an existing node).
    Returns the points in the order given. WorkflowError (one line, exit status 2) for
    empty text, a bad name, a repeated name, a bad number or direction, a point off the
    article.
    """
    article = parse_article(article if article is not None else BUILT_IN_ARTICLES[DEFAULT_ARTICLE])
    if not isinstance(text, str) or not text.strip():
        raise WorkflowError("--points is empty: give e.g. p1=0.1,p2=0.2", exit_code=2)
    items = [item.strip() for item in text.split(",")]
    if len(items) > MAX_POINTS:
        raise WorkflowError(f"--points names {len(items)} points, more than {MAX_POINTS}", exit_code=2)
    points: list[Point] = []
    seen: set[str] = set()
    for item in items:
        point = _parse_one(item, article)
        if point.name in seen:
            raise WorkflowError(f"--points: point {point.name} is given twice", exit_code=2)
        seen.add(point.name)
        points.append(point)
    return points


def format_points(points: list[Point]) -> str:
    """The ``--points`` text of ``points`` (parse_points reads it back to the same points)."""
    return ",".join(
        f"{p.name}={_format_position(p.position_m) if p.node is None else p.node}:{p.direction}"
        for p in points
    )


def parse_fixed_point(text: str, points: list[Point], article: dict[str, Any] | None = None) -> Point:
    """The fixed point of ``--sensor`` (roving hammer) or ``--force-at`` (roving sensor):
    the name of one of ``points`` (the driving point), ``tip`` (a beam's free end, "+z"),
    or a new point ``name=where[:direction]`` as in --points. WorkflowError (exit 2)."""
    article = parse_article(article if article is not None else BUILT_IN_ARTICLES[DEFAULT_ARTICLE])
    if not isinstance(text, str) or not text.strip():
        raise WorkflowError("the fixed point is empty: give a point's name, tip, or name=position", 2)
    text = text.strip()
    for point in points:
        if point.name == text:
            return point
    if "=" in text:
        point = _parse_one(text, article)
        clash = [p for p in points if p.name == point.name]
        if clash and not (clash[0].same_place(point) and clash[0].direction == point.direction):
            raise WorkflowError(f"fixed point {point.name} has the name of a point elsewhere", exit_code=2)
        return point
    length = article_length_m(article)
    if text == "tip" and length is not None:
        return Point("tip", length, "+z")
    names = ", ".join(p.name for p in points)
    raise WorkflowError(
        f"fixed point {text!r} is none of the points ({names}){' nor tip' if length is not None else ''}; "
        "give name=position",
        exit_code=2,
    )


def _parse_one(item: str, article: dict[str, Any]) -> Point:
    name, sep, rest = item.partition("=")
    name = name.strip()
    if not sep:
        raise WorkflowError(f"--points: {_show(item)} is not name=position (e.g. p1=0.1)", exit_code=2)
    where, colon, direction = rest.strip().partition(":")
    where, direction = where.strip(), direction.strip()
    if colon and direction not in DIRECTIONS:
        raise WorkflowError(
            f"--points: point {_show(name)}: direction {_show(direction)} is not one of "
            + ", ".join(DIRECTIONS),
            exit_code=2,
        )
    try:
        if article["kind"] == "free":
            node = next((n for n in article["nodes"] if n["name"] == where), None)
            if node is None:
                raise ValueError(f"point {name}: the article has no node {where!r}")
            point = Point(name, None, direction if colon else node["direction"], node=where)
        else:
            try:
                position = float(where)
            except ValueError:
                raise ValueError(
                    f"point {name}: position {where!r} is not a number of metres from the clamp"
                ) from None
            if not math.isfinite(position):
                raise ValueError(f"point {name}: position {where!r} is not finite")
            point = Point(name, position, direction if colon else "+z")
        return check_point_on_article(point, article)
    except ValueError as exc:
        raise WorkflowError(f"--points: {exc}", exit_code=2) from None


def _format_position(position: float) -> str:
    return repr(float(position))


def _show(text: str) -> str:
    return repr(text if len(text) <= 40 else text[:40] + "...")
