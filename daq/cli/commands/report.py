"""`daq report RUN [-o DIR]`: PNG figures, one self-contained HTML page and a PDF of the
same report of a run and its analysis (analysed first if its stored analysis is missing
or stale)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Annotated

import typer

from daq.cli.errors import UserError
from daq.cli.options import StoreOption


def register(app: typer.Typer) -> None:
    app.command(name="report")(report)


def report(
    run: Annotated[
        str, typer.Argument(metavar="RUN", show_default=False, help="Run id, unique prefix, or latest.")
    ],
    output: Annotated[
        Path | None,
        typer.Option("--output", "-o", metavar="<dir>", help="Folder to write [default: ./report-<run id>]."),
    ] = None,
    force: Annotated[
        bool, typer.Option("--force", help="Write over an earlier report in that folder.")
    ] = False,
    band: Annotated[
        str | None,
        typer.Option(
            metavar="<low:high>", show_default=False, help="Analyse in this band first, Hz (as daq analyze)."
        ),
    ] = None,
    frequencies: Annotated[
        str | None,
        typer.Option(
            metavar="<f1,f2,...>", show_default=False, help="Analyse for these frequencies first, Hz."
        ),
    ] = None,
    max_order: Annotated[
        int | None,
        typer.Option(metavar="<2-200>", show_default=False, help="Analyse with this LSCF order first."),
    ] = None,
    estimator: Annotated[
        str | None,
        typer.Option(metavar="<h1|h2|hv>", show_default=False, help="Analyse with this estimator first."),
    ] = None,
    store: StoreOption = None,
) -> None:
    """Write a run's report: acquisition, cautions, hits, FRF, stability, synthesis, Table 2, fits.

    PNG files, index.html (everything embedded: it opens from disk, no network) and
    report.pdf (the same sections, to print or file).
    The analysis shown is the stored one, made by `daq analyze` with the options it was
    given; analysis options here analyse again with them first (stored as by daq analyze).
    """
    from daq.report.build import build_report_files
    from daq.store import Store, StoreError, resolve_store_dir

    store_dir, _ = resolve_store_dir(store)
    try:
        run_id = Store(store_dir).resolve(run).stem
    except StoreError as exc:
        raise UserError(" ".join(str(exc).split())) from None
    folder = output if output is not None else Path(f"report-{run_id}")
    if folder.exists() and not folder.is_dir():
        raise UserError(f"{folder} exists and is not a folder")
    if (folder / "index.html").exists() and not force:
        raise UserError(
            f"{folder} already holds a report; give --force to write over it or -o another folder"
        )
    options = _options(band, frequencies, max_order, estimator)
    try:
        files = build_report_files(store_dir, run_id, options)
    except (StoreError, ValueError) as exc:
        raise UserError(" ".join(str(exc).split())) from None
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise UserError(f"cannot create {folder}: {exc.strerror or exc}") from None
    for name, png in files.pngs.items():
        _write(folder / f"{name}.png", png)
    assert files.pdf is not None
    _write(folder / "report.pdf", files.pdf)
    _write(folder / "index.html", files.html.encode("utf-8"))
    figures = f"{len(files.pngs)} figures"
    typer.echo(f"Report of run {run_id}: {folder / 'index.html'} and {folder / 'report.pdf'} ({figures})")


def _options(band: str | None, frequencies: str | None, max_order: int | None, estimator: str | None):
    """AnalysisOptions of the options given, or None when none was (the stored analysis is drawn)."""
    if band is None and frequencies is None and max_order is None and estimator is None:
        return None
    from analysis.run_analysis import AnalysisOptions
    from daq.cli.commands.analyze import parse_band, parse_frequencies

    try:
        return AnalysisOptions(
            band_hz=parse_band(band), max_order=max_order, frequencies_hz=parse_frequencies(frequencies),
            estimator=(estimator or "h1").lower(),
        )  # fmt: skip
    except ValueError as exc:
        text = str(exc).replace("max_order", "--max-order").replace("estimator", "--estimator")
        raise UserError(text.replace("band ", "--band "), exit_code=2) from None


def _write(path: Path, data: bytes) -> None:
    """Whole or not at all: a temporary beside it, then a rename."""
    temp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    try:
        temp.write_bytes(data)
        os.replace(temp, path)
    except OSError as exc:
        temp.unlink(missing_ok=True)
        raise UserError(f"cannot write {path}: {exc.strerror or exc}") from None
