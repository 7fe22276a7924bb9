"""`daq instruments`, `daq identify`, `daq send`, `daq query`: talking to the analyzer directly."""

from __future__ import annotations

import json
from typing import Annotated

import typer

from daq.errors import UserError

ResourceOption = Annotated[
    str,
    typer.Option(
        "--resource",
        "-r",
        envvar="DAQ_RESOURCE",
        help="GPIB0::11::INSTR, TCPIP::host::port::SOCKET, PROLOGIX::/dev/ttyUSB0::11, or sim "
        "(the built-in simulator). Default: $DAQ_RESOURCE.",
    ),
]
TimeoutOption = Annotated[float, typer.Option("--timeout", help="Seconds to wait for each reply.")]


def _open(resource: str, timeout: float):
    from daq.instrument import open_analyzer

    if not timeout > 0:
        raise UserError("--timeout must be positive", exit_code=2)
    try:
        return open_analyzer(resource, timeout_s=timeout)
    except ValueError as exc:
        raise UserError(str(exc), exit_code=2) from None


def instruments() -> None:
    """List the VISA resources and serial ports this machine offers."""
    from rich.console import Console

    from drivers.resources import list_resources

    found = list_resources()
    console = Console()
    console.print("[bold]VISA resources[/] (pyvisa-py, this machine's buses):")
    for name in found["visa"] or ["(none found)"]:
        console.print(f"  {name}")
    console.print("[bold]Serial ports[/] (a Prologix GPIB-USB shows here; use PROLOGIX::<port>::<address>):")
    for name in found["serial"] or ["(none found)"]:
        console.print(f"  {name}")
    console.print("Built in: [bold]sim[/] (the simulated HP 35660A; sim:realistic for the exact beam)")
    for note in found["notes"]:
        console.print(f"[dim]note: {note}[/]")


def identify(resource: ResourceOption, timeout: TimeoutOption = 5.0) -> None:
    """Say what answers at a resource."""
    with _open(resource, timeout) as dsa:
        print(f"{dsa.identify()} at {resource}")


def send(
    command: Annotated[str, typer.Argument(help="The command, e.g. 'FRS 200 HZ'.")],
    resource: ResourceOption,
    timeout: TimeoutOption = 5.0,
    check: Annotated[bool, typer.Option(help="Ask the analyzer for errors afterwards.")] = True,
) -> None:
    """Send one command line to the analyzer (several may be joined with ';')."""
    with _open(resource, timeout) as dsa:
        try:
            dsa.send(command)
        except ValueError as exc:
            raise UserError(str(exc), exit_code=2) from None
        if check:
            dsa.check_errors()


def query(
    command: Annotated[str, typer.Argument(help="The query, e.g. 'FRS?', or DDAN for the active trace.")],
    resource: ResourceOption,
    timeout: TimeoutOption = 5.0,
    as_json: Annotated[bool, typer.Option("--json", help="DDAN: print the trace as JSON.")] = False,
) -> None:
    """Send a query and print the reply; DDAN dumps are decoded."""
    with _open(resource, timeout) as dsa:
        from drivers.commands import replies

        if replies(command) == ["block"] and command.strip().split(";")[-1].strip().upper() == "DDAN":
            _print_trace(dsa.dump_trace(command), as_json)
            return
        try:
            print(dsa.query(command))
        except ValueError as exc:
            raise UserError(str(exc), exit_code=2) from None


def _print_trace(trace, as_json: bool) -> None:
    import dataclasses

    h = trace.header
    if as_json:
        data = trace.data
        values = [[v.real, v.imag] for v in data] if h.complex_data else data.tolist()
        print(json.dumps({"header": dataclasses.asdict(h), "x": trace.x.tolist(), "data": values}))
        return
    kind = "complex" if h.complex_data else "real"
    print(
        f"# {h.display_function}: {h.n_points} {kind} points, {h.n_averages} averages, "
        f"y in {h.y_units or 'ratio'}, x from {h.start_x:g} {h.x_units} step {h.delta_x:g}"
        + (", OVERLOAD" if h.overflow else "")
    )
    for x, v in zip(trace.x, trace.data, strict=True):
        print(f"{x:.9g}\t{v.real:.9g}\t{v.imag:.9g}" if h.complex_data else f"{x:.9g}\t{v:.9g}")
