"""`daq model`: the seed's Table 2 redone, and the modal damping of a damping matrix (docs/method.md)."""

from __future__ import annotations

import json
from enum import StrEnum
from pathlib import Path
from typing import Annotated

import typer

from daq.cli.errors import UserError
from daq.cli.options import given_once
from daq.workflows.model_inputs import MAX_FUNCTIONS

#: The default of --functions (the seed's 3-function model).
DEFAULT_FUNCTIONS = 3


class Section(StrEnum):
    tabulated = "tabulated"
    derived = "derived"


def model(
    functions: Annotated[
        int | None,
        typer.Option(
            "--functions",
            "-n",
            metavar="<N>",
            show_default=False,
            help=f"Number N of Ritz admissible functions (1-{MAX_FUNCTIONS}).  "
            f"[default: {DEFAULT_FUNCTIONS}]",
        ),
    ] = None,
    modes_n: Annotated[
        int | None, typer.Option("--modes-n", hidden=True, help="Old name of --functions.")
    ] = None,
    section: Annotated[
        Section,
        typer.Option(
            help="Area A and second moment I of the Ritz and damped models: tabulated (Table 1) "
            "or derived from width b and height h (b·h, b·h³/12)."
        ),
    ] = Section.tabulated,
    damping: Annotated[
        Path | None,
        typer.Option(
            metavar="<file>",
            help="Damping matrix in N s/m: .npy, .json or rows of numbers in text.  "
            "[default: the seed's eq (18)]",
            dir_okay=False,
        ),
    ] = None,
    beam_file: Annotated[
        Path | None,
        typer.Option(
            "--beam",
            metavar="<file>",
            help="Beam properties, TOML or JSON, SI field names such as length_m.  [default: Table 1]",
        ),
    ] = None,
    as_json: Annotated[
        bool, typer.Option("--json", help="Print the report as JSON instead of tables.")
    ] = False,
) -> None:
    """Beam models beside the seed's Table 2, and modal damping.

    Prints the seed paper's Table 2 (analytical and measured natural frequencies)
    beside the exact beam and the Ritz model with N functions, then the natural
    frequency and damping ratio of each mode of the damped model for a damping
    matrix: the seed's eq (18) unless --damping names a file.
    """
    given = given_once("--functions", functions, "--modes-n", modes_n)
    n_functions = DEFAULT_FUNCTIONS if given is None else int(given)  # type: ignore[call-overload]
    if not 1 <= n_functions <= MAX_FUNCTIONS:
        flag = "--functions" if modes_n is None else "--modes-n"  # as the user spelled it
        raise UserError(f"{flag} must be between 1 and {MAX_FUNCTIONS}, got {n_functions}", exit_code=2)
    # Imported here so that `daq --help` does not pay for scipy.
    import numpy as np
    from rich.console import Console

    from analysis.beam import TABLE_1
    from analysis.seed import eq18_damping_matrix
    from daq.workflows.model_inputs import read_beam, read_damping_matrix
    from daq.workflows.model_report import build_report, render

    beam = TABLE_1 if beam_file is None else read_beam(beam_file)
    if damping is None:
        matrix, source = eq18_damping_matrix(), "seed eq (18)"
    else:
        matrix, source = read_damping_matrix(damping), str(damping)
    try:
        # Finite but extreme inputs (a 1e200 m beam, a 1e300 damping entry) must end
        # in one clear line, not in NaN tables or a LAPACK traceback.
        with np.errstate(over="raise", invalid="raise", divide="raise"):
            t2, ds, report = build_report(beam, n_functions, section.value, matrix, source)  # type: ignore[arg-type]
    except (FloatingPointError, np.linalg.LinAlgError, OverflowError, ValueError) as exc:
        raise UserError(f"the model cannot be evaluated with these numbers ({exc})") from None
    if as_json:
        print(json.dumps(report, indent=2))
    else:
        render(Console(), beam, t2, ds, source)
