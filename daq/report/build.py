"""A run's report as one self-contained HTML page (and a PDF of the same sections):
used by ``daq report`` and, the page alone, by the service's ``/api/runs/<id>/report``."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any


@dataclass
class ReportFiles:
    """A run's report: ``html`` (index.html), ``pngs`` (figure name -> PNG bytes) and
    ``pdf`` (report.pdf bytes, the same sections; None when not asked for)."""

    html: str
    pngs: dict[str, bytes]
    pdf: bytes | None = None


def build_report(store_dir: Path, run_id: str, options: Any = None) -> tuple[str, dict[str, bytes]]:
    """(index.html text, {figure name: PNG bytes}) of run ``run_id`` (see build_report_files)."""
    files = build_report_files(store_dir, run_id, options, pdf=False)
    return files.html, files.pngs


def build_report_files(store_dir: Path, run_id: str, options: Any = None, pdf: bool = True) -> ReportFiles:
    """The report of run ``run_id``: its HTML page, PNG figures and (``pdf``) its PDF.

    The analysis drawn is the stored one, with the options it was made with (brought up
    to date with those same options if the software changed); ``options``
    (AnalysisOptions) analyses with these instead; a run never analysed is analysed
    with ``options`` or the defaults. The damping fits drawn are those `daq fit`
    stored (none is made here). StoreError or ValueError when the run cannot be read
    or analysed."""
    from analysis.run_analysis import AnalysisOptions
    from daq.report import figures, page
    from daq.store import Store
    from daq.workflows.analysis import RESULT_NAME, analyze_stored, stored_options
    from daq.workflows.fit import FitOptions

    the_store = Store(store_dir)
    if options is None:
        options = stored_options(the_store, run_id) or AnalysisOptions()
    try:
        analyze_stored(store_dir, run_id, options)
    except ValueError as exc:  # e.g. a run of spectra alone: say which run has nothing to show
        raise ValueError(f"run {run_id}: {exc}") from None
    the_run = the_store.open(run_id)
    result = the_store.read_result(run_id, RESULT_NAME)
    fits = stored_fits(the_store, run_id)
    # The default least-squares fit when there is one, whatever else was tried.
    order = sorted(fits, key=lambda name: name != FitOptions().result_name)
    with_response = [fits[name] for name in order if "model_response" in fits[name]]
    drawers: dict[str, Any] = {
        "frf": lambda: figures.draw_frf(result),
        "stability": lambda: figures.draw_stability(result),
        "synthesis": lambda: figures.draw_synthesis(result),
    }
    if the_run.hits is not None:
        drawers["hits"] = lambda: figures.draw_hits(the_run)
        indices = figures.quality_indices(the_run)
        views, average = figures.hit_quality_views(the_run, indices)
        for i in views:
            verdict = page.hit_verdict(the_run, i)[0]
            drawers[f"hit_quality_{i + 1}"] = lambda i=i, verdict=verdict: figures.draw_hit_quality(
                the_run, i, views[i], average, verdict
            )
    if with_response and the_run.hits is not None:
        drawers["response_fit"] = lambda: figures.draw_response_fit(the_run, with_response[0])
    if any("history" in f for f in fits.values()):
        drawers["convergence"] = lambda: figures.draw_convergence(fits)
    drawn: dict[str, Any] = {}
    try:
        pngs = {}
        for name, draw in drawers.items():
            drawn[name] = draw()
            pngs[name] = figures._png(drawn[name], close=not pdf)
        report = page.sections(the_run, result, pngs, fits, fit_hint=not fits)
        html = page.render_sections(the_run, report, pngs)
        pdf_bytes = page.render_pdf(the_run, report, drawn) if pdf else None
    finally:
        if pdf:
            plt = figures._pyplot()
            for fig in drawn.values():
                plt.close(fig)
    return ReportFiles(html, pngs, pdf_bytes)


def stored_fits(the_store: Any, run_id: str) -> dict[str, dict]:
    """The damping fits stored beside the run (``<id>.fit-*.h5``), by result name. None
    is made here: a report draws what `daq fit` stored, and says so when there is none.
    A fit made from another analysis than the one stored now carries a caution."""
    from daq.store import StoreError
    from daq.workflows.analysis import RESULT_NAME

    try:
        analysis_key = the_store.read_result(run_id, RESULT_NAME).get("cache_key")
    except StoreError:
        analysis_key = None
    names = sorted(p.name[len(run_id) + 1 : -3] for p in the_store.path.glob(f"{run_id}.fit-*.h5"))
    fits = {}
    for name in names:
        try:
            fit = the_store.read_result(run_id, name)
        except StoreError:
            continue
        if fit.get("analysis_key") != analysis_key:
            summary = dict(fit["summary"])
            summary["cautions"] = [
                f"this fit was made from an earlier analysis of the run than the one shown above: "
                f"`daq fit {run_id}` fits the analysis as it is now",
                *summary.get("cautions", []),
            ]
            fit = {**fit, "summary": summary}
        fits[name] = fit
    return fits
