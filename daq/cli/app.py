"""The `daq` command line.

Every failure ends as one line on stderr and a non-zero exit status: 2 for bad
usage, 1 for everything else the user can fix (each layer's error and its status:
daq/cli/errors.py), 70 for a bug (with the traceback only when DAQ_DEBUG=1), 130
for Ctrl-C.

Only typer's public API is used (typer.TyperException, Exit, Abort, Context):
typer vendors click as the private typer._click, whose names may move in any
release.
"""

from __future__ import annotations

import os
import sys
import warnings
from typing import Annotated

# Before numpy loads: the analysis solves many small matrices, where BLAS threads cost
# more than they give (one thread is twice as fast here), and `daq analyze` runs
# one worker process per core instead. A user's own setting wins.
for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")

import typer

# Every command module is imported here, to put its options in the help: each imports
# typer, daq.cli.options and the standard library only, and loads numpy, scipy, h5py,
# rich, the drivers or the service inside the function that needs them, so that
# `daq --help` and `daq runs list` start fast (bench/bench_startup.py).
from daq import __version__
from daq.cli import options
from daq.cli.commands import (
    analyze as analyze_command,
)
from daq.cli.commands import (
    capture as capture_command,
)
from daq.cli.commands import (
    config as config_command,
)
from daq.cli.commands import (
    export as export_command,
)
from daq.cli.commands import (
    fit as fit_command,
)
from daq.cli.commands import (
    import_file as import_command,
)
from daq.cli.commands import (
    replay as replay_command,
)
from daq.cli.commands import (
    report as report_command,
)
from daq.cli.commands import (
    runs as runs_command,
)
from daq.cli.commands import (
    serve as serve_command,
)
from daq.cli.commands import (
    setup as setup_command,
)
from daq.cli.commands import talk
from daq.cli.commands import (
    test as test_command,
)
from daq.cli.commands.demo import demo
from daq.cli.commands.model import model
from daq.cli.commands.sim import sim_app

app = typer.Typer(
    name="daq",
    help="Impact testing of a cantilever beam with an HP 35660A: model, simulate, capture, analyse.",
    # A bare `daq` prints the help (see _root), as a bare `daq sim` does.
    invoke_without_command=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    # Plain help: typer's rich panels give every flag, --help included, a <bool>
    # metavar as if it took a value, and cannot be written to docs/cli.md as text.
    rich_markup_mode=None,
    context_settings={"help_option_names": ["-h", "--help"]},
)


def _version(value: bool) -> None:
    if value:
        print(f"daq {__version__}")
        raise typer.Exit()


def _log_to_stderr(ctx: typer.Context, verbose: int) -> None:
    import logging

    # Quiet by default: a failure is reported once, as one line, by main(); the
    # CRITICAL handler also keeps logging's last-resort handler from printing warnings.
    root = logging.getLogger()
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(logging.Formatter("%(asctime)s %(name)s %(levelname)s %(message)s"))
    old_level = root.level
    root.addHandler(handler)
    root.setLevel(logging.CRITICAL if verbose == 0 else logging.INFO if verbose == 1 else logging.DEBUG)

    def restore() -> None:
        # main() runs in-process in tests and scripts: leave logging as it was found.
        root.removeHandler(handler)
        root.setLevel(old_level)

    ctx.call_on_close(restore)


@app.callback()
def _root(
    ctx: typer.Context,
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
            show_default=False,
            help="Log to stderr: -v retries and progress, -vv every byte on the wire.",
        ),
    ] = 0,
) -> None:
    if ctx.invoked_subcommand is None:
        # A bare `daq`: the help is the answer, not an error.
        typer.echo(ctx.get_help())
        raise typer.Exit()
    # Here, not at import: a command is about to run (not --help, not --version).
    from daq.batch.memory_tuning import keep_freed_memory

    keep_freed_memory()
    _log_to_stderr(ctx, verbose)


app.command(name="model")(model)
app.add_typer(sim_app, name="sim")
app.command(name="instruments")(talk.instruments)
app.command(name="identify")(talk.identify)
app.command(name="send")(talk.send)
app.command(name="query")(talk.query)
app.command(name="demo")(demo)
capture_command.register(app)
runs_command.register(app)
replay_command.register(app)
import_command.register(app)
export_command.register(app)
analyze_command.register(app)
fit_command.register(app)
report_command.register(app)
config_command.register(app)
serve_command.register(app)
test_command.register(app)
setup_command.register(app)


def _fail(message: str, exit_code: int) -> int:
    # One line, whatever the message holds: the contract with scripts and technicians.
    # The notes of old option spellings ride on it (daq/cli/options.py: renamed).
    notes = options.take_notes()
    if notes:
        message = f"{message} (note: {'; '.join(notes)})"
    line = " ".join(str(message).split())
    sys.stderr.write(f"daq: error: {line}\n")
    sys.stderr.flush()
    return exit_code


def help_hint(exc: typer.TyperException) -> str:
    """The hint " (see 'daq sim serve --help')" for a usage error about a command, else "".

    typer exports no UsageError: its usage errors are TyperExceptions with exit
    code 2 that keep the typer.Context of the command they are about in ``ctx``.
    tests/test_cli_basics.py::test_usage_errors_point_at_the_commands_help
    fails if a typer release drops that attribute.
    """
    path = getattr(getattr(exc, "ctx", None), "command_path", None)
    return f" (see '{path} --help')" if isinstance(path, str) and path else ""


def main(argv: list[str] | None = None) -> int:
    """Entry point of the `daq` console script; returns the exit status."""
    command = typer.main.get_command(app)
    options.take_notes()  # none left from an earlier call in this process
    try:
        with warnings.catch_warnings():
            if not os.environ.get("DAQ_DEBUG"):
                # numpy's RuntimeWarnings name source lines, not the input: a failure is one
                # line from the layers' own errors, and what may mislead is a caution.
                warnings.simplefilter("ignore", RuntimeWarning)
            result = command.main(args=argv, prog_name="daq", standalone_mode=False)
    except typer.TyperException as exc:
        # Usage errors (exit code 2), bad files given to typer and the like.
        code = exc.exit_code or 1
        return _fail(exc.format_message() + (help_hint(exc) if code == 2 else ""), code)
    except typer.Abort:
        return _fail("aborted", 130)
    except KeyboardInterrupt:
        return _fail("interrupted", 130)
    except BrokenPipeError:
        # `daq model | head`: the reader left; not worth a message.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 1
    except Exception as exc:
        # The layers' own errors (formats, store, workflows, drivers) and UserError:
        # one line and their exit status (daq/cli/errors.py). Anything else is a bug.
        from daq.cli.errors import exit_code_and_message

        known = exit_code_and_message(exc)
        if known is not None:
            code, message = known
            return _fail(message, code)
        if os.environ.get("DAQ_DEBUG"):
            raise
        return _fail(f"internal error: {type(exc).__name__}: {exc} (set DAQ_DEBUG=1 for a traceback)", 70)
    if result == 130:
        # typer turns a Ctrl-C inside a command into a silent exit 130; nothing
        # in daq exits 130 on purpose, so this is that Ctrl-C.
        return _fail("interrupted", 130)
    for note in options.take_notes():
        sys.stderr.write(f"daq: note: {note}\n")
    return result if isinstance(result, int) else 0
