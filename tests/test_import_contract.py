"""The import contract of the house (docs/architecture.md), read from the code itself.

Every `import` and `from ... import` of our four packages is collected from the source
(those under ``if TYPE_CHECKING:`` excepted: they never run), at any depth, since an
import inside a function is as much a dependency as one at the top. Then:

* `analysis` and `drivers` import nothing of ours; `sims` only itself and `analysis`
  (the simulator must not share the driver's encoders, so that a bug on one side is
  caught by the other);
* nothing outside `daq/cli/` imports `daq.cli` (the command line is the top floor);
* the service takes only workflows, batch, the store and the report, plus the driver's
  error and settings types, which it maps to HTTP answers and holds for a capture;
* the layers under the command line never reach up: store and formats import no
  workflow, batch, service or command; workflows no batch, service or command; batch no
  service or command;
* no two modules import each other, directly or round a longer loop.
"""

from __future__ import annotations

import ast
import functools
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("analysis", "drivers", "sims", "daq")


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(tree: ast.AST, module: str, is_package: bool) -> set[str]:
    """The modules of ours that ``tree`` imports (``pkg.mod`` for ``from pkg import mod``
    when that names a module), skipping ``if TYPE_CHECKING:`` blocks."""
    found: set[str] = set()

    def visit(node: ast.AST) -> None:
        if isinstance(node, ast.If) and _is_type_checking(node.test):
            for child in node.orelse:
                visit(child)
            return
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = module.split(".")
                base = base if is_package else base[:-1]
                base = base[: len(base) - node.level + 1]
                prefix = ".".join(base + ([node.module] if node.module else []))
            else:
                prefix = node.module or ""
            found.add(prefix)
            found.update(f"{prefix}.{alias.name}" for alias in node.names)
        for child in ast.iter_child_nodes(node):
            visit(child)

    visit(tree)
    return found


def _graph() -> dict[str, set[str]]:
    sources = {
        _module_name(path): path
        for package in PACKAGES
        for path in (ROOT / package).rglob("*.py")
        if "static" not in path.parts
    }
    graph: dict[str, set[str]] = {}
    for module, path in sources.items():
        named = _imports(ast.parse(path.read_text(), str(path)), module, path.name == "__init__.py")
        # Only what names one of our modules: `from daq.store import Run` is daq.store.
        graph[module] = {name for name in named if name in sources and name != module}
    return graph


@functools.cache
def _house() -> dict[str, set[str]]:
    """The graph of our packages, parsed once by the first test that needs it: parsed at
    import, it cost every pytest worker its collection time (about 1.5 s each)."""
    return _graph()


def _in(module: str, *rooms: str) -> bool:
    return any(module == room or module.startswith(room + ".") for room in rooms)


def _breaches(importer_rooms: tuple[str, ...], allowed: tuple[str, ...]) -> list[str]:
    return sorted(
        f"{module} -> {target}"
        for module, targets in _house().items()
        if _in(module, *importer_rooms)
        for target in targets
        if not _in(target, *allowed) and target != "daq"  # daq.__version__: every room may say it
    )


def test_the_contract_reads_the_whole_house():
    # A parser that found nothing would pass every rule below.
    assert len(_house()) > 150
    assert "daq.store" in _house()["daq.workflows.capture"]
    assert any(_in(t, "analysis") for t in _house()["sims.scenarios"])


@pytest.mark.parametrize(
    ("rooms", "allowed"),
    [
        (("analysis",), ("analysis",)),
        (("drivers",), ("drivers",)),
        (("sims",), ("sims", "analysis")),
        (
            ("daq.service",),
            (
                "daq.service",
                "daq.workflows",
                "daq.batch",
                "daq.store",
                "daq.report",
                "drivers.errors",
                "drivers.settings",
            ),
        ),
        (("daq.store",), ("daq.store", "drivers.locking")),
        (("daq.formats",), ("daq.formats", "daq.store", "analysis")),
        (
            ("daq.workflows",),
            ("daq.workflows", "daq.store", "daq.formats", "daq.report", "analysis", "drivers", "sims"),
        ),
        (("daq.batch",), ("daq.batch", "daq.workflows", "daq.store", "analysis")),
    ],
    ids=lambda value: value[0] if isinstance(value, tuple) and len(value) == 1 else None,
)
def test_each_room_imports_only_what_it_may(rooms, allowed):
    assert _breaches(rooms, allowed) == []


def test_nothing_outside_the_command_line_imports_it():
    outside = [m for m in _house() if not _in(m, "daq.cli") and m != "daq.__main__"]
    assert sorted(f"{m} -> {t}" for m in outside for t in _house()[m] if _in(t, "daq.cli")) == []


def _loops(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    loops: list[list[str]] = []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for nxt in graph.get(node, ()):
            if nxt not in index:
                visit(nxt)
                low[node] = min(low[node], low[nxt])
            elif nxt in on_stack:
                low[node] = min(low[node], index[nxt])
        if low[node] == index[node]:
            component = []
            while True:
                member = stack.pop()
                on_stack.discard(member)
                component.append(member)
                if member == node:
                    break
            if len(component) > 1:
                loops.append(sorted(component))

    for node in sorted(graph):
        if node not in index:
            visit(node)
    return loops


def _without_package_faces(graph: dict[str, set[str]]) -> dict[str, set[str]]:
    # A package's __init__ that hands on its modules' names is not a loop with them:
    # `from daq.store import Run` in daq/store/x.py would be, and stays one.
    return {
        m: {t for t in targets if not (t in graph and m.startswith(t + "."))} for m, targets in graph.items()
    }


def test_no_loops_of_imports():
    assert _loops(_without_package_faces(_house())) == []


def test_the_loop_finder_finds_a_loop():
    assert _loops({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
