"""Articles and points from what a user types (daq/workflows/article.py): the article
file and the built-ins, the analysis objects they become, and the --points parser
(property tests: any points written out read back the same; bad text is one line)."""

from __future__ import annotations

import math

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from analysis.beam import TABLE_1, BeamProperties
from daq.store import Point, RunPoints
from daq.store.model import DIRECTIONS, SEED_BEAM
from daq.workflows.article import (
    Node,
    article_beam,
    article_nodes,
    cantilever_article,
    format_points,
    parse_fixed_point,
    parse_points,
    read_article,
    sample_for,
)
from daq.workflows.errors import WorkflowError

SETTINGS = settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
SEED = {"kind": "seed-beam"}
FREE = {
    "kind": "free",
    "nodes": [
        {"name": "n1", "x_m": 0.0, "y_m": 0.0, "z_m": 0.0, "direction": "+z"},
        {"name": "corner-2", "x_m": 0.5, "y_m": 0.2, "z_m": -0.1, "direction": "-x"},
    ],
}
ARTICLE_FILE = """\
# a steel bar clamped at one end
[article]
kind = "cantilever"
name = "steel bar"
length_m = 0.5
width_m = 0.03
thickness_m = 0.004

[article.material]
name = "S235"
youngs_modulus_pa = 2.1e11
density_kg_m3 = 7850
"""


def test_the_store_knows_the_seed_beam_as_the_analysis_does():
    assert TABLE_1.to_dict() == SEED_BEAM


def test_built_in_and_file_articles(tmp_path):
    assert read_article() == read_article("seed-beam") == SEED
    assert article_beam(read_article()) == TABLE_1
    path = tmp_path / "bar.toml"
    path.write_text(ARTICLE_FILE)
    bar = read_article(path)
    assert bar == read_article(str(path))
    assert bar["material"]["name"] == "S235"
    beam = article_beam(bar)
    assert beam == BeamProperties(7850.0, 2.1e11, 0.03, 0.004, 0.5, 0.03 * 0.004, 0.03 * 0.004**3 / 12)
    assert cantilever_article(2.1e11, 7850, 0.5, 0.03, 0.004, name="steel bar") == {
        k: v for k, v in bar.items() if k != "material"
    } | {"material": {"youngs_modulus_pa": 2.1e11, "density_kg_m3": 7850.0}}
    # top-level keys work as well as an [article] table
    flat = tmp_path / "flat.toml"
    flat.write_text(ARTICLE_FILE.replace("[article]\n", "").replace("[article.material]", "[material]"))
    assert read_article(flat) == bar
    assert article_beam(FREE) is None
    assert article_nodes(FREE) == [Node("n1", 0.0, 0.0, 0.0, "+z"), Node("corner-2", 0.5, 0.2, -0.1, "-x")]
    assert article_nodes(bar) == []


@pytest.mark.parametrize(
    ("text", "says"),
    [
        ('kind = "plate"', "article.kind is 'plate'"),
        ("length_m = 0.5", "article.kind is missing"),
        (ARTICLE_FILE.replace("width_m = 0.03\n", ""), "article.width_m is missing"),
        (ARTICLE_FILE.replace("0.004", '"thin"'), "article.thickness_m must be a number, got str"),
        (ARTICLE_FILE.replace("7850", "-1"), "article.material.density_kg_m3 must be positive"),
        (ARTICLE_FILE.replace("length_m", "lenght_m"), "unknown key(s) lenght_m"),
        (ARTICLE_FILE + "\nmass = 1\n", "unknown key(s) mass"),
        ("kind = [1", "not valid TOML"),
        ('kind = "free"\nnodes = []', "article.nodes must be a non-empty list"),
        (
            'kind = "free"\n[[nodes]]\nname = "a"\nx_m = 0\ny_m = 0\nz_m = 0\ndirection = "+z"\n'
            '[[nodes]]\nname = "a"\nx_m = 1\ny_m = 0\nz_m = 0\ndirection = "+z"\n',
            "article.nodes[1].name 'a' is used by an earlier node",
        ),
        (
            'kind = "free"\n[[nodes]]\nname = "a"\nx_m = 0\ny_m = 0\ndirection = "+z"\n',
            "nodes[0].z_m is missing",
        ),
    ],
)
def test_bad_article_files_are_one_line_naming_the_field(tmp_path, text, says):
    path = tmp_path / "article.toml"
    path.write_text(text)
    with pytest.raises(WorkflowError) as caught:
        read_article(path)
    message = str(caught.value)
    assert says in message
    assert str(path) in message
    assert "\n" not in message


def test_unknown_articles_and_missing_files(tmp_path):
    with pytest.raises(WorkflowError, match="unknown article 'plate'") as caught:
        read_article("plate")
    assert caught.value.exit_code == 2
    with pytest.raises(WorkflowError, match="cannot read article file"):
        read_article(tmp_path / "absent.toml")
    (tmp_path / "bin.toml").write_bytes(b"\xff\xfe")
    with pytest.raises(WorkflowError, match="not UTF-8"):
        read_article(tmp_path / "bin.toml")


def test_points_on_a_beam_and_on_a_free_structure():
    assert parse_points("p1=0.1, p2=0.2:-y ,tip=0.7") == [
        Point("p1", 0.1),
        Point("p2", 0.2, "-y"),
        Point("tip", 0.7),
    ]
    assert parse_points("a=n1,b=corner-2,c=corner-2:+z", FREE) == [
        Point("a", node="n1", direction="+z"),
        Point("b", node="corner-2", direction="-x"),  # the node's own direction
        Point("c", node="corner-2", direction="+z"),
    ]


def test_fixed_points():
    points = parse_points("p1=0.1,p2=0.5")
    assert parse_fixed_point("p2", points) == Point("p2", 0.5)
    assert parse_fixed_point("tip", points) == Point("tip", 0.7)
    assert parse_fixed_point("s=0.3:-z", points) == Point("s", 0.3, "-z")
    assert parse_fixed_point("p1=0.1", points) == Point("p1", 0.1)
    for bad, says in [
        ("nowhere", "fixed point 'nowhere' is none of the points (p1, p2) nor tip"),
        ("p1=0.3", "fixed point p1 has the name of a point elsewhere"),
        ("s=0.8", "outside the beam"),
        ("", "the fixed point is empty"),
    ]:
        with pytest.raises(WorkflowError) as caught:
            parse_fixed_point(bad, points)
        assert says in str(caught.value)
        assert caught.value.exit_code == 2
    with pytest.raises(WorkflowError, match="none of the points"):
        parse_fixed_point("tip", [Point("a", node="n1")], FREE)  # a free structure has no tip


def test_sample_for_what_older_software_reads():
    points = RunPoints(SEED, Point("p3", 0.3), (Point("tip", 0.7),), test="bar")
    sample = sample_for(points)
    assert (sample.force_position_m, sample.sensor_position_m, sample.length_m) == (0.3, 0.7, 0.7)
    assert sample_for(RunPoints(FREE, Point("a", node="n1"), (Point("b", node="n1"),))) is None


# --- property tests of the --points parser ------------------------------------------------------

NAMES = st.from_regex(r"[A-Za-z0-9][A-Za-z0-9_-]{0,20}", fullmatch=True)
# On the beam: 0 < x <= L (nothing moves at the clamp, so no point may sit there).
POSITIONS = st.floats(
    min_value=0.0, max_value=TABLE_1.length_m, exclude_min=True, allow_nan=False, allow_infinity=False
).filter(lambda x: x > 1e-9)


def test_a_point_at_the_clamp_is_refused_in_one_line():
    with pytest.raises(WorkflowError) as refused:
        parse_points("p1=0")
    assert "\n" not in str(refused.value)
    assert "0 < x <= 0.7 m" in str(refused.value)


@st.composite
def beam_points(draw) -> list[Point]:
    names = draw(st.lists(NAMES, min_size=1, max_size=12, unique=True))
    return [Point(name, draw(POSITIONS), draw(st.sampled_from(DIRECTIONS))) for name in names]


@SETTINGS
@given(beam_points())
def test_points_written_out_read_back_the_same(points):
    text = format_points(points)
    assert parse_points(text) == points
    assert [p.position_m for p in parse_points(text)] == [p.position_m for p in points]  # bit for bit


@SETTINGS
@given(st.lists(st.sampled_from(["n1", "corner-2"]), min_size=1, max_size=6), st.data())
def test_free_points_written_out_read_back_the_same(nodes, data):
    points = [
        Point(f"q{i}", node=node, direction=data.draw(st.sampled_from(DIRECTIONS)))
        for i, node in enumerate(nodes)
    ]
    assert parse_points(format_points(points), FREE) == points


@SETTINGS
@given(st.text(max_size=60))
def test_any_text_is_points_or_one_line(text):
    try:
        points = parse_points(text)
    except WorkflowError as exc:
        refused = exc
    else:
        refused = None
    if refused is not None:
        message = str(refused)
        assert message
        assert "\n" not in message
        assert "\r" not in message
        assert refused.exit_code == 2
        return
    assert points
    assert len({p.name for p in points}) == len(points)
    for point in points:
        assert 0.0 <= point.position_m <= TABLE_1.length_m + 1e-9
        assert math.isfinite(point.position_m)
        assert point.direction in DIRECTIONS


@SETTINGS
@given(beam_points(), st.sampled_from(["=", ",", ":", " ", "=x", ":+q", ",,", "=1e9"]), st.data())
def test_damaged_points_text_is_refused_in_one_line(points, junk, data):
    text = format_points(points)
    where = data.draw(st.integers(min_value=0, max_value=len(text)))
    damaged = text[:where] + junk + text[where:]
    try:
        parsed = parse_points(damaged)
    except WorkflowError as exc:
        message = str(exc)
    else:
        message = None
    if message is not None:
        assert "\n" not in message
        return
    # Some insertions still read (a space beside a comma, say): then they read sensibly.
    assert all(0.0 <= p.position_m <= TABLE_1.length_m + 1e-9 for p in parsed)
