"""`daq fit RUN... | --all`: the damping matrix of stored runs (daq/fit_store.py), each
result beside its run, in worker processes (or on a Dask cluster with --scheduler)
with a progress bar."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

from daq.analyze_command import SchedulerOption
from daq.errors import UserError
from daq.runs_command import JsonOption, StoreOption

#: FitOptions' field names as the options a user types.
OPTION_NAMES = (
    ("n_functions", "--functions"), ("method", "--method"), ("stiffness", "--stiffness"),
    ("domain", "--domain"), ("starts", "--starts"),
)  # fmt: skip


def register(app: typer.Typer) -> None:
    app.command(name="fit")(fit)


def fit(
    runs: Annotated[
        list[str] | None,
        typer.Argument(metavar="[RUN]...", show_default=False, help="Run ids or unique prefixes."),
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
    psd: Annotated[bool, typer.Option("--psd", help="Keep R positive semi-definite (R = L L^T).")] = False,
    stiffness: Annotated[
        str, typer.Option(metavar="<scale|none>", help="Scale E to the identified frequencies first.")
    ] = "scale",
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
        int, typer.Option(metavar="<1-10>", help="Ritz functions of the model: R is N x N.")
    ] = 3,
    jobs: Annotated[
        int | None, typer.Option(metavar="<n>", help="Worker processes [default: one per core].")
    ] = None,
    scheduler: SchedulerOption = None,
    force: Annotated[bool, typer.Option("--force", help="Fit again even if a result is up to date.")] = False,
    json_output: JsonOption = False,
    store: StoreOption = None,
) -> None:
    """Fit the damping matrix R of the beam model to runs (the seed's section 6).

    Reports R, the frequencies and damping ratios it implies, the fit error Psi (eq 17)
    beside the noise floor, and the uncertainty of every term of R, naming the
    combinations the data does not determine.
    """
    from daq.analyze_command import run_batch
    from daq.fit_store import FitOptions

    if bool(runs) == all_runs:
        raise UserError("name the runs to fit, or give --all", exit_code=2)
    try:
        options = FitOptions(
            method=method.lower(),
            seed=seed,
            psd=psd,
            stiffness=stiffness.lower(),
            n_functions=functions,
            domain=domain.lower(),
            starts=starts,
        )
    except ValueError as exc:
        text = str(exc)
        for name, option in OPTION_NAMES:
            text = text.replace(f"{name} must", f"{option} must")
        raise UserError(text, exit_code=2) from None
    run_batch(runs, all_runs, store, options, force, jobs, json_output, fit_one, print_fit, "fit", scheduler)


def fit_one(store_dir: Path, run_id: str, options: Any, force: bool) -> dict | str:
    """The summary of one run's fit, or a one-line reason it failed (picklable)."""
    import numpy as np

    from daq.fit_store import fit_stored
    from daq.store import StoreError

    try:
        return fit_stored(store_dir, run_id, options, force)
    except (StoreError, ValueError) as exc:
        return " ".join(str(exc).split())
    except (np.linalg.LinAlgError, FloatingPointError, ZeroDivisionError) as exc:
        return f"numerical failure ({type(exc).__name__}: {' '.join(str(exc).split())})"


def cautions(info: dict) -> list[str]:
    """What a reader of the fit must not miss: a fit far above the noise, a matrix
    that is not dissipative, modes it makes unstable or overdamped."""
    out = []
    floor = info.get("psi_noise_floor")
    if floor and info["psi"] > 3 * floor:
        out.append(
            f"Psi is {info['psi'] / floor:.0f}x the noise floor: the model does not explain the data "
            "(missing modes, wrong beam, or a local optimum; try --starts or --method de)"
        )
    box = info.get("search_box")
    needed = info.get("start", {}).get("coded_scale")
    if box is not None and needed is not None and needed > box:
        out.append(
            f"the modal estimate needs terms up to {needed:.4g}, outside the search range "
            f"[-{box:g}, {box:g}]{' (the seed paper’s GA range)' if info['method'] == 'ga' else ''}: "
            "this method cannot reach it (use --method ls or de)"
        )
    diag = [info["damping_matrix"][i][i] for i in range(len(info["damping_matrix"]))]
    if any(d < 0 for d in diag):
        out.append("R has a negative diagonal term: not dissipative (--psd keeps R = L L^T)")
    zetas = [m["damping_ratio"] for m in info["modes"]]
    if any(z is None or z <= 0 for z in zetas):
        out.append("with this R some mode is unstable, undamped or overdamped")
    return out


def print_fit(info: dict) -> None:
    cached = " (cached)" if info.get("cached") else ""
    floor = info.get("psi_noise_floor")
    floor_text = f" (noise floor {floor:.3g})" if floor is not None else ""
    domain = "time records" if info.get("domain") == "time" else "FRF"
    psd = " (R = L L^T)" if info["psd"] else ""
    typer.echo(
        f"Run {info['run_id']}: {info['method']} on the {domain}{psd}{cached}, "
        f"Psi = {info['psi']:.4g}{floor_text}, {info['n_evaluations']} evaluations"
    )
    for caution in cautions(info):
        typer.echo(f"  caution: {caution}")
    stiffness = info.get("stiffness") or {}
    if stiffness.get("update") == "scale on E":
        typer.echo(
            f"  model: {info['model']['ritz_functions']} Ritz functions, stiffness scaled by "
            f"{stiffness['scale']:.5f} to the run's frequencies first (--stiffness scale)"
        )
    else:
        n_functions = info["model"]["ritz_functions"]
        typer.echo(f"  model: {n_functions} Ritz functions, stiffness as built (--stiffness none)")
    unc = info["uncertainty"]
    by_name = dict(zip(unc["names"], zip(unc["std"], unc["determined"], strict=True), strict=True))
    r = info["damping_matrix"]
    n = len(r)
    typer.echo("  R (N s/m), ± one standard deviation; ? = not determined by the data:")
    for i in range(n):
        cells = []
        for j in range(n):
            name = f"R{min(i, j) + 1}{max(i, j) + 1}"
            std, determined = by_name.get(name, (None, True))
            spread = f" ± {std:.2g}" if std is not None else ""
            cells.append(f"{r[i][j]:9.4f}{spread:<10}{'' if determined else ' ?'}")
        typer.echo("    " + "  ".join(cells))
    check = info.get("multi_start")
    if check:
        verdict = "a better optimum exists" if check["better_psi_found"] else "no better optimum found"
        typer.echo(
            f"  {check['starts']} random starts: {check['reached_same_psi']} reach the same Psi, {verdict} "
            f"(best {check['best_psi']:.4g})"
        )
    from_hits = unc.get("std_from_hits")
    if from_hits:
        ratios = [
            f"{name} {h / f:.2g}" if h is not None and f else f"{name} -"
            for name, h, f in zip(unc["names"], from_hits, unc["std"], strict=True)
        ]
        typer.echo("  spread of per-hit refits / sqrt(n) over the Fisher std: " + ", ".join(ratios))
    for k, mode in enumerate(info["modes"], 1):
        if mode["frequency_hz"] is None or mode["damping_ratio"] is None:
            typer.echo(f"  mode {k}: overdamped or unstable with this R (no oscillating pole)")
            continue
        typer.echo(f"  mode {k}: {mode['frequency_hz']:.4f} Hz, damping {100 * mode['damping_ratio']:.3g} %")
    for direction in unc["null_directions"]:
        combo = " ".join(f"{w:+.2f} {name}" for name, w in direction["combination"].items() if abs(w) >= 0.05)
        typer.echo(f"  not determined by the data: {combo}")
