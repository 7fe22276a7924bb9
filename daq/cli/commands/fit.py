"""`daq fit RUN... | --all`: the damping matrix of stored runs (daq/workflows/fit.py), each
result beside its run, on the batch executor (daq/batch/executor.py: worker processes,
or a Dask cluster with --scheduler) with a progress bar."""

from __future__ import annotations

from typing import Annotated

import typer

from daq.cli.errors import UserError
from daq.cli.options import JobsOption, JsonOption, SchedulerOption, StoreOption
from daq.report.numbers import plain, with_uncertainty

#: FitOptions' field names as the options a user types.
OPTION_NAMES = (
    ("n_functions", "--functions"), ("method", "--method"), ("stiffness", "--stiffness"),
    ("domain", "--domain"), ("starts", "--starts"), ("seed", "--seed"),
)  # fmt: skip


def _checked_article(spec: str) -> str:
    """``spec`` as the fit's workers read it (a file as its absolute path), refused in one
    line (exit 2) where it names no article or a structure with no beam model."""
    from pathlib import Path

    from daq.workflows.article import BUILT_IN_ARTICLES, article_beam, read_article
    from daq.workflows.errors import WorkflowError

    try:
        beam = article_beam(read_article(spec))
    except WorkflowError as exc:
        raise UserError(f"--article: {exc}", exit_code=2) from None
    if beam is None:
        raise UserError(f"--article {spec}: a free structure has no beam model to fit", exit_code=2)
    return spec if spec in BUILT_IN_ARTICLES else str(Path(spec).resolve())


def register(app: typer.Typer) -> None:
    app.command(name="fit")(fit)


def fit(
    runs: Annotated[
        list[str] | None,
        typer.Argument(metavar="[RUN]...", show_default=False, help="Run ids, unique prefixes, or latest."),
    ] = None,
    all_runs: Annotated[bool, typer.Option("--all", help="Fit every run of the store.")] = False,
    method: Annotated[
        str,
        typer.Option(
            metavar="<modal|ls|ga|de|pilkey-inman>",
            help="modal: proportional estimate from the identified modes; ls: least squares from it; "
            "ga: the seed's genetic algorithm; de: differential evolution; pilkey-inman: from the poles.",
        ),
    ] = "ls",
    seed: Annotated[int, typer.Option(metavar="<int>", help="Random seed of ga and de.")] = 0,
    unconstrained: Annotated[
        bool,
        typer.Option(
            "--unconstrained",
            help="Fit R's terms freely (the raw fit; R may come out not dissipative). "
            "By default R = L L^T, positive semi-definite.",
        ),
    ] = False,
    psd: Annotated[
        bool,
        typer.Option("--psd", help="R = L L^T: the default now; kept for scripts (no-op)."),
    ] = False,
    stiffness: Annotated[
        str,
        typer.Option(
            metavar="<modes|scale|none>",
            help="Fit the model to the identified frequencies first: modes = one factor on E, then each "
            "mode at its identified frequency (light damping only); scale = the factor alone.",
        ),
    ] = "modes",
    domain: Annotated[
        str,
        typer.Option(
            metavar="<time|frequency>",
            help="Fit the hits' time records (eq 17) or the analysed FRF (zoom, FRF-only runs: the FRF).",
        ),
    ] = "time",
    starts: Annotated[
        int,
        typer.Option(metavar="<0-100>", help="Also fit from this many random starts: is the optimum global?"),
    ] = 0,
    functions: Annotated[
        int | None,
        typer.Option(
            metavar="<1-10>",
            show_default=False,
            help="Ritz functions of the model: R is N x N [default: one per mode the run's analysis "
            "identified in the fitted band].",
        ),
    ] = None,
    article: Annotated[
        str | None,
        typer.Option(
            metavar="<seed-beam|file.toml>",
            show_default=False,
            help="The beam to model for runs that record no test article (imported files) "
            "[default: none: such runs are refused, no beam model].",
        ),
    ] = None,
    jobs: JobsOption = None,
    scheduler: SchedulerOption = None,
    recompute: Annotated[
        bool, typer.Option("--recompute", help="Fit again even if a result is up to date.")
    ] = False,
    force: Annotated[bool, typer.Option("--force", hidden=True, help="Old name of --recompute.")] = False,
    json_output: JsonOption = False,
    store: StoreOption = None,
) -> None:
    """Fit the damping matrix R of the beam model to runs (the seed's section 6).

    Reports R, the frequencies and damping ratios it implies, the fit error Psi (eq 17)
    beside the noise floor, and the uncertainty of every term of R, naming the
    combinations the data does not determine.
    """
    from daq.batch.tasks import FitTask
    from daq.cli.commands.analyze import recompute_flag, run_batch
    from daq.workflows.fit import FitOptions, not_a_result

    recompute = recompute_flag(recompute, force)
    if bool(runs) == all_runs:
        raise UserError("name the runs to fit, or give --all", exit_code=2)
    if psd and unconstrained:
        raise UserError("--psd and --unconstrained contradict each other: give one", exit_code=2)
    if article is not None:
        article = _checked_article(article)
    try:
        options = FitOptions(
            method=method.lower(),
            seed=seed,
            psd=not unconstrained,
            stiffness=stiffness.lower(),
            n_functions=functions,
            domain=domain.lower(),
            starts=starts,
            article=article,
        )
    except ValueError as exc:
        text = str(exc)
        for name, option in OPTION_NAMES:
            text = text.replace(f"{name} must", f"{option} must")
        raise UserError(text, exit_code=2) from None
    summaries = run_batch(
        runs, all_runs, store, jobs, scheduler, json_output, print_fit, "fit",
        lambda store_dir, run_id: FitTask(store_dir, run_id, options, recompute),
    )  # fmt: skip
    # Printed (and stored) for a look, but no estimate: a script must not take it for one.
    failed = [(s["run_id"], why) for s in summaries if (why := not_a_result(s))]
    if len(failed) == 1 and len(summaries) == 1:
        raise UserError(f"run {failed[0][0]}: no damping matrix: {failed[0][1]}")
    if failed:
        raise UserError(f"{len(failed)} of {len(summaries)} fits are no damping matrix: " + "; ".join(
            f"run {run_id}: {why}" for run_id, why in failed))  # fmt: skip


def print_fit(info: dict) -> None:
    cached = " (cached)" if info.get("cached") else ""
    floor = info.get("psi_noise_floor")
    floor_text = (
        f" (noise floor {plain(floor, '.3g')}, {plain(info['psi'] / floor, '.3g')}x)" if floor else ""
    )
    domain = "time records" if info.get("domain") == "time" else "FRF"
    constraint = info.get("constraint") or ("R = L L^T" if info["psd"] else "unconstrained")
    typer.echo(
        f"Run {info['run_id']}: {info['method']} on the {domain} ({constraint}){cached}, "
        f"Psi = {plain(info['psi'], '.4g')}{floor_text}, {info['n_evaluations']} evaluations"
    )
    for caution in info.get("cautions", []):
        typer.echo(f"caution: {caution}")
    model = info["model"]
    if model.get("functions_reason"):
        typer.echo(f"  {model['functions_reason']}")
    stiffness = info.get("stiffness") or {}
    n_functions = model["ritz_functions"]
    if stiffness.get("update", "none") != "none":
        modes = stiffness.get("mode_frequencies") or {}
        then = ", then each mode at its identified frequency" if modes.get("applied") else ""
        why = "" if modes.get("applied") or not modes.get("reason") else f" (modes kept: {modes['reason']})"
        typer.echo(
            f"  model: {n_functions} Ritz functions, stiffness scaled by "
            f"{stiffness['scale']:.5f} to the run's frequencies first{then} (--stiffness "
            f"{info['options'].get('stiffness', 'scale')}){why}"
        )
    else:
        typer.echo(f"  model: {n_functions} Ritz functions, stiffness as built (--stiffness none)")
    unc = info["uncertainty"]
    by_name = dict(zip(unc["names"], zip(unc["std"], unc["determined"], strict=True), strict=True))
    r = info["damping_matrix"]
    n = len(r)
    sources = unc.get("std_source") or ["fisher"] * len(unc["names"])
    from_hits = [name for name, src in zip(unc["names"], sources, strict=True) if src == "hits"]
    from_readings = [name for name, src in zip(unc["names"], sources, strict=True) if src == "readings"]
    label = (
        "the Fisher (Cramér-Rao) std"
        if not unc.get("std_from_hits")
        else "the larger of the Fisher std and the per-hit refits' spread / sqrt(n)"
        + (f" (per-hit for {', '.join(from_hits)})" if from_hits else "")
    )
    if unc.get("time_reading") is not None:
        label += ", and the difference from the time records' R" + (
            f" (for {', '.join(from_readings)})" if from_readings else ""
        )
    typer.echo(f"  R (N s/m), ± {label}; ? = not determined by the data:")
    for i in range(n):
        cells = []
        for j in range(n):
            name = f"R{min(i, j) + 1}{max(i, j) + 1}"
            std, determined = by_name.get(name, (None, True))
            spread = f" ± {plain(std, '.2g')}" if std is not None else ""
            cells.append(f"{r[i][j]:9.4f}{spread:<10}{'' if determined else ' ?'}")
        typer.echo("    " + "  ".join(cells))
    check = info.get("multi_start")
    if check:
        verdict = "a better optimum exists" if check["better_psi_found"] else "no better optimum found"
        typer.echo(
            f"  {check['starts']} random starts: {check['reached_same_psi']} reach the same Psi, {verdict} "
            f"(best {plain(check['best_psi'], '.4g')})"
        )
    per_hit = unc.get("std_from_hits")
    if per_hit:
        fisher = unc.get("std_fisher") or unc["std"]
        ratios = [
            f"{name} {plain(h / f, '.2g')}" if h is not None and f else f"{name} -"
            for name, h, f in zip(unc["names"], per_hit, fisher, strict=True)
        ]
        typer.echo("  spread of per-hit refits / sqrt(n) over the Fisher std: " + ", ".join(ratios))
    for mode in info["modes"]:
        if mode["frequency_hz"] is None or mode["damping_ratio"] is None:
            typer.echo("  a mode is overdamped or unstable with this R (no oscillating pole)")
            continue
        zeta = plain(100 * mode["damping_ratio"], ".3g")
        partner = mode.get("identified")
        # Numbered as the run's analysis numbers its modes (`daq analyze`), with its reading.
        label = f"mode {partner['mode']}" if partner else "a mode with no identified partner"
        read = f" (analysis: {_identified_text(partner)})" if partner else ""
        typer.echo(f"  {label}: {mode['frequency_hz']:.4f} Hz, damping {zeta} % with this R{read}")
    for direction in unc["null_directions"]:
        combo = " ".join(f"{w:+.2f} {name}" for name, w in direction["combination"].items() if abs(w) >= 0.05)
        typer.echo(f"  not determined by the data: {combo}")


def _identified_text(partner: dict) -> str:
    """'97.7098 Hz, 0.3998 % ± 0.0063 %': a fitted mode's partner as `daq analyze` writes it."""
    f_text, _ = with_uncertainty(partner["frequency_hz"], partner.get("frequency_u_hz"), ".4f")
    zeta = partner.get("damping_ratio")
    if zeta is None:
        return f"{f_text} Hz"
    u = partner.get("damping_u")
    z_text, u_text = with_uncertainty(100 * zeta, 100 * u if u else None, ".3g")
    return f"{f_text} Hz, {z_text} %" + (f" ± {u_text} %" if u_text != "–" else "")
