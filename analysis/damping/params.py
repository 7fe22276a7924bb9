"""Parameter vectors theta <-> symmetric N x N damping matrices R.

Two codings, both with P = N (N + 1) / 2 parameters:

* ``psd=False`` (the seed's): theta is the upper triangle of R read row by row,
  theta = (R11, R12, ..., R1N, R22, R23, ..., R2N, ..., RNN), and R is its
  symmetric completion. Any R is reachable, including indefinite ones, which can
  make the model unstable (energy generation): the objective has to cope.
* ``psd=True``: theta is the lower-triangular Cholesky factor L read row by row,
  theta = (L11, L21, L22, L31, L32, L33, ...), and R = L L^T. Every theta gives a
  positive semi-definite (dissipative) R, so a search cannot leave the physical set.
  The map is many-to-one (signs of the columns of L), which a local fit does not mind.

Units: R in N s/m (generalized coordinates); L in sqrt(N s/m).
"""

from __future__ import annotations

import numpy as np


def n_params(n: int) -> int:
    """P = n (n + 1) / 2, the free entries of a symmetric n x n matrix."""
    if not isinstance(n, (int, np.integer)) or n < 1:
        raise ValueError(f"n must be a positive integer, got {n!r}")
    return int(n) * (int(n) + 1) // 2


def _indices(n: int, psd: bool) -> tuple[np.ndarray, np.ndarray]:
    # numpy's triu/tril indices are already in row-major order.
    return np.tril_indices(n) if psd else np.triu_indices(n)


def theta_to_matrix(theta: np.ndarray, n: int, psd: bool = False) -> np.ndarray:
    """Damping matrices from parameter vectors.

    Parameters
    ----------
    theta : (..., P) with P = n (n + 1) / 2 (order: see the module docstring).
    n : matrix size N.
    psd : theta is the Cholesky factor L and R = L L^T.

    Returns
    -------
    (..., n, n) symmetric, N s/m.
    """
    t = np.asarray(theta, dtype=float)
    p = n_params(n)
    if t.ndim < 1 or t.shape[-1] != p:
        raise ValueError(f"theta must have shape (..., {p}) for n = {n}, got {t.shape}")
    rows, cols = _indices(n, psd)
    m = np.zeros((*t.shape[:-1], n, n))
    m[..., rows, cols] = t
    if psd:
        return m @ np.swapaxes(m, -1, -2)
    # Fill the lower triangle from the upper one; the diagonal is written twice, same value.
    m[..., cols, rows] = t
    return m


def matrix_to_theta(matrix: np.ndarray, psd: bool = False) -> np.ndarray:
    """Parameter vector (P,) of one symmetric damping matrix (N, N), N s/m.

    With ``psd=True`` this is the Cholesky factor of R; a semi-definite R gets a
    jitter of 1e-12 x its largest eigenvalue on the diagonal first (so L exists),
    and an indefinite R raises ValueError: no L L^T equals it.
    """
    r = np.asarray(matrix, dtype=float)
    if r.ndim != 2 or r.shape[0] != r.shape[1] or r.shape[0] < 1:
        raise ValueError(f"expected one square matrix, got shape {r.shape}")
    if not np.all(np.isfinite(r)):
        raise ValueError("matrix holds non-finite values")
    n = r.shape[0]
    scale = float(np.max(np.abs(r))) or 1.0
    if not np.allclose(r, r.T, rtol=0.0, atol=1e-12 * scale):
        raise ValueError("damping matrix must be symmetric")
    r = 0.5 * (r + r.T)
    rows, cols = _indices(n, psd)
    if not psd:
        return r[rows, cols].copy()
    eig = np.linalg.eigvalsh(r)
    if eig[-1] <= 0.0 and eig[0] >= 0.0:
        return np.zeros(rows.size)  # R = 0: L = 0
    if eig[0] < -1e-10 * max(abs(eig[-1]), 1e-300):
        raise ValueError(f"damping matrix is indefinite (smallest eigenvalue {eig[0]:.3g}); no R = L L^T")
    jitter = 1e-12 * max(abs(eig[-1]), 1e-300)
    try:
        low = np.linalg.cholesky(r)
    except np.linalg.LinAlgError:
        low = np.linalg.cholesky(r + (jitter - min(eig[0], 0.0)) * np.eye(n))
    return low[rows, cols].copy()


def parameter_names(n: int, psd: bool = False) -> list[str]:
    """Names of theta's entries: "R11", "R12", ... (or "L11", "L21", ... with psd), 1-based."""
    n_params(n)
    rows, cols = _indices(n, psd)
    letter = "L" if psd else "R"
    # Indices above 9 would run together ("R111"): separate them then.
    sep = "," if n > 9 else ""
    return [f"{letter}{i + 1}{sep}{j + 1}" for i, j in zip(rows, cols, strict=True)]
