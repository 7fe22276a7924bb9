"""Multi-point modal tests: one TOML file per test in the store, ``<store>/tests/<name>.toml``.

A test names its article (a beam or a free structure, model.check_article), its
measurement points, which of hammer or sensor roves and the point that stays fixed,
and the runs that joined it, point by point. docs/modal-tests.md describes the file.

Writing follows the runs' protocol (writer.write_atomically): the whole text goes to a
hidden temporary in the tests folder, is fsynced and published by a link (a new test:
an existing one is never replaced) or a rename (joining a run), and the folder is
fsynced. A writer killed at any moment leaves the old file or the new one, never half
of one. Changes (read, modify, write) hold ``<store>/tests/.<name>.lock`` with flock,
so two processes joining runs at once both land. This lock is not the store's lock
(daq/store/lock.py): that one is held by ``daq serve`` for its whole life, and a
capture inside the service must still be able to join its run.
"""

from __future__ import annotations

import contextlib
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from daq.store import layout
from daq.store.errors import StoreError
from daq.store.ids import validate_run_id
from daq.store.model import (
    Point,
    RunPoints,
    check_article,
    check_iso_utc,
    check_point_on_article,
    check_test_name,
)
from daq.store.text_files import file_lock, now_utc, parse_toml, read_bounded, toml_string
from daq.store.writer import run_path, write_atomically

TESTS_FOLDER = "tests"
TEST_SUFFIX = ".toml"
TEST_SCHEMA_NAME = "cantilever-daq.test"
TEST_SCHEMA_VERSION = 1
ROVING = ("hammer", "sensor")
#: A test file larger than this is refused unread (a real one is a few kB).
MAX_TEST_FILE_BYTES = 4 * 2**20
#: Points in one test; runs joined to one test.
MAX_POINTS = 10_000
MAX_RUNS = 100_000


@dataclass(frozen=True)
class JoinedRun:
    """A run that joined a test at one of its points.

    point: the test's point name. run_id: the run's id. accepted: whether it counts
    (a rejected run stays listed). joined: ISO 8601 UTC time it joined (or was last
    accepted or rejected).
    """

    point: str
    run_id: str
    accepted: bool
    joined: str

    def to_dict(self) -> dict[str, Any]:
        return {"point": self.point, "run_id": self.run_id, "accepted": self.accepted, "joined": self.joined}


@dataclass(frozen=True)
class ModalTest:
    """A multi-point modal test as its file holds it.

    name: the test's name (model.TEST_NAME_PATTERN), also its file name.
    created: ISO 8601 UTC time of creation.
    article: the test article, as model.check_article returns it.
    roving: "hammer" (the hammer moves from point to point, the sensor stays at
        ``fixed_point``) or "sensor" (the sensor moves, the hammer strikes ``fixed_point``).
    fixed_point: the point that stays (Point); it may be one of ``points`` (then the
        test has a driving point) or not.
    points: the roving points, in measuring order (tuple of Point, distinct names).
    runs: every run that joined, in the order they joined (tuple of JoinedRun).
    """

    name: str
    created: str
    article: dict[str, Any]
    roving: str
    fixed_point: Point
    points: tuple[Point, ...]
    runs: tuple[JoinedRun, ...] = field(default=())

    def point(self, name: str) -> Point:
        """The roving point ``name``; StoreError if the test has none of that name."""
        for point in self.points:
            if point.name == name:
                return point
        raise StoreError(
            f"test {self.name} has no point {name!r}; its points: {', '.join(p.name for p in self.points)}"
        )

    def runs_at(self, point: str) -> list[JoinedRun]:
        """The runs joined at ``point``, oldest first (by run id, i.e. creation time)."""
        return sorted((r for r in self.runs if r.point == point), key=lambda r: r.run_id)

    def counted_run(self, point: str) -> str | None:
        """The run that counts at ``point``: the newest accepted one; None if there is none."""
        accepted = [r.run_id for r in self.runs_at(point) if r.accepted]
        return accepted[-1] if accepted else None

    def counted_runs(self) -> dict[str, str | None]:
        """{point name: the run that counts there, or None}, in the points' order."""
        return {p.name: self.counted_run(p.name) for p in self.points}

    def run_points(self, point: str) -> RunPoints:
        """Where a run measured at roving point ``point`` is measured: for a roving
        hammer, force at ``point`` and response at the fixed point; for a roving sensor,
        force at the fixed point and response at ``point``. What a capture or an import
        into this test records on its run (Run.points)."""
        roving = self.point(point)
        if self.roving == "hammer":
            return RunPoints(self.article, roving, (self.fixed_point,), test=self.name)
        return RunPoints(self.article, self.fixed_point, (roving,), test=self.name)


def modal_tests_dir(store_dir: Path | str) -> Path:
    """The folder of the tests of store ``store_dir``."""
    return Path(store_dir) / TESTS_FOLDER


def modal_test_path(store_dir: Path | str, name: str) -> Path:
    """Where test ``name`` lives in ``store_dir`` (the name is validated)."""
    return modal_tests_dir(store_dir) / f"{_valid_name(name)}{TEST_SUFFIX}"


def next_point(test: ModalTest) -> str | None:
    """The first point of ``test`` (in its order) without an accepted run; None when
    every point has one."""
    for point in test.points:
        if test.counted_run(point.name) is None:
            return point.name
    return None


def create_test(
    store_dir: Path | str,
    name: str,
    article: dict[str, Any],
    points: list[Point] | tuple[Point, ...],
    fixed_point: Point | str,
    roving: str = "hammer",
) -> ModalTest:
    """Create test ``name`` in ``store_dir`` and return it.

    article: a test article (model.check_article: seed-beam, cantilever or free).
    points: the roving points (at least one, distinct names, each on the article).
    fixed_point: the point that stays: a Point, or the name of one of ``points``
        (the driving point).
    roving: "hammer" or "sensor".
    StoreError (one line) for an existing test, a bad name, article or point; nothing is
    written then.
    """
    test = _build_test(name, article, points, fixed_point, roving)
    final = modal_test_path(store_dir, test.name)
    if os.path.lexists(final):
        raise StoreError(
            f"test {test.name} already exists in {modal_tests_dir(store_dir)}; choose another name"
        )
    text = _encode(dump_test(test))
    with _test_lock(store_dir, test.name):
        # write_atomically links the new file, so a racing creator still loses cleanly.
        write_atomically(modal_tests_dir(store_dir), final, text, what=f"test {test.name}")
    return test


def load_test(store_dir: Path | str, name: str) -> ModalTest:
    """Test ``name`` of ``store_dir``; StoreError (one line, naming the file) if it does
    not exist or cannot be read."""
    path = modal_test_path(store_dir, name)
    try:
        data = read_bounded(path, MAX_TEST_FILE_BYTES, str(path))
    except FileNotFoundError:
        known = list_tests(store_dir)
        hint = f"; tests: {', '.join(known)}" if known else "; there are no tests in this store"
        raise StoreError(f"no test {name} in {Path(store_dir)}{hint}") from None
    test = parse_test(data, str(path))
    if test.name != name:
        raise StoreError(f"{path}: names test {test.name!r}, not {name!r} (renamed by hand?)")
    return test


def list_tests(store_dir: Path | str) -> list[str]:
    """The names of the tests in ``store_dir``, sorted (hidden files and names that are
    no valid test name are not tests)."""
    try:
        entries = os.listdir(modal_tests_dir(store_dir))
    except FileNotFoundError:
        return []
    except OSError as exc:
        raise StoreError(f"cannot list {modal_tests_dir(store_dir)}: {os.strerror(exc.errno or 0)}") from None
    names = []
    for entry in entries:
        stem = entry[: -len(TEST_SUFFIX)] if entry.endswith(TEST_SUFFIX) else None
        if stem is None:
            continue
        try:
            check_test_name(stem)
        except ValueError:
            continue
        names.append(stem)
    return sorted(names)


def join_run(store_dir: Path | str, name: str, point: str, run_id: str, accepted: bool = True) -> ModalTest:
    """Record that run ``run_id`` of ``store_dir`` measured point ``point`` of test
    ``name``; return the test as written.

    A point may have several runs; the newest accepted one counts (ModalTest.counted_run).
    Joining a run already joined at this point again sets its ``accepted`` flag (so a
    run is rejected later by joining it with accepted=False). Refused (StoreError, one
    line, nothing written): an unknown test or point, a run not in the store, a run
    joined at another point, a run whose recorded points (Run.resolved_points) are not
    where this test puts that point, or another test's run.
    """
    validate_run_id(run_id)
    if not isinstance(accepted, bool):
        raise StoreError(f"accepted must be True or False, got {accepted!r}")
    store_dir = Path(store_dir)
    if not modal_test_path(store_dir, name).is_file():
        load_test(store_dir, name)  # its one-line "no test" error, and no lock file left behind
    with _test_lock(store_dir, name):
        test = load_test(store_dir, name)
        test.point(point)
        for joined in test.runs:
            if joined.run_id == run_id and joined.point != point:
                raise StoreError(f"run {run_id} already joined test {name} at point {joined.point}")
        _check_run_fits(store_dir, test, point, run_id)
        if len(test.runs) >= MAX_RUNS:
            raise StoreError(f"test {name} already holds {MAX_RUNS} runs; refused")
        entry = JoinedRun(point, run_id, accepted, now_utc())
        runs = [r for r in test.runs if r.run_id != run_id] + [entry]
        test = ModalTest(
            test.name, test.created, test.article, test.roving, test.fixed_point, test.points, tuple(runs)
        )
        write_atomically(
            modal_tests_dir(store_dir),
            modal_test_path(store_dir, name),
            _encode(dump_test(test)),
            what=f"test {name}",
            overwrite=True,
        )
    return test


# --- the file -----------------------------------------------------------------------


def dump_test(test: ModalTest) -> str:
    """The TOML text of ``test`` (docs/modal-tests.md)."""
    lines = [
        "# A modal test of cantilever-daq (docs/modal-tests.md). Written by the program:",
        "# edit with care, a file that does not check is refused whole.",
        f"schema = {_toml_value(TEST_SCHEMA_NAME)}",
        f"schema_version = {TEST_SCHEMA_VERSION}",
        f"name = {_toml_value(test.name)}",
        f"created = {_toml_value(test.created)}",
        f"roving = {_toml_value(test.roving)}",
        "",
    ]
    lines += _toml_table("fixed_point", test.fixed_point.to_dict())
    lines += _toml_table("article", test.article)
    for point in test.points:
        lines += _toml_table("points", point.to_dict(), array=True)
    for run in test.runs:
        lines += _toml_table("runs", run.to_dict(), array=True)
    return "\n".join(lines).rstrip("\n") + "\n"


def parse_test(data: bytes, where: str) -> ModalTest:
    """The test in TOML ``data`` (the bytes of a test file, ``where`` names it in
    messages); StoreError (one line) for anything that does not check."""
    doc = parse_toml(data, where)
    try:
        return _test_from_doc(doc)
    except ValueError as exc:
        raise StoreError(f"{where}: {exc}") from None


def _test_from_doc(doc: dict[str, Any]) -> ModalTest:
    if doc.get("schema") != TEST_SCHEMA_NAME:
        raise ValueError(f"not a test file (schema {doc.get('schema')!r}, expected {TEST_SCHEMA_NAME!r})")
    version = doc.get("schema_version")
    if not isinstance(version, int) or isinstance(version, bool) or version < 1:
        raise ValueError(f"schema_version {version!r} is not valid")
    if version > TEST_SCHEMA_VERSION:
        raise ValueError(
            f"test schema version {version} is newer than this software reads "
            f"({TEST_SCHEMA_VERSION}); update cantilever-daq"
        )
    known = {
        "schema",
        "schema_version",
        "name",
        "created",
        "roving",
        "fixed_point",
        "article",
        "points",
        "runs",
    }
    unknown = sorted(set(doc) - known)
    if unknown:
        raise ValueError(f"unknown key(s) {', '.join(unknown)}")
    for key in ("name", "created", "roving", "fixed_point", "article", "points"):
        if key not in doc:
            raise ValueError(f"{key} is missing")
    points = doc["points"]
    if not isinstance(points, list):
        raise ValueError("points must be an array of tables")
    built = [Point.from_dict(p, f"points[{i}]") for i, p in enumerate(points)]
    test = _build_test(
        doc["name"], doc["article"], built, Point.from_dict(doc["fixed_point"], "fixed_point"), doc["roving"]
    )
    created = doc["created"]
    if not isinstance(created, str):
        raise ValueError("created must be an ISO 8601 UTC text")
    check_iso_utc(created, "created")
    runs = doc.get("runs", [])
    if not isinstance(runs, list) or len(runs) > MAX_RUNS:
        raise ValueError(f"runs must be an array of at most {MAX_RUNS} tables")
    joined = [_joined_from_dict(r, f"runs[{i}]", test) for i, r in enumerate(runs)]
    ids = [r.run_id for r in joined]
    if len(set(ids)) != len(ids):
        raise ValueError("runs: a run is listed twice")
    return ModalTest(
        test.name, created, test.article, test.roving, test.fixed_point, test.points, tuple(joined)
    )


def _joined_from_dict(value: object, what: str, test: ModalTest) -> JoinedRun:
    if not isinstance(value, dict):
        raise ValueError(f"{what} must be a table")
    keys = {"point", "run_id", "accepted", "joined"}
    if set(value) != keys:
        raise ValueError(f"{what} must hold exactly {', '.join(sorted(keys))}")
    if not any(p.name == value["point"] for p in test.points):
        raise ValueError(f"{what}: the test has no point {value['point']!r}")
    try:
        validate_run_id(value["run_id"])
    except StoreError as exc:
        raise ValueError(f"{what}: {exc}") from None
    if not isinstance(value["accepted"], bool):
        raise ValueError(f"{what}.accepted must be true or false")
    check_iso_utc(value["joined"], f"{what}.joined")
    return JoinedRun(value["point"], value["run_id"], value["accepted"], value["joined"])


def _build_test(
    name: object, article: object, points: object, fixed_point: object, roving: object
) -> ModalTest:
    """A new test (no runs) from its parts, every one checked; StoreError (one line)."""
    try:
        name = check_test_name(name)
        article = check_article(article)
        if roving not in ROVING:
            raise ValueError(f"roving must be one of {', '.join(ROVING)}, got {roving!r}")
        if isinstance(points, Point) or not isinstance(points, (list, tuple)) or not points:
            raise ValueError("a test needs at least one point")
        if len(points) > MAX_POINTS:
            raise ValueError(f"a test holds at most {MAX_POINTS} points, got {len(points)}")
        seen: set[str] = set()
        for point in points:
            if not isinstance(point, Point):
                raise ValueError(f"points must be Point objects, got a {type(point).__name__}")
            if point.name in seen:
                raise ValueError(f"point name {point.name!r} is used twice")
            seen.add(point.name)
            check_point_on_article(point, article)
        if isinstance(fixed_point, str):
            matches = [p for p in points if p.name == fixed_point]
            if not matches:
                names = ", ".join(p.name for p in points)
                raise ValueError(
                    f"fixed point {fixed_point!r} is none of the points ({names}); "
                    "give it as a point with its position"
                )
            fixed_point = matches[0]
        if not isinstance(fixed_point, Point):
            raise ValueError(
                f"the fixed point must be a Point or a point's name, got {type(fixed_point).__name__}"
            )
        check_point_on_article(fixed_point, article, "fixed point")
        for point in points:
            if point.name == fixed_point.name and not (
                point.same_place(fixed_point) and point.direction == fixed_point.direction
            ):
                raise ValueError(
                    f"fixed point {fixed_point.name} has the name of a point elsewhere; name it otherwise"
                )
    except ValueError as exc:
        raise StoreError(str(exc)) from None
    return ModalTest(name, now_utc(), article, roving, fixed_point, tuple(points))


def _check_run_fits(store_dir: Path, test: ModalTest, point: str, run_id: str) -> None:
    """StoreError unless run ``run_id`` is in the store and was measured where ``test``
    puts ``point`` (its recorded or default points)."""
    path = run_path(store_dir, run_id)
    if not path.is_file():
        raise StoreError(f"no run {run_id} in {store_dir}: a test joins runs of its store")
    # Imported here: reading a run needs h5py and numpy, listing tests does not.
    from daq.store.decode import check_schema, decode_points
    from daq.store.h5io import get_float, get_group
    from daq.store.model import Sample, default_points
    from daq.store.reader import open_h5

    with open_h5(path) as f:
        check_schema(f)
        recorded = decode_points(get_group(f, layout.ENTRY))
        if recorded is None:
            group = get_group(f, layout.SAMPLE, required=False)
            sample = None
            if group is not None:
                values = {k: get_float(group, k) for k in layout.SAMPLE_ATTRS}
                values |= {k: get_float(group, k) for k in layout.SAMPLE_OPTIONAL_ATTRS if k in group.attrs}
                try:
                    sample = Sample(**values)
                except (TypeError, ValueError) as exc:
                    raise StoreError(f"{path}: inconsistent sample data: {exc}") from None
            recorded = default_points(sample)
    want = test.run_points(point)
    if recorded.test not in ("", test.name):
        raise StoreError(f"run {run_id} was measured for test {recorded.test}, not {test.name}")
    if recorded.article != want.article:
        raise StoreError(f"run {run_id} was measured on another article ({_article_label(recorded.article)})")
    if not recorded.force_point.same_place(want.force_point):
        raise StoreError(
            f"run {run_id} has its force at {_where(recorded.force_point)}, but test {test.name} "
            f"puts it at {_where(want.force_point)} for point {point}"
        )
    if not any(r.same_place(want.response_points[0]) for r in recorded.response_points):
        raise StoreError(
            f"run {run_id} has no response at {_where(want.response_points[0])}, where test {test.name} "
            f"measures point {point}"
        )


def _encode(text: str) -> bytes:
    try:
        return text.encode("utf-8")
    except UnicodeEncodeError:  # a lone surrogate in a free text (the article's name)
        raise StoreError("the test holds text that is not valid Unicode (a lone surrogate)") from None


def _where(point: Point) -> str:
    return f"{point.position_m} m" if point.node is None else f"node {point.node}"


def _article_label(article: dict[str, Any]) -> str:
    return article["kind"] + (f" {article['name']}" if "name" in article else "")


def _valid_name(name: object) -> str:
    try:
        return check_test_name(name)
    except ValueError as exc:
        raise StoreError(str(exc)) from None


def _test_lock(store_dir: Path | str, name: str) -> contextlib.AbstractContextManager[None]:
    """Hold ``<store>/tests/.<name>.lock`` for a change of test ``name``."""
    return file_lock(modal_tests_dir(store_dir), f".{name}.lock", f"test {name}")


# --- a TOML writer for the test file's few types ----------------------------------------------------


def _toml_table(name: str, values: dict[str, Any], array: bool = False) -> list[str]:
    """``[name]`` (or ``[[name]]``) with ``values``; nested dicts become sub-tables and
    lists of dicts arrays of sub-tables."""
    lines = [f"[[{name}]]" if array else f"[{name}]"]
    nested: list[tuple[str, Any]] = []
    for key, value in values.items():
        if isinstance(value, dict) or (isinstance(value, list) and value and isinstance(value[0], dict)):
            nested.append((key, value))
        else:
            lines.append(f"{key} = {_toml_value(value)}")
    lines.append("")
    for key, value in nested:
        if isinstance(value, dict):
            lines += _toml_table(f"{name}.{key}", value)
        else:
            for item in value:
                lines += _toml_table(f"{name}.{key}", item, array=True)
    return lines


def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if not math.isfinite(value):
            raise StoreError(f"internal: {value} cannot go into a test file")
        return repr(value)  # repr round-trips every float; TOML reads "1e-05" and "7.1e+10"
    if isinstance(value, str):
        return toml_string(value)
    raise StoreError(f"internal: a {type(value).__name__} cannot go into a test file")
