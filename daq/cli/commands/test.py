"""`daq test new|list|show|analyze|fit|export|report`: multi-point modal tests.

A test is a file in the store (daq/store/modal_tests.py) naming the article, its points
and which of hammer or sensor roves; `daq capture --test NAME --point P` and
`daq import FILE --test NAME --point P` add runs to it. The work is done in
daq/workflows/test.py and daq/workflows/test_analysis.py.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Annotated, Any

import typer

from daq.cli.errors import UserError
from daq.cli.options import JsonOption, StoreOption

test_app = typer.Typer(
    help="Multi-point modal tests: points on a test article, one run per point, analysed together.\n\n"
    "Create a test with `daq test new`, measure its points with `daq capture --test NAME --next` "
    "(or import them), then `daq test analyze` for the mode shapes and MAC and `daq test fit` for "
    "the damping matrix.",
    invoke_without_command=True,
)

NameArgument = Annotated[str, typer.Argument(metavar="NAME", show_default=False, help="The test's name.")]


def register(app: typer.Typer) -> None:
    """Add `daq test` to ``app`` (once)."""
    if any(group.name == "test" for group in app.registered_groups):
        return
    app.add_typer(test_app, name="test")


@test_app.callback()
def _test(ctx: typer.Context) -> None:
    if ctx.invoked_subcommand is None:
        typer.echo(ctx.get_help())
        raise typer.Exit()


def _store_dir(store: str | None) -> Path:
    from daq.store import resolve_store_dir

    return resolve_store_dir(store)[0]


def _dumps(data: Any) -> str:
    return json.dumps(data, indent=2, allow_nan=False, default=_plain)


def _plain(value: Any) -> Any:
    import numpy as np

    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError(f"not JSON: {type(value).__name__}")


@test_app.command("new")
def new(
    name: NameArgument,
    points: Annotated[
        str,
        typer.Option(
            metavar="<p1=0.1,p2=0.2,...>",
            help="The points: name=metres from the clamp (name=node on a free structure), "
            "optionally :direction (+z default).",
        ),
    ],
    article: Annotated[
        str,
        typer.Option(metavar="<seed-beam|file.toml>", help="The test article (docs/modal-tests.md)."),
    ] = "seed-beam",
    sensor: Annotated[
        str | None,
        typer.Option(
            metavar="<tip|point|name=x>",
            help="Roving hammer: where the accelerometer stays [default: tip].",
        ),
    ] = None,
    force_at: Annotated[
        str | None,
        typer.Option(
            "--force-at",
            metavar="<tip|point|name=x>",
            help="Roving sensor: where the hammer strikes every time [default: tip].",
        ),
    ] = None,
    roving: Annotated[
        str, typer.Option(metavar="<hammer|sensor>", help="What moves from point to point.")
    ] = "hammer",
    json_output: JsonOption = False,
    store: StoreOption = None,
) -> None:
    """Create a multi-point test: an article, named points and a fixed sensor (or hammer)."""
    from daq.workflows.test import new_test, test_view

    roving = roving.lower()
    if roving == "hammer" and force_at is not None:
        raise UserError(
            "--force-at is the fixed hammer of --roving sensor; with a roving hammer give --sensor", 2
        )
    if roving == "sensor" and sensor is not None:
        raise UserError(
            "--sensor is the fixed accelerometer of a roving hammer; with --roving sensor give --force-at", 2
        )
    fixed = (sensor if roving == "hammer" else force_at) or "tip"
    store_dir = _store_dir(store)
    test = new_test(store_dir, name, article, points, fixed, roving)
    if json_output:
        typer.echo(_dumps(test_view(store_dir, name)))
        return
    fixed_role = "accelerometer" if roving == "hammer" else "hammer"
    typer.echo(
        f"Test {test.name} created: {len(test.points)} points, roving {roving}, {fixed_role} at "
        f"{_where(test.fixed_point)}; measure with: daq capture --test {test.name} --next"
    )


def _where(point: Any) -> str:
    from daq.workflows.test import describe_point

    return describe_point(point)


@test_app.command("list")
def list_(json_output: JsonOption = False, store: StoreOption = None) -> None:
    """The store's tests, with how many points each has measured."""
    from daq.workflows.test import test_names, test_view

    store_dir = _store_dir(store)
    views = [test_view(store_dir, name) for name in test_names(store_dir)]
    if json_output:
        typer.echo(_dumps(views))
        return
    if not views:
        sys.stderr.write(f"no tests in {store_dir} (daq test new NAME --points ...)\n")
        return
    for view in views:
        typer.echo(
            f"{view['name']}  {view['measured']}/{len(view['points'])} points measured, roving "
            f"{view['roving']}, {_article_text(view['article'])}, created {view['created']}"
        )


def _article_text(article: dict[str, Any]) -> str:
    kind = article.get("kind", "?")
    name = article.get("name") or ""
    return f"{kind} {name}".strip()


@test_app.command("show")
def show(name: NameArgument, json_output: JsonOption = False, store: StoreOption = None) -> None:
    """A test's points: which are measured, by which runs, with their coherence."""
    from daq.workflows.test import test_view

    view = test_view(_store_dir(store), name)
    if json_output:
        typer.echo(_dumps(view))
        return
    fixed = view["fixed_point"]
    fixed_role = "accelerometer" if view["roving"] == "hammer" else "hammer"
    typer.echo(
        f"Test {view['name']}: {_article_text(view['article'])}, roving {view['roving']}, {fixed_role} at "
        f"{_point_text(fixed)}; {view['measured']} of {len(view['points'])} points measured"
    )
    for point in view["points"]:
        if point["measured"]:
            coherence = point["mean_coherence"]
            coh = f", mean coherence {coherence:.3f}" if coherence is not None else ", no coherence"
            state = f"run {point['counted_run']}{coh}"
        else:
            state = "not measured"
        others = len(point["runs"]) - (1 if point["measured"] else 0)
        extra = f" (+{others} other run{'s' if others != 1 else ''})" if others > 0 else ""
        problem = f"; caution: {point['problem']}" if point.get("problem") else ""
        typer.echo(f"  {_point_text(point):<28} {state}{extra}{problem}")
    if view["next_point"] is not None:
        typer.echo(f"next: daq capture --test {view['name']} --point {view['next_point']}")


def _point_text(point: dict[str, Any]) -> str:
    where = (
        f"{point['position_m']:g} m" if point.get("position_m") is not None else f"node {point.get('node')}"
    )
    return f"{point['name']} ({where}, {point.get('direction', '+z')})"
