"""`daq capture`: take an impact test's hits, check each, seal the run into the store.

With --sim the built-in simulator serves on 127.0.0.1 (a real TCP socket) and the first
line says so; without --sim an analyzer must be configured (--resource, $DAQ_RESOURCE,
the config file's ``resource``). Before the first hit the operator and note are checked,
and the store must be writable with room for the whole run. The workflow itself lives
in daq/workflows/capture.py; every hit is journaled in the store as it is taken.
"""

from __future__ import annotations

import contextlib
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from daq.cli.errors import UserError
from daq.cli.options import (
    DEFAULT_SCENARIO,
    DEFAULT_TIME_SCALE,
    DialectOption,
    ForceAtOption,
    NextPointOption,
    OldSimModelOption,
    PointOption,
    SensorAtOption,
    SetupOption,
    SimHammerOption,
    SimModel,
    SimModelOption,
    SimScenarioOption,
    SimSeedOption,
    SimTimeScaleOption,
    StoreOption,
    TestOption,
    check_dialect,
    given_once,
)

if TYPE_CHECKING:
    # The driver's settings load with the first function that needs them (the command
    # line's start-up stays light): `from drivers.settings import ...` in each.
    from drivers.settings import ImpactSettings


def register(app: typer.Typer) -> None:
    app.command(name="capture")(capture)


def read_setup(path: Path) -> ImpactSettings:
    """The setup file at ``path`` (the codec: daq/workflows/setup_codec.py)."""
    from daq.workflows.setup_codec import read_setup_file

    return read_setup_file(path)


def capture(
    resource: Annotated[
        str | None,
        typer.Option(
            "--resource",
            "-r",
            metavar="<resource>",
            help="The analyzer's VISA resource (else $DAQ_RESOURCE, the config file).",
        ),
    ] = None,
    sim: Annotated[
        bool, typer.Option("--sim", help="Use the built-in simulator even if an analyzer is configured.")
    ] = False,
    dialect: DialectOption = None,
    setup: SetupOption = None,
    auto_range: Annotated[
        int | None,
        typer.Option(
            metavar="<n>",
            help="Take n practice hits first (not kept) and set the ranges and trigger from them.",
        ),
    ] = None,
    hits: Annotated[
        int | None,
        typer.Option(metavar="<1-9999>", help="Accepted hits to average [default: the setup's averages]."),
    ] = None,
    yes: Annotated[
        bool,
        typer.Option(
            "--yes", "-y", help="Accept hits that pass the checks, reject the others, without asking."
        ),
    ] = False,
    operator: Annotated[
        str, typer.Option(metavar="<name>", help="Who hits the beam (stored with the run).")
    ] = "",
    note: Annotated[str, typer.Option(metavar="<text>", help="Free text stored with the run.")] = "",
    store: StoreOption = None,
    scenario: SimScenarioOption = None,
    seed: SimSeedOption = None,
    time_scale: SimTimeScaleOption = None,
    hammer: SimHammerOption = None,
    analyzer: SimModelOption = None,
    model: OldSimModelOption = None,
    force_at: ForceAtOption = None,
    sensor_at: SensorAtOption = None,
    test: TestOption = None,
    point: PointOption = None,
    next_point: NextPointOption = False,
    print_setup: Annotated[
        bool, typer.Option("--print-setup", help="Print the default setup file and exit.")
    ] = False,
) -> None:
    """Capture an impact test: hit, check, accept or reject, seal the run.

    Each hit is checked (overload, double impact, force roll-off, too weak) and offered
    for accept/reject with the checks' verdict as the default. The analyzer averages only
    accepted hits; its FRF and coherence are stored with every hit's time records.
    Ctrl-C keeps the hits so far as an incomplete run.
    """
    from daq.workflows.connect import configured_resource
    from drivers.settings import ImpactSettings

    simulated = given_once("--analyzer", analyzer, "--model", model)
    if print_setup:
        from daq.workflows.setup_codec import settings_to_toml

        sys.stdout.write(settings_to_toml(ImpactSettings()))
        return
    check_operator_and_note(operator, note)
    if auto_range is not None and not 1 <= auto_range <= 100:
        raise UserError("--auto-range must be 1..100 practice hits", exit_code=2)
    resolved = resolve(store, setup) if setup is not None else None
    settings = resolved.settings if resolved is not None else ImpactSettings()
    hits_wanted = hits if hits is not None else settings.averages
    if not 1 <= hits_wanted <= 9999:
        raise UserError("--hits must be 1..9999", exit_code=2)
    if sim and resource:
        raise UserError("--sim and --resource exclude each other", exit_code=2)
    real = None if sim else configured_resource(resource)
    if real is None and not sim:
        raise UserError(
            "no analyzer configured: give --resource <resource> (or set $DAQ_RESOURCE, or resource "
            "in the config file, see daq config), or --sim for the built-in simulator",
            exit_code=2,
        )
    sim_options = {
        "--scenario": scenario, "--seed": seed, "--time-scale": time_scale, "--hammer": hammer,
        "--analyzer": analyzer, "--model": model, "--force-at": force_at, "--sensor-at": sensor_at,
    }  # fmt: skip
    if real is not None and (given := [k for k, v in sim_options.items() if v is not None]):
        raise UserError(f"{', '.join(given)} only apply to the simulator (use --sim)", exit_code=2)
    if time_scale is not None and not time_scale >= 0:
        raise UserError("--time-scale must be >= 0", exit_code=2)
    where = None
    if test is None and (point is not None or next_point):
        raise UserError("--point and --next need --test NAME", exit_code=2)
    if test is not None:
        if force_at is not None or sensor_at is not None:
            raise UserError("--force-at and --sensor-at come from the test's point with --test", exit_code=2)
        where = test_point(store, test, point, next_point)
        force_at, sensor_at = where.force_at_m, where.sensor_at_m
    run_capture(
        real, settings, hits_wanted, yes, operator, note, store,
        scenario=(scenario or DEFAULT_SCENARIO).value, seed=seed,
        time_scale=DEFAULT_TIME_SCALE if time_scale is None else time_scale, hammer=hammer, sim_asked=sim,
        dialect=check_dialect(dialect), model=(simulated or SimModel.hp35660a).value,
        force_at_m=force_at if real is None else None, sensor_at_m=sensor_at if real is None else None,
        where=where, resolved=resolved, auto_range=auto_range,
    )  # fmt: skip


def resolve(store: str | None, setup: str):
    """The setup ``setup`` (a name in the store, or a .toml file), its cautions printed
    as "caution: ..." lines; UserError (one line) when it does not resolve."""
    from daq.cli.commands.setup import print_cautions
    from daq.store import resolve_store_dir
    from daq.workflows.setups import resolve_setup

    resolved = resolve_setup(resolve_store_dir(store)[0], setup)
    print_cautions(resolved.cautions)
    return resolved


def test_point(store: str | None, test: str, point: str | None, next_point: bool):
    """The test's point a capture or an import measures (daq.workflows.test.TestPoint);
    UserError (one line) on a bad test or point."""
    from daq.store import resolve_store_dir
    from daq.workflows.errors import WorkflowError
    from daq.workflows.test import point_to_measure

    store_dir, _ = resolve_store_dir(store)
    try:
        return point_to_measure(store_dir, test, point, next_point)
    except WorkflowError as exc:
        raise UserError(str(exc), exit_code=exc.exit_code) from None


def join_test(store_dir: Path, where, run_id: str, accepted: bool = True) -> None:
    """Join the sealed run to its test and say so; UserError when it could not be joined."""
    typer.echo(join_run(store_dir, where, run_id, accepted))


def join_run(store_dir: Path, where, run_id: str, accepted: bool = True) -> str:
    """Join the sealed run to its test; the line that says so (UserError when it could not
    be joined)."""
    from daq.workflows.errors import WorkflowError
    from daq.workflows.test import join

    try:
        test = join(store_dir, where, run_id, accepted)
    except WorkflowError as exc:
        raise UserError(str(exc)) from None
    if not accepted:
        return f"Run {run_id} listed in test {where.test} at point {where.point}, not counted (incomplete)"
    left = [p.name for p in test.points if test.counted_run(p.name) is None]
    rest = f"; next: {left[0]} ({len(left)} left)" if left else "; every point is measured"
    return f"Run {run_id} joined test {where.test} at point {where.point}{rest}"


def moved_points(force_at_m: float, sensor_at_m: float):
    """The points of a simulated run with the hammer and accelerometer moved (no test):
    the seed's beam, force at ``force_at_m``, response at ``sensor_at_m`` (m from the clamp)."""
    from daq.store import Point, RunPoints

    return RunPoints({"kind": "seed-beam"}, Point("force", force_at_m), (Point("response", sensor_at_m),))


def check_operator_and_note(operator: str, note: str) -> None:
    """UserError (exit 2) unless --operator is one line and --note is text, both valid
    UTF-8 without control characters: the rule the service applies to its requests."""
    from daq.workflows.capture import check_plain_text

    try:
        check_plain_text(operator, "--operator", one_line=True)
        check_plain_text(note, "--note", one_line=False)
    except ValueError as exc:
        raise UserError(str(exc), exit_code=2) from None


def run_capture(
    resource: str | None,
    settings: ImpactSettings,
    hits_wanted: int,
    yes: bool,
    operator: str,
    note: str,
    store: str | None,
    scenario: str,
    seed: int | None,
    time_scale: float,
    hammer: str | None,
    sim_asked: bool = False,
    dialect: str | None = None,
    model: str = "35660A",
    force_at_m: float | None = None,
    sensor_at_m: float | None = None,
    where=None,
    resolved=None,
    auto_range: int | None = None,
) -> None:
    """Open the analyzer (or start the simulator when ``resource`` is None, playing
    ``seed``, or a fresh random seed when None: printed and recorded in the run), run the
    capture with a display, and seal the run; an interrupted capture is sealed incomplete."""
    from rich.console import Console

    from daq.cli.capture_session import drive
    from daq.store import Store, StoreError, resolve_store_dir
    from daq.workflows.capture import Capture
    from daq.workflows.connect import fresh_seed, open_analyzer, serve_simulator, simulator_source

    console = Console(highlight=False, soft_wrap=True)
    store_dir, _ = resolve_store_dir(store)
    try:
        Store(store_dir).ensure_writable()
    except StoreError as exc:
        raise UserError(str(exc)) from None
    points = where.points if where is not None else None
    with contextlib.ExitStack() as stack:
        simulator = None
        if resource is None:
            if seed is None:
                seed = fresh_seed()
            try:
                source = simulator_source(scenario, seed, hammer or "")
            except ValueError as exc:
                raise UserError(f"--hammer: {exc}", exit_code=2) from None
            try:
                resource = serve_simulator(stack, source, time_scale, model, force_at_m, sensor_at_m)
            except ValueError as exc:
                raise UserError(str(exc), exit_code=2) from None
            simulator = {
                "scenario": scenario, "seed": seed, "time_scale": time_scale, "hammer": hammer or "",
                "model": model, "force_at_m": source.specimen.force_at_m,
                "sensor_at_m": source.specimen.sensor_at_m,
            }  # fmt: skip
            moved = ""
            if force_at_m is not None or sensor_at_m is not None:
                moved = (
                    f", hammer at {source.specimen.force_at_m:g} m, accelerometer at "
                    f"{source.specimen.sensor_at_m:g} m"
                )
            console.print(
                f"Simulated {model} ({scenario} beam{moved}, seed {seed}, time scale {time_scale:g}) "
                f"at {resource}: --sim"
            )
            if points is not None and points.article.get("kind") != "seed-beam":
                console.print(
                    f"note: the simulator plays the seed's beam, not test {where.test}'s article "
                    f"({points.article.get('kind')}); the run records the article"
                )
            if points is None and (force_at_m is not None or sensor_at_m is not None):
                points = moved_points(source.specimen.force_at_m, source.specimen.sensor_at_m)
        try:
            dsa = stack.enter_context(open_analyzer(resource, dialect=dialect))
        except ValueError as exc:
            raise UserError(f"--resource {resource}: {exc}") from None
        settings, ranged = check_for_analyzer(console, dsa, settings, auto_range)
        job = Capture(
            dsa, settings, hits_wanted, resource=resource, transport=type(dsa.transport).__name__,
            simulator=simulator, operator=operator, note=note, store_dir=store_dir,
            points=points, transducers=resolved.transducers if resolved is not None else None,
            setup_name=resolved.name if resolved is not None else "",
            setup_version=resolved.version if resolved is not None else None,
            cautions=resolved.cautions if resolved is not None else [],
            auto_range=ranged.record() if ranged is not None else None,
        )  # fmt: skip
        try:
            run = drive(console, job, store_dir, ask=not yes)
        except UserError:
            if where is not None and (store_dir / f"{job.run_id}.h5").exists():
                # An interrupted capture is sealed incomplete: listed at its point, not counted.
                join_test(store_dir, where, job.run_id, accepted=False)
            raise
    if where is not None:
        join_test(store_dir, where, run.run_id)


def check_for_analyzer(console, dsa, settings: ImpactSettings, auto_range: int | None):
    """(settings, AutoRange or None): ``settings`` checked against the analyzer that
    answered (lines, span, ranges, the trigger level; one error line naming the field,
    before any hit); with ``auto_range`` the practice hits next, their peaks and the
    ranges and trigger chosen printed, and the settings with those (the AutoRange says
    what they were, for the run's provenance)."""
    from daq.workflows.auto_range import practice_hits
    from daq.workflows.setups import validate_for_model
    from drivers.dialects import model_of

    model = model_of(dsa.dialect, dsa.identify())
    validate_for_model(settings, model)  # the setup as given, before any hit (practice too)
    if auto_range is None:
        return settings, None

    def shown(index: int, force_n: float, response_m_s2: float) -> None:
        console.print(
            f"practice hit {index + 1} of {auto_range}: peak force {force_n:.3g} N, "
            f"peak response {response_m_s2:.3g} m/s^2 (not kept)"
        )

    console.print(f"Auto-range: {auto_range} practice hit(s) at the analyzer's widest span and largest range")
    found = practice_hits(dsa, settings, auto_range, on_hit=shown)
    console.print(
        f"Auto-range: hammer range {found.hammer_range_v:.4g} V, accelerometer range "
        f"{found.accelerometer_range_v:.4g} V, trigger level {found.trigger_level_eu:.3g} "
        f"{'m/s^2' if found.settings.trigger_source == 'CH2' else 'N'}"
    )
    validate_for_model(found.settings, model)
    return found.settings, found
