"""Automatic modal identification: LSCF poles -> stability diagram -> clusters -> LSFD.

identify_modes() is the top level; see lscf, stability and lsfd for the pieces and
their definitions (model order = number of pole pairs; status codes; residual terms).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from analysis.modal_id.lscf import lscf_poles
from analysis.modal_id.lsfd import FORMS, lsfd
from analysis.modal_id.refine import missing, missing_beside_heavy, redundant, refine_poles, to_refine
from analysis.modal_id.stability import (
    Cluster,
    cluster_poles,
    frequency_damping,
    pick_clusters,
    stability_diagram,
)
from analysis.modal_id.zones import (
    PEAK_PROMINENCE_DB,
    Zone,
    around_peaks,
    indicator_peaks,
    mode_indicator,
    plan_zones,
)


@dataclass
class ModeQuality:
    """n_stable_orders: stable links of the mode's cluster; *_scatter_rel: std/median of
    the cluster's frequencies and damping ratios; synthesis_share: energy of the mode's
    term (both poles of the pair) over the sum of the energies of all terms of the
    synthesis (modes and residuals), over the FRFs and lines used; accepted: False for
    a cluster picked for a frequency of interest that failed a selection rule (too few
    stable orders, ...); refined: the pole was refined on the FRF (analysis.modal_id.refine),
    not LSCF's; added: a mode LSCF missed among close ones or beside a heavily damped
    one, found by refitting them (refine.missing, refine.missing_beside_heavy), with no
    cluster (n_stable_orders 0, scatters NaN); for_peak: kept by the third pass for a
    clear peak of the FRF no other mode accounts for (_kept_for_peaks), whether or not its
    chain passed the selection rules; *_spread_top:
    standard deviation of the cluster's frequency (Hz) and damping over its poles in the
    top TOP_ORDERS orders of its zone (the models a result is read from; the lowest
    orders of a chain are still immature), with,
    for a mode read with the second normalisation (NORMALISATIONS), the standard deviation
    of its reading and the first normalisation's poles near it added in quadrature)."""

    n_stable_orders: int
    frequency_scatter_rel: float
    damping_scatter_rel: float
    synthesis_share: float
    accepted: bool = True
    refined: bool = False
    frequency_spread_top_hz: float = float("nan")
    damping_spread_top: float = float("nan")
    added: bool = False
    for_peak: bool = False


@dataclass
class Mode:
    """frequency_hz: undamped natural frequency; pole: rad/s, lambda = -zeta w_n + j w_n
    sqrt(1 - zeta^2); modal_constant (n_frf,) complex residue A with
    H(jw) = sum_r A_r/(jw - lambda_r) + conj(A_r)/(jw - conj(lambda_r)) (+ residuals),
    in the FRF's units times rad/s."""

    frequency_hz: float
    damping_ratio: float
    pole: complex
    modal_constant: np.ndarray
    quality: ModeQuality
    normalisation: str | None = "highest"  # None: an added mode, read from no LSCF fit


@dataclass
class SetAside:
    """A stable chain left out by spurious_check although removing it worsens the fit
    near it: frequency_hz (Hz), damping_ratio, n_stable_orders, normalisation, and
    worse: how many times the misfit near it grows without it (the others refitted)."""

    frequency_hz: float
    damping_ratio: float
    n_stable_orders: int
    normalisation: str
    worse: float


@dataclass
class StabilityDiagram:
    """orders (n_orders,) pole pairs of each model; poles per order, complex rad/s;
    status per order, one code per pole ("stable", "damping", "frequency", "new", see
    analysis.modal_id.stability); selected_cluster per order: index into
    ModalResult.modes of the mode each pole belongs to, or -1; normalisation per order:
    the LSCF normalisation (NORMALISATIONS) of the fit each pole comes from (every zone
    is fitted once with each, so an order holds the poles of both fits)."""

    orders: np.ndarray
    poles: list[np.ndarray]
    status: list[np.ndarray]
    selected_cluster: list[np.ndarray]
    normalisation: list[np.ndarray] = field(default_factory=list)


@dataclass
class ModalResult:
    """frequency_hz (n_lines,) the lines used; modes sorted by frequency; synthesized
    (n_frf, n_lines); residuals {"lower", "upper"}: (n_frf,) complex coefficients of the
    residual terms (analysis.modal_id.lsfd); synthesis_error ||H - H_syn|| / ||H||;
    set_aside: SetAside chains that passed every stability rule and improve the fit near
    them, but fell below the spurious test's thresholds (spurious_check): not modes of
    the result, candidates the user may keep with frequencies_hz; unexplained_peaks_hz:
    clear peaks of the FRF no mode accounts for (unexplained_peaks), after the second
    pass that looks at them in zones of their own; weak_peaks_hz: peaks of the FRF as
    clear but only WEAK_PEAK_PROMINENCE_DB above the dips beside them (no second pass),
    that no mode accounts for."""

    frequency_hz: np.ndarray
    modes: list[Mode]
    synthesized: np.ndarray
    residuals: dict
    synthesis_error: float
    stability: StabilityDiagram
    method: str
    zones: list = field(default_factory=list)
    set_aside: list = field(default_factory=list)
    unexplained_peaks_hz: list = field(default_factory=list)
    weak_peaks_hz: list = field(default_factory=list)


def _check_inputs(frequency_hz, frf, band, max_order, form):
    f = np.asarray(frequency_hz, dtype=float)
    h = np.asarray(frf)
    if f.ndim != 1 or f.size < 4:
        raise ValueError(f"frequency_hz must be a 1-D array of at least 4 lines, got shape {f.shape}")
    if not np.all(np.isfinite(f)) or np.any(np.diff(f) <= 0) or f[0] < 0:
        raise ValueError("frequency_hz must be finite, non-negative and strictly increasing")
    if h.ndim not in (1, 2) or h.shape[-1] != f.size or h.size == 0:
        raise ValueError(f"frf must have shape ({f.size},) or (n_frf, {f.size}), got {h.shape}")
    h = np.atleast_2d(h.astype(complex))
    if not np.all(np.isfinite(h)):
        raise ValueError("frf holds non-finite values")
    if form not in FORMS:
        raise ValueError(f"form must be one of {', '.join(FORMS)}, got {form!r}")
    if max_order is not None and (not isinstance(max_order, int | np.integer) or max_order < 2):
        raise ValueError(f"max_order must be an integer >= 2, got {max_order!r}")
    if band is None:
        band = (float(f[0]), float(f[-1]))
    f1, f2 = map(float, band)
    if not f1 < f2:
        raise ValueError(f"band must be (f1, f2) with f1 < f2, got {band}")
    use = (f >= f1) & (f <= f2)
    # A zone's order is cut to what its lines hold (_fit_zone); an order given must fit.
    need = 2 * (max_order or 2) + 2
    if use.sum() < need:
        most = (int(use.sum()) - 2) // 2
        raise ValueError(
            f"band {f1:.6g}-{f2:.6g} Hz holds {use.sum()} lines; an LSCF of order {max_order or 2} needs at "
            f"least {need}: widen the band"
            + (f" or give --max-order {most} or less" if max_order and most >= 2 else "")
        )
    return f, h, (f1, f2), use


@dataclass
class _ZoneFit:
    zone: Zone
    fit: object
    status: list
    clusters: list
    label: list
    normalisation: str = "highest"


#: The LSCF denominator normalisations fitted in every zone, the first preferred
#: (analysis.modal_id.lscf): "highest" reads lightly damped, well-resolved modes best;
#: "lowest" keeps the chains of heavily damped modes in noisy data steady. A mode is read
#: from the first that holds it stable; the second adds only the modes the first misses.
NORMALISATIONS = ("highest", "lowest")
#: Each normalisation as the coefficient it fixes.
DENOMINATOR = {"highest": "alpha_p = 1", "lowest": "alpha_0 = 1"}


def _fit_zone(f, h, zone, freq_tol, damping_tol, vector_tol, min_stable_orders, max_damping, line_hz,
              normalisation="highest"):  # fmt: skip
    use = (f >= zone.low_hz) & (f <= zone.high_hz)
    order = min(zone.max_order, (int(use.sum()) - 2) // (2 if zone.basis == "real" else 1))
    fit = lscf_poles(f[use], h[:, use], order, basis=zone.basis, normalisation=normalisation)
    status, partner = stability_diagram(fit.poles, fit.residues, freq_tol, damping_tol, vector_tol, line_hz)
    min_orders = min_stable_orders if min_stable_orders is not None else max(4, order // 5)
    clusters, label = cluster_poles(
        fit.poles, status, partner, (zone.low_hz, zone.high_hz), freq_tol=freq_tol, damping_tol=damping_tol,
        min_stable_orders=min_orders, max_damping=max_damping, line_hz=line_hz,
    )  # fmt: skip
    return _ZoneFit(zone, fit, status, clusters, label, normalisation)


def identify_modes(
    frequency_hz: np.ndarray,
    frf: np.ndarray,
    band: tuple[float, float] | None = None,
    max_order: int | None = None,
    frequencies_hz: np.ndarray | None = None,
    form: str = "accelerance",
    *,
    freq_tol: float = 0.01,
    damping_tol: float = 0.05,
    vector_tol: float = 0.1,
    min_stable_orders: int | None = None,
    max_damping: float = 0.3,
    zones: list[Zone] | None = None,
    noise_std: np.ndarray | None = None,
    refine: bool = True,
) -> ModalResult:
    """Find the modes of FRFs without being told how many.

    frequency_hz (n_lines,) Hz, increasing; frf (n_lines,) or (n_frf, n_lines) complex
    in the units of ``form`` (accelerance: (m/s^2)/N); band (f1, f2) Hz, default all
    lines; max_order: the LSCF order of every zone, default from each zone's peaks
    (analysis.modal_id.zones); frequencies_hz: if given, the cluster nearest each is
    selected instead of every accepted cluster. Tolerances are relative, the damping
    tolerance widened to a fraction of a line (analysis.modal_id.stability).
    min_stable_orders defaults to max(4, zone order // 5). zones: given zones instead of
    planning them. noise_std (n_lines,) or (n_frf, n_lines): the standard deviation of
    the noise of ``frf`` at each line, in its units (from the scatter over hits), which
    names the possible modes left out (spurious_check); default: read from the FRF's
    second differences, right only where the noise is uncorrelated between lines.
    refine: the poles of close, lightly damped modes (refine.to_refine) refined by
    nonlinear least squares on the FRF, lines weighted alike (analysis.modal_id.refine);
    a mode's frequency and damping are its pole's. Where the zones were planned here and
    no frequencies were asked for, a clear peak no mode accounts for (unexplained_peaks)
    gets a zone of its own (zones.around_peaks) and the identification is made again;
    the peaks still unexplained are the result's unexplained_peaks_hz. Raises ValueError
    on bad inputs.
    """
    f, h, band, use = _check_inputs(frequency_hz, frf, band, max_order, form)
    fu, hu = f[use], h[:, use]
    noise_u = _check_noise(noise_std, h.shape, use)
    line_hz = float(np.median(np.diff(fu)))
    planned = zones is None
    if planned:
        zones = plan_zones(fu, hu, max_order)
    args = (form, freq_tol, damping_tol, vector_tol, min_stable_orders, max_damping, noise_u, refine, line_hz)
    result = _identify_in_zones(fu, hu, zones, frequencies_hz, *args)
    if not planned:
        return result
    if frequencies_hz is not None:
        # A clear peak no mode accounts for near a frequency asked for (unexplained_peaks
        # of the reading without the ask) is read in a zone of its own, as the second
        # pass reads it (a 3 Hz mode at 3 % in a 0.25-800 Hz band: 7 +- 5.7 % from a
        # chain over 2 orders, 3.0 % in its zone). A frequency with no clear peak keeps
        # the first reading: a zone of its own would fit the noise there.
        asked = np.atleast_1d(np.asarray(frequencies_hz, dtype=float))
        shaky = [f_ask for f_ask in asked if not _stable_near(result, f_ask, line_hz)]
        if shaky:
            unasked = _identify_in_zones(fu, hu, zones, None, *args)
            peaks = [p for p in unexplained_peaks(fu, hu, unasked, line_hz, noise_u)
                     if any(abs(p - f_ask) <= ASKED_PEAK_TOLERANCE * f_ask for f_ask in shaky)]  # fmt: skip
            if peaks:
                local = around_peaks(fu, zones, peaks, line_hz, max_order)
                result = _identify_in_zones(fu, hu, local, frequencies_hz, *args)
        return result
    peaks = unexplained_peaks(fu, hu, result, line_hz, noise_u)
    if peaks:
        # A second pass, as a user would take it with --band: each clear peak no mode
        # accounts for in a zone of its own, the modes elsewhere read as before.
        local = around_peaks(fu, zones, peaks, line_hz, max_order)
        result = _identify_in_zones(fu, hu, local, None, *args)
        result.unexplained_peaks_hz = unexplained_peaks(fu, hu, result, line_hz, noise_u)
        if result.unexplained_peaks_hz:
            result = _kept_for_peaks(fu, hu, local, result, args, line_hz, max_order)
    # Peaks too shallow for a second pass (which moves the zones, and with them modes
    # elsewhere: pyfrf-impact lost 5074 Hz at 6 dB) are named, not looked at.
    weak = unexplained_peaks(fu, hu, result, line_hz, noise_u, WEAK_PEAK_PROMINENCE_DB)
    result.weak_peaks_hz = [
        p for p in weak if all(abs(p - q) > 2 * line_hz for q in result.unexplained_peaks_hz)
    ]
    return result


#: A third pass keeps what the diagram holds at the clear peaks still unexplained only
#: when the synthesis error falls to this fraction of the second pass's or below.
PEAK_PASS_GAIN = 0.9


def _kept_for_peaks(fu, hu, zones, result: ModalResult, args, line_hz: float, max_order) -> ModalResult:
    """The third pass: what the stability diagram holds nearest each clear peak still
    unexplained, kept beside the modes found, as --frequencies keeps it (the modes found
    and the peaks asked for, the peaks in zones of their own); ``result`` unchanged unless
    every mode found is found again, a mode stands at each peak, and the synthesis error
    falls to PEAK_PASS_GAIN of result's. The modes kept for a peak are marked
    (ModeQuality.for_peak)."""
    peaks = list(result.unexplained_peaks_hz)
    found = [m.frequency_hz for m in result.modes]
    asked = np.array(sorted(found + peaks))
    local = around_peaks(fu, zones, peaks, line_hz, max_order)
    trial = _identify_in_zones(fu, hu, local, asked, *args)
    trial_f = np.array([m.frequency_hz for m in trial.modes])

    def near(f: float, width: float) -> np.ndarray:
        return np.abs(trial_f - f) <= max(width, 2 * line_hz)

    if trial_f.size != asked.size:
        return result
    again = [int(np.argmin(np.abs(trial_f - m.frequency_hz))) for m in result.modes]
    for m, k in zip(result.modes, again, strict=True):
        if not near(m.frequency_hz, m.damping_ratio * m.frequency_hz)[k]:
            return result
    new = [int(np.argmin(np.abs(trial_f - p))) for p in peaks]
    if any(not near(p, 0.0)[k] or k in again for p, k in zip(peaks, new, strict=True)):
        return result
    if not trial.synthesis_error <= PEAK_PASS_GAIN * result.synthesis_error:
        return result
    for k in new:
        trial.modes[k].quality.for_peak = True
    trial.set_aside = result.set_aside
    trial.unexplained_peaks_hz = unexplained_peaks(fu, hu, trial, line_hz, args[6])
    return trial


#: A clear peak this close (relative) to a frequency asked for is read in its own zone.
ASKED_PEAK_TOLERANCE = 0.05


def _stable_near(result: ModalResult, frequency_hz: float, line_hz: float) -> bool:
    """True when a mode of ``result`` that passed every selection rule lies within its
    half-power half-width (at least 2 lines) of ``frequency_hz`` (Hz)."""
    return any(
        m.quality.accepted
        and abs(m.frequency_hz - frequency_hz) <= max(m.damping_ratio * m.frequency_hz, 2 * line_hz)
        for m in result.modes
    )


def _identify_in_zones(
    fu, hu, zones, frequencies_hz, form, freq_tol, damping_tol, vector_tol, min_stable_orders, max_damping,
    noise_u, refine, line_hz,
) -> ModalResult:  # fmt: skip
    """identify_modes on the lines used ``fu`` (n_lines,) Hz, ``hu`` (n_frf, n_lines), in
    the given zones (the rest as identify_modes' arguments)."""
    fits = [
        _fit_zone(fu, hu, z, freq_tol, damping_tol, vector_tol, min_stable_orders, max_damping, line_hz, n)
        for n in NORMALISATIONS
        for z in zones
    ]
    # Every cluster of every zone whose frequency lies in the zone's core, by global index.
    clusters: list[Cluster] = []
    owner: list[tuple[int, int]] = []  # (fit, cluster within the fit)
    for zi, zf in enumerate(fits):
        for ci, c in enumerate(zf.clusters):
            if zf.zone.in_core(c.frequency_hz, zf.zone == zones[-1]):
                clusters.append(c)
                owner.append((zi, ci))
    _drop_second_opinions(clusters, [fits[zi].normalisation for zi, _ in owner], freq_tol)
    freqs = None if frequencies_hz is None else np.atleast_1d(np.asarray(frequencies_hz, dtype=float))
    chosen = pick_clusters(clusters, freqs, line_hz=line_hz)
    if freqs is not None:
        chosen = _one_per_mode(clusters, chosen, line_hz)
    poles = np.array([clusters[c].pole for c in chosen], dtype=complex)
    est = lsfd(fu, hu, poles, form)
    set_aside: list[SetAside] = []
    if poles.size:
        keep, worse, candidate = spurious_check(fu, hu, poles, est, form, line_hz, noise_u)
        if freqs is not None:
            # Asked for: an accepted cluster stays where it is at least worth naming (a
            # broad mode the test drops, SET_ASIDE_RATIO); one that failed a selection rule
            # must be a feature of the data. A chain stable over 8 orders on an
            # antiresonance (a new user's 117.4 Hz, 3.4e-05 % of the synthesis, asked for
            # with --frequencies 120) is neither: "no mode found within 5 %" says so.
            keep |= np.array([clusters[c].accepted for c in chosen], dtype=bool) & candidate
        for c, k, w, cand in zip(chosen, keep, worse, candidate, strict=True):
            if k:
                continue
            clusters[c].accepted, clusters[c].reason = (
                False,
                "no feature in the data: removing it does not worsen the fit",
            )
            if freqs is None and cand:
                cl = clusters[c]
                norm = fits[owner[c][0]].normalisation
                set_aside.append(
                    SetAside(cl.frequency_hz, cl.damping_ratio, cl.n_stable_orders, norm, float(w))
                )
        chosen = [c for c, k in zip(chosen, keep, strict=True) if k]
        changed = not keep.all()
        poles = poles[keep]
    else:
        changed = False
    if poles.size > 1 and refine and freqs is None:
        # A pole a refined close group does as well without (refine.redundant).
        extra = redundant(fu, hu, poles, line_hz, to_refine(poles))
        for c in np.asarray(chosen)[extra]:
            clusters[c].accepted, clusters[c].reason = (
                False,
                "redundant: the close modes beside it, refined, fit the FRF as well without it",
            )
        chosen = [c for c, x in zip(chosen, extra, strict=True) if not x]
        poles = poles[~extra]
        changed = changed or bool(extra.any())
    beside_heavy = np.zeros(poles.size, dtype=bool)
    if poles.size and refine and freqs is None:
        # A mode LSCF missed among close ones (refine.missing), or beside a heavily damped
        # one (refine.missing_beside_heavy): a pole with no chain.
        added = missing(fu, hu, poles, line_hz, to_refine(poles))
        before = np.concatenate([poles, added])
        heavy_added, parent = missing_beside_heavy(fu, hu, before, line_hz)
        if heavy_added.size:
            # A pole added must stand above the noise as a mode set aside must (spurious_check):
            # the F test reads the misfit's lines as independent, which windowed hits'
            # noise, smooth over lines, is not.
            both = np.concatenate([before, heavy_added])
            keep, _, worth_naming = spurious_check(
                fu, hu, both, lsfd(fu, hu, both, form), form, line_hz, noise_u
            )
            kept = keep | worth_naming
            heavy_added, parent = heavy_added[kept[before.size :]], parent[kept[before.size :]]
        if heavy_added.size:
            # ... and hold where it is refined from its own value, as each hit or bootstrap
            # replicate is refined for its ±: on the tool holder a pole added beside 1073
            # Hz settled at 1300 Hz and, refined again, ran to the 1968 Hz mode.
            heavy_added, parent = _holding(fu, hu, before, heavy_added, parent, line_hz)
        if added.size or heavy_added.size:
            order = np.argsort(np.abs(np.concatenate([before, heavy_added])))
            poles = np.concatenate([before, heavy_added])[order]
            sources: list[int | None] = [*chosen, *[None] * (added.size + heavy_added.size)]
            chosen = [sources[k] for k in order]
            mark = np.zeros(before.size + heavy_added.size, dtype=bool)
            mark[parent] = True
            mark[before.size :] = True
            beside_heavy = mark[order]
            changed = True
    refined = np.zeros(poles.size, dtype=bool)
    if poles.size and refine:
        # Close modes' LSCF poles carry a bias from the noise in H (analysis.modal_id.refine);
        # a pole added beside a heavy one has no other reading to start from.
        poles, refined = refine_poles(fu, hu, poles, line_hz, refine=to_refine(poles) | beside_heavy)
    if changed or refined.any():
        # The synthesis of the poles kept, as they are now (none left: residual terms only).
        est = lsfd(fu, hu, poles, form)
    f_modes, zeta_modes = frequency_damping(poles) if poles.size else (np.empty(0), np.empty(0))
    energy_modes = np.sum(np.abs(est.mode_terms) ** 2, axis=(1, 2))
    total = energy_modes.sum() + np.sum(np.abs(est.residual_terms) ** 2)
    modes = []
    for r, c in enumerate(chosen):
        share = float(energy_modes[r] / total) if total > 0 else 0.0
        f_r, zeta_r = float(f_modes[r]), float(zeta_modes[r])
        if c is None:
            quality = ModeQuality(0, np.nan, np.nan, share, refined=bool(refined[r]), added=True)
            modes.append(Mode(f_r, zeta_r, poles[r], est.modal_constants[r], quality, None))
            continue
        cl = clusters[c]
        quality = ModeQuality(
            n_stable_orders=cl.n_stable_orders,
            frequency_scatter_rel=cl.frequency_scatter_rel,
            damping_scatter_rel=cl.damping_scatter_rel,
            synthesis_share=share,
            accepted=bool(cl.accepted),
            refined=bool(refined[r]),
            **_top_spread(fits[owner[c][0]], cl, fits[owner[c][0] % len(zones)]),
        )
        normalisation = fits[owner[c][0]].normalisation
        modes.append(Mode(f_r, zeta_r, poles[r], est.modal_constants[r], quality, normalisation))
    diagram = _diagram(fits, owner, chosen)
    orders_text = ", ".join(f"{z.low_hz:g}-{z.high_hz:g} Hz order {z.max_order}" for z in zones)
    return ModalResult(
        frequency_hz=fu,
        modes=modes,
        synthesized=est.synthesized,
        residuals={"lower": est.lower, "upper": est.upper},
        synthesis_error=est.relative_error,
        stability=diagram,
        method=f"LSCF ({', then '.join(DENOMINATOR[n] for n in NORMALISATIONS)}) in {len(zones)} zone(s) "
        f"({orders_text}) + stability clustering + LSFD ({form})",
        zones=list(zones),
        set_aside=set_aside,
    )


def _holding(f, h, before, added, parent, line_hz) -> tuple[np.ndarray, np.ndarray]:
    """The poles ``added`` (n_added,) beside the heavy poles ``before[parent]`` that stay
    refined when refined again from their refined values (refine.refine_poles' limits on
    how far a pole may move), with their parents' indices."""
    poles = np.concatenate([before, added])
    mask = to_refine(poles)
    mask[parent] = True
    mask[before.size :] = True
    once, done_once = refine_poles(f, h, poles, line_hz, refine=mask)
    _, done_twice = refine_poles(f, h, once, line_hz, refine=mask)
    holds = (done_once & done_twice)[before.size :]
    return added[holds], parent[holds]


def _one_per_mode(clusters: list[Cluster], chosen: list[int], line_hz: float) -> list[int]:
    """``chosen`` with one cluster per mode: two frequencies asked for may find one
    cluster, or two readings of one mode (within the half-power half-width, at least 2
    lines, of a cluster kept; accepted ones kept first). Left in, each would make the
    other look redundant to spurious_check, and neither would stay (run_analysis says
    which asks found the same mode)."""
    kept: list[int] = []
    for c in sorted(dict.fromkeys(chosen), key=lambda c: not clusters[c].accepted):
        cl = clusters[c]
        if not any(
            abs(cl.frequency_hz - clusters[k].frequency_hz)
            <= max(clusters[k].damping_ratio * clusters[k].frequency_hz, 2 * line_hz)
            for k in kept
        ):
            kept.append(c)
    return sorted(kept, key=lambda c: clusters[c].frequency_hz)


def _check_noise(noise_std, shape: tuple[int, int], use: np.ndarray) -> np.ndarray | None:
    """noise_std as (n_frf, n_lines used), or None; ValueError if it does not fit the FRF."""
    if noise_std is None:
        return None
    noise = np.asarray(noise_std, dtype=float)
    if noise.shape not in ((shape[1],), shape):
        raise ValueError(f"noise_std must have shape ({shape[1]},) or {shape}, got {noise.shape}")
    return np.broadcast_to(noise, shape)[:, use]


def _drop_second_opinions(clusters: list[Cluster], normalisation: list[str], freq_tol: float) -> None:
    """An accepted cluster of a later normalisation (NORMALISATIONS) that stands for a mode
    an earlier one already holds is no mode of its own: closer than freq_tol (relative)
    or than the two half-power half-widths (zeta f) added."""
    rank = {n: i for i, n in enumerate(NORMALISATIONS)}
    for c, n in zip(clusters, normalisation, strict=True):
        if not c.accepted or rank[n] == 0:
            continue
        for d, m in zip(clusters, normalisation, strict=True):
            if not d.accepted or rank[m] >= rank[n]:
                continue
            gap = abs(c.frequency_hz - d.frequency_hz)
            width = c.damping_ratio * c.frequency_hz + d.damping_ratio * d.frequency_hz
            if gap <= max(freq_tol * d.frequency_hz, width):
                c.accepted, c.reason = (
                    False,
                    f"the mode at {d.frequency_hz:.6g} Hz, read with {DENOMINATOR[m]}",
                )
                break


#: Orders at the top of a zone whose poles give a mode's spread over the model orders.
TOP_ORDERS = 11


def _top_spread(zone_fit: _ZoneFit, cluster: Cluster, preferred: _ZoneFit) -> dict[str, float]:
    """The cluster's spread over the top orders of its zone; for a mode read with a later
    normalisation, the disagreement with the preferred one's poles added (``preferred``,
    the same zone's fit with NORMALISATIONS[0]): where the preferred fit holds no stable
    chain the mode's reading depends on the normalisation, and its poles there (nearest
    the mode, medians over the top orders) say by how much."""
    top = len(zone_fit.fit.poles) - TOP_ORDERS
    p = np.array([zone_fit.fit.poles[k][i] for k, i in cluster.members if k >= top])
    f, z = frequency_damping(p)
    # A chain can step to a close neighbour for an order or two (two lightly damped modes
    # 0.85 % apart pass the 1 % tolerance): such poles are the neighbour's, not spread.
    others = np.array([c.frequency_hz for c in zone_fit.clusters if c.accepted and c is not cluster])
    if others.size and f.size:
        nearer = np.abs(f[:, None] - others[None, :]).min(axis=1) < np.abs(f - cluster.frequency_hz)
        f, z = f[~nearer], z[~nearer]
    if f.size < 2:
        return {}
    spread_f, spread_z = float(np.std(f, ddof=1)), float(np.std(z, ddof=1))
    if preferred is not zone_fit:
        near = []
        for poles in preferred.fit.poles[len(preferred.fit.poles) - TOP_ORDERS :]:
            fp, zp = frequency_damping(poles)
            if fp.size:
                j = int(np.argmin(np.abs(fp - cluster.frequency_hz)))
                width = max(cluster.damping_ratio * cluster.frequency_hz, 0.01 * cluster.frequency_hz)
                if abs(fp[j] - cluster.frequency_hz) <= width:
                    near.append((fp[j], zp[j]))
        if near:
            f_other, z_other = np.median(np.array(near), axis=0)
            # The two readings' sample standard deviation, |a - b| / sqrt(2).
            spread_f = float(np.hypot(spread_f, abs(f_other - cluster.frequency_hz) / np.sqrt(2)))
            spread_z = float(np.hypot(spread_z, abs(z_other - cluster.damping_ratio) / np.sqrt(2)))
    return {"frequency_spread_top_hz": spread_f, "damping_spread_top": spread_z}


def _diagram(fits: list[_ZoneFit], owner: list[tuple[int, int]], chosen: list) -> StabilityDiagram:
    """One stability diagram of all zones: per order, the poles of every zone (chosen:
    each mode's cluster, None for a mode added without one)."""
    to_mode = {owner[c]: r for r, c in enumerate(chosen) if c is not None}
    n_orders = max(len(zf.fit.poles) for zf in fits)
    poles, status, selected, normalisation = [], [], [], []
    for k in range(n_orders):
        p, s, m = [np.empty(0, complex)], [np.empty(0, dtype="<U9")], [np.empty(0, dtype=int)]
        n = [np.empty(0, dtype="<U7")]
        for zi, zf in enumerate(fits):
            if k < len(zf.fit.poles):
                p.append(zf.fit.poles[k])
                s.append(np.asarray(zf.status[k], dtype="<U9"))
                m.append(np.array([to_mode.get((zi, int(c)), -1) for c in zf.label[k]], dtype=int))
                n.append(np.full(len(zf.fit.poles[k]), zf.normalisation, dtype="<U7"))
        poles.append(np.concatenate(p))
        status.append(np.concatenate(s))
        selected.append(np.concatenate(m))
        normalisation.append(np.concatenate(n))
    return StabilityDiagram(np.arange(1, n_orders + 1), poles, status, selected, normalisation)


#: A mode is kept when removing it (the others refitted) worsens the fit near it by this
#: factor at least ...
SPURIOUS_ERROR_RATIO = 1.25
#: ... and by this fraction of the FRF's norm there.
SPURIOUS_ERROR_GAIN = 0.02


def spurious_check(
    f, h, poles, est, form, line_hz, noise_std: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(n_modes,) bool: True for each pole that is a feature of the data; (n_modes,)
    float: how many times the misfit near each grows when it is removed (NaN: too few
    lines to tell, kept); (n_modes,) bool: a pole dropped that is still worth naming
    (SET_ASIDE_RATIO, SET_ASIDE_ROUGHNESS).

    Near each pole (3 half-power half-widths, at least 3 lines, either side) its term
    must peak NOISE_FACTOR times above the misfit around it (a pole fitted to noise is
    as large as the noise), and removing it, the residues of the others
    refitted, must worsen the fit there by SPURIOUS_ERROR_RATIO and by
    SPURIOUS_ERROR_GAIN of |H| there. Poles on antiresonances lower the synthesis;
    poles with no feature leave the fit unchanged. The refit is local (the lines within
    LOCAL_SPAN half-widths, the poles there, residual terms for the rest), so the check
    costs a few small solves per mode, not a fit of the whole band.

    The noise a dropped pole is named against is ``noise_std`` (n_frf, n_lines), the
    noise's standard deviation per line (RMS over the lines near the pole; non-finite
    values ignored), where given, else _roughness. Windows make the noise smooth over
    the lines (a force window of width T over 1/T Hz): there the second differences
    read it many times too low and noise bumps would be named.
    """
    fn = np.abs(poles) / (2 * np.pi)
    zeta = -poles.real / np.abs(poles)
    keep = np.ones(poles.size, dtype=bool)
    worse_by = np.full(poles.size, np.nan)
    candidate = np.zeros(poles.size, dtype=bool)
    for r in range(poles.size):
        half = max(3 * zeta[r] * fn[r], 3 * line_hz)
        near = np.abs(f - fn[r]) <= half
        if near.sum() < 3:
            continue
        local = np.abs(f - fn[r]) <= LOCAL_SPAN * half
        noise = np.sqrt(np.mean(np.abs(h[:, local] - est.synthesized[:, local]) ** 2))
        peak = np.max(np.sqrt(np.mean(np.abs(est.mode_terms[r][:, near]) ** 2, axis=0)))
        inside = np.abs(fn - fn[r]) <= LOCAL_SPAN * half
        fit_with = lsfd(f[local], h[:, local], poles[inside], form)
        fit_without = lsfd(f[local], h[:, local], poles[inside & (np.arange(poles.size) != r)], form)
        sub = near[local]
        e_with = np.linalg.norm(h[:, near] - fit_with.synthesized[:, sub])
        e_without = np.linalg.norm(h[:, near] - fit_without.synthesized[:, sub])
        scale = np.linalg.norm(h[:, near])
        worse, gain = e_without / max(e_with, 1e-300), (e_without - e_with) / max(scale, 1e-300)
        worse_by[r] = worse
        floor = SET_ASIDE_ROUGHNESS * _noise_level(h, noise_std, local)
        candidate[r] = worse >= SET_ASIDE_RATIO and peak >= floor
        if peak < NOISE_FACTOR * noise:
            # Below the misfit around it: a feature only if the fit cannot do without it.
            strong = worse > STRONG_ERROR_RATIO and gain > STRONG_ERROR_GAIN
            keep[r] = bool(strong and near.sum() >= STRONG_LINES)
            continue
        keep[r] = bool(worse > SPURIOUS_ERROR_RATIO and gain > SPURIOUS_ERROR_GAIN)
    return keep, worse_by, candidate & ~keep


def _noise_level(h: np.ndarray, noise_std: np.ndarray | None, lines: np.ndarray) -> float:
    """The noise's standard deviation over ``lines`` (bool, (n_lines,)): the RMS of
    noise_std there where it is given and finite, else _roughness of h there."""
    if noise_std is not None:
        values = noise_std[:, lines]
        values = values[np.isfinite(values)]
        if values.size:
            return float(np.sqrt(np.mean(values**2)))
    return _roughness(h[:, lines])


def _roughness(h: np.ndarray) -> float:
    """The noise of ``h`` (n_frf, n_lines) read from its second differences between lines:
    for white noise of standard deviation s, |H[k-1] - 2 H[k] + H[k+1]|^2 has mean 6 s^2
    and median ln 2 times that; a mode spanning a few lines hardly adds to the median."""
    if h.shape[1] < 3:
        return 0.0
    d2 = h[:, 2:] - 2 * h[:, 1:-1] + h[:, :-2]
    return float(np.sqrt(np.median(np.abs(d2) ** 2) / (6 * np.log(2))))


#: A peak of the mode indicator no mode accounts for is named when |H| there stands this
#: many dB above the noise (read over UNEXPLAINED_NOISE_LINES lines either side): the
#: clear peaks of a close pair the first pass missed (31 and 33 Hz at 0.4 and 0.6 %,
#: 4 hits, 54 dB), not the bumps of a noisy FRF (lvm-2ch m1: 2-21 dB).
UNEXPLAINED_SNR_DB = 25.0
UNEXPLAINED_NOISE_LINES = 25
#: ... where the synthesis misses |H| by this many times its median miss over the band:
#: a mode left out leaves its whole peak (31/33 Hz: 118 times; pyfrf-impact's 5074 Hz:
#: 142), an error smooth over many lines leaves a bump no larger than the misfit elsewhere
#: (a 6 % error over 40 lines: 2 times) ...
UNEXPLAINED_MISFIT = 5.0
#: ... outside this fraction of the band at either edge (poles there stand in for modes
#: outside; stability.cluster_poles' guard), at the low edge never wider than the gap
#: below the band (a band from 0.25 Hz has no modes below it to stand in for: a clear
#: 3 Hz mode inside a 16 Hz guard of a 0.25-800 Hz band was left out unsaid).
UNEXPLAINED_EDGE = 0.02
#: A peak of the mode indicator this many dB above the dips beside it (where a second pass
#: needs zones.PEAK_PROMINENCE_DB), clear by the rules above, is named in a caution: the
#: second of a close pair, 7 dB above the dip between them (a public spruce plate's 404 and
#: 409 Hz: one mode at 0.92 % for the first's 0.58 % by half power, unsaid).
WEAK_PEAK_PROMINENCE_DB = 6.0


def unexplained_peaks(
    f: np.ndarray,
    h: np.ndarray,
    result: ModalResult,
    line_hz: float,
    noise_std: np.ndarray | None = None,
    prominence_db: float = PEAK_PROMINENCE_DB,
) -> list[float]:
    """The frequencies (Hz) of the clear peaks of the FRFs ``h`` (n_frf, n_lines) on the
    lines ``f`` that the modes of ``result`` do not account for: peaks of the mode
    indicator (zones.indicator_peaks) inside the band's edge guard, standing
    UNEXPLAINED_SNR_DB above the noise (noise_std (n_frf, n_lines) where given, else
    _roughness), where the synthesis misses |H| by UNEXPLAINED_MISFIT times its median
    miss, with no mode within its half-power half-width (at least 2 lines)."""
    peaks = indicator_peaks(mode_indicator(h), prominence_db)
    if peaks.size == 0:
        return []
    fm = np.array([m.frequency_hz for m in result.modes], dtype=float)
    width = np.maximum(np.array([m.damping_ratio for m in result.modes], dtype=float) * fm, 2 * line_hz)
    guard = UNEXPLAINED_EDGE * (f[-1] - f[0])
    low_guard = min(guard, f[0])
    magnitude = np.sqrt(np.mean(np.abs(h) ** 2, axis=0))
    miss = np.sqrt(np.mean(np.abs(h - result.synthesized) ** 2, axis=0))
    typical = float(np.median(miss))
    out = []
    for i in peaks:
        if not f[0] + low_guard <= f[i] <= f[-1] - guard:
            continue
        if fm.size and np.any(np.abs(fm - f[i]) <= width):
            continue
        if miss[i] < UNEXPLAINED_MISFIT * typical:
            continue
        near = np.zeros(f.size, dtype=bool)
        near[max(0, i - UNEXPLAINED_NOISE_LINES) : i + UNEXPLAINED_NOISE_LINES + 1] = True
        noise = _noise_level(h, noise_std, near)
        if noise > 0 and magnitude[i] >= noise * 10 ** (UNEXPLAINED_SNR_DB / 20):
            out.append(float(f[i]))
    return out


#: A mode's term must peak this many times above the misfit around it (the noise there) ...
NOISE_FACTOR = 3.0
#: ... unless removing it worsens the fit near it this many times, by this fraction of |H|
#: there, over at least this many lines: a broad, heavily damped mode beside an
#: antiresonance the model follows poorly (the tool holder's 297 Hz at 4.3 %: its term 2.3
#: times the misfit around it, the fit 5.5 times worse without it), which a pole fitted
#: to noise over that many lines does not do.
STRONG_ERROR_RATIO = 2.0
STRONG_ERROR_GAIN = 0.1
STRONG_LINES = 20
#: A chain spurious_check drops is set aside, named to the user as a candidate, when the
#: misfit near it grows at least this many times without it (a pole on an antiresonance
#: or on nothing leaves it under 1.1) ...
SET_ASIDE_RATIO = 1.1
#: ... and its term peaks this many times above the noise (_noise_level: the scatter over
#: hits where the caller gives it, else the line-to-line noise of _roughness). Poles
#: fitted to white noise reach 2.4 times it (the highest of 425 such poles in 1,600-line
#: FRFs at 2-10 % noise and of pure noise, 48 draws); the broad modes of the corpus that
#: our thresholds drop stand 4.9 to 320 times above it. Windowed hits make the noise
#: smooth over lines, where _roughness reads it 20 times too low (the seed scenario):
#: the scatter over hits is given there. A candidate is no mode: the user decides.
SET_ASIDE_ROUGHNESS = 4.0
#: The local refit of spurious_check spans this many of its windows' half-widths.
LOCAL_SPAN = 8
