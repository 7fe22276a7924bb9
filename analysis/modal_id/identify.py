"""Automatic modal identification: LSCF poles -> stability diagram -> clusters -> LSFD.

identify_modes() is the top level; see lscf, stability and lsfd for the pieces and
their definitions (model order = number of pole pairs; status codes; residual terms).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from analysis.modal_id.lscf import lscf_poles
from analysis.modal_id.lsfd import FORMS, lsfd
from analysis.modal_id.stability import cluster_poles, pick_clusters, stability_diagram


@dataclass
class ModeQuality:
    """n_stable_orders: stable links of the mode's cluster; *_scatter_rel: std/median of
    the cluster's frequencies and damping ratios; synthesis_share: energy of the mode's
    term (both poles of the pair) over the sum of the energies of all terms of the
    synthesis (modes and residuals), over the FRFs and lines used."""

    n_stable_orders: int
    frequency_scatter_rel: float
    damping_scatter_rel: float
    synthesis_share: float


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


@dataclass
class StabilityDiagram:
    """orders (n_orders,) pole pairs of each model; poles per order, complex rad/s;
    status per order, one code per pole ("stable", "damping", "frequency", "new", see
    analysis.modal_id.stability); selected_cluster per order: index into
    ModalResult.modes of the mode each pole belongs to, or -1."""

    orders: np.ndarray
    poles: list[np.ndarray]
    status: list[np.ndarray]
    selected_cluster: list[np.ndarray]


@dataclass
class ModalResult:
    """frequency_hz (n_lines,) the lines used; modes sorted by frequency; synthesized
    (n_frf, n_lines); residuals {"lower", "upper"}: (n_frf,) complex coefficients of the
    residual terms (analysis.modal_id.lsfd); synthesis_error ||H - H_syn|| / ||H||."""

    frequency_hz: np.ndarray
    modes: list[Mode]
    synthesized: np.ndarray
    residuals: dict
    synthesis_error: float
    stability: StabilityDiagram
    method: str


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
    if not isinstance(max_order, int | np.integer) or max_order < 2:
        raise ValueError(f"max_order must be an integer >= 2, got {max_order!r}")
    if band is None:
        band = (float(f[0]), float(f[-1]))
    f1, f2 = map(float, band)
    if not f1 < f2:
        raise ValueError(f"band must be (f1, f2) with f1 < f2, got {band}")
    use = (f >= f1) & (f <= f2)
    if use.sum() < 2 * max_order + 2:
        raise ValueError(
            f"band {band} holds {use.sum()} lines; LSCF of order {max_order} needs at least "
            f"{2 * max_order + 2}: widen the band or lower max_order"
        )
    return f, h, (f1, f2), use


def identify_modes(
    frequency_hz: np.ndarray,
    frf: np.ndarray,
    band: tuple[float, float] | None = None,
    max_order: int = 40,
    frequencies_hz: np.ndarray | None = None,
    form: str = "accelerance",
    *,
    freq_tol: float = 0.01,
    damping_tol: float = 0.05,
    vector_tol: float = 0.1,
    min_stable_orders: int | None = None,
    max_damping: float = 0.3,
) -> ModalResult:
    """Find the modes of FRFs without being told how many.

    frequency_hz (n_lines,) Hz, increasing; frf (n_lines,) or (n_frf, n_lines) complex
    in the units of ``form`` (accelerance: (m/s^2)/N); band (f1, f2) Hz, default all
    lines; max_order: largest LSCF model (pole pairs); frequencies_hz: if given, the
    stable cluster nearest each is selected instead of every accepted cluster.
    Tolerances are relative (see analysis.modal_id.stability). min_stable_orders defaults
    to max(4, max_order // 5). Raises ValueError on bad inputs.
    """
    f, h, band, use = _check_inputs(frequency_hz, frf, band, max_order, form)
    if min_stable_orders is None:
        min_stable_orders = max(4, max_order // 5)
    fu, hu = f[use], h[:, use]
    fit = lscf_poles(fu, hu, max_order)
    status, partner = stability_diagram(fit.poles, fit.residues, freq_tol, damping_tol, vector_tol)
    clusters, label = cluster_poles(
        fit.poles,
        status,
        partner,
        band,
        freq_tol=freq_tol,
        damping_tol=damping_tol,
        min_stable_orders=min_stable_orders,
        max_damping=max_damping,
    )
    freqs = None if frequencies_hz is None else np.atleast_1d(np.asarray(frequencies_hz, dtype=float))
    chosen = pick_clusters(clusters, freqs)
    poles = np.array([clusters[c].pole for c in chosen], dtype=complex)
    est = lsfd(fu, hu, poles, form)
    energy_modes = np.sum(np.abs(est.mode_terms) ** 2, axis=(1, 2))
    total = energy_modes.sum() + np.sum(np.abs(est.residual_terms) ** 2)
    modes = []
    for r, c in enumerate(chosen):
        cl = clusters[c]
        quality = ModeQuality(
            n_stable_orders=cl.n_stable_orders,
            frequency_scatter_rel=cl.frequency_scatter_rel,
            damping_scatter_rel=cl.damping_scatter_rel,
            synthesis_share=float(energy_modes[r] / total) if total > 0 else 0.0,
        )
        modes.append(Mode(cl.frequency_hz, cl.damping_ratio, poles[r], est.modal_constants[r], quality))
    to_mode = {c: r for r, c in enumerate(chosen)}
    selected = [np.array([to_mode.get(int(c), -1) for c in lab], dtype=int) for lab in label]
    diagram = StabilityDiagram(fit.orders, fit.poles, status, selected)
    return ModalResult(
        frequency_hz=fu,
        modes=modes,
        synthesized=est.synthesized,
        residuals={"lower": est.lower, "upper": est.upper},
        synthesis_error=est.relative_error,
        stability=diagram,
        method=f"LSCF (orders 1..{max_order}) + stability clustering + LSFD ({form})",
    )
