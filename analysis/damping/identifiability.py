"""How well a fit determines each term of the damping matrix, and what it leaves open.

A least-squares fit of theta (the upper triangle of R, row-major: R11, R12, ...,
R1N, R22, ...) with residual Jacobian J and residual noise sigma has, to first
order, the covariance sigma^2 (J^T J)^-1: the Cramer-Rao bound when the noise is
Gaussian and sigma is its true level. Where J^T J is singular the data say
nothing about some combination of terms; those combinations are named.

Every term is judged against the diagonal: the scale of R_ij is
sqrt(|R_ii R_jj|), so an off-diagonal term whose standard deviation is a large
fraction of that is not determined, however small its own value.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from analysis.structure import StructuralModel

#: Singular values below this fraction of the largest count as exactly zero (round-off).
RANK_TOLERANCE = 1e-12
#: Singular values below this fraction of the largest are reported as near-null directions.
NULL_TOLERANCE = 1e-3


@dataclass
class Identifiability:
    """Uncertainty of each damping-matrix term and the combinations the data leave open.

    names : "R11", "R12", ... (row-major upper triangle).
    value : (P,) parameter values, N s/m.
    std : (P,) standard deviation, N s/m, from sigma^2 (J^T J)^-1 (pseudo-inverse;
        inf for a term with a component along an exactly null direction).
    relative_std : (P,) std / scale with scale_ij = sqrt(|R_ii R_jj|).
    determined : (P,) bool, relative_std < threshold.
    singular_values : (P,) of the Jacobian with columns scaled by the scale
        (descending), in residual units per unit relative change.
    null_directions : for each scaled-Jacobian direction with a singular value
        below NULL_TOLERANCE of the largest, or whose standard deviation exceeds
        the scale (noise_std / s > 1): {"singular_value": s, "relative_std":
        noise_std / s, "combination": {name: component}} with the components a
        unit vector in scaled terms (largest component positive): moving R along
        it by the reported relative_std changes the fit by one noise level.
    noise_std : sigma, in residual units.
    """

    names: list[str]
    value: np.ndarray
    std: np.ndarray
    relative_std: np.ndarray
    determined: np.ndarray
    singular_values: np.ndarray
    null_directions: list[dict]
    noise_std: float


def parameter_names(n: int) -> list[str]:
    """Names of the upper-triangle terms of an n x n matrix, row-major."""
    rows, cols = np.triu_indices(n)
    sep = "" if n < 10 else "_"
    return [f"R{i + 1}{sep}{j + 1}" for i, j in zip(rows, cols, strict=True)]


def parameter_scale(value: np.ndarray, n: int) -> np.ndarray:
    """sqrt(|R_ii R_jj|) for each upper-triangle term; falls back to the largest |R_ii| (or 1) where 0."""
    theta = np.asarray(value, dtype=float)
    rows, cols = np.triu_indices(n)
    diag = np.zeros(n)
    diag[rows[rows == cols]] = np.abs(theta[rows == cols])
    scale = np.sqrt(diag[rows] * diag[cols])
    fallback = np.max(diag) if np.max(diag) > 0 else 1.0
    return np.where((scale > 0) & np.isfinite(scale), scale, fallback)


def identifiability(
    jacobian: np.ndarray,
    residual: np.ndarray,
    value: np.ndarray,
    n: int,
    threshold: float = 0.3,
    noise_std: float | None = None,
) -> Identifiability:
    """Linearised uncertainty of a least-squares fit of R's upper triangle.

    Parameters
    ----------
    jacobian : (n_res, P), d residual / d theta (sign irrelevant), P = n (n + 1) / 2.
    residual : (n_res,) at the fit, used for sigma = sqrt(r^T r / (n_res - P)).
    value : (P,) fitted theta, N s/m.
    n : matrix size N.
    threshold : relative_std below which a term counts as determined.
    noise_std : sigma if known (e.g. 1 for a whitened Jacobian); overrides the
        residual estimate.
    """
    jac = np.asarray(jacobian, dtype=float)
    theta = np.asarray(value, dtype=float)
    res = np.asarray(residual, dtype=float).ravel()
    p = n * (n + 1) // 2
    if jac.ndim != 2 or jac.shape[1] != p or theta.shape != (p,):
        raise ValueError(f"jacobian must be (n_res, {p}) and value ({p},) for n = {n}")
    if res.size != jac.shape[0]:
        raise ValueError("residual and jacobian must have the same number of rows")
    if noise_std is None:
        dof = res.size - p
        sigma = float(np.sqrt(res @ res / dof)) if dof > 0 else float("nan")
    else:
        sigma = float(noise_std)

    names = parameter_names(n)
    scale = parameter_scale(theta, n)
    # Scaled columns: each parameter in units of its scale, so singular values compare alike.
    _, s, vt = np.linalg.svd(jac * scale, full_matrices=False)
    s_max = s[0] if s.size and s[0] > 0 else 1.0
    nonzero = s > RANK_TOLERANCE * s_max
    v = vt.T
    with np.errstate(divide="ignore"):
        inv_s = np.where(nonzero, 1.0 / np.where(nonzero, s, 1.0), 0.0)
    rel_var = sigma**2 * (v**2) @ (inv_s**2)
    # A term with a component along an exactly null direction is not determined at all.
    touches_null = np.any(np.abs(v[:, ~nonzero]) > 1e-8, axis=1) if np.any(~nonzero) else np.zeros(p, bool)
    relative_std = np.where(touches_null, np.inf, np.sqrt(rel_var))
    std = relative_std * scale

    null_directions = []
    for k in range(s.size):
        direction_std = sigma / s[k] if s[k] > 0 else np.inf
        if s[k] < NULL_TOLERANCE * s_max or direction_std > 1.0:
            vec = v[:, k] * np.sign(v[np.argmax(np.abs(v[:, k])), k])
            null_directions.append(
                {
                    "singular_value": float(s[k]),
                    "relative_std": float(direction_std),
                    "combination": {name: float(c) for name, c in zip(names, vec, strict=True)},
                }
            )
    return Identifiability(
        names=names,
        value=theta.copy(),
        std=std,
        relative_std=relative_std,
        determined=relative_std < threshold,
        singular_values=s,
        null_directions=null_directions,
        noise_std=sigma,
    )


def cramer_rao_frf(
    model: StructuralModel,
    damping: np.ndarray,
    frequencies_hz: np.ndarray,
    noise_rel: float = 0.01,
    threshold: float = 0.3,
) -> Identifiability:
    """Cramer-Rao bound of R's terms from one driving-point accelerance FRF.

    The noise on each line k is complex Gaussian with E|e_k|^2 = (noise_rel |H_k|)^2,
    real and imaginary parts independent with standard deviation
    noise_rel |H_k| / sqrt(2) each. The Jacobian of H with respect to the upper
    triangle of R comes from central differences (step 1e-6 of each term's scale)
    over one batched ``frequency_response`` call; whitened by the noise, it gives
    the bound (J^T J)^-1 (``noise_std`` = 1 in the result, whitened units).
    Lines where H vanishes (0 Hz for an accelerance) carry no information and
    are dropped (their relative noise would be undefined).

    Parameters
    ----------
    damping : (N, N) N s/m, the true R.
    frequencies_hz : (F,) Hz.
    noise_rel : relative complex noise level (0.01 for 1 %).
    """
    from analysis.response import frequency_response

    r = model.check_damping(damping)
    n = model.n_dof
    if r.shape != (n, n):
        raise ValueError(f"damping must be one ({n}, {n}) matrix")
    r = 0.5 * (r + r.T)
    f = np.asarray(frequencies_hz, dtype=float)
    rows, cols = np.triu_indices(n)
    theta = r[rows, cols]
    p = theta.size
    scale = parameter_scale(theta, n)
    h = 1e-6 * scale

    batch = np.empty((2 * p + 1, n, n))
    batch[0] = r
    for j in range(p):
        for sign, slot in ((1.0, 1 + 2 * j), (-1.0, 2 + 2 * j)):
            d = r.copy()
            d[rows[j], cols[j]] += sign * h[j]
            d[cols[j], rows[j]] = d[rows[j], cols[j]]
            batch[slot] = d
    resp = frequency_response(model, batch, f, output="acceleration")
    h0 = resp[0]
    jac = (resp[1::2] - resp[2::2]).T / (2.0 * h)  # (F, P) complex
    keep = np.abs(h0) > 1e-12 * np.max(np.abs(h0))
    sigma = noise_rel * np.abs(h0[keep]) / np.sqrt(2.0)
    white = np.concatenate([jac[keep].real / sigma[:, None], jac[keep].imag / sigma[:, None]])
    return identifiability(white, np.zeros(white.shape[0]), theta, n, threshold=threshold, noise_std=1.0)
