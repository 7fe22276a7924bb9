"""`daq sim serve`: run a simulated HP analyzer (35660A, 3562A, 35670A) in the foreground."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Annotated

import typer

from daq.cli.errors import UserError
from daq.cli.options import (
    DEFAULT_SCENARIO,
    DEFAULT_TIME_SCALE,
    FRESH_SEED_HELP,
    MODEL_HELP,
    MODEL_METAVAR,
    SCENARIO_HELP,
    SEED_HELP,
    TIME_SCALE_HELP,
    ForceAtOption,
    Scenario,
    SensorAtOption,
    given_once,
)

#: The analyzer simulated unless --analyzer names another.
DEFAULT_ANALYZER = "35660A"
AnalyzerOption = Annotated[
    str | None,
    typer.Option(
        "--analyzer",
        metavar=MODEL_METAVAR,
        show_default=False,
        help=f"{MODEL_HELP}  [default: {DEFAULT_ANALYZER}]",
    ),
]
#: --analyzer's old spelling, hidden, for one release.
OldModelOption = Annotated[str | None, typer.Option("--model", hidden=True, help="Old name of --analyzer.")]

sim_app = typer.Typer(
    help="Run a simulated HP analyzer (35660A, 3562A, 35670A), or list the commands it speaks.\n\n"
    "The simulator is what tests, demos and new users run against when the lab's "
    "analyzer is not at hand.",
    invoke_without_command=True,
)


@sim_app.callback()
def _sim(ctx: typer.Context) -> None:
    if ctx.invoked_subcommand is None:
        # A bare `daq sim`: the help is the answer, not an error.
        typer.echo(ctx.get_help())
        raise typer.Exit()


def _model(analyzer: str | None, model: str | None):
    """The sims Model that --analyzer (or its old spelling --model) names; a usage error
    (exit 2) naming the choices if none is."""
    from sims.models import get_model

    name = given_once("--analyzer", analyzer, "--model", model)
    try:
        return get_model(DEFAULT_ANALYZER if name is None else str(name))
    except ValueError as exc:
        flag = "--analyzer" if model is None else "--model"  # as the user spelled it
        raise UserError(f"{flag}: {exc}", exit_code=2) from None


@sim_app.command()
def serve(
    tcp: Annotated[
        int | None,
        typer.Option(
            metavar="<port>",
            help="Serve pyvisa-py's TCPIP SOCKET on this port; 0 picks a free one.  [default: 5025]",
        ),
    ] = None,
    pty: Annotated[
        bool,
        typer.Option(
            "--pty", help="Serve a Prologix GPIB-USB emulation on a pseudo-terminal instead of TCP."
        ),
    ] = False,
    host: Annotated[
        str,
        typer.Option(
            metavar="<IPv4 address>",
            help="Address to listen on (TCP). Any but loopback is reachable from other machines.",
        ),
    ] = "127.0.0.1",
    gpib_address: Annotated[
        int,
        typer.Option(metavar="<0-30>", help="With --pty: the analyzer's GPIB address behind the Prologix."),
    ] = 11,
    scenario: Annotated[
        Scenario | None,
        typer.Option(
            show_default=False,
            help=f"{SCENARIO_HELP} [default: {DEFAULT_SCENARIO.value}; seed with --damping-matrix]",
        ),
    ] = None,
    seed: Annotated[
        int | None,
        typer.Option(
            metavar="<int>",
            show_default=False,
            help=f"{SEED_HELP} {FRESH_SEED_HELP.format(' at each start, printed')}",
        ),
    ] = None,
    time_scale: Annotated[float, typer.Option(metavar="<factor>", help=TIME_SCALE_HELP)] = DEFAULT_TIME_SCALE,
    noise: Annotated[
        bool, typer.Option("--noise/--no-noise", help="Add sensor noise to the signals.")
    ] = True,
    fault: Annotated[
        list[str] | None,
        typer.Option(
            metavar="<spec>",
            help="Arm a fault on every connection, e.g. truncate or slow,delay=0.2; repeatable.",
        ),
    ] = None,
    replay: Annotated[
        Path | None,
        typer.Option(metavar="<file>", help="Serve the hits of this recorded run (HDF5) instead of physics."),
    ] = None,
    loop: Annotated[bool, typer.Option(help="With --replay: start over after the last hit.")] = False,
    hammer: Annotated[
        str | None,
        typer.Option(
            metavar="<key=value,...>",
            help="Adjust the simulated hammer, e.g. peak_force_n=3,pulse_width_s=0.001.",
        ),
    ] = None,
    force_at: ForceAtOption = None,
    sensor_at: SensorAtOption = None,
    damping_matrix: Annotated[
        str | None,
        typer.Option(
            metavar="<9 numbers|file>",
            show_default=False,
            help="Simulate the seed's 3-function beam with this damping matrix instead of eq (18): "
            "9 numbers in N s/m, row by row, comma separated (or a file holding them); "
            "symmetric positive semi-definite. The scenario is then custom.",
        ),
    ] = None,
    analyzer: AnalyzerOption = None,
    model: OldModelOption = None,
) -> None:
    """Serve the simulated analyzer until Ctrl-C.

    Prints the VISA resource to connect to, alone on stdout, for scripts to read;
    the banner goes to stderr. SIGTERM stops it as Ctrl-C does.
    """
    from rich.console import Console

    from sims.instrument import Analyzer
    from sims.sources import PhysicsSource, ReplaySource

    instrument = _model(analyzer, model)
    if pty and tcp is not None:
        raise UserError("choose one of --tcp PORT and --pty", exit_code=2)
    if not 0 <= gpib_address <= 30:
        raise UserError("--gpib-address must be 0..30", exit_code=2)
    if tcp is not None and not 0 <= tcp <= 65535:
        raise UserError("--tcp must be a port number 0..65535", exit_code=2)
    if not time_scale >= 0:
        raise UserError("--time-scale must be >= 0", exit_code=2)
    faults = list(fault or [])
    from sims.faults import parse_fault

    for spec in faults:
        try:
            parse_fault(spec)
        except ValueError as exc:
            raise UserError(f"--fault {spec}: {exc}", exit_code=2) from None

    if replay is not None:
        given = [
            flag
            for flag, value in (
                ("--force-at", force_at),
                ("--sensor-at", sensor_at),
                ("--damping-matrix", damping_matrix),
            )
            if value is not None
        ]
        if given:
            verb = "applies" if len(given) == 1 else "apply"
            raise UserError(f"{', '.join(given)} only {verb} to the physics, not to --replay", exit_code=2)
    damping = None
    if scenario is None:
        # A damping matrix is the seed's beam's: it alone chooses that beam.
        scenario = Scenario.seed if damping_matrix is not None else DEFAULT_SCENARIO
    if damping_matrix is not None:
        if scenario is not Scenario.seed:
            raise UserError(
                f"--damping-matrix goes with the seed's beam (--scenario seed), not {scenario.value}",
                exit_code=2,
            )
        from sims.scenarios import read_damping_matrix

        try:
            damping = read_damping_matrix(damping_matrix)
        except ValueError as exc:
            raise UserError(f"--damping-matrix: {exc}", exit_code=2) from None

    console = Console(stderr=True)
    if replay is not None:
        from daq.workflows.recorded_hits import load_recorded_hits

        hits = load_recorded_hits(replay)
        try:
            source: PhysicsSource | ReplaySource = ReplaySource(hits, loop=loop, model=instrument)
        except ValueError as exc:
            raise UserError(f"--replay {replay}: {exc}", exit_code=2) from None
        what = f"replay of {replay} ({len(hits)} hits)"
    else:
        if seed is None:
            from daq.workflows.connect import fresh_seed

            seed = fresh_seed()
        try:
            source = PhysicsSource(
                scenario.value, seed=seed, force_at_m=force_at, sensor_at_m=sensor_at, damping=damping
            )
        except ValueError as exc:
            flag = "--force-at" if str(exc).startswith("force") else "--sensor-at"
            raise UserError(f"{flag}: {exc}", exit_code=2) from None
        source.set_noise(noise)
        if hammer:
            from sims.hammer import adjusted

            try:
                source.hammer = adjusted(source.hammer, hammer)
            except ValueError as exc:
                raise UserError(f"--hammer: {exc}", exit_code=2) from None
        spec = source.specimen
        at = (
            ""
            if force_at is None and sensor_at is None
            else f", hammer at {spec.force_at_m:g} m, accelerometer at {spec.sensor_at_m:g} m"
        )
        what = f"scenario {spec.name}{at}, seed {seed}{'' if noise else ', no noise'}"
    analyzer = Analyzer(source, time_scale=time_scale, model=instrument)

    server: object
    if pty:
        from sims.prologix import PrologixPty

        server = PrologixPty(analyzer, gpib_address, faults).start()
        resource = f"PROLOGIX::{server.port}::{gpib_address}"
        where = (
            f"Prologix GPIB-USB emulation on {server.port} (pyserial, or pyvisa-py as {server.resource}), "
            f"analyzer at GPIB address {gpib_address}"
        )
    else:
        import ipaddress

        from sims.tcp_server import TcpServer

        try:
            address = ipaddress.ip_address(host)
        except ValueError:
            raise UserError(f"--host {host!r} is not an IP address", exit_code=2) from None
        if address.version != 4:
            raise UserError(
                "--host must be an IPv4 address: VISA resource names have no IPv6 form", exit_code=2
            )
        if not address.is_loopback:
            console.print(f"[yellow]warning:[/] serving on {host}, reachable from other machines")
        try:
            server = TcpServer(analyzer, host, 5025 if tcp is None else tcp, faults).start()
        except OSError as exc:
            raise UserError(
                f"cannot listen on {host}:{5025 if tcp is None else tcp}: {exc.strerror}"
            ) from None
        resource = server.resource
        where = f"TCP {server.host}:{server.port}"

    import gc
    import signal
    import time

    # The handler only appends to a list: it runs in the main thread between two
    # bytecodes, maybe inside a lock's critical section, so a lock of its own (as
    # threading.Event.set takes the one Event.wait holds) could deadlock the stop.
    terminated: list[int] = []
    # The handler and the try come before the resource line: a script that reads
    # the line and stops the server at once must still get a clean stop.
    signal.signal(signal.SIGTERM, lambda signum, _frame: terminated.append(signum))
    try:
        console.print(f"Simulated HP {instrument.name} ({what}, time scale {time_scale:g}) on {where}")
        if faults:
            console.print(f"Faults on every connection: {', '.join(faults)}")
        console.print("Ctrl-C stops it.")
        print(resource, flush=True)  # alone on stdout: scripts read it to connect
        while not terminated:
            time.sleep(0.1)  # a signal runs the handler at once; this looks up within 0.1 s
    except KeyboardInterrupt:
        pass
    finally:
        server.close()  # type: ignore[attr-defined]
    console.print("Stopped.")
    sys.stdout.flush()
    # Only the exit is left. The interpreter's teardown would walk every object of
    # the ~900 modules imported (scipy's, mostly) in its garbage collections: 0.4 s of
    # CPU, 5-10 s after SIGTERM on a loaded machine. Nothing needs collecting now.
    gc.freeze()


@sim_app.command()
def commands(
    analyzer: AnalyzerOption = None,
    model: OldModelOption = None,
) -> None:
    """List the commands the simulated analyzer understands.

    Each entry says where it comes from. For the 35660A and 3562A: seen in code
    driving an HP 3562A, or a project choice still to be confirmed on a real
    35660A. For the 35670A and 35665A (SCPI): the IEEE 488.2 / SCPI standard, seen
    in public driver code (PyMeasure), or a project choice.
    """
    from rich.console import Console
    from rich.table import Table

    instrument = _model(analyzer, model)
    console = Console()
    if instrument.dialect == "scpi":
        from sims.scpi_table import COMMANDS as SCPI_COMMANDS

        table = Table(title=f"HP {instrument.name} command set (SCPI subset)", title_justify="left")
        for column in ("Sent", "Long form", "Kind", "Source", "What it does"):
            table.add_column(column)
        for c in SCPI_COMMANDS:
            sent = f"{c.sent} / {c.sent}?" if c.kind == "setting" else c.sent
            table.add_row(sent, c.pattern, c.kind, c.source, c.doc)
        console.print(table)
        console.print(
            "std: IEEE 488.2 / SCPI. peer: seen in PyMeasure's 35670A driver. proj: a project choice, "
            "to be confirmed on a real instrument (docs/instrument-scpi.md). Simulator control (SIM:FAULT, "
            "SIM:NOISE, ...) is listed in sims/session.py."
        )
        return
    from sims.command_table import commands_for

    table = Table(title=f"HP {instrument.name} command set (3562A family dialect)", title_justify="left")
    for column in ("Mnemonic", "Kind", "Source", "What it does"):
        table.add_column(column)
    for c in commands_for(instrument.name):
        mnemonic = f"{c.mnemonic} / {c.mnemonic}?" if c.kind == "setting" else c.mnemonic
        table.add_row(mnemonic, c.kind, c.source, c.doc)
    console.print(table)
    console.print(
        "3562A: seen in public code driving an HP 3562A. proj: a project choice, to be confirmed "
        "on a real 35660A. Simulator control (SIM:FAULT, SIM:NOISE, ...) is listed in sims/session.py."
    )
