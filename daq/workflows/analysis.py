"""Analysing stored runs: which data of a run to analyse, with which windows, and the
analysis result file beside the run (``<run_id>.analysis.h5``) with its cache key.

The run's raw data is only read. A result is reused when its cache key (the run
file's identity, the options and the software version) matches; otherwise the run
is analysed again and the result file replaced atomically.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from analysis.beam import TABLE_1, BeamProperties
from analysis.hit_checks import FORCE_GLITCH, NO_IMPACT, RESPONSE_TIMING
from analysis.modal_id import NORMALISATIONS
from analysis.run_analysis import AnalysisOptions, RunAnalysis, analyze_frfs, analyze_hits, set_aside
from analysis.spectra import convert_form
from analysis.table2 import identified_table2
from analysis.windows import WindowSpec
from daq.store import Run, Store, StoreError
from daq.store.model import SOFTWARE
from daq.workflows.outcome import RunOutcome, failure_reason

RESULT_NAME = "analysis"
#: Bumped when the analysis changes what it computes from the same run and options
#: (3: both LSCF normalisations, the spurious test's second way in, input cautions;
#: 4: records without windows cut at the impact where their pre-trigger biases a pole;
#: 5: close modes' poles refined on the FRF, analysis.modal_id.refine;
#: 6: a close group's pole its refined neighbours do as well without dropped, a pole
#: it misses added, analysis.modal_id.refine redundant and missing; 7: a refined pole's
#: damping may move by a factor 3, a second pass in zones of their own around clear peaks
#: no mode accounts for, --frequencies takes the nearest chain; 8: the ± carry the
#: zones' ends and the hits' force weights, a clear peak near a band's low edge that
#: starts near 0 Hz gets its second pass, a cluster asked for must be a feature, shallow
#: peaks without a mode are named; 9: the zones' spread counts only readings of the same
#: mode, an imported rate known roughly goes into every frequency's ±; 10: a heavily
#: damped chain may wander by half its half-width, the damping read from several hits is
#: corrected for the noise bias their own readings show, and that bias enters the ±; an
#: FRF whose coherence is poor beside good ones is named in a caution; a light mode beside
#: heavy ones only is no longer refined; 11: what the diagram holds at a clear peak still
#: unexplained after the second pass is kept when the fit gains by it, a skewed file's
#: response is cautioned).
ANALYSIS_VERSION = 11
#: The analyzer's window mnemonics (stored settings) as analysis window kinds.
WINDOW_KINDS = {"UNIF": "uniform", "HANN": "hann", "FLAT": "flattop", "FORC": "force", "EXPO": "exponential"}
STATUS_CODES = {"new": 0, "frequency": 1, "damping": 2, "stable": 3}
#: How the reason a run has no data to analyse ends: a run of spectra alone is not a
#: failure for `daq analyze --all` and `daq fit --all`, which skip it with that line.
NOTHING_TO_IDENTIFY = "nothing to identify modes from"


def nothing_to_identify(reason: str) -> bool:
    """``reason`` (a one-line failure) says the run holds nothing to analyse (spectra alone)."""
    return reason.endswith(NOTHING_TO_IDENTIFY)


def window_specs(run: Run) -> tuple[WindowSpec, WindowSpec, str]:
    """(force window, response window, where they came from) for a run's hits: the
    analyzer's settings as stored, else the windows an importer read from the file
    (SDF channel headers), else uniform (an imported record is taken as is)."""
    settings = run.instrument.settings if run.instrument is not None else {}
    imported = (getattr(run, "provenance", None) or {}).get("imported_from", {})
    if not settings and isinstance(imported, dict) and isinstance(imported.get("windows"), dict):
        settings = imported["windows"]
    specs = []
    for channel in ("hammer", "accelerometer"):
        setup = settings.get(channel) if isinstance(settings, dict) else None
        kind = WINDOW_KINDS.get(setup.get("window")) if isinstance(setup, dict) else None
        if kind is None:
            specs.append(WindowSpec("uniform"))
        elif kind == "force":
            specs.append(WindowSpec("force", force_width_s=float(setup["force_width_s"])))
        elif kind == "exponential":
            specs.append(WindowSpec("exponential", exp_decay_s=float(setup["exp_decay_s"])))
        else:
            specs.append(WindowSpec(kind))
    recorded = "analyzer settings" if run.instrument is not None else "the imported file's channel headers"
    origin = recorded if any(s.kind != "uniform" for s in specs) else "uniform (none recorded)"
    return specs[0], specs[1], origin


#: What Table 2 says of a run whose test article is not a beam (or not recorded).
NO_BEAM_MODEL = "no beam model for this run"


def beam_of(run: Run) -> tuple[BeamProperties, str]:
    """The beam the damping fit models: the run's test article, else Table 1 (said)."""
    if run.sample is None:
        return TABLE_1, "Table 1 (the run records no test article)"
    fields = {name: getattr(run.sample, name) for name in BeamProperties.__dataclass_fields__}
    return BeamProperties(**fields), "the run's test article"


def analyze(run: Run, options: AnalysisOptions) -> tuple[RunAnalysis, dict[str, Any]]:
    """The analysis of ``run`` and notes on what was analysed (JSON-able)."""
    notes: dict[str, Any] = {}
    if run.hits is not None and run.hits.accepted.any():
        force_window, response_window, origin = window_specs(run)
        result = analyze_hits(
            run.hits.force_n, run.hits.response_m_s2, run.hits.sample_rate_hz, run.hits.accepted,
            force_window, response_window, run.hits.center_hz, options,
        )  # fmt: skip
        windows = {"force": asdict(force_window), "response": asdict(response_window)}
        notes["windows"] = {**windows, "from": origin}
        # H1 of acceleration over force: accelerance, as made, with nothing converted.
        notes["form"] = {"stored": "time records", "analysed": "accelerance"}
    elif run.measured_frfs is not None or run.analyzer is not None:
        source = "measured_frf" if run.measured_frfs is not None else "analyzer"
        frfs = run.measured_frfs if run.measured_frfs is not None else run.analyzer
        decay, origin = _frf_window_decay(run, source)
        form = getattr(frfs, "form", "accelerance")
        frf = frfs.frf
        if form != "accelerance":
            # One form for every run: a receptance file and the same data as accelerance
            # identify the same modes (the residual terms differ by form).
            frf = convert_form(frf, frfs.frequency_hz, "accelerance", form)
        result = analyze_frfs(frfs.frequency_hz, frf, frfs.coherence, source, options, decay)
        if options.estimator != AnalysisOptions.estimator:
            result.cautions.insert(
                0,
                f"--estimator {options.estimator} was not used: the run holds FRFs, not hits, and they "
                "are analysed as they are",
            )
        notes["windows"] = {"from": origin}
        notes["form"] = {"stored": form, "analysed": "accelerance"}
    elif run.spectra is not None and run.hits is None:
        # Power, linear and cross spectra carry no phase between force and response:
        # no FRF can be made of them here (docs/sdf.md), so no modes either.
        raise ValueError(f"the run holds spectra but no time records or FRF: {NOTHING_TO_IDENTIFY}")
    else:
        raise ValueError("the run has no accepted hit and no FRF to analyse")
    _rate_doubt(run, result)
    return result, notes


def _rate_doubt(run: Run, result: RunAnalysis) -> None:
    """A rate the imported file knew only roughly (a coarsely printed time column or
    LabVIEW's Delta_X; its relative standard uncertainty ``sample_rate_u_rel`` in the
    provenance) scales every frequency alike: its share goes into each frequency's ±, and
    a caution says so. A new user's Delta_X 0.000488 gave 2049.18 Hz for 2048 Hz, every
    frequency 0.06 % high, 250 of its ± off, with an import note alone."""
    imported = run.provenance.get("imported_from", {})
    if not isinstance(imported, dict):
        return
    u_rel = imported.get("frequency_axis_u_rel")
    if result.source == "measured_frf" and isinstance(u_rel, (int, float)) and u_rel > 0:
        # An FRF file's frequency step printed to few digits (UFF 58 ASCII): the same share.
        dominant = False
        for mode in result.modes:
            share = mode.frequency_hz * u_rel
            dominant |= bool(share >= mode.frequency_u_hz)
            mode.frequency_u_hz = float(np.hypot(mode.frequency_u_hz, share))
        if dominant:  # said where it is the larger part of some ±, not for every ASCII file
            result.cautions.append(
                f"the file's frequency step is known only to ±{100 * u_rel * np.sqrt(3.0):.2g} % (printed to "
                "6 significant digits): every frequency may be off by that much, and each ± holds its share"
            )
        return
    u_rel = imported.get("sample_rate_u_rel")
    if not isinstance(u_rel, (int, float)) or not u_rel > 0 or run.hits is None:
        return
    for mode in result.modes:
        mode.frequency_u_hz = float(np.hypot(mode.frequency_u_hz, mode.frequency_hz * u_rel))
    half = 100 * u_rel * np.sqrt(3.0)
    result.cautions.append(
        f"the sample rate ({float(run.hits.sample_rate_hz):.8g} Hz) is known only to ±{half:.2g} % from the "
        f"file's printed times or step: every frequency may be off by that much, and each ± holds its "
        f"share; import the file again with --sample-rate HZ if you know the rate"
    )


def _frf_window_decay(run: Run, source: str) -> tuple[float, str]:
    """(1/tau of the exponential window the stored FRFs went through, where that came
    from). Unknown windows give 0 and say so: the damping then includes them."""
    if source == "analyzer":
        _, response_window, origin = window_specs(run)
        if response_window.kind == "exponential":
            return 1.0 / float(response_window.exp_decay_s), "analyzer settings"
        return 0.0, origin
    imported = run.provenance.get("imported_from", {})
    if isinstance(imported, dict) and imported.get("exp_decay_s"):
        return 1.0 / float(imported["exp_decay_s"]), "the imported file's exponential window"
    return 0.0, "unknown: the damping includes any window the source applied"


def form_assumed(run: Run) -> bool:
    """True when the run's FRFs were imported from a file that does not say their form
    (receptance, mobility, accelerance) and were read as the default, accelerance."""
    imported = run.provenance.get("imported_from", {})
    said = imported.get("form_from", "") if isinstance(imported, dict) else ""
    return isinstance(said, str) and said.startswith("default")


def input_cautions(run: Run, notes: dict[str, Any]) -> list[str]:
    """Cautions about what the run's file did not say: the windows its FRFs went through,
    and the FRFs' form (a text table without units is read as accelerance; read as the
    wrong form, its modes are wrong and its synthesis poor)."""
    out = []
    windows = notes.get("windows", {}).get("from", "")
    if isinstance(windows, str) and windows.startswith("unknown"):
        out.append(f"windows {windows}")
    if form_assumed(run):
        out.append(
            "FRF form assumed: the file does not say what its FRFs are, so they were read as "
            "accelerance, (m/s^2)/N; if they are receptance (m/N) or mobility ((m/s)/N), import the "
            "file again with --frf-form"
        )
    imported = run.provenance.get("imported_from", {})
    if isinstance(imported, dict) and imported.get("phase_looks_like_radians"):
        # Said at import only, the analysis of a phase read 57 times too slow gave one
        # mode at 2624 Hz under generic cautions (a new user's trial).
        out.append(
            "phase read as degrees though it looks like radians (every value within ±π, no unit): read "
            "as degrees, the FRF's phase barely turns and its modes are wrong; if it is in radians, write "
            "[rad] in the phase column's header and import the file again"
        )
    if (hits := _averaged_against_checks(run)) is not None:
        out.append(hits)
    return out


def _averaged_against_checks(run: Run) -> str | None:
    """One caution naming the accepted hits whose checks failed (a double impact, a clipped
    record: their FRFs are wrong and bias the average), or None. Hits counted from 1."""
    from daq.workflows.run_views import (
        accepted_against_checks,
        failed_check_names,
        skewed_channels,
        swapped_columns,
    )

    against = accepted_against_checks(run)
    swapped = swapped_columns(run)
    if swapped is not None and set(against) & set(swapped[0]):
        # One caution for the file: the other checks of those hits read the response as the force.
        return f"{swapped[1]}; until then the modes and damping are not the structure's"
    checks = run.hits.checks if run.hits is not None else []
    skewed = skewed_channels(run)
    skew = ""
    if skewed is not None:
        # Said once for the file (leaving hits out does not mend the recorder's skew), and
        # the hits' other failed checks after it.
        skew = f"{skewed[1]}; until then the modes, damping and residues may not be the structure's; "
    if not against:
        return skew.removesuffix("; ") or None
    if set(against) == set(np.flatnonzero(run.hits.accepted)) and all(
        NO_IMPACT in failed_check_names(checks[i]) for i in against
    ):
        # Not one hammer hit: the FRF is the noise's, and so are its "modes" (a new user's
        # file of noise got 17 modes and 20 cautions, this one buried among them).
        first = checks[against[0]][NO_IMPACT].get("detail", "no hammer pulse")
        return (
            f"no hit in the average is a hammer impact (hit {against[0] + 1} failed the no impact check: "
            f"{first}): the FRF and its "
            "modes are those of noise or of an excitation this analysis is not made for, not the "
            "structure's; import the hits of a hammer test"
        )
    glitched = [i for i in against if FORCE_GLITCH in failed_check_names(checks[i])]
    glitch = ""
    if glitched:
        # Leaving the hit out throws its hammer hit away with the glitch: mend the sample.
        which = ", ".join(str(i + 1) for i in glitched)
        glitch = (
            f"the force of hit{'s' * (len(glitched) > 1)} {which} holds a glitch (hit {glitched[0] + 1}: "
            f"{checks[glitched[0]][FORCE_GLITCH].get('detail', '')}): it stands for the hammer in the FRF "
            "and in the band chosen from the force spectrum, both wrong; set that sample to the force's "
            "level beside it in the file and import it again"
        )
        glitch += "; "

    def named(i: int) -> list[str]:
        # What is left to say of hit i once the file's skew and its glitch are said.
        return [
            n
            for n in failed_check_names(checks[i])
            if n != FORCE_GLITCH and not (skew and n == RESPONSE_TIMING)
        ]

    against = [i for i in against if named(i)]
    if not against:
        return f"{skew}{glitch}".removesuffix("; ") or None
    said = "; ".join(
        f"hit {i + 1}: {name} ({checks[i][name].get('detail', 'failed')})"
        for i in against
        for name in named(i)
    )
    count = (
        "1 hit in the average failed its checks"
        if len(against) == 1
        else (f"{len(against)} hits in the average failed their checks")
    )
    leave_out = _leave_out(run, against, [", ".join(named(i)) for i in against])
    wrong = (
        "its FRF is wrong and pulls the modes and damping"
        if len(against) == 1
        else "their FRFs are wrong and pull the modes and damping"
    )
    return f"{skew}{glitch}{count}, {said}: {wrong}; {leave_out}"


def _leave_out(run: Run, against: list[int], reasons: list[str]) -> str:
    """How to leave the hits ``against`` (0-based) out of the average: for an imported run,
    the exact '# rejected hit K: reason' lines to add, K the hit's position in the file
    counted from 0 (daq/formats/csv_text.py reads them so, whatever a hit column labels the
    hits), to the CSV file itself or to the run exported as CSV; for a capture, a new test."""
    one = len(against) == 1
    if run.kind != "imported":
        return f"take the test again without {'it' if one else 'them'}"
    lines = [f"'# rejected hit {i}: {reason}'" for i, reason in zip(against, reasons, strict=True)]
    shown = lines[0] if one else ", ".join(lines[:-1]) + " and " + lines[-1]
    add = f"add the line{'' if one else 's'} {shown}"
    imported = run.provenance.get("imported_from", {})
    if isinstance(imported, dict) and imported.get("format") == "csv":
        return (
            f"to leave {'it' if one else 'them'} out, {add} to the file and import it again "
            "(the line counts the file's hits from 0 in file order, whatever its hit column says)"
        )
    return (
        f"to leave {'it' if one else 'them'} out, export the run as CSV (daq export {run.run_id} "
        f"--format csv), {add} to that file and import it"
    )


def cache_key(path: Path, options: AnalysisOptions) -> str:
    stat = path.stat()
    identity = {
        "file": path.name, "size": stat.st_size, "mtime_ns": stat.st_mtime_ns, "options": asdict(options),
        "software": SOFTWARE, "analysis_version": ANALYSIS_VERSION,
    }  # fmt: skip
    return hashlib.sha256(json.dumps(identity, sort_keys=True).encode()).hexdigest()


def summary(run: Run, result: RunAnalysis, notes: dict[str, Any], options: AnalysisOptions) -> dict[str, Any]:
    """The JSON-able summary stored in the result and printed by ``daq analyze --json``."""
    return {
        "run_id": run.run_id,
        "kind": run.kind,
        "source": result.source,
        "estimator": result.estimator if result.source == "hits" else None,
        "n_averages": result.n_averages,
        "added_decay_1_s": result.added_decay_1_s,
        "pretrigger_cut_s": result.pretrigger_cut_s,
        "pretrigger_range_s": list(result.pretrigger_range_s),
        "record_after_cut_s": result.record_after_cut_s,
        "band": _band(result),
        # A zone whose core a clear peak's own zone cut in two is listed once per piece of
        # its core (the same lines fitted, the modes kept from each piece).
        "zones": [
            {
                "low_hz": z.low_hz,
                "high_hz": z.high_hz,
                "core_low_hz": z.core_low_hz,
                "core_high_hz": z.core_high_hz,
                "max_order": z.max_order,
                "basis": z.basis,
            }
            for z in result.modal.zones
        ],
        "synthesis_error": _num(result.modal.synthesis_error),
        "modes": [
            {
                "frequency_hz": m.frequency_hz,
                "damping_ratio": _num(m.damping_ratio),
                "damping_ratio_windowed": _num(m.damping_ratio_windowed),
                "frequency_u_hz": _num(m.frequency_u_hz),
                "damping_u": _num(m.damping_u),
                "uncertainty_from": m.uncertainty_from or None,
                "frequency_std_hz": _num(m.frequency_std_hz),
                "damping_std": _num(m.damping_std),
                "n_hits_matched": m.n_hits_matched,
                "modal_constant": [[float(c.real), float(c.imag)] for c in m.modal_constant],
                "quality": {k: _num(v) if isinstance(v, float) else v for k, v in m.quality.items()},
            }
            for m in result.modes
        ],
        "set_aside": [{"frequency_hz": f, "damping_ratio": _num(z)} for f, z in set_aside(result)],
        "cautions": input_cautions(run, notes) + list(result.cautions),
        "table2": _table2(run, result),
        "options": asdict(options),
        **notes,
    }


def _band(result: RunAnalysis) -> dict[str, Any] | None:
    b = result.band
    return None if b is None else {"low_hz": b.low_hz, "high_hz": b.high_hz, "reason": b.reason}


def _table2(run: Run, result: RunAnalysis) -> dict[str, Any]:
    """Table 2 of the seed beside the run's modes, for a run whose test article is a beam."""
    if run.sample is None:
        return {"beam": f"{NO_BEAM_MODEL}: it records no test article", "n_functions": None, "rows": []}
    beam, beam_origin = beam_of(run)
    freqs = np.array([m.frequency_hz for m in result.modes])
    zetas = np.array([m.damping_ratio for m in result.modes])
    table = identified_table2(freqs, zetas, beam, n_rows=max(3, min(6, freqs.size)))
    rows = []
    for k in range(table.identified_hz.size):
        rows.append(
            {
                "mode": k + 1,
                "ritz_hz": _num(table.ritz_hz[k]),
                "exact_hz": _num(table.exact_hz[k]),
                "identified_hz": _num(table.identified_hz[k]),
                "difference_exact_pct": _num(table.difference_pct(table.exact_hz)[k]),
                "difference_ritz_pct": _num(table.difference_pct(table.ritz_hz)[k]),
                "damping_ratio": _num(table.damping_ratio[k]),
            }
        )
    return {"beam": beam_origin, "n_functions": table.n_functions, "rows": rows}


def _num(value: float) -> float | None:
    """JSON has no NaN: an unknown number is null."""
    value = float(value)
    return value if np.isfinite(value) else None


def result_arrays(result: RunAnalysis) -> dict[str, np.ndarray]:
    """The arrays a result file holds beside the summary: those a report plots."""
    stab = result.modal.stability
    orders = np.concatenate([np.full(len(p), o) for o, p in zip(stab.orders, stab.poles, strict=True)])
    out: dict[str, np.ndarray] = {
        "frequency_hz": result.frequency_hz,
        "frf": result.frf,
        "synthesized_frequency_hz": result.modal.frequency_hz,
        "synthesized": result.modal.synthesized,
    }
    if result.coherence is not None:
        out["coherence"] = result.coherence
    if orders.size:
        out["stability_order"] = orders.astype(np.int64)
        out["stability_pole"] = np.concatenate(stab.poles).astype(complex)
        out["stability_status"] = np.concatenate(
            [np.array([STATUS_CODES.get(str(s), 0) for s in codes], dtype=np.int64) for codes in stab.status]
        )
        out["stability_mode"] = np.concatenate([np.asarray(c, dtype=np.int64) for c in stab.selected_cluster])
        if stab.normalisation:
            # Index into NORMALISATIONS: which of a zone's two LSCF fits each pole is from.
            rank = {name: i for i, name in enumerate(NORMALISATIONS)}
            out["stability_normalisation"] = np.concatenate(
                [np.array([rank[str(n)] for n in names], dtype=np.int64) for names in stab.normalisation]
            )
    return out


def payload(result: RunAnalysis, info: dict[str, Any], key: str) -> dict[str, Any]:
    """What the result file holds: the summary, the cache key and the arrays."""
    return {"summary": info, "cache_key": key, **result_arrays(result)}


# The analysis in two steps, so that the computing can happen where the store is not
# (a Dask worker, daq/batch/dask_backend.py) and the storing where it is: compute_analysis
# takes a run in memory and touches no file; cached_analysis and store_analysis are
# the store's side, with the cache key computed beside the run file.


def compute_analysis(run: Run, options: AnalysisOptions) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """(summary, arrays) of analysing ``run``, in memory: no file read or written."""
    result, notes = analyze(run, options)
    info = summary(run, result, notes, options)
    return info, result_arrays(result)


def cached_analysis(store: Store, run_id: str, key: str) -> dict[str, Any] | None:
    """The stored analysis of run ``run_id`` (summary, cache key, arrays) if its cache
    key is ``key``; None if there is none, it is unreadable or it is out of date."""
    try:
        stored = store.read_result(run_id, RESULT_NAME)
    except StoreError:
        return None
    return stored if stored.get("cache_key") == key else None


def store_analysis(
    store: Store, run_id: str, key: str, info: dict[str, Any], arrays: dict[str, np.ndarray]
) -> Path:
    """Write (or replace, atomically) the analysis result of run ``run_id``."""
    payload = {"summary": info, "cache_key": key, **arrays}
    return store.write_result(run_id, RESULT_NAME, payload, overwrite=True)


def stored_options(store: Store, run_id: str) -> AnalysisOptions | None:
    """The options the stored analysis of ``run_id`` was made with (None: none stored or
    unreadable): a report draws what the user tuned, not a default analysis."""
    try:
        info = store.read_result(run_id, RESULT_NAME)["summary"]
        options = dict(info["options"])
    except (StoreError, KeyError, TypeError, ValueError):
        return None
    for key in ("band_hz", "frequencies_hz"):
        if options.get(key) is not None:
            options[key] = tuple(float(v) for v in options[key])
    try:
        return AnalysisOptions(
            **{k: v for k, v in options.items() if k in AnalysisOptions.__dataclass_fields__}
        )
    except (TypeError, ValueError):
        return None


def analyze_stored(store_dir: Path, run_id: str, options: AnalysisOptions, recompute: bool = False) -> dict:
    """Analyse run ``run_id`` of the store (or reuse its up-to-date result, unless
    ``recompute``); its summary with ``cached`` saying which. StoreError / ValueError
    name what is wrong."""
    store = Store(store_dir)
    path = store.resolve(run_id)
    key = cache_key(path, options)
    if not recompute:
        stored = cached_analysis(store, path.stem, key)
        if stored is not None:
            return {**stored["summary"], "cached": True}
    run = store.open(path.stem)
    info, arrays = compute_analysis(run, options)
    store_analysis(store, run.run_id, key, info, arrays)
    return {**info, "cached": False}


def analyze_one(
    store_dir: Path, run_id: str, options: AnalysisOptions, recompute: bool = False
) -> RunOutcome:
    """Analyse run ``run_id`` of the store (analyze_stored): its outcome, the summary or
    the one-line reason it failed. An exception that is no failure of the run (a bug)
    is raised."""
    try:
        return RunOutcome.done(run_id, analyze_stored(store_dir, run_id, options, recompute))
    except Exception as exc:
        reason = failure_reason(exc)  # the reasons a run on a Dask cluster gives too
        if reason is None:
            raise
        return RunOutcome.failed(run_id, reason)
