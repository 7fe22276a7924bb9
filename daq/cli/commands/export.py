"""`daq export RUN --format csv|uff|sdf [-o PATH]`: a stored run written for other tools.

CSV holds the time records (every hit, its number in a ``hit`` column); UFF holds
them as dataset 58 time records plus the FRFs and coherence, in binary 58 so that
float64 values come back exactly (daq/formats/); SDF holds the same and the run's
spectra as an HP Standard Data Format revision 3 file of float64 values
(daq/formats/sdf/run_export.py). A run's spectra go to SDF only: CSV and UFF say so
(one line; an error when the run holds nothing else). An existing file is never
overwritten without --force, and the file appears whole or not at all.
"""

from __future__ import annotations

import enum
import os
import sys
from pathlib import Path
from typing import Annotated

import typer

from daq.cli.errors import UserError
from daq.cli.options import StoreOption
from daq.workflows.export import SUFFIX, write_run


class ExportFormat(enum.StrEnum):
    csv = "csv"
    uff = "uff"
    sdf = "sdf"


def export_target(output: str | None, default_name: str, force: bool) -> Path:
    """Where to write: ``output`` (a file, or a folder to put ``default_name`` in) or
    ./default_name. UserError for what must not be written over."""
    if output == "-":
        raise UserError("-o -: writing to stdout is not supported; give a file name", exit_code=2)
    # Kept as text until here: Path("x/") forgets the slash that says "a folder".
    if output is not None and output.endswith(os.sep) and not Path(output).is_dir():
        raise UserError(f"{output}: no such folder")
    target = Path(output).expanduser() if output is not None else Path(default_name)
    if target.is_dir():
        target = target / default_name
    if target.is_symlink() or (target.exists() and not target.is_file()):
        # A device, FIFO or link: replacing it would not write "a file" (as root,
        # `-o /dev/null --force` would put a regular file in place of the device).
        raise UserError(f"{target} is not a regular file; export writes only files")
    if target.exists() and not force:
        raise UserError(f"{target} exists; give --force to overwrite it or -o another path")
    if not target.parent.is_dir():
        raise UserError(f"{target.parent}: no such folder")
    return target


def register(app: typer.Typer) -> None:
    app.command(name="export")(export)


def export(
    run: Annotated[
        str, typer.Argument(metavar="RUN", show_default=False, help="Run id, unique prefix, or latest.")
    ],
    format: Annotated[
        ExportFormat, typer.Option("--format", "-f", help="csv, uff (dataset 58) or sdf (HP SDF revision 3).")
    ],
    output: Annotated[
        str | None,
        typer.Option(
            "--output", "-o", metavar="<path>", help="Where to write [default: ./<run id>.csv|uff|sdf]."
        ),
    ] = None,
    force: Annotated[bool, typer.Option("--force", help="Overwrite an existing output file.")] = False,
    store: StoreOption = None,
) -> None:
    """Write a stored run as CSV (time records), UFF 58 (and FRFs, coherence) or SDF (and spectra)."""
    from daq.store import Store, StoreError, resolve_store_dir

    store_dir, _ = resolve_store_dir(store)
    try:
        the_run = Store(store_dir).open(run)
    except StoreError as exc:
        raise UserError(str(exc)) from None
    _check_holds(the_run, format.value)
    target = export_target(output, f"{the_run.run_id}{SUFFIX[format.value]}", force)
    write_run(the_run, target, format.value)
    _note_left_out(the_run, format.value)
    typer.echo(f"Run {the_run.run_id} written as {format.value.upper()}: {target}")


#: What each format holds of a run, for the line saying why spectra are not written.
HOLDS = {"csv": "CSV holds time records only", "uff": "UFF export holds time records and FRFs only"}


def _check_holds(run, fmt: str) -> None:
    """UserError when ``fmt`` can hold nothing of the run (spectra only, in CSV or UFF)."""
    alone = all(part is None for part in (run.hits, run.analyzer, run.measured_frfs))
    if run.spectra is not None and fmt in HOLDS and alone:
        raise UserError(
            f"run {run.run_id} holds only spectra ({run.spectra.n_traces}); {HOLDS[fmt]}: "
            "export it with --format sdf"
        )


def _note_left_out(run, fmt: str) -> None:
    """One line on stderr when the written file leaves the run's spectra out."""
    if run.spectra is not None and fmt in HOLDS:
        sys.stderr.write(
            f"daq export: the run's {run.spectra.n_traces} spectra are not written "
            f"({HOLDS[fmt]}; --format sdf keeps them)\n"
        )
