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
    DialectOption,
    OldSimModelOption,
    Scenario,
    SimModel,
    SimModelOption,
    SimScenarioOption,
    SimSeedOption,
    SimTimeScaleOption,
    StoreOption,
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
    setup: Annotated[
        Path | None, typer.Option(metavar="<file.toml>", help="Settings file (see --print-setup).")
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
    hammer: Annotated[
        str | None,
        typer.Option(
            metavar="<k=v,...>", help="Simulator only: the simulated hammer, e.g. double_hit_probability=1."
        ),
    ] = None,
    analyzer: SimModelOption = None,
    model: OldSimModelOption = None,
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
    settings = read_setup(setup) if setup is not None else ImpactSettings()
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
        "--analyzer": analyzer, "--model": model,
    }  # fmt: skip
    if real is not None and (given := [k for k, v in sim_options.items() if v is not None]):
        raise UserError(f"{', '.join(given)} only apply to the simulator (use --sim)", exit_code=2)
    if time_scale is not None and not time_scale >= 0:
        raise UserError("--time-scale must be >= 0", exit_code=2)
    run_capture(
        real, settings, hits_wanted, yes, operator, note, store,
        scenario=(scenario or Scenario.realistic).value, seed=1 if seed is None else seed,
        time_scale=0.05 if time_scale is None else time_scale, hammer=hammer, sim_asked=sim,
        dialect=check_dialect(dialect), model=(simulated or SimModel.hp35660a).value,
    )  # fmt: skip


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
    seed: int,
    time_scale: float,
    hammer: str | None,
    sim_asked: bool = False,
    dialect: str | None = None,
    model: str = "35660A",
) -> None:
    """Open the analyzer (or start the simulator when ``resource`` is None), run the
    capture with a display, and seal the run; an interrupted capture is sealed incomplete."""
    from rich.console import Console

    from daq.cli.capture_session import drive
    from daq.store import Store, StoreError, resolve_store_dir
    from daq.workflows.capture import Capture
    from daq.workflows.connect import open_analyzer, serve_simulator

    console = Console(highlight=False, soft_wrap=True)
    store_dir, _ = resolve_store_dir(store)
    try:
        Store(store_dir).ensure_writable()
    except StoreError as exc:
        raise UserError(str(exc)) from None
    with contextlib.ExitStack() as stack:
        simulator = None
        if resource is None:
            from sims.hammer import HammerModel, adjusted
            from sims.sources import PhysicsSource

            try:
                hammer_model = adjusted(HammerModel(), hammer) if hammer else HammerModel()
            except ValueError as exc:
                raise UserError(f"--hammer: {exc}", exit_code=2) from None
            source = PhysicsSource(scenario, hammer=hammer_model, seed=seed)
            resource = serve_simulator(stack, source, time_scale, model)
            simulator = {
                "scenario": scenario, "seed": seed, "time_scale": time_scale, "hammer": hammer or "",
                "model": model,
            }  # fmt: skip
            console.print(f"Simulated {model} ({scenario} beam) at {resource}: --sim")
        try:
            dsa = stack.enter_context(open_analyzer(resource, dialect=dialect))
        except ValueError as exc:
            raise UserError(f"--resource {resource}: {exc}") from None
        job = Capture(
            dsa, settings, hits_wanted, resource=resource, transport=type(dsa.transport).__name__,
            simulator=simulator, operator=operator, note=note, store_dir=store_dir,
        )  # fmt: skip
        drive(console, job, store_dir, ask=not yes)
