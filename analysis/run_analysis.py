"""One run's analysis from its arrays: FRFs averaged over the accepted hits, modes
found from the stability diagram, the damping the exponential window adds taken out,
the scatter of each mode over the hits, and the seed's Table 2 beside the result.

Pure: arrays and small dataclasses in, results out. daq/workflows/analysis.py reads runs,
calls this and stores what it returns beside the run.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field, replace

import numpy as np

from analysis.band_choice import BandChoice, choose_band, edge_text, poor_coherence
from analysis.measurement_text import with_uncertainty
from analysis.modal_id import ModalResult, identify_modes
from analysis.modal_id.identify import UNEXPLAINED_SNR_DB, WEAK_PEAK_PROMINENCE_DB
from analysis.modal_id.lscf import lscf_poles
from analysis.modal_id.refine import MAX_DAMPING as REFINE_MAX_DAMPING
from analysis.modal_id.refine import refine_poles
from analysis.modal_id.stability import overlapped
from analysis.modal_id.zones import Zone
from analysis.pretrigger import cut_at_impact, impact_starts, moved, screen, single_hit_noise
from analysis.spectra import frf_estimate, linear_spectra, per_hit_frf
from analysis.windows import WindowSpec, added_decay_rate, correct_pole, window

ESTIMATORS = ("h1", "h2", "hv")
#: A mode of one hit is the run's mode when its frequency is this close (relative).
HIT_MATCH_TOLERANCE = 0.03
#: A mode found for a frequency of interest must lie this close to it (relative).
FREQUENCY_OF_INTEREST_TOLERANCE = 0.05
#: Consecutive LSCF orders each hit is fitted at for the scatter (their median is kept).
SCATTER_ORDERS = 11


@dataclass(frozen=True)
class AnalysisOptions:
    """What the user may choose.

    band_hz : (low, high) Hz to identify in; None = chosen from the data
        (analysis.band_choice: the force spectrum and the coherence).
    max_order : the LSCF order of every frequency zone; None = each zone's own, from
        the peaks it holds (analysis.modal_id.zones).
    frequencies_hz : frequencies of interest; None = let the stability diagram decide.
    estimator : "h1", "h2" or "hv" (hits only; FRFs read from a file are used as they are).
    per_hit : also identify every accepted hit alone, for the scatter of each mode.
    """

    band_hz: tuple[float, float] | None = None
    max_order: int | None = None
    frequencies_hz: tuple[float, ...] | None = None
    estimator: str = "h1"
    per_hit: bool = True

    def __post_init__(self) -> None:
        if self.estimator not in ESTIMATORS:
            raise ValueError(f"estimator must be one of {', '.join(ESTIMATORS)}, got {self.estimator!r}")
        if self.max_order is not None and not 2 <= int(self.max_order) <= 200:
            raise ValueError(f"max_order must be 2..200, got {self.max_order}")
        if self.band_hz is not None:
            low, high = (float(v) for v in self.band_hz)
            if not (np.isfinite(low) and np.isfinite(high) and 0 <= low < high):
                raise ValueError(f"band must be two frequencies 0 <= low < high, got {self.band_hz}")


@dataclass
class ModeEstimate:
    """One identified mode as reported.

    frequency_hz, damping_ratio : undamped natural frequency (Hz) and damping ratio,
        with the exponential window's added decay removed.
    damping_ratio_windowed : the ratio as seen through the windows (before correction).
    modal_constant : (n_frf,) complex residue of the run's FRF, (m/s^2)/N x rad/s.
    frequency_u_hz, damping_u : standard uncertainty of frequency_hz and damping_ratio
        (see uncertainty_from and docs/analysis.md); NaN when it could not be estimated.
    uncertainty_from : how: "N hits" (the spread over the accepted hits / sqrt(N),
        with the spread over model orders) or "bootstrap over lines" (one averaged FRF).
    frequency_std_hz, damping_std : sample standard deviation over the accepted hits
        identified one by one (NaN with fewer than 2 hits matched): the spread of ONE hit.
    n_hits_matched : hits in which this mode was found again.
    quality : from the stability diagram (orders stable, scatter, synthesis share).
    pole : the pole as fitted, rad/s, window decay still in it (analysis.modal_id).
    """

    frequency_hz: float
    damping_ratio: float
    damping_ratio_windowed: float
    modal_constant: np.ndarray
    frequency_u_hz: float = float("nan")
    damping_u: float = float("nan")
    uncertainty_from: str = ""
    frequency_std_hz: float = float("nan")
    damping_std: float = float("nan")
    n_hits_matched: int = 0
    quality: dict = field(default_factory=dict)
    pole: complex = complex("nan")


@dataclass
class RunAnalysis:
    """frequency_hz : (n_lines,). frf : (n_frf, n_lines) complex accelerance, (m/s^2)/N.
    coherence : (n_frf, n_lines) or None. source : "hits", "measured_frf" or "analyzer".
    added_decay_1_s : the exponential window's decay rate removed from every pole, 1/s.
    pretrigger_cut_s : the pre-trigger (median over hits) cut off before the analysis, s;
        0 when the records were analysed whole (analysis.pretrigger); pretrigger_range_s:
        its least and largest over the hits, s; record_after_cut_s: the records' length
        from each impact, s.
    band : the band analysed and why (given by the user, or chosen from the data).
    cautions : one sentence each: what in the result may mislead, and what to try.
    """

    frequency_hz: np.ndarray
    frf: np.ndarray
    coherence: np.ndarray | None
    source: str
    estimator: str
    n_averages: int
    added_decay_1_s: float
    modal: ModalResult
    modes: list[ModeEstimate]
    band: BandChoice | None = None
    cautions: list[str] = field(default_factory=list)
    pretrigger_cut_s: float = 0.0
    pretrigger_range_s: tuple[float, float] = (0.0, 0.0)
    record_after_cut_s: float = 0.0


def analyze_hits(
    force_n: np.ndarray,
    response_m_s2: np.ndarray,
    sample_rate_hz: float,
    accepted: np.ndarray,
    force_window: WindowSpec,
    response_window: WindowSpec,
    center_hz: float = 0.0,
    options: AnalysisOptions | None = None,
) -> RunAnalysis:
    """Analyse time records (n_hits, n_samples), N and m/s^2, over the accepted hits.

    Records without windows whose pre-trigger may bias a mode that has not died away by
    the record's end (analysis.pretrigger) are analysed again, cut to start at the
    impact; where a mode moved by more than MOVED_BY_U (analysis.pretrigger) of its u,
    that result is returned and ``pretrigger_cut_s`` says so.
    """
    options = options or AnalysisOptions()
    accepted = np.asarray(accepted, dtype=bool)
    if not accepted.any():
        raise ValueError("no accepted hit to analyse")
    result = _analyze_records(
        force_n, response_m_s2, sample_rate_hz, accepted, force_window, response_window, center_hz, options
    )
    unwindowed = force_window.kind == response_window.kind == "uniform"
    if not (unwindowed and center_hz == 0 and result.modes and np.isrealobj(force_n)):
        return result
    force, response = np.atleast_2d(force_n)[accepted], np.atleast_2d(response_m_s2)[accepted]
    starts = impact_starts(force)
    n = force.shape[1]
    found = screen(result.modes, starts, n, sample_rate_hz)
    if found is None:
        return result
    if found.too_short:
        result.cautions.append(found.caution_text(n / sample_rate_hz))
        return result
    force, response = cut_at_impact(force, response, starts)
    cut = _analyze_records(
        force, response, sample_rate_hz, np.ones(force.shape[0], dtype=bool), force_window, response_window,
        center_hz, options,
    )  # fmt: skip
    if not moved(found.suspects, cut.modes, cut.frequency_hz):
        return result
    cut.pretrigger_cut_s = found.pretrigger_s
    cut.pretrigger_range_s = found.range_s
    cut.record_after_cut_s = found.kept_samples / sample_rate_hz
    return cut


def _analyze_records(
    force_n, response_m_s2, sample_rate_hz, accepted, force_window, response_window, center_hz, options
) -> RunAnalysis:
    spectra = linear_spectra(
        force_n[accepted], response_m_s2[accepted], sample_rate_hz, force_window, response_window, center_hz
    )
    estimate = frf_estimate(spectra)
    frf = getattr(estimate, options.estimator)[np.newaxis, :]
    # The force window multiplies a pulse it does not touch; only the response's
    # exponential window adds decay to the poles.
    decay = added_decay_rate(response_window) - added_decay_rate(force_window)
    coherence = estimate.coherence[np.newaxis, :]
    band = _band(
        estimate.frequency_hz, options, estimate.g_ff, coherence if estimate.n_averages >= 2 else None
    )
    hit_frfs = per_hit_frf(spectra) if estimate.n_averages >= 2 else None
    noise = None if hit_frfs is None else _noise_of_mean(hit_frfs)
    windowed = force_window.kind != "uniform" or response_window.kind != "uniform"
    if hit_frfs is None and windowed and center_hz == 0:
        # One windowed hit: no scatter, and the FRF's second differences read the noise
        # a window smooths over the lines too low; its pre-trigger tells it, if it has one.
        n = force_n.shape[-1]
        noise = single_hit_noise(
            force_n[accepted][0], response_m_s2[accepted][0], spectra.force[0] / spectra.force_scale,
            frf[0], window(force_window, n, sample_rate_hz), window(response_window, n, sample_rate_hz),
        )  # fmt: skip
    result = _identify(estimate.frequency_hz, frf, coherence, "hits", options, decay, band, noise)
    result.n_averages = estimate.n_averages
    if estimate.n_averages == 1:
        result.cautions.append(
            "one hit: its coherence is 1 by construction and says nothing of the noise; the ± come "
            "from a bootstrap over lines; take more hits to average"
        )
    if result.modes:
        if options.per_hit and estimate.n_averages >= 2:
            # H1 averages the hits' FRFs weighted by their force power at each line.
            weights = np.abs(spectra.force) ** 2 if options.estimator == "h1" else None
            _scatter(result, hit_frfs, options, decay, weights)
        else:
            _bootstrap(result, decay)
        _zone_spread(result, decay)
        _circular_pole_floor(result)
    result.cautions += _cautions(result, options)
    return result


def analyze_frfs(
    frequency_hz: np.ndarray,
    frf: np.ndarray,
    coherence: np.ndarray | None,
    source: str,
    options: AnalysisOptions | None = None,
    added_decay_1_s: float = 0.0,
) -> RunAnalysis:
    """Analyse FRFs (n_frf, n_lines) read from a file or the analyzer (no FFT step),
    in the form of analysis.modal_id.lsfd.FORMS given by ``form`` (accelerance unless
    the source says otherwise)."""
    options = options or AnalysisOptions()
    frf = np.atleast_2d(np.asarray(frf, dtype=complex))
    coherence = None if coherence is None else np.atleast_2d(np.asarray(coherence, dtype=float))
    f = np.asarray(frequency_hz, float)
    band = _band(f, options, None, coherence)
    result = _identify(f, frf, coherence, source, options, added_decay_1_s, band)
    if result.modes:
        _bootstrap(result, added_decay_1_s)
        _zone_spread(result, added_decay_1_s)
        _circular_pole_floor(result)
    result.cautions += _cautions(result, options)
    return result


def _band(frequency_hz, options: AnalysisOptions, g_ff, coherence) -> BandChoice:
    if options.band_hz is not None:
        low, high = options.band_hz
        lines = frequency_hz[np.isfinite(frequency_hz) & (frequency_hz > 0)]
        if lines.size and (low < lines[0] or high > lines[-1]):
            low, high = max(low, float(lines[0])), min(high, float(lines[-1]))
            if not low < high:
                raise ValueError(
                    f"band {options.band_hz[0]:g}-{options.band_hz[1]:g} Hz holds no line of the run "
                    f"({lines[0]:g}-{lines[-1]:g} Hz)"
                )
            return BandChoice(
                low,
                high,
                f"given with --band, cut to the run's lines ({edge_text(low)}-{edge_text(high)} Hz)",
            )
        return BandChoice(float(low), float(high), "given with --band")
    return choose_band(frequency_hz, g_ff, coherence)


#: Lines an analysis needs at least (daq/formats/imported.py's MIN_ANALYSIS_LINES, copied
#: there so that an import need not load the numerics; a test keeps the two equal).
MIN_LINES = 8


def _lines(frequency_hz: np.ndarray, band: BandChoice) -> np.ndarray:
    above_zero = np.isfinite(frequency_hz) & (frequency_hz > 0)
    keep = above_zero & (frequency_hz >= band.low_hz) & (frequency_hz <= band.high_hz)
    if above_zero.sum() < MIN_LINES:
        raise ValueError(
            f"the run has {int(above_zero.sum())} lines above 0 Hz and an analysis needs {MIN_LINES}: "
            "the record is too short (record more samples per hit, or a finer frequency step)"
        )
    if keep.sum() < MIN_LINES:
        raise ValueError(
            f"only {int(keep.sum())} lines in the band {edge_text(band.low_hz)}-{edge_text(band.high_hz)} Hz "
            f"and an analysis needs {MIN_LINES}: widen it"
        )
    return keep


def _noise_of_mean(hit_frfs: np.ndarray) -> np.ndarray:
    """(n_lines,) the standard deviation of the noise of the hits' averaged FRF at each
    line: the scatter of the hits' own FRFs (n_hits, n_lines) over sqrt(hits); NaN where
    fewer than 2 hits have a finite FRF. It holds whatever the windows do to the noise
    (smooth over the lines under a force window), which the FRF alone cannot show."""
    finite = np.isfinite(hit_frfs)
    n = finite.sum(axis=0)
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # a line without 2 finite hits: NaN
        spread = np.nanstd(np.where(finite, hit_frfs, np.nan), axis=0, ddof=1)
    return np.where(n >= 2, spread / np.sqrt(np.maximum(n, 1)), np.nan)


def _identify(frequency_hz, frf, coherence, source, options, decay, band, noise=None) -> RunAnalysis:
    keep = _lines(frequency_hz, band) & np.all(np.isfinite(frf), axis=0)
    if keep.sum() < MIN_LINES:
        raise ValueError(
            f"only {int(keep.sum())} lines of the band hold a finite FRF (where the force's spectrum is "
            "zero the FRF is not defined): the record is too short or holds no force"
        )
    if options.frequencies_hz is not None:
        low, high = float(frequency_hz[keep].min()), float(frequency_hz[keep].max())
        outside = [f for f in options.frequencies_hz if not low <= f <= high]
        if outside:
            said = "frequency {} Hz lies" if len(outside) == 1 else "frequencies {} Hz lie"
            lines = frequency_hz[np.isfinite(frequency_hz) & (frequency_hz > 0)]
            first, last = float(lines.min()), float(lines.max())
            given = options.band_hz is not None
            text = said.format(", ".join(f"{f:g}" for f in outside)) + (
                f" outside the band analysed, {edge_text(low)}-{edge_text(high)} Hz, "
                + ("given with --band" if given else "which was chosen from the data")
            )
            if not all(first <= f <= last for f in outside):
                text += f"; the run has no lines there (they span {edge_text(first)}-{edge_text(last)} Hz)"
            elif given:
                text += f"; the run's lines span {edge_text(first)}-{edge_text(last)} Hz: widen --band"
            else:
                # The run has lines there; the band chosen from the data left them out.
                wanted = sorted([low, high, *outside])
                them = "it" if len(outside) == 1 else "them"
                text += (
                    f"; the run's lines span {edge_text(first)}-{edge_text(last)} Hz: give --band "
                    f"{edge_text(wanted[0])}:{edge_text(wanted[-1])} to take {them} in"
                )
            raise ValueError(text)
    modal = identify_modes(
        frequency_hz[keep],
        frf[:, keep],
        max_order=options.max_order,
        frequencies_hz=options.frequencies_hz,
        noise_std=None if noise is None else noise[keep],
    )
    modes = []
    cautions = []
    for mode in modal.modes:
        if options.frequencies_hz is not None and not any(
            abs(mode.frequency_hz - f) <= FREQUENCY_OF_INTEREST_TOLERANCE * f for f in options.frequencies_hz
        ):
            continue  # the nearest cluster to a frequency of interest, but not near it
        f_true, zeta_true = correct_pole(np.array([mode.frequency_hz]), np.array([mode.damping_ratio]), decay)
        modes.append(
            ModeEstimate(
                frequency_hz=float(f_true[0]),
                damping_ratio=float(zeta_true[0]),
                damping_ratio_windowed=float(mode.damping_ratio),
                modal_constant=np.asarray(mode.modal_constant, dtype=complex),
                quality={
                    "n_stable_orders": int(mode.quality.n_stable_orders),
                    "frequency_scatter_rel": float(mode.quality.frequency_scatter_rel),
                    "damping_scatter_rel": float(mode.quality.damping_scatter_rel),
                    "synthesis_share": float(mode.quality.synthesis_share),
                    "accepted": bool(mode.quality.accepted),
                    "refined": bool(mode.quality.refined),
                    "added": bool(mode.quality.added),
                    "for_peak": bool(mode.quality.for_peak),
                    "frequency_spread_top_hz": float(mode.quality.frequency_spread_top_hz),
                    "damping_spread_top": float(mode.quality.damping_spread_top),
                    "normalisation": mode.normalisation,
                },
                pole=complex(mode.pole),
            )
        )
    if options.frequencies_hz is not None:
        answered: dict[int, float] = {}  # mode index -> the frequency asked that it answers
        for f_asked in options.frequencies_hz:
            near = [
                k
                for k, m in enumerate(modes)
                if abs(m.frequency_hz - f_asked) <= FREQUENCY_OF_INTEREST_TOLERANCE * f_asked
            ]
            if not near:
                cautions.append(
                    f"no mode found within {100 * FREQUENCY_OF_INTEREST_TOLERANCE:g} % of {f_asked:g} Hz: "
                    "look at the stability diagram (daq report), or give a --band around it"
                )
                continue
            k = min(near, key=lambda k: abs(modes[k].frequency_hz - f_asked))
            if k in answered:
                same = modes[k].frequency_hz
                cautions.append(
                    f"{f_asked:g} Hz and {answered[k]:g} Hz found the same mode, {same:.6g} Hz: no second "
                    f"mode stands near {f_asked:g} Hz; look at the stability diagram (daq report)"
                )
            else:
                answered[k] = f_asked
    return RunAnalysis(
        frequency_hz=frequency_hz, frf=frf, coherence=coherence, source=source, estimator=options.estimator,
        n_averages=1, added_decay_1_s=float(decay), modal=modal, modes=modes, band=band, cautions=cautions,
    )  # fmt: skip


#: The synthesis error above which the result is flagged.
POOR_SYNTHESIS = 0.2
#: A mode this close to a band edge (fraction of the band width) is flagged.
EDGE_FRACTION = 0.02


def _cautions(result: RunAnalysis, options: AnalysisOptions | None = None) -> list[str]:
    """What in the result may mislead, and what to try: one sentence each. ``options``:
    those the result was made with (frequencies of interest, when given, have a caution
    each when not found)."""
    options = options or AnalysisOptions()
    asked = options.frequencies_hz is not None
    out = []
    band = result.band
    span = f"{edge_text(band.low_hz)}-{edge_text(band.high_hz)} Hz" if band else "the band"
    aside = set_aside(result)
    if not result.modes and not asked:
        out.append(
            f"no mode kept in {span}: the poles that stay stable were all left out as too weak (see the "
            "possible modes left out)"
            if aside
            else f"no mode found in {span}: the stability diagram holds no pole that stays stable; try "
            "--band around a peak of the FRF, --max-order higher, or --frequencies with the peaks you expect"
        )
    error = result.modal.synthesis_error
    if np.isfinite(error) and error > POOR_SYNTHESIS:
        out.append(
            f"the modes reproduce the FRF poorly (synthesis error {100 * error:.3g} % > "
            f"{100 * POOR_SYNTHESIS:.0f} %): modes are missing or the data are noisy; look at synthesis.png "
            "of daq report and try --band or --max-order"
        )
    if band is not None and not band.coherence_ok:
        out.append(
            "the coherence is below 0.5 over the whole band: the FRF is mostly noise (too weak a hit, "
            "a loose sensor, or the wrong channels)"
        )
    if band is not None and (
        poor := poor_coherence(result.frequency_hz, result.coherence, band.low_hz, band.high_hz)
    ):
        named = ", ".join(f"FRF {k + 1} (below 0.5 over {share:.0%} of the band, median {median:.2f})"
                          for k, share, median in poor)  # fmt: skip
        it, one = ("it", True) if len(poor) == 1 else ("them", False)
        out.append(
            f"{named} {'is' if one else 'are'} mostly noise, yet {'it weighs' if one else 'they weigh'} in "
            "the modes as the others do, and the band, chosen from the FRFs' mean coherence, does not show "
            f"it: leave {it} out of the file and import it again, or measure {it} again"
        )
    if aside:
        out.append(_set_aside_caution(result, aside, options))
    if for_peak := [m for m in result.modes if m.quality.get("for_peak")]:
        out.append(_for_peak_caution(result, for_peak, options))
    unexplained = _unexplained(result, aside)
    if unexplained and not asked:
        out.append(_unexplained_caution(result, unexplained, options))
    # ModalResult.weak_peaks_hz leaves out the clear peaks already named above.
    weak = [
        p for p in getattr(result.modal, "weak_peaks_hz", None) or []
        if not any(abs(p - f) <= 2 * _line(result) for f, _ in aside)
    ]  # fmt: skip
    if weak and not asked:
        out.append(_weak_peaks_caution(result, weak))
    over_hits = [m for m in result.modes if m.uncertainty_from.endswith(" hits")]
    few = [m for m in over_hits if m.n_hits_matched in FEW_HITS_COVERAGE]
    if few:
        n = min(m.n_hits_matched for m in few)
        uncertain = (
            f"so few that the spread is itself uncertain, and the truth may lie within ±2 u only about "
            f"{FEW_HITS_COVERAGE[n]} % of the time, not 95 %"
        )
        if result.n_averages in FEW_HITS_COVERAGE:
            out.append(f"the ± come from the spread over {n} hits: {uncertain}; take 5 or more hits")
        else:
            # Hits enough, but some modes were found in only a few of them.
            which = ", ".join(f"{_at(m)} Hz" for m in few)
            them = "mode at" if len(few) == 1 else "modes at"
            out.append(
                f"the ± of the {them} {which} come from the spread over only {n} of the {result.n_averages} "
                f"hits (the others hold no pole near them): {uncertain}; a --band around them may read "
                "them in every hit"
            )
    vague = [m for m in result.modes if np.isfinite(m.damping_u) and m.damping_u > m.damping_ratio]
    if len(vague) == 1:
        (m,) = vague
        value, u = with_uncertainty(100 * m.damping_ratio, 100 * m.damping_u)
        out.append(
            f"the damping of the mode at {_at(m)} Hz is not fixed by the data: its ± "
            f"({u} %) is larger than the value ({value} %); a finer "
            "frequency step, more hits or a --band around the mode may fix it"
        )
    elif vague:
        # One line for them all: a noisy run has many, and a line each buried the rest.
        listed = ", ".join(_at(m) for m in vague)
        out.append(
            f"the damping of the modes at {listed} Hz is not fixed by the data: the ± of each is larger "
            "than its value; a finer frequency step, more hits or a --band around them may fix it"
        )
    unrefined = _overlapping_unrefined(result)
    if unrefined:
        listed = ", ".join(_at(m) for m in unrefined)
        one = len(unrefined) == 1
        out.append(
            f"the mode{'' if one else 's'} at {listed} Hz overlap{'s' if one else ''} a neighbour and "
            f"{'is' if one else 'are'} too damped (over {100 * REFINE_MAX_DAMPING:g} %) to be refined on the "
            "FRF: LSCF's bias, the same in every hit, can move such values by more than their ± (in "
            "simulations of two modes at 2 and 2.5 % the truth lay within 2 u only 40-80 % of the time); "
            "take the ± as a lower bound"
        )
    line = float(np.median(np.diff(result.frequency_hz))) if result.frequency_hz.size > 1 else 0.0
    narrow = [
        m for m in result.modes if line > 0 and 2 * m.damping_ratio * m.frequency_hz < NARROW_LINES * line
    ]
    if narrow:
        listed = ", ".join(_at(m) for m in narrow)
        widest = max(2 * m.damping_ratio * m.frequency_hz for m in narrow)
        out.append(
            f"the mode{'s' * (len(narrow) > 1)} at {listed} Hz {'are' if len(narrow) > 1 else 'is'} read "
            f"from a peak narrower than {NARROW_LINES:g} of a line (half-power band {widest:.2g} Hz at "
            f"most, lines {line:.3g} Hz): with noise the damping may read high and the frequency off by "
            "more than their ±, the same in every hit; record longer for finer lines"
        )
    if band is not None:
        margin = EDGE_FRACTION * (band.high_hz - band.low_hz)
        # At the low edge no wider than the band's distance from 0 Hz, twice (a mode below
        # twice the edge): 150 Hz in a band of 36.5-8658 Hz is no edge mode (a new user's
        # file was told it was, 2 % of the width reaching 209 Hz).
        low_margin = min(margin, 2 * band.low_hz)
        lines = result.frequency_hz[np.isfinite(result.frequency_hz) & (result.frequency_hz > 0)]
        step = float(np.median(np.diff(lines))) if lines.size > 1 else 0.0
        for m in result.modes:
            low = m.frequency_hz < band.low_hz + low_margin
            if not low and m.frequency_hz <= band.high_hz - margin:
                continue
            # A band that already reaches the run's first (last) line cannot be widened.
            at_data = lines.size > 0 and (
                band.low_hz <= lines[0] + step if low else band.high_hz >= lines[-1] - step
            )
            out.append(
                f"the mode at {_at(m)} Hz lies at an edge of the band {span}: it may stand for modes "
                + (
                    f"outside the run's lines, which these data cannot show (they "
                    f"{'begin' if low else 'end'} at {edge_text(float(lines[0] if low else lines[-1]))} Hz); "
                    "take its values with care"
                    if at_data
                    else "outside; widen the band to check it"
                )
            )
    return out


def _overlapping_unrefined(result: RunAnalysis) -> list[ModeEstimate]:
    """The modes with a neighbour within stability.OVERLAP summed half-power half-widths that
    were not refined for being damped over refine.MAX_DAMPING (LSCF's noise bias stays)."""
    modes = [m for m in result.modes if np.isfinite(m.damping_ratio)]
    if len(modes) < 2:
        return []
    f = np.array([m.frequency_hz for m in modes])
    zeta = np.array([m.damping_ratio for m in modes])
    close = overlapped(f, zeta)
    return [
        m
        for m, c in zip(modes, close, strict=True)
        if c and m.damping_ratio > REFINE_MAX_DAMPING and not m.quality.get("refined")
    ]


def _at(mode: ModeEstimate) -> str:
    """A mode's frequency in a caution as its own line writes it (to the decimal place of
    its u: analysis.measurement_text), so that the two can be matched by eye."""
    return with_uncertainty(mode.frequency_hz, mode.frequency_u_hz, ".6g")[0]


#: A mode whose half-power band 2 zeta f is narrower than this share of a line is read
#: from the skirt of a peak the lines do not resolve: a new user's files with noise read a
#: 0.2 % mode's damping 4.7 u high at 0.17 of a line (1.1 Hz lines), 5.5 u at 0.08, and
#: within 1.5 u at 0.38; noise-free, exactly. A second user's files read the frequency off
#: too: 42 Hz at 0.1 % (0.08 of a line) 5-7 u, and 155 Hz at 0.08 % (0.25 of a line) 3-6.6
#: u, where the damping read at the threshold kept the caution away; 0.4 leaves margin.
NARROW_LINES = 0.4


#: Hits too few for their spread to give a trustworthy ±, and how often ±2 u held the
#: truth on simulated hits (the coverage test's four modes, 30 draws, 120 modes each):
#: 78-82 % with 2 hits, 85-86 % with 3 (Student's t alone, without the spread over the
#: orders that u also holds, gives 70.5 % and 81.6 %); with 5 hits 86-92 %.
FEW_HITS_COVERAGE = {2: 80, 3: 85}


def _set_aside_caution(
    result: RunAnalysis, aside: list[tuple[float, float]], options: AnalysisOptions
) -> str:
    """The chains set aside, what they may be, where to see them and the options that keep
    them (the same band, order and estimator as this result, so that the same chains come)."""
    one = len(aside) == 1
    listed = ", ".join(f"{f:.6g}" for f, _ in aside)
    again = _keep_options(result, [f for f, _ in aside], options)
    return (
        f"{len(aside)} possible mode{'' if one else 's'} left out, at {listed} Hz: "
        f"{'it improves' if one else 'each improves'} the fit where it lies, but not clearly enough to "
        "be told from noise or from the misfit larger, heavily damped modes leave; look at "
        f"{'it' if one else 'them'} on the report's stability diagram (dashed) before keeping "
        f"{'it' if one else 'them'} with {again}"
    )


def _keep_options(result: RunAnalysis, more_hz: list[float], options: AnalysisOptions) -> str:
    """The options that ask for the modes found and ``more_hz`` (Hz) with the same band,
    order and estimator as this result, so that the same chains come."""
    every = sorted([m.frequency_hz for m in result.modes] + list(more_hz))
    again = f"--frequencies {','.join(f'{f:.6g}' for f in every)}"
    if options.band_hz is not None:
        again += f" --band {options.band_hz[0]:g}:{options.band_hz[1]:g}"
    if options.max_order is not None:
        again += f" --max-order {options.max_order}"
    if options.estimator != AnalysisOptions.estimator and result.source == "hits":
        again += f" --estimator {options.estimator}"
    return again


def _for_peak_caution(result: RunAnalysis, kept: list[ModeEstimate], options: AnalysisOptions) -> str:
    """Modes kept for a clear peak of the FRF by the third pass (analysis/modal_id/
    identify.py, _kept_for_peaks): what they rest on, and the --frequencies that leave
    them out."""
    one = len(kept) == 1
    listed = ", ".join(f"{m.frequency_hz:.4g}" for m in kept)
    failed = [m for m in kept if not m.quality.get("accepted", True)]
    if failed:
        orders = ", ".join(str(int(m.quality.get("n_stable_orders", 0))) for m in failed)
        plural = "" if orders == "1" else "s"
        held = (
            f"; the stability diagram holds {'it' if one else 'those failing a selection rule'} over "
            f"{orders} order{plural}, too few or too unsteady for a mode found by itself, so its values rest "
            "on little"
        )
    else:
        held = "; the stability diagram holds it in a zone of its own, where the passes before did not"
    others = [m.frequency_hz for m in result.modes if not m.quality.get("for_peak")]
    leave = ""
    if others:
        leave = (
            "; to leave "
            + ("it" if one else "them")
            + " out, "
            + _keep_options(replace(result, modes=[]), others, options)
        )
    return (
        f"the mode{'' if one else 's'} at {listed} Hz {'is' if one else 'are'} kept for a clear peak of "
        f"the FRF ({UNEXPLAINED_SNR_DB:g} dB or more above the noise, no other mode there; a mode narrower "
        f"than a line, or one of a close pair){held}{leave}"
    )


def _unexplained(result: RunAnalysis, aside: list[tuple[float, float]]) -> list[float]:
    """The clear peaks of the FRF no mode accounts for (ModalResult.unexplained_peaks_hz),
    but those a possible mode left out already names (within two lines)."""
    peaks = getattr(result.modal, "unexplained_peaks_hz", None) or []
    return [p for p in peaks if not any(abs(p - f) <= 2 * _line(result) for f, _ in aside)]


def _unexplained_caution(result: RunAnalysis, peaks: list[float], options: AnalysisOptions) -> str:
    """A clear peak without a mode, what it may be, the --band that looks at it alone (but
    where the result's own --band is hardly wider) and the --frequencies that keep what the
    diagram holds there beside the modes found."""
    one = len(peaks) == 1
    p = peaks[0]
    band, listed = _look_band(result, p), ", ".join(f"{f:.4g}" for f in peaks)
    what = "a mode" if one else "modes"
    look = f"look at {'it' if one else 'each'} with --band" + (
        f" {band}" if one else f", e.g. --band {band} for {p:.4g} Hz"
    )
    keep = f"; or keep what the diagram holds there with {_keep_options(result, peaks, options)}"
    low, high = (float(v) for v in band.split(":"))
    given = options.band_hz
    if given is not None and high - low >= LOOKED_BAND_SHARE * (given[1] - given[0]):
        # Its band was given and is hardly wider: the same --band again finds nothing again
        # (a measured beam's 224.6 Hz on 9.8 Hz lines was sent round from band to band, and
        # --frequencies in that band held nothing either).
        look = (
            f"its --band {given[0]:g}:{given[1]:g} already looks at {'it' if one else 'them'} and holds "
            f"nothing: a mode narrower than a line ({_line(result):.3g} Hz) is likely; record longer for "
            "finer lines, or analyse without --band"
        )
        keep = ""
    return (
        f"{'a clear peak' if one else 'clear peaks'} of the FRF at {listed} Hz "
        f"({UNEXPLAINED_SNR_DB:g} dB or more above the noise) {'has' if one else 'have'} no mode, even "
        f"analysed in {'a zone of its own' if one else 'zones of their own'}: {what} the stability diagram "
        f"does not hold (one of a close pair, a mode narrower than a line, or a small mode beside a larger "
        f"one); {look}{keep}"
    )


#: An unexplained peak's caution suggests no --band when the result's own --band is no more
#: than this many times wider than the band it would suggest.
LOOKED_BAND_SHARE = 0.5


def _look_band(result: RunAnalysis, peak_hz: float) -> str:
    """The --band LOW:HIGH a peak's caution suggests: PEAK_BAND_LINES lines or
    PEAK_BAND_FRACTION of its frequency either side, within the lines analysed."""
    low, high = (float(v) for v in result.modal.frequency_hz[[0, -1]])
    reach = max(PEAK_BAND_LINES * _line(result), PEAK_BAND_FRACTION * peak_hz)
    return f"{edge_text(max(low, peak_hz - reach))}:{edge_text(min(high, peak_hz + reach))}"


def _line(result: RunAnalysis) -> float:
    """The line spacing (Hz) of the lines analysed; 0 for fewer than 2."""
    f = result.modal.frequency_hz
    return float(np.median(np.diff(f))) if f.size > 1 else 0.0


def _weak_peaks_caution(result: RunAnalysis, peaks: list[float]) -> str:
    """A peak too shallow for the second pass, without a mode, and the --band for it."""
    one = len(peaks) == 1
    p = peaks[0]
    band, listed = _look_band(result, p), ", ".join(f"{f:.4g}" for f in peaks)
    return (
        f"{'a peak' if one else 'peaks'} of the FRF at {listed} Hz ({WEAK_PEAK_PROMINENCE_DB:g} dB or more "
        f"above the dips beside {'it' if one else 'them'}, {UNEXPLAINED_SNR_DB:g} dB above the noise) "
        f"{'has' if one else 'have'} no mode: the second of a close pair, or a small mode beside a larger "
        "one, may be missing and the modes beside it read wrong; look with --band"
        + (f" {band}" if one else f", e.g. --band {band} for {p:.4g} Hz")
    )


#: The --band an unexplained peak's caution suggests spans this many lines either side of
#: it, or this fraction of its frequency if more (analysis.modal_id.zones.around_peaks).
PEAK_BAND_LINES = 25
PEAK_BAND_FRACTION = 0.1


def set_aside(result: RunAnalysis) -> list[tuple[float, float]]:
    """(frequency Hz, damping ratio) of each chain the spurious test set aside
    (analysis.modal_id.identify.SetAside), the window's decay removed like the modes'."""
    aside = result.modal.set_aside
    if not aside:
        return []
    f, z = correct_pole(
        np.array([a.frequency_hz for a in aside]), np.array([a.damping_ratio for a in aside]),
        result.added_decay_1_s,
    )  # fmt: skip
    return [(float(a), float(b)) for a, b in zip(f, z, strict=True)]


def _match(poles: np.ndarray, wanted: np.ndarray, tolerance_hz: np.ndarray, decay: float) -> np.ndarray:
    """(n_wanted, 2) (frequency Hz, damping) of the pole nearest each wanted frequency,
    window decay removed; NaN where none lies within its tolerance."""
    out = np.full((wanted.size, 2), np.nan)
    if poles.size == 0:
        return out
    w_n = np.abs(poles)
    f, z = correct_pole(w_n / (2 * np.pi), -poles.real / w_n, decay)
    j = np.argmin(np.abs(f[None, :] - wanted[:, None]), axis=1)
    ok = np.abs(f[j] - wanted) <= tolerance_hz
    out[ok, 0], out[ok, 1] = f[j[ok]], z[j[ok]]
    return out


def _tolerances(result: RunAnalysis) -> np.ndarray:
    """How far (Hz) a pole may lie from each mode and still be it: HIT_MATCH_TOLERANCE,
    at most half the gap to the nearest other mode, at least one line."""
    wanted = np.array([m.frequency_hz for m in result.modes])
    gap = np.full(wanted.size, np.inf)
    if wanted.size > 1:
        d = np.abs(wanted[:, None] - wanted[None, :])
        np.fill_diagonal(d, np.inf)
        gap = d.min(axis=1)
    line = float(np.median(np.diff(result.modal.frequency_hz)))
    return np.maximum(np.minimum(HIT_MATCH_TOLERANCE * wanted, 0.5 * gap), line)


def _zone_fits(
    result: RunAnalysis, frf: np.ndarray, weights: np.ndarray | None, normalisation: str, wanted: np.ndarray,
    zones: list[Zone] | None = None,
):  # fmt: skip
    """Per zone holding one of the ``wanted`` modes (Hz): the LSCF poles of ``frf``
    (n_lines_used,) or (n_frf, n_lines_used), all FRFs sharing one denominator
    normalised as ``normalisation``, at the top SCATTER_ORDERS orders of the zone
    (``zones``, default the result's)."""
    f = result.modal.frequency_hz
    h = np.atleast_2d(frf)
    # A zone whose core a clear peak's own zone cut in two is listed once per piece: the
    # same lines and order, fitted once.
    zones = result.modal.zones if zones is None else zones
    fitted = {(z.low_hz, z.high_hz, z.max_order, z.basis): z for z in zones}
    for zone in fitted.values():
        if not np.any((wanted >= zone.low_hz) & (wanted <= zone.high_hz)):
            continue
        use = (f >= zone.low_hz) & (f <= zone.high_hz) & np.all(np.isfinite(h), axis=0)
        top = min(zone.max_order, (int(use.sum()) - 2) // (2 if zone.basis == "real" else 1))
        orders = tuple(range(max(1, top - SCATTER_ORDERS + 1), top + 1))
        w = None if weights is None else weights[use]
        try:
            fit = lscf_poles(f[use], h[:, use], top, orders=orders, basis=zone.basis, weights=w,
                             normalisation=normalisation)  # fmt: skip
        except (ValueError, np.linalg.LinAlgError):
            continue  # a hit too poor to fit alone adds nothing to the scatter
        yield [fit.poles[o - 1] for o in orders]


def _estimates(result: RunAnalysis, frf: np.ndarray, decay: float, weights=None, zones=None) -> np.ndarray:
    """(n_modes, 2): each mode's (frequency, damping) in ``frf`` (one FRF, or several
    sharing their poles), the median over the top orders of its zone (``zones``, default
    the result's) of the pole nearest it (NaN: not found)."""
    wanted = np.array([m.frequency_hz for m in result.modes])
    tol = _tolerances(result)
    # Each mode is found again with the normalisation it was read with.
    normalisation = np.array([m.quality.get("normalisation", "highest") for m in result.modes])
    found = []
    for norm in dict.fromkeys(normalisation):
        mine = normalisation == norm
        for per_order in _zone_fits(result, frf, weights, norm, wanted[mine], zones):
            for p in per_order:
                row = np.full((wanted.size, 2), np.nan)
                row[mine] = _match(p, wanted[mine], tol[mine], decay)
                found.append(row)
    if not found:
        return np.full((wanted.size, 2), np.nan)
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN: that mode not found
        return np.nanmedian(np.array(found), axis=0)


def _order_spread(result: RunAnalysis, k: int) -> tuple[float, float]:
    """Standard deviation of mode k's frequency (Hz) and damping over the top orders of
    its zone: the part of the uncertainty the choice of model order makes (0 if unknown)."""
    q = result.modes[k].quality
    f, z = q.get("frequency_spread_top_hz", np.nan), q.get("damping_spread_top", np.nan)
    return (float(f) if np.isfinite(f) else 0.0, float(z) if np.isfinite(z) else 0.0)


def _scatter(
    result: RunAnalysis, hit_frfs: np.ndarray, options: AnalysisOptions, decay: float,
    hit_weights: np.ndarray | None = None,
) -> None:  # fmt: skip
    """Each mode's spread over the accepted hits, each hit's FRF fitted alone, and its
    standard uncertainty.

    Each hit is fitted by LSCF at the top SCATTER_ORDERS orders of each zone holding a
    mode; each mode takes, at each order, the hit's pole nearest to it, and the median
    over the orders (one order alone makes the spread depend on which order was picked).
    The standard uncertainty of the averaged result combines the spread over the hits
    with the spread of the mode's cluster over the orders. hit_weights (n_hits, n_lines):
    how much each hit counts in the averaged FRF at each line (H1: its force power); the
    hits' values are weighed alike where not given (_mean_u).
    """
    keep = np.isin(result.frequency_hz, result.modal.frequency_hz)
    found = np.array([_estimates(result, h[keep], decay) for h in hit_frfs])  # (n_hits, n_modes, 2)
    _refine_per_hit(result, hit_frfs[:, keep], decay, found)
    for k, mode in enumerate(result.modes):
        ok = np.isfinite(found[:, k, 0]) & np.isfinite(found[:, k, 1])
        mode.n_hits_matched = int(ok.sum())
        if ok.sum() >= 2:
            mode.frequency_std_hz = float(np.std(found[ok, k, 0], ddof=1))
            mode.damping_std = float(np.std(found[ok, k, 1], ddof=1))
            f_order, z_order = _order_spread(result, k)
            weights = None
            if hit_weights is not None:
                line = int(np.argmin(np.abs(result.frequency_hz - mode.frequency_hz)))
                weights = hit_weights[ok, line]
            n = ok.sum()
            f_bias = _noise_bias(found[ok, k, 0], mode.frequency_hz, weights)
            z_bias = _noise_bias(found[ok, k, 1], mode.damping_ratio, weights)
            # The damping's bias is LSCF's known one (docs/analysis.md): corrected, and
            # its size kept in the u, as the correction is only as good as its model.
            if mode.damping_ratio - z_bias > 0:
                mode.damping_ratio -= z_bias
                mode.damping_ratio_windowed -= z_bias
                mode.quality["noise_bias_damping"] = z_bias
            f_u = [_mean_u(found[ok, k, 0], weights), f_order, f_bias]
            z_u = [_mean_u(found[ok, k, 1], weights), z_order, z_bias]
            mode.frequency_u_hz = float(np.sqrt(np.sum(np.square(f_u))))
            mode.damping_u = float(np.sqrt(np.sum(np.square(z_u))))
            mode.uncertainty_from = f"{n} hits" if n == len(hit_frfs) else f"{n} of {len(hit_frfs)} hits"
    if any(m.uncertainty_from == "" for m in result.modes):
        _bootstrap(result, decay, only_missing=True)


#: The noise bias is read only where the hits count as more than this many: with two,
#: the hits' mean less the average is divided by at most 1 and is mostly their scatter
#: (lvm-2ch m2's 21.2 Hz, 2 hits: 0.21 % "corrected" to 0.11 +- 0.14 %).
NOISE_BIAS_MIN_HITS = 2.5


def _noise_bias(values: np.ndarray, averaged: float, weights: np.ndarray | None = None) -> float:
    """The bias the noise gives ``averaged``, the value read from the hits' averaged FRF,
    estimated from ``values`` (n,), the same quantity read from each hit alone.

    A least-squares fit with the measured H inside its equations is biased in proportion
    to the noise variance in H; one hit's FRF holds n_eff times the variance of the
    average of n_eff hits (n_eff = 1 / sum w^2, w the hits' weights summing to 1), so the
    hits' mean sits n_eff - 1 biases of the average away from it:
    bias = (sum w x - averaged) / (n_eff - 1). A heavily damped mode (300 Hz at 8 %, 5
    hits at 5 % noise) read 6.3-7.6 % from the average and 3-6 % hit by hit: the spread
    over hits put the truth more than 2 u away in 8 of 20 draws, 9 u at worst. 0 where n_eff <=
    NOISE_BIAS_MIN_HITS."""
    n = values.size
    usable = weights is not None and np.all(np.isfinite(weights)) and weights.sum() > 0
    w = weights / weights.sum() if usable else np.full(n, 1.0 / n)
    n_eff = 1.0 / float(np.sum(w**2))
    if n_eff <= NOISE_BIAS_MIN_HITS:
        return 0.0
    return float((np.sum(w * values) - averaged) / (n_eff - 1.0))


def _mean_u(values: np.ndarray, weights: np.ndarray | None = None) -> float:
    """The standard uncertainty of the weighted mean of ``values`` (n,), n >= 2, from
    their own scatter: s sqrt(sum w_i^2), s their sample standard deviation, w summing
    to 1 (equal weights: the familiar s / sqrt(n)). A weighted mean of n values counts
    as (sum w)^2 / sum w^2 of them where each value is as noisy as the others (a
    response whose noise grows with the hit); where the weak hits are the noisier ones
    (a sensor's noise floor), H1's weights are the best and this reads high, never low."""
    n = values.size
    usable = weights is not None and np.all(np.isfinite(weights)) and weights.sum() > 0
    w = weights / weights.sum() if usable else np.full(n, 1.0 / n)
    return float(np.std(values, ddof=1) * np.sqrt(np.sum(w**2)))


def _refine_per_hit(result: RunAnalysis, hit_frfs: np.ndarray, decay: float, found: np.ndarray) -> None:
    """Each hit's (frequency, damping) of each mode in ``found`` (n_hits, n_modes, 2),
    where LSCF found it in that hit, replaced by the pole refined on that hit's FRF
    (n_hits, n_lines used) from the averaged FRF's refined poles, as the averaged
    result's were (analysis.modal_id.refine): the spread over hits is then the spread of
    the estimator that gave the value, not of LSCF's, whose noise bias differs."""
    for k, frf in enumerate(hit_frfs):
        finite = np.isfinite(frf)
        _refined_estimates(result, frf[finite], result.modal.frequency_hz[finite], decay, found[k])


def _refined_estimates(result: RunAnalysis, frf, frequency_hz, decay: float, found, noise=None) -> None:
    """``found`` (n_modes, 2), the (frequency, damping) of each mode in ``frf`` (n_lines,)
    or (n_frf, n_lines) on ``frequency_hz``: for each mode refined in the result where
    LSCF found it in ``frf`` (or it was added, refine.missing), replaced by its pole
    refined on ``frf`` from the result's (noise: refine_poles' noise_std, the
    bootstrap's weights)."""
    refine = np.array([bool(m.quality.get("refined")) for m in result.modes], dtype=bool)
    added = np.array([bool(m.quality.get("added")) for m in result.modes], dtype=bool)
    poles = np.array([m.pole for m in result.modes], dtype=complex)
    if not refine.any() or not np.all(np.isfinite(poles)) or frequency_hz.size < 2:
        return
    line = float(np.median(np.diff(frequency_hz)))
    new, done = refine_poles(frequency_hz, frf, poles, line, noise, refine=refine)
    w_n = np.abs(new)
    f_true, z_true = correct_pole(w_n / (2 * np.pi), -new.real / w_n, decay)
    # A mode added among close ones (refine.missing) has no LSCF pole to be found by.
    use = done & (np.isfinite(found[:, 0]) | added)
    found[use, 0], found[use, 1] = f_true[use], z_true[use]


#: The zone ends' moves of _zone_spread, as a fraction of each zone's width.
ZONE_SHIFT = 0.1
#: Both ends out, both in, the zone slid down and up.
ZONE_SHIFTS = ((-1, 1), (1, -1), (-1, -1), (1, 1))


#: A moved zone's reading is of the same mode when within this many half-power
#: half-widths (f zeta) of it, plus SAME_MODE_LINES lines (_zone_spread).
SAME_MODE_HALF_WIDTHS = 2.0
SAME_MODE_LINES = 2.0


def _zone_spread(result: RunAnalysis, decay: float) -> None:
    """Add to each mode's standard uncertainty the part the choice of band makes: the
    mode read again (as _estimates, refined as the result's) with the ends of every zone
    moved by ZONE_SHIFT of its width (ZONE_SHIFTS, within the lines analysed); the
    sample standard deviation of those readings and the mode's own value.

    Why: the scatter over hits and the bootstrap over lines see the noise, not the
    modes the model leaves out. Where those matter (heavily damped modes among
    smaller ones, a synthesis error of 30 %) a mode moves with the band by many times
    its noise: the tool holder's 1968.0 Hz read 1965.4-1972.7 Hz as the band changed,
    with ± 0.7 Hz. Where the model holds, the readings agree and nothing is added."""
    f = result.modal.frequency_hz
    if not result.modes or f.size < 2:
        return
    keep = np.isin(result.frequency_hz, f)
    frf = result.frf[:, keep]
    readings = []
    for low_sign, high_sign in ZONE_SHIFTS:
        zones = []
        for z in result.modal.zones:
            width = z.high_hz - z.low_hz
            low = max(f[0], z.low_hz + low_sign * ZONE_SHIFT * width)
            high = min(f[-1], z.high_hz + high_sign * ZONE_SHIFT * width)
            zones.append(replace(z, low_hz=float(low), high_hz=float(high)))
        found = _estimates(result, frf, decay, zones=zones)
        _refined_estimates(result, frf, f, decay, found)
        readings.append(found)
    readings = np.array(readings)  # (len(ZONE_SHIFTS), n_modes, 2)
    line = float(np.median(np.diff(f)))
    for k, mode in enumerate(result.modes):
        ok = np.all(np.isfinite(readings[:, k, :]), axis=1)
        # Another pole that a moved zone matched to this mode is no reading of it: on a
        # 0.01 % mode of a 51,201-line FRF a moved zone's 602.2 Hz was taken for 596.4 Hz
        # and made its ± 2.6 Hz. The same mode stays within its half-power band.
        same = SAME_MODE_HALF_WIDTHS * mode.frequency_hz * abs(mode.damping_ratio) + SAME_MODE_LINES * line
        ok &= np.abs(readings[:, k, 0] - mode.frequency_hz) <= same
        if not ok.any() or not (np.isfinite(mode.frequency_u_hz) and np.isfinite(mode.damping_u)):
            continue
        values = np.vstack([readings[ok, k, :], [[mode.frequency_hz, mode.damping_ratio]]])
        spread_f, spread_zeta = np.std(values, axis=0, ddof=1)
        mode.frequency_u_hz = float(np.hypot(mode.frequency_u_hz, spread_f))
        mode.damping_u = float(np.hypot(mode.damping_u, spread_zeta))


#: How far apart the pole's two uncertainties may be before the smaller is raised
#: (_circular_pole_floor).
POLE_UNCERTAINTY_RATIO = 3.0


def _circular_pole_floor(result: RunAnalysis) -> None:
    """Raise the smaller of a mode's two standard uncertainties to 1/POLE_UNCERTAINTY_RATIO
    of the other, in the pole's terms: u_f (Hz) against f u_zeta (Hz).

    The least-squares estimate of an isolated mode's pole -zeta w + j w sqrt(1 - zeta^2)
    is as uncertain in its real part as in its imaginary part (the FRF near a resonance
    is a circle in the complex plane), so u_f = f u_zeta; on simulated hits the medians
    of f u_zeta / u_f are 1.0-1.2 (tests/analysis/test_uncertainty_coverage.py's four
    modes, 10 draws). Where one
    reads over 3 times the other, the smaller misses something the larger saw: on the
    tool-holder-like FRFs of bench/heavy_damping_coverage.py a mode read with alpha_0 = 1
    came out 11 Hz low with u_f = 1.05 Hz and f u_zeta = 19 Hz. Neither is ever lowered."""
    for mode in result.modes:
        u_f, u_zeta, f = mode.frequency_u_hz, mode.damping_u, mode.frequency_hz
        if np.isfinite(u_f) and np.isfinite(u_zeta) and f > 0:
            mode.frequency_u_hz = max(u_f, f * u_zeta / POLE_UNCERTAINTY_RATIO)
            mode.damping_u = max(u_zeta, u_f / f / POLE_UNCERTAINTY_RATIO)


#: Replicates of the bootstrap over lines.
BOOTSTRAP_REPLICATES = 20


def _bootstrap(result: RunAnalysis, decay: float, only_missing: bool = False) -> None:
    """Standard uncertainty of each mode from one averaged FRF: the FRFs' lines are
    resampled (each line counted a Poisson(1) number of times, a bootstrap over the lines)
    and each replicate fitted as the hits are in _scatter (all FRFs together, sharing
    their poles); the spread over the replicates,
    with the spread over model orders. Seeded: the same run gives the same figures."""
    rng = np.random.default_rng(20261124)
    keep = np.isin(result.frequency_hz, result.modal.frequency_hz)
    frf = result.frf[:, keep]
    n_lines = frf.shape[1]
    found = []
    lines = result.modal.frequency_hz
    for _ in range(BOOTSTRAP_REPLICATES):
        weights = rng.poisson(1.0, n_lines).astype(float)
        # All FRFs in one fit, as the run's poles were found: one solve per zone.
        estimates = _estimates(result, frf, decay, weights)
        with np.errstate(divide="ignore"):
            _refined_estimates(result, frf, lines, decay, estimates, noise=1.0 / np.sqrt(weights))
        found.append(estimates)
    found = np.array(found)  # (B, n_modes, 2)
    for k, mode in enumerate(result.modes):
        if only_missing and mode.uncertainty_from:
            continue
        ok = np.isfinite(found[:, k, 0]) & np.isfinite(found[:, k, 1])
        if ok.sum() >= 3:
            f_order, z_order = _order_spread(result, k)
            mode.frequency_u_hz = float(np.hypot(np.std(found[ok, k, 0], ddof=1), f_order))
            mode.damping_u = float(np.hypot(np.std(found[ok, k, 1], ddof=1), z_order))
            mode.uncertainty_from = "bootstrap over lines"
