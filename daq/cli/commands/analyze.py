"""`daq analyze RUN... | --all`: FRFs, modes and Table 2 of stored runs, kept beside each
run (daq/workflows/analysis.py), in parallel over the cores, or on a Dask cluster with
--scheduler (daq/batch/dask_backend.py), with a progress bar.

Without --json it prints each run's modes; with --json a list with one object per
run (``run_id``, ``modes`` sorted by frequency, ``table2``, ...). A run that cannot
be analysed gets one line on stderr and the others go on; the exit status is 1 if
any failed.
"""

from __future__ import annotations

import json
import os
import sys
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path
from typing import Annotated, Any

import typer

from daq.batch.dask_backend import failure_reason, run_on_cluster, scheduler_address
from daq.batch.memory_tuning import worker_setup
from daq.cli.options import JobsOption, JsonOption, SchedulerOption, StoreOption
from daq.errors import UserError


def register(app: typer.Typer) -> None:
    app.command(name="analyze")(analyze)


def parse_band(text: str | None) -> tuple[float, float] | None:
    if text is None:
        return None
    try:
        low, high = (float(v) for v in text.split(":"))
    except ValueError:
        raise UserError(f"--band {text!r}: give two frequencies in Hz as LOW:HIGH, e.g. 2:150", 2) from None
    if not (0 <= low < high < float("inf")):
        raise UserError(f"--band {text!r}: need 0 <= LOW < HIGH", 2)
    return low, high


def parse_frequencies(text: str | None) -> tuple[float, ...] | None:
    if text is None:
        return None
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        raise UserError(
            f"--frequencies {text!r}: give Hz values separated by commas, e.g. 5.6,36,97", 2
        ) from None
    if not values or not all(0 < v < float("inf") for v in values):
        raise UserError(f"--frequencies {text!r}: every frequency must be positive", 2)
    return values


def analyze(
    runs: Annotated[
        list[str] | None,
        typer.Argument(metavar="[RUN]...", show_default=False, help="Run ids or unique prefixes."),
    ] = None,
    all_runs: Annotated[bool, typer.Option("--all", help="Analyse every run of the store.")] = False,
    band: Annotated[
        str | None,
        typer.Option(
            metavar="<low:high>",
            show_default=False,
            help="Identify modes in this band only, Hz [default: where the hammer put energy and the "
            "coherence is usable].",
        ),
    ] = None,
    frequencies: Annotated[
        str | None,
        typer.Option(metavar="<f1,f2,...>", help="Frequencies of interest, Hz (else found automatically)."),
    ] = None,
    max_order: Annotated[
        int | None,
        typer.Option(
            metavar="<2-200>",
            show_default=False,
            help="LSCF model order of every frequency zone [default: each zone's, from its peaks].",
        ),
    ] = None,
    estimator: Annotated[
        str, typer.Option(metavar="<h1|h2|hv>", help="FRF estimator for time records.")
    ] = "h1",
    jobs: JobsOption = None,
    scheduler: SchedulerOption = None,
    force: Annotated[
        bool, typer.Option("--force", help="Analyse again even if a result is up to date.")
    ] = False,
    json_output: JsonOption = False,
    store: StoreOption = None,
) -> None:
    """Analyse runs: FRFs over the accepted hits, modes from the stability diagram, Table 2.

    Each result is stored beside its run (<run id>.analysis.h5; the run file is never
    written). An unchanged run analysed with unchanged options is a cache hit.
    """
    from analysis.run_analysis import AnalysisOptions

    if bool(runs) == all_runs:
        raise UserError("name the runs to analyse, or give --all", exit_code=2)
    try:
        options = AnalysisOptions(
            band_hz=parse_band(band), max_order=max_order, frequencies_hz=parse_frequencies(frequencies),
            estimator=estimator.lower(),
        )  # fmt: skip
    except ValueError as exc:
        # The options' names as the user typed them.
        text = str(exc).replace("max_order", "--max-order").replace("estimator", "--estimator")
        raise UserError(text.replace("band ", "--band "), exit_code=2) from None
    run_batch(
        runs, all_runs, store, options, force, jobs, json_output, analyze_one, _print, "analyse", scheduler
    )


def run_batch(
    runs: list[str] | None,
    all_runs: bool,
    store: str | None,
    options: Any,
    force: bool,
    jobs: int | None,
    json_output: bool,
    worker: Any,
    printer: Any,
    verb: str,
    scheduler: str | None = None,
) -> None:
    """The part `daq analyze` and `daq fit` share: pick the runs (named, or every run
    file with --all, damaged ones too so that they fail with a line, never silently),
    run ``worker`` on each in worker processes (or on the Dask cluster of
    ``scheduler``, the --scheduler option, else $DAQ_SCHEDULER), print each summary
    (``printer``) or the JSON list, and end with one error line if any run failed."""
    from daq.store import Store, StoreError, resolve_store_dir

    if jobs is not None and jobs < 1:
        raise UserError("--jobs must be at least 1", exit_code=2)
    if jobs is not None and scheduler is not None:
        raise UserError("give --jobs (local worker processes) or --scheduler (a Dask cluster), not both", 2)
    # An explicit --jobs asks for the local pool, whatever $DAQ_SCHEDULER says.
    address = None if jobs is not None else scheduler_address(scheduler)
    store_dir, _ = resolve_store_dir(store)
    the_store = Store(store_dir)
    try:
        if all_runs:
            ids = [s.file_name.removesuffix(".h5") for s in the_store.list()]
        else:
            ids = list(dict.fromkeys(the_store.resolve(name).stem for name in runs or []))
    except StoreError as exc:
        raise UserError(str(exc)) from None
    if not ids:
        raise UserError(f"no runs to {verb} in {store_dir}")
    label = {"analyse": "analysing", "fit": "fitting"}.get(verb, verb)
    quiet = len(ids) == 1
    results, failures = run_all(
        store_dir, ids, options, force, jobs, worker, label, quiet, address, skip_empty=all_runs
    )
    if json_output:
        typer.echo(json.dumps([results[i] for i in ids if i in results], indent=2, ensure_ascii=False))
    else:
        for run_id in ids:
            if run_id in results:
                printer(results[run_id])
    if failures and len(ids) == 1:
        raise UserError(f"run {ids[0]}: {failures[0][1]}")
    if failures:
        raise UserError(
            f"{len(failures)} of {len(ids)} runs could not be {'analysed' if verb == 'analyse' else 'fitted'}"
        )


def run_all(
    store_dir: Path,
    ids: list[str],
    options: Any,
    force: bool,
    jobs: int | None,
    worker: Any = None,
    label: str = "analysing",
    quiet: bool = False,
    scheduler: str | None = None,
    skip_empty: bool = False,
) -> tuple[dict[str, dict], list[tuple[str, str]]]:
    """Run ``worker(store_dir, run_id, options, force)`` (default: analyze_one) on
    ``ids`` in worker processes; (summaries by run id, failed ids). A worker returns a
    summary dict or a one-line reason; failures, (run id, reason), are reported on
    stderr unless ``quiet`` (one run: the caller makes its reason the one error line).

    scheduler: a Dask scheduler's address (daq/dask_batch.scheduler_address): the
    runs are computed on its cluster instead (the same outcomes and stored results;
    ``jobs`` unused).

    skip_empty: a run with nothing to analyse (analysis_store.nothing_to_identify) is
    reported as skipped, even when ``quiet``, and is not among the failures."""
    from daq.workflows.analysis import nothing_to_identify

    worker = worker or analyze_one
    command = "fit" if worker is not analyze_one else "analyze"
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    workers = min(jobs or os.cpu_count() or 1, len(ids))
    results: dict[str, dict] = {}
    failures: list[tuple[str, str]] = []
    console = Console(stderr=True)
    columns = (TextColumn(label), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn())
    with Progress(*columns, console=console, transient=True, disable=not console.is_terminal) as progress:
        task = progress.add_task("runs", total=len(ids))

        def done(run_id: str, outcome: dict | str) -> None:
            if isinstance(outcome, str) and skip_empty and nothing_to_identify(outcome):
                sys.stderr.write(f"daq {command}: run {run_id}: skipped: {outcome}\n")
            elif isinstance(outcome, str):
                if not quiet:
                    sys.stderr.write(f"daq {command}: run {run_id}: {outcome}\n")
                failures.append((run_id, outcome))
            else:
                results[run_id] = outcome
            progress.advance(task)

        if scheduler is not None:
            run_on_cluster(scheduler, store_dir, ids, options, force, command, done)
        elif workers == 1:
            for run_id in ids:
                done(run_id, worker(store_dir, run_id, options, force))
        else:
            # Workers die with this process: killed, it must not leave them running for good.
            pool = ProcessPoolExecutor(max_workers=workers, initializer=worker_setup, initargs=(os.getpid(),))
            with pool:
                futures = {pool.submit(worker, store_dir, r, options, force): r for r in ids}
                for future in as_completed(futures):
                    done(futures[future], future.result())
    return results, failures


def analyze_one(store_dir: Path, run_id: str, options: Any, force: bool) -> dict | str:
    """The summary of one run's analysis, or a one-line reason it failed (picklable)."""
    from daq.workflows.analysis import analyze_stored

    try:
        return analyze_stored(store_dir, run_id, options, force)
    except Exception as exc:
        reason = failure_reason(exc)  # the reasons a run on a Dask cluster gives too
        if reason is None:
            raise
        return reason


def np_errors() -> tuple[type[BaseException], ...]:
    import numpy as np

    return (np.linalg.LinAlgError, FloatingPointError, ZeroDivisionError)


def _print(info: dict) -> None:
    cached = " (cached)" if info.get("cached") else ""
    n_hits = info.get("n_averages")
    hits_text = f"{n_hits} hit{'s' * (n_hits != 1)}"  # "1 hit", never "1 hits"
    source = {"hits": f"{hits_text}, {info.get('estimator', '')}".rstrip(", ")}.get(
        info["source"], info["source"]
    )
    n_modes = len(info["modes"])
    typer.echo(
        f"Run {info['run_id']} ({info['kind']}, {source}){cached}: {n_modes} mode{'s' * (n_modes != 1)}"
    )
    band = info.get("band")
    if band:
        typer.echo(f"  band {band['low_hz']:.6g}-{band['high_hz']:.6g} Hz: {band['reason']}")
    zones = info.get("zones") or []
    if len(zones) > 1:
        typer.echo(f"  {len(zones)} frequency zones, LSCF orders {min(z['max_order'] for z in zones)}-"
                   f"{max(z['max_order'] for z in zones)}")  # fmt: skip
    windows = str(info.get("windows", {}).get("from", ""))
    if windows.startswith("unknown"):
        typer.echo(f"  caution: windows {windows}")
    for k, mode in enumerate(info["modes"], 1):
        typer.echo(f"  mode {k}: {_mode_text(mode)}")
    if n_modes:
        u_from = {m.get("uncertainty_from") for m in info["modes"]} - {None}
        how = f" from {', '.join(sorted(u_from))}" if u_from else ""
        typer.echo(f"  ± is the standard uncertainty of the value{how} (docs/analysis.md)")
    error = info.get("synthesis_error")
    if error is not None:
        typer.echo(f"  synthesis error {100 * error:.3g} % (the modes' FRF against the measured one)")
    for text in info.get("cautions", []):
        typer.echo(f"  caution: {text}")
    table = info["table2"]
    rows = [r for r in table["rows"] if r["identified_hz"] is not None]
    if rows:
        typer.echo(f"  Table 2, beam: {table['beam']}")
        typer.echo("    mode   Ritz Hz  exact Hz   run Hz  run vs exact  damping")
        for r in rows:
            ritz = f"{r['ritz_hz']:.3f}" if r["ritz_hz"] is not None else "-"
            zeta = f"{100 * r['damping_ratio']:.3g} %" if r["damping_ratio"] is not None else "-"
            typer.echo(
                f"    {r['mode']:>4}  {ritz:>8}  {r['exact_hz']:>8.3f}  {r['identified_hz']:>7.3f}  "
                f"{r['difference_exact_pct']:>+10.2f} %  {zeta:>7}"
            )
    elif not table["rows"]:
        typer.echo(f"  Table 2: {table['beam']}")


def _mode_text(mode: dict) -> str:
    """'1234.5678 Hz ± 0.01 Hz, damping 0.123 % ± 0.004 %; stable over ...' of one mode."""
    zeta = mode["damping_ratio"]
    f_u, z_u = mode.get("frequency_u_hz"), mode.get("damping_u")
    spread = f" ± {f_u:.2g} Hz" if f_u is not None else ""
    zspread = f" ± {100 * z_u:.2g} %" if z_u is not None else ""
    zeta_text = f"{100 * zeta:.3g} %{zspread}" if zeta is not None else "n/a (window decay larger)"
    q = mode["quality"]
    flag = "" if q.get("accepted", True) else " (asked for; fails a selection rule)"
    return (
        f"{mode['frequency_hz']:.4f} Hz{spread}, damping {zeta_text}; "
        f"stable over {q['n_stable_orders']} orders{flag}, "
        f"{100 * q['synthesis_share']:.2g} % of the synthesis"
    )
