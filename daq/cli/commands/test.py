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
from daq.cli.options import BandOption, FrequenciesOption, JsonOption, MaxOrderOption, StoreOption
from daq.report.numbers import plain, span, with_uncertainty

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

    store_dir = _store_dir(store)
    view = test_view(store_dir, name)
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
        typer.echo(f"next: {_next_command(store_dir, view)}")


def _next_command(store_dir: Path, view: dict[str, Any]) -> str:
    """How to measure the test's next point, the way its runs so far were made: a test
    filled from files goes on with `daq import`, one captured with `daq capture`, one
    with both (or none yet) gets the capture and, when files were used, the import."""
    from daq.store import Store

    name, point = view["name"], view["next_point"]
    capture = f"daq capture --test {name} --point {point}"
    importing = f"daq import FILE --test {name} --point {point}"
    joined = {run["run_id"] for p in view["points"] for run in p["runs"]}
    kinds = {s.kind for s in Store(store_dir).list() if s.run_id in joined} if joined else set()
    if kinds == {"imported"}:
        return importing
    return f"{capture}, or {importing}" if "imported" in kinds else capture


def _point_text(point: dict[str, Any]) -> str:
    where = (
        f"{point['position_m']:g} m" if point.get("position_m") is not None else f"node {point.get('node')}"
    )
    return f"{point['name']} ({where}, {point.get('direction', '+z')})"


def _analysis(store_dir: Path, name: str, band: str | None, frequencies: str | None, max_order: int | None):

    from analysis.run_analysis import AnalysisOptions
    from daq.cli.commands.analyze import parse_band, parse_frequencies
    from daq.workflows.test_analysis import analyze_test

    try:
        options = AnalysisOptions(
            band_hz=parse_band(band), max_order=max_order, frequencies_hz=parse_frequencies(frequencies)
        )
    except ValueError as exc:
        raise UserError(str(exc).replace("max_order", "--max-order").replace("band ", "--band "), 2) from None
    _progress(f"analysing test {name}...")
    return analyze_test(store_dir, name, options)


def _progress(text: str) -> None:
    """A line on stderr for a person watching (a terminal); scripts get errors alone."""
    if sys.stderr.isatty():
        sys.stderr.write(text + "\n")


@test_app.command("analyze")
def analyze(
    name: NameArgument,
    band: BandOption = None,
    frequencies: FrequenciesOption = None,
    max_order: MaxOrderOption = None,
    json_output: JsonOption = False,
    store: StoreOption = None,
) -> None:
    """One set of poles from every point's FRF, the mode shapes at the points (unit modal
    mass through the driving point), their complexity, and MAC against the beam."""
    from daq.workflows.test_analysis import test_analysis_json

    analysis = _analysis(_store_dir(store), name, band, frequencies, max_order)
    info = test_analysis_json(analysis)
    if json_output:
        typer.echo(_dumps(info))
        return
    print_test_analysis(info)


def print_test_analysis(info: dict[str, Any]) -> None:
    n_modes, n_points = len(info["modes"]), len(info["points"])
    error = info["synthesis_error"]
    typer.echo(
        f"Test {info['test']}: {n_modes} mode{'s' * (n_modes != 1)} from {n_points} "
        f"point{'s' * (n_points != 1)}"
        + ("" if error is None else f", synthesis error {plain(100 * error, '.3g')} %")
    )
    typer.echo(f"  band {span(*info['band_hz'], '.4g')}: {info['band_reason']}")
    from daq.workflows.run_views import pretrigger_text

    cut = pretrigger_text(info)
    if cut:
        typer.echo("  " + cut.replace("hits cut", "every point's hits cut", 1))
    for caution in info["cautions"]:
        typer.echo(f"caution: {caution}")
    typer.echo(f"  shapes: {info['shape_scaling']}; ± standard uncertainty, {info['shape_uncertainty_from']}")
    # A test without a beam to compare with (one point, a free structure) has no MAC
    # columns: said once under the table, not in every row.
    paired = any("exact" in mode for mode in info["modes"])
    typer.echo(
        "  mode  frequency Hz (± u)      damping % (± u)       MPC"
        + ("    exact beam (MAC)        Ritz N=3 (MAC)" if paired else "")
    )
    for k, mode in enumerate(info["modes"], start=1):
        f_u = mode["frequency_u_hz"]
        z_u = mode["damping_u"]
        f_text, f_u_text = with_uncertainty(mode["frequency_hz"], f_u, ".4f")
        z_u_percent = None if z_u is None else 100 * z_u
        z_text, z_u_text = with_uncertainty(100 * mode["damping_ratio"], z_u_percent, ".3f")
        row = f"  {k:>4}  {f_text:>10} ± {f_u_text:<8}  {z_text:>7} ± {z_u_text:<8}  {mode['mpc']:>5.3f}"
        if paired:
            row += f"  {_pair_text(mode, 'exact'):<22}  {_pair_text(mode, 'ritz')}"
        typer.echo(row)
    if not paired:
        typer.echo(f"  no MAC against a beam: {_why_no_mac(info)}")
    names = [p["name"] for p in info["points"]]
    typer.echo("  shapes (real part ± u) at " + ", ".join(names) + ":")
    for k, mode in enumerate(info["modes"], start=1):
        values = ", ".join(
            f"{plain(re, '.3g')}±{plain(u, '.2g')}"
            for re, u in zip(mode["shape"]["real"], mode["shape"]["real_u"], strict=True)
        )
        typer.echo(f"    mode {k}: {values}")


def _why_no_mac(info: dict[str, Any]) -> str:
    if len(info["points"]) < 2:
        return "one point measured, and a shape needs two or more"
    if any(x is None for x in info["positions_m"]):
        return "the article is a free structure, with no beam model to compare the shapes with"
    return "the article gives no beam model to compare the shapes with"


def _pair_text(mode: dict[str, Any], model: str) -> str:
    pair = mode.get(model)
    if pair is None:
        return "none within 25 %"
    return f"mode {pair['mode']} {plain(pair['frequency_hz'], '.4g')} Hz ({pair['mac']:.3f})"


@test_app.command("fit")
def fit(
    name: NameArgument,
    method: Annotated[
        str,
        typer.Option(
            metavar="<ls|ga|complex-modes>",
            help="ls: least squares on every point's hits (eq 17 summed over the points); ga: the seed's "
            "GA, then least squares; complex-modes: Adhikari-Woodhouse from the measured complex shapes.",
        ),
    ] = "ls",
    unconstrained: Annotated[
        bool, typer.Option("--unconstrained", help="Fit R's terms freely (R may come out not dissipative).")
    ] = False,
    seed: Annotated[int, typer.Option(metavar="<int>", help="Random seed of ga.")] = 0,
    band: BandOption = None,
    frequencies: FrequenciesOption = None,
    max_order: MaxOrderOption = None,
    json_output: JsonOption = False,
    store: StoreOption = None,
) -> None:
    """The beam's 3 x 3 damping matrix R fitted to every point of the test at once, with
    its standard uncertainty and the combinations the points do not determine."""
    from daq.workflows.test_fit import fit_test, test_fit_json

    store_dir = _store_dir(store)
    analysis = _analysis(store_dir, name, band, frequencies, max_order)
    _progress(f"fitting R to {len(analysis.data.points)} points ({method})...")
    result = fit_test(analysis, store_dir, method.lower(), psd=not unconstrained, seed=seed)
    info = test_fit_json(result)
    if json_output:
        typer.echo(_dumps(info))
        return
    floor = info["psi_noise_floor"]
    floor_text = (
        f" (noise floor {plain(floor, '.3g')}, {plain(info['psi'] / floor, '.3g')}x)" if floor else ""
    )
    typer.echo(
        f"Test {name}: {info['method']} over {info['n_points']} points, {span(*info['band_hz'], '.4g')}, "
        f"Psi = {plain(info['psi'], '.4g')}{floor_text}"
    )
    for caution in info["cautions"]:
        typer.echo(f"caution: {caution}")
    std = info["damping_matrix_u"]
    typer.echo(f"  R (N s/m), ± {info['uncertainty_from']}; ? = not determined by these points:")
    names = [f"R{i + 1}{j + 1}" for i in range(3) for j in range(3)]
    for i, row in enumerate(info["damping_matrix"]):
        cells = []
        for j, value in enumerate(row):
            u = "–" if std is None else plain(std[i][j], ".2g")
            term = names[3 * min(i, j) + max(i, j)]
            mark = " ?" if std is not None and term not in info["determined_terms"] else "  "
            cells.append(f"{plain(value, '.4g'):>10} ± {u:<7}{mark}")
        typer.echo("    " + "".join(cells))


@test_app.command("export")
def export(
    name: NameArgument,
    output: Annotated[Path, typer.Option("--output", "-o", metavar="<file.uff>", help="The file to write.")],
    format: Annotated[str, typer.Option("--format", metavar="<uff>", help="The file format.")] = "uff",
    force: Annotated[bool, typer.Option("--force", help="Write over an existing file.")] = False,
    store: StoreOption = None,
) -> None:
    """A whole test as UFF: 15 (nodes), 82 (trace lines), 58 (every FRF with its node and
    direction, the driving point one node) and 55 (the mode shapes of daq test analyze)."""
    from daq.workflows.test_export import export_test

    if format.lower() != "uff":
        raise UserError(f"--format {format!r}: only uff is offered for a test", exit_code=2)
    if output.exists() and not force:
        raise UserError(f"{output} exists; give --force to write over it", exit_code=2)
    store_dir = _store_dir(store)
    analysis = _analysis(store_dir, name, None, None, None)
    n_frf, n_modes = export_test(analysis, output)
    typer.echo(f"Test {name} written as UFF: {output} ({n_frf} FRFs, {n_modes} mode shapes)")
    if n_modes == 0 and analysis.result.modes:
        typer.echo(
            "note: mode shapes not written: without a driving point the fixed point has no shape value, "
            "and dataset 55 needs one at every node"
        )


@test_app.command("report")
def report(
    name: NameArgument,
    output: Annotated[
        Path | None,
        typer.Option(
            "--output", "-o", metavar="<dir>", help="Folder to write [default: ./report-test-NAME]."
        ),
    ] = None,
    force: Annotated[
        bool, typer.Option("--force", help="Write over an earlier report in that folder.")
    ] = False,
    fit_method: Annotated[
        str | None,
        typer.Option(
            "--fit",
            metavar="<ls|ga|complex-modes>",
            show_default=False,
            help="Also fit R with this method and show it [default: no fit].",
        ),
    ] = None,
    band: BandOption = None,
    frequencies: FrequenciesOption = None,
    max_order: MaxOrderOption = None,
    store: StoreOption = None,
) -> None:
    """The test's report, for a test on a beam with two measured points or more: stability
    diagram over all FRFs, mode shapes along the beam beside the exact and Ritz shapes, MAC,
    R with its uncertainty, measured against fitted FRFs. The analysis is made here with the
    options given (the defaults of daq test analyze). Any other test: daq test analyze."""
    from daq.workflows.article import article_beam
    from daq.workflows.test import open_test

    folder = output if output is not None else Path(f"report-test-{name}")
    if folder.exists() and not folder.is_dir():
        raise UserError(f"{folder} exists and is not a folder")
    if (folder / "index.html").exists() and not force:
        raise UserError(
            f"{folder} already holds a report; give --force to write over it or -o another folder"
        )
    store_dir = _store_dir(store)
    # What the report needs is known before the analysis, which takes seconds.
    test = open_test(store_dir, name)
    measured = sum(run is not None for run in test.counted_runs().values())
    beam = article_beam(test.article)
    if beam is None or measured < 2:
        n_points = len(test.points)
        lacks = (
            "its article is not a beam" if beam is None
            else f"only {measured} of its {n_points} points {'is' if measured == 1 else 'are'} measured"
        )  # fmt: skip
        raise UserError(
            f"test {name}: the report draws shapes along a beam; it needs a beam article and two measured "
            f"points or more, and {lacks} (daq test analyze {name} shows its modes)"
        )
    from daq.cli.commands.report import _write
    from daq.report.modal_test_report import render_modal_test_report
    from daq.workflows.test_export import report_inputs
    from daq.workflows.test_fit import fit_test

    analysis = _analysis(store_dir, name, band, frequencies, max_order)
    fitted = None
    if fit_method is not None:
        _progress(f"fitting R ({fit_method})...")
        fitted = fit_test(analysis, store_dir, fit_method.lower())
    try:
        html, pngs = render_modal_test_report(report_inputs(analysis, fitted))
    except ValueError as exc:
        raise UserError(" ".join(str(exc).split())) from None
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise UserError(f"cannot create {folder}: {exc.strerror or exc}") from None
    for png_name, png in pngs.items():
        _write(folder / f"{png_name}.png", png)
    _write(folder / "index.html", html.encode("utf-8"))
    typer.echo(f"Report of test {name}: {folder / 'index.html'} ({len(pngs)} figures)")


@test_app.command("reject")
def reject(
    name: NameArgument,
    run: Annotated[str, typer.Argument(metavar="RUN", show_default=False, help="A run of the test.")],
    store: StoreOption = None,
) -> None:
    """Stop counting a run at its point (the point is measured again by --next); the run
    stays in the store and in the test's list."""
    _decide(name, run, False, store)


@test_app.command("accept")
def accept(
    name: NameArgument,
    run: Annotated[str, typer.Argument(metavar="RUN", show_default=False, help="A run of the test.")],
    store: StoreOption = None,
) -> None:
    """Count a run of the test again at its point (the newest accepted run counts)."""
    _decide(name, run, True, store)


def _decide(name: str, run: str, accepted: bool, store: str | None) -> None:
    from daq.workflows.test import set_run_accepted

    test, point, run_id = set_run_accepted(_store_dir(store), name, run, accepted)
    counted = test.counted_run(point)
    now = f"run {counted} counts there" if counted else "nothing counts there: measure it again"
    typer.echo(
        f"Run {run_id} {'accepted' if accepted else 'rejected'} at point {point} of test {name}; {now}"
    )
