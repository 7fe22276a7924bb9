"""The `daq` command line.

Every failure ends as one line on stderr and a non-zero exit status: 2 for bad
usage, 1 for everything else the user can fix, 70 for a bug (with the traceback
only when DAQ_DEBUG=1), 130 for Ctrl-C.
"""

from __future__ import annotations

import logging
import os
import sys
from typing import Annotated

import typer

# typer 0.29 vendors click; its exception classes live here (pinned in pyproject).
from typer._click import exceptions as click_exc

from daq import __version__
from daq import talk_command as talk
from daq.demo_command import demo
from daq.errors import UserError
from daq.model_command import model
from daq.sim_command import sim_app
from drivers.errors import DriverError

app = typer.Typer(
    name="daq",
    help="Impact testing of a cantilever beam with an HP 35660A: model, simulate, capture, analyse.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    context_settings={"help_option_names": ["-h", "--help"]},
)


def _version(value: bool) -> None:
    if value:
        print(f"daq {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: Annotated[
        bool,
        typer.Option("--version", callback=_version, is_eager=True, help="Print the version and exit."),
    ] = False,
    verbose: Annotated[
        int,
        typer.Option(
            "--verbose",
            "-v",
            count=True,
            help="Log to stderr: -v retries and progress, -vv every byte on the wire.",
        ),
    ] = 0,
) -> None:
    # Quiet by default: a failure is reported once, as one line, by main().
    level = logging.CRITICAL if verbose == 0 else logging.INFO if verbose == 1 else logging.DEBUG
    logging.basicConfig(
        level=level, stream=sys.stderr, format="%(asctime)s %(name)s %(levelname)s %(message)s"
    )


app.command(name="model")(model)
app.add_typer(sim_app, name="sim")
app.command(name="instruments")(talk.instruments)
app.command(name="identify")(talk.identify)
app.command(name="send")(talk.send)
app.command(name="query")(talk.query)
app.command(name="demo")(demo)


def _fail(message: str, exit_code: int) -> int:
    # One line, whatever the message holds: the contract with scripts and technicians.
    line = " ".join(str(message).split())
    sys.stderr.write(f"daq: error: {line}\n")
    sys.stderr.flush()
    return exit_code


def main(argv: list[str] | None = None) -> int:
    """Entry point of the `daq` console script; returns the exit status."""
    command = typer.main.get_command(app)
    try:
        result = command.main(args=argv, prog_name="daq", standalone_mode=False)
    except click_exc.NoArgsIsHelpError:
        # Bare `daq` (or a bare group): building this error printed the help
        # already; the help is the answer, not an error.
        return 0
    except click_exc.UsageError as exc:
        hint = f" (see '{exc.ctx.command_path} --help')" if exc.ctx else ""
        return _fail(exc.format_message() + hint, 2)
    except click_exc.ClickException as exc:
        return _fail(exc.format_message(), exc.exit_code or 1)
    except typer.Abort:
        return _fail("aborted", 130)
    except UserError as exc:
        return _fail(str(exc), exc.exit_code)
    except DriverError as exc:
        return _fail(str(exc), 1)
    except KeyboardInterrupt:
        return _fail("interrupted", 130)
    except BrokenPipeError:
        # `daq model | head`: the reader left; not worth a message.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 1
    except Exception as exc:
        if os.environ.get("DAQ_DEBUG"):
            raise
        return _fail(f"internal error: {type(exc).__name__}: {exc} (set DAQ_DEBUG=1 for a traceback)", 70)
    return result if isinstance(result, int) else 0
