"""`daq report RUN [-o DIR]`: PNG figures and one self-contained HTML page of a run
and its analysis (analysed first if its stored analysis is missing or stale)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Annotated, Any

import typer

from daq.errors import UserError
from daq.runs_command import StoreOption


def register(app: typer.Typer) -> None:
    app.command(name="report")(report)


def report(
    run: Annotated[str, typer.Argument(metavar="RUN", show_default=False, help="Run id or unique prefix.")],
    output: Annotated[
        Path | None,
        typer.Option("--output", "-o", metavar="<dir>", help="Folder to write [default: ./report-<run id>]."),
    ] = None,
    force: Annotated[
        bool, typer.Option("--force", help="Write over an earlier report in that folder.")
    ] = False,
    store: StoreOption = None,
) -> None:
    """Write a run's report: hits, FRF and coherence, stability diagram, synthesis, Table 2.

    PNG files and index.html (everything embedded: it opens from disk, no network).
    """
    from analysis.run_analysis import AnalysisOptions
    from daq.analysis_store import RESULT_NAME, analyze_stored
    from daq.fit_store import FitOptions
    from daq.report import figures, page
    from daq.store import Store, StoreError, resolve_store_dir

    store_dir, _ = resolve_store_dir(store)
    the_store = Store(store_dir)
    try:
        run_id = the_store.resolve(run).stem
        analyze_stored(store_dir, run_id, AnalysisOptions())
        the_run = the_store.open(run_id)
        result = the_store.read_result(run_id, RESULT_NAME)
    except (StoreError, ValueError) as exc:
        raise UserError(" ".join(str(exc).split())) from None
    folder = output if output is not None else Path(f"report-{run_id}")
    if folder.exists() and not folder.is_dir():
        raise UserError(f"{folder} exists and is not a folder")
    if (folder / "index.html").exists() and not force:
        raise UserError(
            f"{folder} already holds a report; give --force to write over it or -o another folder"
        )
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise UserError(f"cannot create {folder}: {exc.strerror or exc}") from None
    pngs = {
        "frf": figures.frf_figure(result),
        "stability": figures.stability_figure(result),
        "synthesis": figures.synthesis_figure(result),
    }
    if the_run.hits is not None:
        pngs["hits"] = figures.hits_figure(the_run)
    fits = stored_fits(the_store, run_id)
    # The default least-squares fit when there is one, whatever else was tried.
    order = sorted(fits, key=lambda name: name != FitOptions().result_name)
    with_response = [fits[name] for name in order if "model_response" in fits[name]]
    if with_response and the_run.hits is not None:
        pngs["response_fit"] = figures.response_fit_figure(the_run, with_response[0])
    if any("history" in f for f in fits.values()):
        pngs["convergence"] = figures.convergence_figure(fits)
    for name, png in pngs.items():
        _write(folder / f"{name}.png", png)
    _write(folder / "index.html", page.render(the_run, result, pngs, fits).encode("utf-8"))
    typer.echo(f"Report of run {run_id}: {folder / 'index.html'} ({len(pngs)} figures)")


def stored_fits(the_store: Any, run_id: str) -> dict[str, dict]:
    """The damping fits stored beside the run (``<id>.fit-*.h5``), by result name; the
    least-squares fit is made first when there is none (a report shows the matrix)."""
    from daq.store import StoreError

    names = sorted(p.name[len(run_id) + 1 : -3] for p in the_store.path.glob(f"{run_id}.fit-*.h5"))
    if not names:
        from daq.fit_store import FitOptions, fit_stored

        try:
            fit_stored(the_store.path, run_id, FitOptions())
        except (StoreError, ValueError):
            return {}  # e.g. an FRF-only run: the report goes without a fit
        names = [FitOptions().result_name]
    fits = {}
    for name in names:
        try:
            fits[name] = the_store.read_result(run_id, name)
        except StoreError:
            continue
    return fits


def _write(path: Path, data: bytes) -> None:
    """Whole or not at all: a temporary beside it, then a rename."""
    temp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    try:
        temp.write_bytes(data)
        os.replace(temp, path)
    except OSError as exc:
        temp.unlink(missing_ok=True)
        raise UserError(f"cannot write {path}: {exc.strerror or exc}") from None
