"""`daq instruments`, `daq identify`, `daq send`, `daq query`: talking to the analyzer directly."""

from __future__ import annotations

import contextlib
import json
from typing import Annotated

import typer

from daq.cli.errors import UserError
from daq.cli.options import DialectOption, ResourceOption, TimeoutOption, check_dialect


def _open(resource: str | None, timeout: float, dialect: str | None = None, retries: int = 2):
    from daq.workflows.connect import configured_resource, open_analyzer

    dialect = check_dialect(dialect)
    resource = configured_resource(resource)
    if not resource:
        raise UserError(
            "no analyzer given: use --resource (-r), set DAQ_RESOURCE or put resource = ... in the "
            "config file (daq config)",
            exit_code=2,
        )
    if not timeout > 0:
        raise UserError("--timeout must be positive", exit_code=2)
    try:
        return open_analyzer(resource, timeout_s=timeout, dialect=dialect, retries=retries)
    except ValueError as exc:
        raise UserError(str(exc), exit_code=2) from None


def instruments() -> None:
    """List the VISA resources and serial ports of this machine.

    A Prologix GPIB-USB adapter shows as a serial port: reach the analyzer behind
    it as PROLOGIX::<port>::<GPIB address>.
    """
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


def identify(
    resource: ResourceOption = None, timeout: TimeoutOption = 5.0, dialect: DialectOption = None
) -> None:
    """Ask what answers at a resource and print its reply, the dialect chosen and why.

    Without --dialect the analyzer is asked *IDN? (a SCPI 35665A/35670A answers it),
    then ID? (HP35660A, HP3562A); with it, only that dialect's identity query.
    """
    from daq.workflows.connect import configured_resource

    with _open(resource, timeout, dialect) as dsa:
        identification = dsa.identify()  # first: with a forced dialect it checks the reply
        g = dsa.read_settings() if dsa.dialect.family == "scpi" else None
        lines = g.lines if g is not None else dsa.dialect.default_lines
        print(f"{identification} at {configured_resource(resource)}")
        print(f"dialect {dsa.dialect.name}: {dsa.detection}")
        print(f"{lines} lines, {round(2.56 * lines)}-sample records")


def send(
    command: Annotated[str, typer.Argument(metavar="COMMAND", help="The command line, e.g. 'FRS 200 HZ'.")],
    resource: ResourceOption = None,
    timeout: TimeoutOption = 5.0,
    dialect: DialectOption = None,
    check: Annotated[
        bool, typer.Option(help="Then ask the analyzer for errors and fail if it reports one.")
    ] = True,
) -> None:
    """Send a command line that has no reply to the analyzer.

    Several commands may be joined with ';'. A command that answers is refused:
    use `daq query` for it.
    """
    with _open(resource, timeout, dialect) as dsa:
        try:
            dsa.send(command)
        except ValueError as exc:
            raise UserError(str(exc), exit_code=2) from None
        if check:
            dsa.check_errors()


def query(
    command: Annotated[
        str,
        typer.Argument(metavar="QUERY", help="The query, e.g. 'FRS?', or DDAN for the active trace."),
    ],
    resource: ResourceOption = None,
    timeout: TimeoutOption = 5.0,
    dialect: DialectOption = None,
    as_json: Annotated[
        bool, typer.Option("--json", help="For a DDAN dump: print the trace as JSON, not columns.")
    ] = False,
) -> None:
    """Send a query and print the reply; DDAN dumps are decoded.

    A DDAN dump prints as a header line and tab-separated columns: x and the value
    (real and imaginary parts for a complex trace).
    """
    # No retries: a query typed by hand that times out was most often refused (its reason
    # is in the error queue, asked below), and three attempts would triple the wait.
    with _open(resource, timeout, dialect, retries=0) as dsa:
        from drivers.errors import InstrumentTimeout

        try:
            last = command.strip().split(";")[-1].strip().upper()
            if dsa.dialect.family == "hp" and dsa.replies(command) == ["block"] and last == "DDAN":
                _print_trace(dsa.dump_trace(command), as_json)
                return
            if dsa.dialect.family == "scpi" and dsa.replies(command) == ["block"]:
                values = dsa.query_block(command)
                print(json.dumps(values.tolist()) if as_json else "\n".join(f"{v:.17g}" for v in values))
                return
            print(dsa.query(command))
        except ValueError as exc:
            raise UserError(str(exc), exit_code=2) from None
        except InstrumentTimeout:
            # An analyzer that refuses a query stays silent and says why in its error
            # queue; the driver leaves the queue alone, so ask it here.
            with contextlib.suppress(InstrumentTimeout):
                dsa.check_errors()
            raise


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
