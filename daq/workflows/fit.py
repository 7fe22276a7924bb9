"""Fitting the damping matrix of stored runs: the model of the run's beam, the data it
is fitted to, the method, and the result file beside the run (``<run_id>.fit-<method>.h5``).

The run's analysis (daq/workflows/analysis.py) comes first: its identified modes give
the stiffness update and the modal starting point. The run file is only read.
"""

from __future__ import annotations

import hashlib
import json
import time
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from analysis.damping.checks import central_jacobian, multi_start_check, per_hit_std
from analysis.damping.fit_limits import GA_BOUNDS, coded_scale, de_bounds, identified_poles, noise_floor
from analysis.measurement_text import with_uncertainty
from analysis.modal import damped_modes
from analysis.ritz import RitzBeam
from analysis.run_analysis import AnalysisOptions
from daq.store import Run, Store, StoreError
from daq.store.model import SOFTWARE
from daq.workflows.analysis import NO_BEAM_MODEL, analyze_stored, beam_of, stored_options, window_specs
from daq.workflows.analysis import RESULT_NAME as ANALYSIS_RESULT
from daq.workflows.article import article_beam, read_article
from daq.workflows.outcome import RunOutcome, failure_reason

METHODS = ("modal", "ls", "ga", "de", "pilkey-inman")
STIFFNESS = ("modes", "scale", "none")
FIT_VERSION = 4
#: The most Ritz functions the default picks (the largest R a fit supports).
MAX_FUNCTIONS = 10


@dataclass(frozen=True)
class FitOptions:
    """method : one of METHODS. seed : for ga and de. psd : R = L L^T (dissipative;
    the default; False is ``--unconstrained``). n_functions : Ritz functions (the size
    of R); None (the default) takes the number of modes the run's analysis identified
    in the fitted band (``resolve_functions``). stiffness : "modes" (one factor on E,
    then each paired mode at its identified frequency, under light damping), "scale"
    (the factor alone) or "none". domain : "time" (eq 17 on the hits) or "frequency"
    (on the run's FRF); zoom records and FRF-only runs use "frequency" whatever is
    asked. article : the test article to model for a run that records none (an
    imported file): "seed-beam" or an article file (daq.workflows.article); None
    refuses such a run, as Table 2 does ("no beam model for this run")."""

    method: str = "ls"
    seed: int = 0
    psd: bool = True
    n_functions: int | None = None
    stiffness: str = "modes"
    domain: str = "time"
    starts: int = 0
    article: str | None = None

    def __post_init__(self) -> None:
        if self.method not in METHODS:
            raise ValueError(f"method must be one of {', '.join(METHODS)}, got {self.method!r}")
        if self.stiffness not in STIFFNESS:
            raise ValueError(f"stiffness must be modes, scale or none, got {self.stiffness!r}")
        if self.domain not in ("time", "frequency"):
            raise ValueError(f"domain must be time or frequency, got {self.domain!r}")
        if self.n_functions is not None and not 1 <= self.n_functions <= MAX_FUNCTIONS:
            raise ValueError(f"n_functions must be 1..{MAX_FUNCTIONS}, got {self.n_functions}")
        if not 0 <= self.starts <= 100:
            raise ValueError(f"starts must be 0..100, got {self.starts}")
        if self.method == "modal" and not self.psd:
            # The proportional estimate is dissipative by construction: no constraint to drop,
            # and a second result file would hold the same matrix.
            raise ValueError(
                "--unconstrained means nothing for --method modal (the proportional estimate is "
                "dissipative by construction): drop it"
            )
        if not 0 <= self.seed < 2**63:
            # numpy's generators take none else, and would say so naming no option.
            raise ValueError(f"seed must be a whole number from 0 to 2^63 - 1, got {self.seed}")

    @property
    def result_name(self) -> str:
        """``fit-<method>`` for the defaults (R = L L^T, the functions the run's modes
        ask for: the number is in the result, the time domain, --stiffness modes),
        ``-unconstrained`` for a raw R, ``-n<N>`` for an explicit number of functions,
        ``-frequency`` for --domain frequency, ``-stiffness-<scale|none>`` for another
        stiffness and ``-seed<S>`` for ga and de with a seed other than 0: a fit with
        other options never replaces the default one."""
        size = "" if self.n_functions is None else f"-n{self.n_functions}"
        # The global searches' result depends on the seed: another seed, another file.
        seed = f"-seed{self.seed}" if self.method in ("ga", "de") and self.seed != 0 else ""
        domain = "" if self.domain == "time" else f"-{self.domain}"
        stiffness = "" if self.stiffness == "modes" else f"-stiffness-{self.stiffness}"
        return f"fit-{self.method}{seed}{'' if self.psd else '-unconstrained'}{size}{domain}{stiffness}"


def fitted_beam(run: Run, article: str | None) -> tuple[Any, str]:
    """(BeamProperties, where from) of the beam the fit models: the run's test article,
    else the ``article`` given for a run that records none; ValueError (one line) for a
    run that records none without one, or an article that is no beam."""
    if run.sample is not None:
        if article is not None:
            raise ValueError(
                "the run records its test article: --article is for runs that record none (imported files)"
            )
        return beam_of(run)
    if article is None:
        raise ValueError(
            f"{NO_BEAM_MODEL}: it records no test article ({_without_article(run)}), and daq fit fits "
            "a beam's Ritz model; if it is a run of the seed's beam, give --article seed-beam (or an "
            "article file)"
        )
    beam = article_beam(read_article(article))
    if beam is None:
        raise ValueError(f"article {article}: a free structure has no beam model to fit")
    return beam, f"the article given with --article ({article})"


def _without_article(run: Run) -> str:
    """What a run that records no test article is: an imported file, a replay of one, or a run."""
    provenance = getattr(run, "provenance", None) or {}
    replayed = provenance.get("replayed_from")
    if getattr(run, "kind", None) == "replayed" or isinstance(replayed, dict):
        original = replayed.get("kind") if isinstance(replayed, dict) else None
        return (
            "a replay of an imported file"
            if original == "imported"
            else "a replay of a run that records none"
        )
    return "an imported file" if getattr(run, "kind", "imported") == "imported" else "a run that records none"


def model_of(run: Run, n_functions: int, article: str | None = None) -> tuple[Any, str]:
    """The Ritz model of the run's beam with force and sensor where the run says."""
    beam, origin = fitted_beam(run, article)
    force_at = run.sample.force_position_m if run.sample is not None else None
    sensor_at = run.sample.sensor_position_m if run.sample is not None else None
    ritz = RitzBeam.build(beam, n_functions)
    return ritz.structure(force_at, sensor_at), origin


def _matrix_json(r: np.ndarray) -> list[list[float]]:
    return [[float(v) for v in row] for row in np.asarray(r)]


def fit_run(run: Run, analysis: dict[str, Any], options: FitOptions) -> tuple[dict[str, Any], dict[str, Any]]:
    """(summary, arrays) of fitting ``run``'s damping matrix with ``options``.

    analysis : the run's stored analysis summary (identified modes).
    The summary records what the defaults resolved to (``model.ritz_functions`` and
    why, ``options.n_functions``) and the fit's ``cautions`` (``fit_cautions``).
    """
    from analysis import damping
    from analysis.damping.checks import combined_std
    from analysis.damping.identifiability import parameter_scale

    started = time.perf_counter()
    fitted_beam(run, options.article)  # a run with no beam to model is refused first
    modes = analysis["modes"]
    ident_f = np.array([m["frequency_hz"] for m in modes], dtype=float)
    ident_z = np.array([np.nan if m["damping_ratio"] is None else m["damping_ratio"] for m in modes])
    usable = np.isfinite(ident_z) & np.isfinite(ident_f)
    if not usable.any():
        raise ValueError("the run's analysis found no mode with a damping ratio to start from")
    low, high = _band(run, analysis, options)
    in_band = usable & (ident_f >= low) & (ident_f <= high)
    searched = _searched_band(analysis, low, high)
    unsearched = (
        _model_modes_unsearched(run, options, low, high, searched, ident_f[in_band])
        if options.n_functions is None
        else []
    )
    n, reason = resolve_functions(int(in_band.sum()), low, high, options.n_functions, searched, unsearched)
    largest = None  # set where more functions would put a model mode outside the band
    while True:
        model, beam_origin, stiffness_info, start, matching, data, domain = _prepare(
            run, analysis, options, n, ident_f[usable], ident_z[usable]
        )
        try:
            _check_band(run, data, domain, model)
            break
        except ValueError:
            if options.n_functions is not None or n == 1:
                raise
            n -= 1  # the default: the largest model whose modes all lie in the band
            reason = f"{reason}; {n + 1} would put a model mode outside the band, so {n}"
            largest = n
    objective, residual_fn, batched = _objective(data, domain)
    constraint = "R = L L^T" if options.psd else "unconstrained"
    if options.method == "modal":
        result = _fixed(
            damping, "modal", start, objective, 1, True, "proportional estimate from the identified modes"
        )
        constraint = "proportional: dissipative by construction"
    elif options.method == "ls":
        result = damping.fit_least_squares(residual_fn, start, psd=options.psd, batched_residuals=batched)
    elif options.method == "ga":
        result = damping.fit_ga(objective, n, seed=options.seed, psd=options.psd, bounds=GA_BOUNDS)
    elif options.method == "de":
        bounds = de_bounds(start, options.psd)
        result = damping.fit_de(objective, n, seed=options.seed, psd=options.psd, bounds=bounds)
        result = replace(result, message=f"{result.message} (box ±{bounds[1]:.4g} per term)")
    pole_fit = None
    if options.method == "pilkey-inman":
        poles_at = (ident_f[in_band], ident_z[in_band])
        result, pole_fit = _pilkey_inman(damping, model, *poles_at, objective, options.psd)
    r = np.asarray(result.damping_matrix, dtype=float)
    r = 0.5 * (r + r.T)
    jac, res = central_jacobian(batched, r)
    theta = damping.matrix_to_theta(r)
    ident = damping.identifiability(jac, res, theta, n)
    per_hit = per_hit_std(data, r, psd=options.psd) if hasattr(data, "force_n") else None
    std, std_source = combined_std(ident.std, per_hit)
    # Only a least-squares fit of the FRF has a time-records reading to compare with: the
    # modal and Pilkey-Inman estimates do not fit either, and their R is no FRF fit's.
    compare = domain == "frequency" and options.method in ("ls", "ga", "de")
    time_reading = _time_reading(data, r, options.psd) if compare else None
    between = None
    if time_reading is not None:
        # The FRF's errors are not the time records': where the two readings of the same
        # hits differ by more than the FRF fit's own figures, the difference is the honest u.
        between = np.abs(theta - damping.matrix_to_theta(time_reading))
        own = std.copy()
        wider = np.isfinite(between) & (between > std) & ~np.isinf(std)
        std = np.where(wider, between, std)
        std_source = ["readings" if w else src for w, src in zip(wider, std_source, strict=True)]
    relative_std = std / parameter_scale(theta, n)
    global_check = (
        multi_start_check(residual_fn, batched, r, result.psi, options.starts, options.seed, options.psd)
        if options.starts
        else None
    )
    implied = damped_modes(model, r)
    eigenvalues = np.linalg.eigvalsh(r)
    summary = {
        "run_id": run.run_id,
        "method": options.method,
        "engine": result.method,
        "psd": options.psd,
        "constraint": constraint,
        "domain": domain,
        "success": bool(result.success),
        "message": result.message,
        "damping_matrix": _matrix_json(r),
        "damping_eigenvalues": [float(v) for v in eigenvalues],
        "psi": float(result.psi),
        "psi_noise_floor": _noise_floor(run, domain, model, start),
        "relative_residual": _relative_residual(data, domain, res),
        "n_evaluations": int(result.n_evaluations),
        "seconds": time.perf_counter() - started,
        "modes": [
            # NaN pads a mode the fitted R makes overdamped: null in JSON.
            {"frequency_hz": _num(f), "damping_ratio": _num(z), "identified": _partner(f, modes)}
            for f, z in zip(implied.natural_frequencies_hz, implied.damping_ratios, strict=True)
        ],
        "start": {"damping_matrix": _matrix_json(start), "matching": _jsonable(matching),
                  "coded_scale": coded_scale(start, options.psd)},
        "search_box": {"ga": GA_BOUNDS[1], "de": de_bounds(start, options.psd)[1]}.get(options.method),
        "multi_start": global_check,
        "pole_fit": pole_fit,
        "stiffness": stiffness_info,
        "model": {"ritz_functions": n, "beam": beam_origin, "functions_reason": reason,
                  "functions_requested": options.n_functions, "modes_identified_in_band": int(in_band.sum()),
                  "band_hz": [float(low), float(high)],
                  "analysis_band_hz": None if searched is None else [float(searched[0]), float(searched[1])],
                  "largest_in_band": largest},
        "uncertainty": {
            "names": list(ident.names),
            # The larger of the two figures below, term by term (std_source says which).
            "std": [_num(v) for v in std],
            "std_source": std_source,
            "relative_std": [_num(v) for v in relative_std],
            "determined": [bool(v) for v in relative_std < IDENTIFIED_REL_STD],
            "std_fisher": [_num(v) for v in ident.std],
            "null_directions": _jsonable(ident.null_directions),
            "noise_std": _num(ident.noise_std),
            # R refitted to each hit alone; the spread of those fits over sqrt(n_hits)
            # is the uncertainty of the mean (None: frequency domain, or < 3 hits).
            "std_from_hits": None if per_hit is None else [_num(v) for v in per_hit],
            # Frequency domain on a run with hits: R fitted to the same hits' time records
            # (from this fit), and |this R - that R| per term (None otherwise).
            "time_reading": None if time_reading is None else _matrix_json(time_reading),
            "std_between_domains": None if between is None else [_num(v) for v in between],
            "std_own": None if between is None else [_num(v) for v in own],
        },
        "options": {"method": options.method, "seed": options.seed, "psd": options.psd,
                    "n_functions": n, "stiffness": options.stiffness, "domain": options.domain},
    }  # fmt: skip
    summary["cautions"] = fit_cautions(summary)
    arrays = {"damping_matrix": r, "history": np.asarray(result.history, dtype=float)}
    if domain == "time":
        first = int(np.flatnonzero(run.hits.accepted)[0])
        from analysis.damping.bandlimited import BandLimitedData, model_response

        # The response the fit compared with (band-limited force), not a zero-order hold:
        # the report's residual is then the fit's own.
        hit = slice(first, first + 1)
        one = BandLimitedData(
            model, run.hits.force_n[hit], run.hits.response_m_s2[hit], run.hits.sample_rate_hz
        )
        arrays["model_response"] = model_response(one, r[None])[0, 0]
        arrays["hit_index"] = np.array([first])
    if not arrays["history"].size:
        arrays.pop("history")
    return summary, arrays


#: A term whose standard deviation exceeds this fraction of sqrt(|R_ii R_jj|) is not
#: determined by the data (as analysis.damping.identifiability).
IDENTIFIED_REL_STD = 0.3
#: Psi above this multiple of the noise floor: the model does not explain the data.
PSI_CAUTION = 3.0
#: Without a noise floor (the FRF), a residual above this fraction of the data is a poor fit.
RESIDUAL_CAUTION = 0.1


def _model_modes_unsearched(
    run: Run,
    options: FitOptions,
    low_hz: float,
    high_hz: float,
    searched_hz: tuple[float, float] | None,
    identified_hz: np.ndarray,
) -> list[float]:
    """Hz of the beam model's modes (as built, MAX_FUNCTIONS Ritz functions) that lie in
    the fitted band but outside the band the analysis looked for modes in: no one
    counted them, and a model without them cannot pair its modes with the run's. Only
    where every identified mode lies within PARTNER_TOLERANCE of a model mode: a run
    whose modes are not the beam's is refused as before, not fitted with more functions."""
    if searched_hz is None or not identified_hz.size:
        return []
    from analysis.damping import undamped_modes

    try:
        model, _ = model_of(run, MAX_FUNCTIONS, options.article)
    except ValueError:
        return []
    hz = undamped_modes(model)[0] / (2 * np.pi)
    nearest = np.min(np.abs(hz[None, :] / np.asarray(identified_hz, dtype=float)[:, None] - 1.0), axis=1)
    if np.any(nearest > PARTNER_TOLERANCE):
        return []
    inside = (hz >= low_hz) & (hz <= high_hz) & ((hz < searched_hz[0]) | (hz > searched_hz[1]))
    return [float(f) for f in hz[inside]]


def resolve_functions(
    identified_in_band: int,
    low_hz: float,
    high_hz: float,
    requested: int | None,
    searched_hz: tuple[float, float] | None = None,
    unsearched_model_hz: list[float] | None = None,
) -> tuple[int, str]:
    """(N, why): the Ritz functions of the fit. An explicit ``requested`` wins;
    otherwise one per mode the analysis identified in the fitted band, 1..MAX_FUNCTIONS.
    searched_hz: the analysis's band (Hz) where it is narrower than the fitted one
    (_searched_band): the why then says that modes were looked for there only.
    unsearched_model_hz: the beam model's modes in the fitted band outside searched_hz
    (_model_modes_unsearched): the default adds one function for each."""
    band = f"{low_hz:.4g}-{high_hz:.4g} Hz"
    found = f"{identified_in_band} mode{'' if identified_in_band == 1 else 's'} identified in {band}"
    if searched_hz is not None:
        found = (
            f"{found}, looked for in {searched_hz[0]:.4g}-{searched_hz[1]:.4g} Hz only (the analysis's band; "
            f"daq analyze --band {low_hz:.4g}:{high_hz:.4g} looks over the whole fitted band)"
        )
    if requested is not None:
        return requested, f"{requested} Ritz function{'' if requested == 1 else 's'} (--functions); {found}"
    extra = list(unsearched_model_hz or [])
    wanted = identified_in_band + len(extra)
    n = min(max(wanted, 1), MAX_FUNCTIONS)
    if extra:
        shown = ", ".join(f"{f:.4g}" for f in extra)
        found = (
            f"{found}, and {len(extra)} of the beam model's modes ({shown} Hz) in the fitted band outside "
            "the analysis's"
        )
    note = "" if n == wanted else f" (at least 1, at most {MAX_FUNCTIONS})"
    return n, f"{n} Ritz function{'' if n == 1 else 's'}: {found}{note}"


#: The analysis's band is named beside the fit's where it leaves out more than this share
#: of the fitted band at its top, or starts above this share of it: a few lines at 0 Hz
#: the analysis leaves out hold no mode the fit needs.
SEARCHED_SHARE = 0.05


def _searched_band(analysis: dict[str, Any], low_hz: float, high_hz: float) -> tuple[float, float] | None:
    """(low, high) Hz of the band the analysis identified modes in, where it is clearly
    narrower than the fit's (low_hz, high_hz); None where it is not, or not recorded
    (analyses with --frequencies or stored before the band was)."""
    band = analysis.get("band")
    if not isinstance(band, dict):
        return None
    try:
        a_low, a_high = float(band["low_hz"]), float(band["high_hz"])
    except (KeyError, TypeError, ValueError):
        return None
    span = high_hz - low_hz
    narrower = a_high < high_hz - SEARCHED_SHARE * span or a_low > low_hz + SEARCHED_SHARE * span
    return (a_low, a_high) if narrower and np.isfinite([a_low, a_high]).all() else None


def _band(run: Run, analysis: dict[str, Any], options: FitOptions) -> tuple[float, float]:
    """(low, high) Hz of the data the fit compares with (as ``_data`` picks it)."""
    hits = run.hits
    time_ok = hits is not None and not hits.is_zoom and hits.accepted.any()
    if options.domain == "time" and time_ok:
        return 0.0, hits.sample_rate_hz / 2.56
    f = np.asarray(analysis["arrays"]["frequency_hz"], dtype=float)
    return float(f.min()), float(f.max())


def _prepare(
    run: Run, analysis: dict[str, Any], options: FitOptions, n: int, f_hz: np.ndarray, zeta: np.ndarray
) -> tuple[Any, ...]:
    """The model of ``n`` functions with its stiffness updated, the modal start and the data."""
    from analysis import damping

    model, beam_origin = model_of(run, n, options.article)
    stiffness_info: dict[str, Any] = {"update": "none"}
    if options.stiffness in ("scale", "modes"):
        try:
            model, scale, info = damping.update_stiffness(model, f_hz)
        except ValueError as exc:
            raise ValueError(
                f"{exc}: the run's modes do not look like this beam's ({beam_origin}); daq fit fits "
                "that beam's model: check the run's test article (--stiffness none fits the model "
                "as built regardless, which means something only for a run of that beam)"
            ) from None
        stiffness_info = {"update": "scale on E", "scale": float(scale), **_jsonable(info)}
        if options.stiffness == "modes":
            model, modes_info = damping.update_mode_frequencies(model, f_hz, zeta)
            stiffness_info["mode_frequencies"] = _jsonable(modes_info)
            if modes_info["applied"]:
                stiffness_info["update"] = "scale on E, then each mode's frequency"
    start, matching = damping.proportional_estimate(model, f_hz, zeta)
    data, domain = _data(run, analysis, model, options)
    return model, beam_origin, stiffness_info, start, matching, data, domain


def _pilkey_inman(damping: Any, model: Any, f_hz: np.ndarray, zeta: np.ndarray, objective: Any, psd: bool):
    """The pole iteration from the identified poles in the band, each paired with a model
    mode (more identified modes than functions: the unpaired ones are left out)."""
    from analysis.damping.modal_estimate import match_modes

    if not f_hz.size:
        raise ValueError("no identified mode in the fitted band to take a pole from")
    model_hz = damping.undamped_modes(model)[0] / (2 * np.pi)
    paired = match_modes(f_hz, model_hz) >= 0
    poles = identified_poles(f_hz[paired], np.clip(zeta[paired], 0.0, 0.999))
    # Not from the proportional estimate: there the poles do not move to first order
    # with the off-diagonal modal terms, and the iteration cannot leave it.
    r, info = damping.pilkey_inman(model, poles, psd=psd)
    left_out = int((~paired).sum())
    info = {**_jsonable(info), "poles_used": int(paired.sum()), "poles_left_out": left_out}
    miss = info.get("residual")
    # Noisy poles never meet the iteration's 1e-10: matched to POLE_MATCH is success,
    # a larger miss is a caution of its own (fit_cautions).
    matched = miss is not None and miss <= POLE_MATCH
    message = (
        f"Pilkey-Inman from {int(paired.sum())} identified poles"
        + (f" ({left_out} more identified modes than model modes left out)" if left_out else "")
        + (f", matched to {miss:.2g}" if miss is not None else ", not matched")
    )
    iterations = int(info.get("iterations", 0))
    result = _fixed(damping, "pilkey-inman", r, objective, iterations, matched, message)
    return replace(result, psd=psd), info


#: Largest relative pole miss at which the pole iteration counts as matching the poles.
POLE_MATCH = 1e-3


def _time_reading(data: Any, r: np.ndarray, psd: bool) -> np.ndarray | None:
    """R fitted (least squares from ``r``) to the time records of the hits behind a
    frequency-domain fit's FRF (analysis/damping/hit_frf.py); None for an FRF without hits."""
    from analysis.damping import bandlimited, fit_least_squares
    from analysis.damping.hit_frf import HitFrfData

    if not isinstance(data, HitFrfData):
        return None
    records = bandlimited.BandLimitedData(data.model, data.force_n, data.response_m_s2, data.sample_rate_hz)
    fit = fit_least_squares(
        lambda m: bandlimited.residuals(records, m), r, psd=psd,
        batched_residuals=lambda m: bandlimited.batched_residuals(records, m),
    )  # fmt: skip
    t = np.asarray(fit.damping_matrix, dtype=float)
    return 0.5 * (t + t.T)


#: A frequency-domain fit whose R differs from the time records' reading by more than this
#: many of its own u (Fisher, per-hit refits) is cautioned.
READINGS_APART_U = 2.0


def _readings_apart(summary: dict[str, Any]) -> str | None:
    """The caution of a frequency-domain fit that the same hits' time records contradict,
    or of one whose ± is the Fisher figure alone; None otherwise."""
    if summary.get("domain") != "frequency" or summary.get("method") not in ("ls", "ga", "de"):
        return None
    unc = summary.get("uncertainty") or {}
    reading = unc.get("time_reading")
    if reading is None:
        return (
            "the ± is the Fisher figure alone (the FRF's lines taken as independent, no hits to refit or "
            "compare with): on simulated seed-beam runs R's terms spread up to 7 times wider over the noise; "
            "take the ± as a lower bound"
        )
    names, own = unc.get("names", []), unc.get("std_own") or []
    r = np.asarray(summary["damping_matrix"], dtype=float)[np.triu_indices(len(summary["damping_matrix"]))]
    t = np.asarray(reading, dtype=float)[np.triu_indices(len(reading))]
    apart = [
        f"{name} {a:.4g} against {b:.4g}"
        for name, a, b, u in zip(names, r, t, own, strict=False)
        if u is not None and abs(a - b) > READINGS_APART_U * u
    ]
    if not apart:
        return None
    return (
        "the FRF and the time records of the same hits give different R (" + "; ".join(apart) + "): "
        "more than the FRF fit's own ± (Fisher, per-hit refits) allows, so the ± shown is at least the "
        "difference; R's poorly determined terms follow small model errors (a stiffness factor 0.1 % off "
        "moves R33 of the seed beam by about 10 N s/m on the FRF); prefer the time domain (the default)"
    )


def _relative_residual(data: Any, domain: str, residual: np.ndarray) -> float | None:
    """||measured - model|| / ||measured|| over what the fit compares (weighted FRF lines,
    or the compared samples)."""
    if domain == "time":
        measured = data.response_m_s2.reshape(-1)
        if data.keep is not None:
            measured = measured[data.keep]
    else:
        weighted = data.frf * data.weights
        measured = np.concatenate([weighted.real, weighted.imag])
    norm = float(np.linalg.norm(measured))
    return _num(np.linalg.norm(residual) / norm) if norm > 0 else None


#: A fitted mode's partner among the run's identified modes lies within this fraction
#: of its frequency.
PARTNER_TOLERANCE = 0.1
#: The fitted R's damping of a mode disagrees with the run's analysis when they differ by
#: more than this many of the identified value's u and by this fraction of it. The
#: fraction: on the default realistic capture the default fit (4 Ritz functions, R = L L^T)
#: gives 0.376 % for the analysis' 0.39978 +- 0.00014 % (6 %), the model's own limit,
#: which each mode's line shows beside the other; 10 % is a disagreement to act on.
DISAGREE_U = 3.0
DISAGREE_FRACTION = 0.1


def _partner(frequency_hz: float, modes: list[dict[str, Any]]) -> dict[str, Any] | None:
    """The run's identified mode nearest a fitted mode (its number from 1 as `daq analyze`
    prints it, frequency, damping and their u), or None when none lies within
    PARTNER_TOLERANCE: the fit's modes are the model's, numbered by frequency, so an
    overdamped one would shift the numbers of the rest."""
    if not np.isfinite(frequency_hz) or not modes:
        return None
    k = min(range(len(modes)), key=lambda i: abs(modes[i]["frequency_hz"] - frequency_hz))
    m = modes[k]
    if abs(m["frequency_hz"] - frequency_hz) > PARTNER_TOLERANCE * frequency_hz:
        return None
    return {
        "mode": k + 1, "frequency_hz": m["frequency_hz"], "damping_ratio": m.get("damping_ratio"),
        "frequency_u_hz": m.get("frequency_u_hz"), "damping_u": m.get("damping_u"),
    }  # fmt: skip


def _disagreeing(summary: dict[str, Any]) -> list[str]:
    """'mode 3: 0.372 % against 0.400 ± 0.006 %' for each fitted mode whose damping
    disagrees with its identified partner's (DISAGREE_U, DISAGREE_FRACTION)."""
    out = []
    for mode in summary["modes"]:
        partner, zeta = mode.get("identified"), mode.get("damping_ratio")
        if not partner or zeta is None or partner.get("damping_ratio") is None:
            continue
        z_id, u = partner["damping_ratio"], partner.get("damping_u") or 0.0
        if abs(zeta - z_id) > max(DISAGREE_U * u, DISAGREE_FRACTION * z_id):
            value, u_text = with_uncertainty(100 * z_id, 100 * u if u else None, ".3g")
            shown = f"{value} ± {u_text} %" if u_text != "–" else f"{value} %"
            out.append(f"mode {partner['mode']}: {100 * zeta:.3g} % against {shown}")
    return out


def not_a_result(summary: dict[str, Any]) -> str | None:
    """Why a fit's R is no estimate at all (exit non-zero: a script must not take it), or
    None: the model leaves more of the data unexplained than there is (relative residual
    above 1: R = 0 would do better), or the fit stopped unconverged on an R that makes
    some mode unstable, undamped or overdamped. Poorer fits are results with cautions."""
    if "damping_matrix" not in summary:
        return None  # a run skipped or failed, said on its own
    rel = summary.get("relative_residual")
    if rel is not None and rel > 1:
        return f"the model leaves {100 * rel:.3g} % of the data unexplained (R = 0 would leave 100 %)"
    zetas = [m["damping_ratio"] for m in summary.get("modes", [])]
    unphysical = any(z is None or z <= 0 or z >= 1 for z in zetas)
    if not summary.get("success", True) and summary["method"] != "pilkey-inman" and unphysical:
        return "the fit did not converge and its R makes some mode unstable, undamped or overdamped"
    return None


def fit_cautions(summary: dict[str, Any]) -> list[str]:
    """What a reader of the fit must not miss, each a sentence saying what it means and
    what to try: a fit far above the noise floor (or leaving much of the data
    unexplained), fewer functions than identified modes, R not dissipative (a negative
    diagonal term, a negative eigenvalue), modes it makes unstable or overdamped, a
    search range that cannot hold the answer, poles the iteration did not match."""
    out = []
    if why := not_a_result(summary):
        # Said where the fit is shown (JSON, report, page), not only in the exit status.
        out.append(f"no damping matrix: {why}; the R shown is where the fit stopped, for a look only")
    if readings := _readings_apart(summary):
        out.append(readings)
    n = summary["model"]["ritz_functions"]
    found = summary["model"].get("modes_identified_in_band", 0)
    low, high = summary["model"].get("band_hz", (0.0, 0.0))
    # The default stepped down to the largest model whose modes lie in the band: more
    # functions is no remedy there.
    capped = summary["model"].get("largest_in_band") is not None
    more_modes = (
        f"{found} modes were identified in {low:.4g}-{high:.4g} Hz but the model has {n} Ritz functions: "
        f"try --functions {min(found, MAX_FUNCTIONS)}"
        if found > n and not capped
        else ""
    )
    tries = []
    searched = summary["model"].get("analysis_band_hz")
    if searched is not None and not more_modes:
        # The analysis looked in part of the fitted band only: a mode elsewhere is unknown.
        tries.append(
            f"daq analyze --band {low:.4g}:{high:.4g}, then daq fit (the analysis looked for modes "
            f"in {searched[0]:.4g}-{searched[1]:.4g} Hz only)"
        )
    if more_modes:
        tries.append(f"--functions {min(found, MAX_FUNCTIONS)} (one function per identified mode)")
    elif summary["model"].get("functions_requested") is None and n < MAX_FUNCTIONS and not capped:
        tries.append(f"--functions {n + 1} (if the analysis missed a mode in the band)")
    if summary["options"].get("stiffness") != "modes" and summary["stiffness"].get("update") != "none":
        tries.append("--stiffness modes (each mode at its identified frequency)")
    if summary["method"] in ("modal", "pilkey-inman"):
        tries.append("--method ls (fitted to the records themselves)")
    else:
        tries.append("--starts 8 or --method de (is the optimum global?)")
    floor = summary.get("psi_noise_floor")
    if floor and summary["psi"] > PSI_CAUTION * floor:
        out.append(
            f"Psi is {summary['psi'] / floor:.3g}x the noise floor: the model does not explain the data "
            "(missing modes, frequencies it cannot reach, a wrong beam or a local optimum); "
            f"try {'; '.join(tries)}"
        )
    rel = summary.get("relative_residual")
    if not floor and rel is not None and rel > RESIDUAL_CAUTION:
        out.append(
            f"a poor fit: the model leaves {100 * rel:.3g} % of the data unexplained; try {'; '.join(tries)}"
        )
    elif more_modes and not (floor and summary["psi"] > PSI_CAUTION * floor):
        out.append(f"{more_modes} (the modes beyond the model are left to the residual)")
    if not summary.get("success", True) and summary["method"] != "pilkey-inman":
        out.append(f"the {summary['method']} fit did not converge ({summary.get('message', '')}): "
                   "its R is where it stopped; try --starts 8 or another --method")  # fmt: skip
    box = summary.get("search_box")
    needed = summary.get("start", {}).get("coded_scale")
    at_floor = bool(floor) and summary["psi"] <= PSI_CAUTION * floor
    if box is not None and needed is not None and needed > box and not at_floor:
        out.append(
            f"the modal estimate needs terms up to {needed:.4g}, outside the search range "
            f"[-{box:g}, {box:g}]{' (the seed paper’s GA range)' if summary['method'] == 'ga' else ''}: "
            "this method cannot reach it (use --method ls or de)"
        )
    r = np.asarray(summary["damping_matrix"], dtype=float)
    negative = [f"R{i + 1}{i + 1} = {r[i, i]:.4g}" for i in range(r.shape[0]) if r[i, i] < 0]
    unconstrained = not summary.get("psd", True) and summary["method"] != "modal"
    fix = "drop --unconstrained to keep R = L L^T" if unconstrained else "try --unconstrained to compare"
    if negative:
        out.append(
            f"R has a negative diagonal term ({', '.join(negative)}): a motion of that coordinate alone "
            f"would gain energy, so R is not a physical damping matrix; {fix}"
        )
    eigenvalues = np.linalg.eigvalsh(r)
    if eigenvalues[0] < -1e-9 * max(abs(eigenvalues[-1]), 1e-300):
        out.append(
            f"R is not positive semi-definite (smallest eigenvalue {eigenvalues[0]:.4g} N s/m): some motion "
            f"gains energy, so R fits the data without being a damping matrix (often it bends to absorb "
            f"the model's frequency errors); {fix}"
        )
    apart = _disagreeing(summary)
    if apart:
        out.append(
            "the fitted R gives dampings the run's analysis does not ("
            + "; ".join(apart)
            + "): R does not reproduce the measured damping of those modes (a model missing modes, a "
            "band or Ritz functions that do not hold them); look at --functions and --band"
        )
    zetas = [m["damping_ratio"] for m in summary["modes"]]
    if any(z is None or z <= 0 or z >= 1 for z in zetas):
        out.append("with this R some mode is unstable, undamped or overdamped: R does not describe the beam")
    poles = summary.get("pole_fit") or {}
    if poles and (poles.get("residual") is None or poles["residual"] > POLE_MATCH):
        miss = poles.get("residual")
        out.append(
            "the pole iteration did not match the identified poles"
            + (f" (largest relative miss {miss:.2g})" if miss is not None else "")
            + ": no R of this model has them (noise or a stiffness error); prefer --method ls"
        )
    unc = summary.get("uncertainty") or {}
    determined = unc.get("determined") or []
    if determined and not all(determined):
        names = [name for name, ok in zip(unc.get("names", []), determined, strict=False) if not ok]
        which = (
            "no single term of R is determined"
            if len(names) == len(determined)
            else f"{', '.join(names)} {'is' if len(names) == 1 else 'are'} not determined"
        )
        out.append(
            f"{which} by these data (marked ?): only the combinations the data fix are (the modal "
            "dampings the fit reports); more measurement points or fewer --functions determine more"
        )
    return out


def _check_band(run: Run, data: Any, domain: str, model: Any) -> None:
    """ValueError unless every mode of the model lies in the measured band: a mode
    outside it leaves its part of R to chance (a zoom band around one mode gave
    -99 % damping on the others)."""
    from analysis.damping import undamped_modes

    model_hz = undamped_modes(model)[0] / (2 * np.pi)
    if domain == "time":
        low, high = 0.0, run.hits.sample_rate_hz / 2.56
    else:
        low, high = float(data.frequency_hz.min()), float(data.frequency_hz.max())
    outside = model_hz[(model_hz < low) | (model_hz > high)]
    if outside.size:
        shown = ", ".join(f"{f:.4g}" for f in outside)
        raise ValueError(
            f"the data cover {low:.4g}-{high:.4g} Hz but the {model_hz.size}-function model has modes at "
            f"{shown} Hz outside it; capture a band holding them all or give --functions "
            f"{model_hz.size - outside.size}" + ("" if model_hz.size - outside.size else " (none would fit)")
        )


def _fixed(damping: Any, method: str, r: np.ndarray, objective: Any, n_eval: int, ok: bool, message: str):
    """A FitResult for a matrix computed directly (not by minimising Psi)."""
    psi = float(objective(r[None])[0])
    return damping.FitResult(
        method=method, damping_matrix=r, theta=damping.matrix_to_theta(r), psi=psi, n_evaluations=n_eval,
        history=np.array([]), success=ok, message=message, psd=False,
    )  # fmt: skip


def _data(run: Run, analysis: dict[str, Any], model: Any, options: FitOptions) -> tuple[Any, str]:
    """The data the fit compares with: the accepted hits (band-limited, time domain,
    eq 17), or the FRF the run's analysis stored (frequency domain, with the
    exponential window put into the model). Zoom and FRF-only runs have no baseband
    hits and always use the FRF."""
    from analysis.damping.bandlimited import BandLimitedData
    from analysis.damping.windowed_frf import WindowedFrfData

    hits = run.hits
    time_ok = hits is not None and not hits.is_zoom and hits.accepted.any()
    if options.domain == "time" and time_ok:
        pick = hits.accepted
        return BandLimitedData(
            model, hits.force_n[pick], hits.response_m_s2[pick], hits.sample_rate_hz
        ), "time"
    if hits is not None and not hits.is_zoom and hits.accepted.any() and np.isrealobj(hits.force_n):
        # The hits' own FRF against the one the model's response to the same hits gives
        # through the same windows (analysis/damping/hit_frf.py): exact, where the
        # windowed model below leaves errors R absorbs.
        from analysis.damping.hit_frf import HitFrfData
        from analysis.windows import window

        force_window, response_window, _ = window_specs(run)
        pick = hits.accepted
        n, fs = hits.force_n.shape[1], hits.sample_rate_hz
        return HitFrfData(
            model, hits.force_n[pick], hits.response_m_s2[pick], fs,
            window(force_window, n, fs), window(response_window, n, fs),
        ), "frequency"  # fmt: skip
    arrays = analysis["arrays"]
    coherence = arrays.get("coherence")
    imported = run.provenance.get("imported_from", {})
    if hits is not None:
        pulse_s = max(0.0, -hits.start_s)
    else:  # an FRF-only run: the pulse time its source recorded, if any
        pulse_s = float(imported.get("pulse_s") or 0.0) if isinstance(imported, dict) else 0.0
    data = WindowedFrfData(
        model, arrays["frequency_hz"], np.atleast_2d(arrays["frf"])[0],
        None if coherence is None else np.atleast_2d(coherence)[0],
        float(analysis.get("added_decay_1_s") or 0.0), pulse_s,
    )  # fmt: skip
    return data, "frequency"


def _objective(data: Any, domain: str):
    """Psi (eq 17's form) and the residuals, single and batched: band-limited time
    records (analysis/damping/bandlimited.py) or the windowed FRF
    (analysis/damping/windowed_frf.py)."""
    from analysis.damping import bandlimited, hit_frf, windowed_frf
    from analysis.damping.hit_frf import HitFrfData

    module = bandlimited if domain == "time" else hit_frf if isinstance(data, HitFrfData) else windowed_frf

    def objective(r: np.ndarray) -> np.ndarray:
        return module.psi(data, r)

    def residual_fn(r: np.ndarray) -> np.ndarray:
        return module.residuals(data, r)

    def batched(r: np.ndarray) -> np.ndarray:
        return module.batched_residuals(data, r)

    return objective, residual_fn, batched


def _noise_floor(run: Run, domain: str, model: Any, damping: np.ndarray) -> float | None:
    """Psi that the noise alone would leave (analysis/damping/fit_limits.noise_floor) for
    the run's accepted hits; None in the frequency domain or without hits."""
    hits = run.hits
    if domain != "time" or hits is None:
        return None
    pick = hits.accepted
    return noise_floor(hits.force_n[pick], hits.response_m_s2[pick], hits.sample_rate_hz, model, damping)


def _num(value: float) -> float | None:
    value = float(value)
    return value if np.isfinite(value) else None


def _jsonable(value: Any) -> Any:
    """``value`` as plain JSON types; NaN and infinities (a model mode with no
    identified partner, say) become null."""
    plain = json.loads(json.dumps(value, default=lambda v: v.tolist() if hasattr(v, "tolist") else str(v)))

    def clean(v: Any) -> Any:
        if isinstance(v, float):
            return v if np.isfinite(v) else None
        if isinstance(v, list):
            return [clean(x) for x in v]
        if isinstance(v, dict):
            return {k: clean(x) for k, x in v.items()}
        return v

    return clean(plain)


# Like the analysis (daq/workflows/analysis.py), the fit in two steps: fit_run computes in
# memory (a run and its analysis in, summary and arrays out); fit_cache_key,
# cached_fit and store_fit are the store's side. daq/batch/dask_backend.py runs fit_run on a
# Dask worker and the other three beside the store.


def fit_cache_key(path: Path, analysis_key: str | None, options: FitOptions) -> str:
    """The cache key of fitting the run file at ``path`` with ``options``, given the
    cache key of the run's stored analysis (the one with default options)."""
    stat = path.stat()
    identity = {
        "analysis": analysis_key, "options": asdict(options), "software": SOFTWARE,
        "fit_version": FIT_VERSION, "size": stat.st_size, "mtime_ns": stat.st_mtime_ns,
    }  # fmt: skip
    return hashlib.sha256(json.dumps(identity, sort_keys=True, default=str).encode()).hexdigest()


def cached_fit(store: Store, run_id: str, options: FitOptions, key: str) -> dict[str, Any] | None:
    """The stored fit summary of run ``run_id`` with ``options`` if its cache key is
    ``key``; None if there is none, it is unreadable or it is out of date."""
    try:
        stored = store.read_result(run_id, options.result_name)
    except StoreError:
        return None
    return stored["summary"] if stored.get("cache_key") == key else None


def store_fit(
    store: Store,
    run_id: str,
    options: FitOptions,
    key: str,
    summary: dict[str, Any],
    arrays: dict[str, Any],
    analysis_key: str | None = None,
) -> Path:
    """Write (or replace, atomically) the fit result of run ``run_id`` with ``options``;
    ``analysis_key``: the cache key of the analysis it was fitted to (a report says when
    the stored analysis has changed since)."""
    payload = {"summary": summary, "cache_key": key, "analysis_key": analysis_key or "", **arrays}
    return store.write_result(run_id, options.result_name, payload, overwrite=True)


def fit_stored(store_dir: Path, run_id: str, options: FitOptions, recompute: bool = False) -> dict[str, Any]:
    """Fit run ``run_id`` of the store (or reuse an up-to-date result, unless
    ``recompute``); its summary."""
    store = Store(store_dir)
    path = store.resolve(run_id)
    # The analysis the user made (its options kept), not a default one made behind their back.
    analysis = analyze_stored(store_dir, path.stem, stored_options(store, path.stem) or AnalysisOptions())
    stored_analysis = store.read_result(path.stem, ANALYSIS_RESULT)
    analysis["arrays"] = {k: v for k, v in stored_analysis.items() if isinstance(v, np.ndarray)}
    key = fit_cache_key(path, stored_analysis.get("cache_key"), options)
    if not recompute:
        stored = cached_fit(store, path.stem, options, key)
        if stored is not None:
            return {**stored, "cached": True}
    run = store.open(path.stem)
    summary, arrays = fit_run(run, analysis, options)
    store_fit(store, run.run_id, options, key, summary, arrays, stored_analysis.get("cache_key"))
    return {**summary, "cached": False}


def fit_one(store_dir: Path, run_id: str, options: FitOptions, recompute: bool = False) -> RunOutcome:
    """Fit run ``run_id`` of the store (fit_stored): its outcome, the summary or the
    one-line reason it failed. An exception that is no failure of the run (a bug) is
    raised."""
    try:
        return RunOutcome.done(run_id, fit_stored(store_dir, run_id, options, recompute))
    except Exception as exc:
        reason = failure_reason(exc)
        if reason is None:
            raise
        return RunOutcome.failed(run_id, reason)


__all__ = [
    "ANALYSIS_RESULT", "METHODS", "FitOptions", "cached_fit", "fit_cache_key", "fit_one", "fit_run",
    "fit_stored", "store_fit",
]  # fmt: skip
