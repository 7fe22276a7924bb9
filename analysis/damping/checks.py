"""Checks on a fitted damping matrix: the Jacobian behind its uncertainty, refits to
each hit alone (the uncertainty checked another way), and random starts (is the
optimum global?). Pure numerics, used by daq/workflows/fit.py."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import numpy as np

from analysis.damping import hit_frf
from analysis.damping.bandlimited import BandLimitedData, batched_residuals, residuals
from analysis.damping.hit_frf import HitFrfData
from analysis.damping.local import fit_least_squares, multi_start
from analysis.damping.params import matrix_to_theta, theta_to_matrix


def multi_start_check(
    residual_fn: Callable,
    batched: Callable,
    r: np.ndarray,
    psi: float,
    starts: int,
    seed: int = 0,
    psd: bool = False,
) -> dict:
    """Local fits from ``starts`` random starts beside the chosen fit, in the same
    coding (``psd``: R = L L^T, so that an indefinite R does not count as a better
    optimum of a dissipative fit): how many reach its Psi (to 0.1 %), whether any does
    better, and the largest distance of the equally good ones from its R (a flat
    direction shows as equal Psi, other R)."""
    fits = multi_start(residual_fn, batched, r.shape[0], starts=starts, seed=seed, psd=psd)
    psis = np.array([f.psi for f in fits])
    same = np.abs(psis - psi) <= 1e-3 * psi
    distances = [
        float(np.linalg.norm(np.asarray(f.damping_matrix) - r) / np.linalg.norm(r))
        for f, ok in zip(fits, same, strict=True)
        if ok
    ]
    return {
        "starts": int(starts),
        "reached_same_psi": int(same.sum()),
        "better_psi_found": bool(np.any(psis < psi * (1 - 1e-3))),
        "best_psi": float(psis.min()),
        "largest_relative_distance_at_same_psi": max(distances) if distances else None,
    }


def per_hit_std(data: BandLimitedData | HitFrfData, r: np.ndarray, psd: bool = False) -> np.ndarray | None:
    """(P,) standard deviation of each term of R (upper triangle, row-major) over
    least-squares fits to each accepted hit alone (started from the joint fit ``r``,
    R = L L^T with ``psd``), divided by sqrt(n_hits): the spread of the mean of the
    refits, the figure comparable with the joint fit's. None with fewer than 3 hits.
    ``data``: the time records (bandlimited) or the hits' FRF (hit_frf: each hit's own
    FRF against the model's for that hit).
    """
    n_hits = data.force_n.shape[0]
    if n_hits < 3:
        return None
    start = np.asarray(r, dtype=float)
    if psd:
        # A full-rank start: at a rank-deficient R = L L^T the factor's zero columns do
        # not move R to first order, and refits would stay put along them.
        start = _nearest_psd(start)
        start = start + PER_HIT_LIFT * np.max(np.linalg.eigvalsh(start)) * np.eye(start.shape[0])
    thetas = []
    frequency = isinstance(data, HitFrfData)
    single, batched = (
        (hit_frf.residuals, hit_frf.batched_residuals) if frequency else (residuals, batched_residuals)
    )
    for k in range(n_hits):
        if frequency:
            one = data.hit(k)
        else:
            one = replace(data, force_n=data.force_n[k : k + 1], response_m_s2=data.response_m_s2[k : k + 1])
        fit = fit_least_squares(
            lambda m, d=one: single(d, m),
            start,
            psd=psd,
            batched_residuals=lambda m, d=one: batched(d, m),
            max_nfev=PER_HIT_MAX_NFEV,
        )
        thetas.append(matrix_to_theta(np.asarray(fit.damping_matrix)))
    return np.std(np.array(thetas), axis=0, ddof=1) / np.sqrt(n_hits)


#: The smallest eigenvalue given to a per-hit refit's start with R = L L^T, as a
#: fraction of the largest.
PER_HIT_LIFT = 1e-3
#: Iterations (scipy's count) each per-hit refit may take: they start at the joint
#: optimum, and a flat direction must not make one wander for minutes.
PER_HIT_MAX_NFEV = 50


def _nearest_psd(r: np.ndarray) -> np.ndarray:
    """``r`` with negative eigenvalues set to zero (a start for R = L L^T)."""
    w, v = np.linalg.eigh(0.5 * (r + r.T))
    return (v * np.clip(w, 0.0, None)) @ v.T


def combined_std(fisher: np.ndarray, from_hits: np.ndarray | None) -> tuple[np.ndarray, list[str]]:
    """(P,) the larger of the Fisher (Cramer-Rao) standard deviation and the per-hit
    refits' figure for each term, and which one it is ("fisher" or "hits").

    The Fisher figure takes the residual as white noise; coloured residuals (the
    analyzer's band-limited samples, the force's noise seen through H) make the refits
    spread wider, and the Fisher figure is then too small. Neither is taken alone: the
    printed uncertainty is never smaller than what refits show. A non-finite figure
    (an undetermined term) wins over a finite one."""
    f = np.asarray(fisher, dtype=float)
    if from_hits is None:
        return f.copy(), ["fisher"] * f.size
    h = np.asarray(from_hits, dtype=float)
    use_hits = np.isfinite(h) & (h > np.where(np.isnan(f), -np.inf, f)) & ~np.isinf(f)
    return np.where(use_hits, h, f), ["hits" if u else "fisher" for u in use_hits]


def central_jacobian(batched: Callable, r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(Jacobian (n_res, P), residual (n_res,)) at the symmetric matrix ``r`` (N, N):
    central differences in its N(N+1)/2 parameters, all in one batched call of
    ``batched`` ((B, N, N) -> (B, n_res))."""
    theta = matrix_to_theta(r)
    n = r.shape[0]
    step = 1e-6 * max(1.0, float(np.max(np.abs(theta))))
    eye = np.eye(theta.size) * step
    thetas = np.concatenate([theta + eye, theta - eye, theta[None]])
    res = batched(theta_to_matrix(thetas, n))
    p = theta.size
    jac = (res[:p] - res[p : 2 * p]).T / (2 * step)
    return jac, res[-1]
