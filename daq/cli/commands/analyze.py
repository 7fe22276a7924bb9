"""`daq analyze RUN... | --all`: FRFs, modes and Table 2 of stored runs, kept beside each
run (daq/workflows/analysis.py), on the batch executor (daq/batch/executor.py: in
parallel over the cores, or on a Dask cluster with --scheduler), with a progress bar.

Without --json it prints each run's modes; with --json a list with one object per
run (``run_id``, ``modes`` sorted by frequency, ``table2``, ...). A run that cannot
be analysed gets one line on stderr and the others go on; the exit status is 1 if
any failed.
"""

from __future__ import annotations

import json
import sys
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Annotated

import typer

from daq.cli.errors import UserError
from daq.cli.options import (
    BandOption,
    FrequenciesOption,
    JobsOption,
    JsonOption,
    MaxOrderOption,
    SchedulerOption,
    StoreOption,
)
from daq.report.numbers import plain, span, with_uncertainty

if TYPE_CHECKING:
    from daq.batch.executor import Backend, BatchReport
    from daq.batch.tasks import Task
    from daq.workflows.outcome import RunOutcome

#: The hidden alias of --recompute, kept for one release.
FORCE_NOTE = "daq: note: --force is now --recompute; --force will go in the next release\n"


def recompute_flag(recompute: bool, force: bool) -> bool:
    """--recompute, or the old --force (one note on stderr that it is going)."""
    if force:
        sys.stderr.write(FORCE_NOTE)
    return recompute or force


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
        typer.Argument(metavar="[RUN]...", show_default=False, help="Run ids, unique prefixes, or latest."),
    ] = None,
    all_runs: Annotated[bool, typer.Option("--all", help="Analyse every run of the store.")] = False,
    band: BandOption = None,
    frequencies: FrequenciesOption = None,
    max_order: MaxOrderOption = None,
    estimator: Annotated[
        str, typer.Option(metavar="<h1|h2|hv>", help="FRF estimator for time records.")
    ] = "h1",
    jobs: JobsOption = None,
    scheduler: SchedulerOption = None,
    recompute: Annotated[
        bool, typer.Option("--recompute", help="Analyse again even if a result is up to date.")
    ] = False,
    force: Annotated[bool, typer.Option("--force", hidden=True, help="Old name of --recompute.")] = False,
    json_output: JsonOption = False,
    store: StoreOption = None,
) -> None:
    """Analyse runs: FRFs over the accepted hits, modes from the stability diagram, Table 2.

    Each result is stored beside its run (<run id>.analysis.h5; the run file is never
    written). An unchanged run analysed with unchanged options is a cache hit.
    """
    from analysis.run_analysis import AnalysisOptions
    from daq.batch.tasks import AnalyseTask

    recompute = recompute_flag(recompute, force)
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
        runs, all_runs, store, jobs, scheduler, json_output, _print, "analyse",
        lambda store_dir, run_id: AnalyseTask(store_dir, run_id, options, recompute), _json_summary,
    )  # fmt: skip


def _json_summary(info: dict) -> dict:
    """A run's summary as --json prints it: an FRF read as it was measured was made by no
    estimator, so ``options.estimator`` (asked for, and kept in the stored result, whose
    cache key it is part of) is null there too, as the top-level ``estimator`` is."""
    options = info.get("options")
    if info.get("estimator") is None and isinstance(options, dict) and "estimator" in options:
        return {**info, "options": {**options, "estimator": None}}
    return info


def run_batch(
    runs: Sequence[str] | None,
    all_runs: bool,
    store: str | None,
    jobs: int | None,
    scheduler: str | None,
    json_output: bool,
    printer: Callable[[dict], None],
    verb: str,
    make_task: Callable[..., Task],
    json_view: Callable[[dict], dict] | None = None,
) -> list[dict]:
    """The part `daq analyze` and `daq fit` share: pick where to run (--jobs,
    --scheduler, $DAQ_SCHEDULER), pick the runs (named, or every run file with --all),
    run ``make_task(store_dir, run_id)`` of each on the executor (daq/batch/executor.py)
    with a progress bar, say each failure (or skip) on stderr as it comes, print each
    summary (``printer``, a blank line between runs) or the JSON list (each summary
    through ``json_view`` when given), and end with one error line if any run failed.
    The summaries printed."""
    from daq.batch.executor import choose_backend, select_runs
    from daq.store import resolve_store_dir

    choice = choose_backend(jobs, scheduler)
    store_dir, _ = resolve_store_dir(store)
    ids = select_runs(store_dir, runs, all_runs)
    if not ids:
        raise UserError(f"no runs to {verb} in {store_dir}")
    label = {"analyse": "analysing", "fit": "fitting"}.get(verb, verb)
    tasks = [make_task(store_dir, run_id) for run_id in ids]
    backend = choice.backend(len(tasks))
    report = run_with_progress(tasks, backend, label, quiet=len(ids) == 1, skip_empty=all_runs)
    summaries = report.summaries(ids)
    if json_output:
        shown = [json_view(s) for s in summaries] if json_view is not None else summaries
        typer.echo(json.dumps(shown, indent=2, ensure_ascii=False))
    else:
        for k, summary in enumerate(summaries):
            if k:
                typer.echo("")  # one run's lines apart from the next's
            printer(summary)
    if report.failures and len(ids) == 1:
        raise UserError(f"run {ids[0]}: {report.failures[0].error}")
    if report.failures:
        done = "analysed" if verb == "analyse" else "fitted"
        raise UserError(f"{len(report.failures)} of {len(ids)} runs could not be {done}")
    return summaries


def run_with_progress(
    tasks: Sequence[Task], backend: Backend, label: str, quiet: bool = False, skip_empty: bool = False
) -> BatchReport:
    """daq.batch.executor.execute with a progress bar on stderr (when it is a terminal)
    and a line there for each run skipped (always) or failed (unless ``quiet``: one run,
    whose reason the caller makes its one error line); a failure is a `daq: error:` line
    like every other error. The BatchReport."""
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    from daq.batch.executor import execute

    console = Console(stderr=True)
    columns = (TextColumn(label), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn())
    with Progress(*columns, console=console, transient=True, disable=not console.is_terminal) as progress:
        bar = progress.add_task("runs", total=len(tasks))

        def said(task: Task, outcome: RunOutcome) -> None:
            if outcome.status == "skipped":
                sys.stderr.write(f"daq {task.command}: run {task.run_id}: skipped: {outcome.error}\n")
            elif outcome.status == "failed" and not quiet:
                sys.stderr.write(f"daq: error: run {task.run_id}: {outcome.error}\n")
            progress.advance(bar)

        return execute(tasks, backend, skip_empty=skip_empty, on_outcome=said)


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
        # Four digits: the edges are lines (1.75021 Hz), the band is what a reader wants.
        typer.echo(f"  band {span(band['low_hz'], band['high_hz'], '.4g')}: {band['reason']}")
    if info.get("pretrigger_cut_s"):
        from daq.workflows.run_views import pretrigger_text

        typer.echo(f"  {pretrigger_text(info)}")
    from daq.workflows.run_views import zones_text

    zones = zones_text(info.get("zones"))
    if zones and not zones.startswith("one "):
        typer.echo(f"  {zones}")
    windows = str(info.get("windows", {}).get("from", ""))
    if windows.startswith("unknown") and f"windows {windows}" not in info.get("cautions", []):
        typer.echo(f"  caution: windows {windows}")  # an analysis stored before it was a caution
    for k, mode in enumerate(info["modes"], 1):
        typer.echo(f"  mode {k}: {_mode_text(mode)}")
    if n_modes:
        u_from = {m.get("uncertainty_from") for m in info["modes"]} - {None}
        how = f" from {', '.join(sorted(u_from))}" if u_from else ""
        typer.echo(f"  ± is the standard uncertainty of the value{how} (docs/analysis.md)")
    error = info.get("synthesis_error")
    if error is not None:
        shown = plain(100 * error, ".3g")
        typer.echo(f"  synthesis error {shown} % (the modes' FRF against the measured one)")
    for text in info.get("cautions", []):
        typer.echo(f"  caution: {text}")
    table = info["table2"]
    rows = [r for r in table["rows"] if r["identified_hz"] is not None]
    if rows:
        typer.echo(f"  Table 2, beam: {table['beam']}")
        typer.echo("    mode   Ritz Hz  exact Hz   run Hz  run vs exact  damping")
        for r in rows:
            ritz = f"{r['ritz_hz']:.3f}" if r["ritz_hz"] is not None else "-"
            zeta = f"{plain(100 * r['damping_ratio'], '.3g')} %" if r["damping_ratio"] is not None else "-"
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
    # Each value to the decimal place of its u (two significant digits), as measurements are written.
    f_text, f_u_text = with_uncertainty(mode["frequency_hz"], f_u, ".4f")
    spread = f" ± {f_u_text} Hz" if f_u_text != "–" else ""
    if zeta is None:
        zeta_text = "n/a (window decay larger)"
    else:
        z_text, z_u_text = with_uncertainty(100 * zeta, None if z_u is None else 100 * z_u, ".3g")
        zeta_text = f"{z_text if z_u_text != '–' else plain(100 * zeta, '.3g')} %" + (
            f" ± {z_u_text} %" if z_u_text != "–" else ""
        )
    q = mode["quality"]
    flag = (
        ""
        if q.get("accepted", True)
        else " (kept for a clear peak; fails a selection rule)"
        if q.get("for_peak")
        else " (asked for; fails a selection rule)"
    )
    # The second LSCF normalisation (analysis/modal_id/identify.py) is said: its poles differ.
    read_with = " with alpha_0 = 1" if q.get("normalisation") == "lowest" else ""
    # A mode added among close ones (analysis/modal_id/refine.py, missing) has no chain.
    how = (
        "found by refitting the close modes beside it (LSCF missed it)"
        if q.get("added")
        else f"stable over {q['n_stable_orders']} order{'' if q['n_stable_orders'] == 1 else 's'}"
        f"{read_with}{flag}"
    )
    share = plain(100 * q["synthesis_share"], ".2g")
    return f"{f_text} Hz{spread}, damping {zeta_text}; {how}, {share} % of the synthesis"
