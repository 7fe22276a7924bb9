"""`daq sim serve`: run the simulated HP 35660A in the foreground."""

from __future__ import annotations

import ipaddress
import signal
import sys
import threading
from enum import StrEnum
from pathlib import Path
from typing import Annotated

import typer

from daq.errors import UserError

sim_app = typer.Typer(
    help="The simulated HP 35660A that tests, demos and new users run against.",
    no_args_is_help=True,
)


class Scenario(StrEnum):
    seed = "seed"
    realistic = "realistic"


@sim_app.command()
def serve(
    tcp: Annotated[
        int | None, typer.Option(help="Serve pyvisa-py's TCPIP SOCKET on this port (0: any free port).")
    ] = None,
    pty: Annotated[
        bool, typer.Option("--pty", help="Serve a Prologix GPIB-USB emulation on a pseudo-terminal.")
    ] = False,
    host: Annotated[
        str, typer.Option(help="Address to bind (TCP); loopback unless you mean otherwise.")
    ] = "127.0.0.1",
    gpib_address: Annotated[int, typer.Option(help="The analyzer's GPIB address behind the Prologix.")] = 11,
    scenario: Annotated[Scenario, typer.Option(help="The specimen the physics simulates.")] = Scenario.seed,
    seed: Annotated[int, typer.Option(help="Random seed: same seed and commands, same data.")] = 0,
    time_scale: Annotated[
        float, typer.Option(help="1 = real time (a hit every 0.5-2 s), 0 = instant, 0.1 = ten times faster.")
    ] = 1.0,
    noise: Annotated[bool, typer.Option("--noise/--no-noise", help="Sensor noise.")] = True,
    fault: Annotated[
        list[str] | None,
        typer.Option(help="Arm a fault on every connection, e.g. truncate or slow,delay=0.2 (repeatable)."),
    ] = None,
    replay: Annotated[
        Path | None, typer.Option(help="Serve the hits of this recorded run (HDF5) instead of physics.")
    ] = None,
    loop: Annotated[bool, typer.Option(help="With --replay: start over after the last hit.")] = False,
    hammer: Annotated[
        str | None,
        typer.Option(
            help="The simulated hammer, e.g. peak_force_n=3,pulse_width_s=0.001,double_hit_probability=0.2."
        ),
    ] = None,
) -> None:
    """Serve the simulated analyzer until Ctrl-C; prints the resource to connect to."""
    from rich.console import Console

    from sims.instrument import Analyzer
    from sims.sources import PhysicsSource, ReplaySource

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

    console = Console(stderr=True)
    if replay is not None:
        from daq.recorded_hits import load_recorded_hits

        hits = load_recorded_hits(replay)
        source: PhysicsSource | ReplaySource = ReplaySource(hits, loop=loop)
        what = f"replay of {replay} ({len(hits)} hits)"
    else:
        source = PhysicsSource(scenario.value, seed=seed)
        source.set_noise(noise)
        if hammer:
            from sims.hammer import adjusted

            try:
                source.hammer = adjusted(source.hammer, hammer)
            except ValueError as exc:
                raise UserError(f"--hammer: {exc}", exit_code=2) from None
        what = f"scenario {scenario.value}, seed {seed}{'' if noise else ', no noise'}"
    analyzer = Analyzer(source, time_scale=time_scale)

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

    stop = threading.Event()
    # The handler and the try come before the resource line: a script that reads
    # the line and stops the server at once must still get a clean stop.
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    try:
        console.print(f"Simulated HP 35660A ({what}, time scale {time_scale:g}) on {where}")
        if faults:
            console.print(f"Faults on every connection: {', '.join(faults)}")
        console.print("Ctrl-C stops it.")
        print(resource, flush=True)  # alone on stdout: scripts read it to connect
        while not stop.wait(0.2):
            pass
    except KeyboardInterrupt:
        pass
    finally:
        server.close()  # type: ignore[attr-defined]
    console.print("Stopped.")
    sys.stdout.flush()


@sim_app.command()
def commands() -> None:
    """List the command set the simulated analyzer speaks, with each entry's source."""
    from rich.console import Console
    from rich.table import Table

    from sims.command_table import COMMANDS

    table = Table(title="HP 35660A command set (3562A family dialect)", title_justify="left")
    for column in ("Mnemonic", "Kind", "Source", "What it does"):
        table.add_column(column)
    for c in COMMANDS:
        mnemonic = f"{c.mnemonic} / {c.mnemonic}?" if c.kind == "setting" else c.mnemonic
        table.add_row(mnemonic, c.kind, c.source, c.doc)
    console = Console()
    console.print(table)
    console.print(
        "3562A: seen in public code driving an HP 3562A. proj: a project choice, to be confirmed "
        "on a real 35660A. Simulator control (SIM:FAULT, SIM:NOISE, ...) is listed in sims/session.py."
    )
