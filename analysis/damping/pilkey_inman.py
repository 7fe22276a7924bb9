"""Damping matrix from identified complex poles with M and K known (Pilkey-Inman type).

What it needs
-------------
M and K (the model) and the identified complex poles lambda_r (rad/s, one per
mode, the one with positive imaginary part). No mode shapes: a single driving
point (hammer and accelerometer both at the tip) measures one row of the
residue matrix, not the N components of each complex mode.

The iteration
-------------
Pilkey and Inman (IMAC 1997/1998; Pilkey's 1998 thesis) iterate the damping
matrix through the quadratic eigenproblem (lambda^2 M + lambda R_k + K) phi = 0
of the current model: its eigenvectors phi_r(R_k) stand in for the unmeasured
mode shapes, and the measured poles are imposed to get R_{k+1}. Two updates
are offered:

* ``update="lancaster"``, the literal substitution: phi_r normalised by
  phi_r^T (2 lambda_r M + R_k) phi_r = 1 (lambda_r of the current model, which
  makes Lancaster's identity exact for the model) and
  R_{k+1} = -2 Re(M Phi diag(lambda_measured^2) Phi^T M). Every R whose poles
  equal the measured ones is a fixed point, but not conversely: with the model's
  eigenvectors held, the map from pole changes to R changes has rank N only (the
  Lancaster identities Re(Phi Phi^T) = 0 and 2 Re(Phi Lambda Phi^T) = M^-1 remove
  the rest), so the substitution enforces N of the 2N real pole conditions. For
  the seed's eq (18) poles (N = 3) it reaches, from the classically damped
  start, a fixed point whose poles miss by ~3 %, and diverges from
  ``default_start``. Kept for comparison, not recommended.
* ``update="newton"`` (default), the variant used here: the same eigenproblem of
  the current model gives the first-order pole sensitivities
  d lambda_r = -lambda_r phi_r^T dR phi_r / phi_r^T (2 lambda_r M + R_k) phi_r
  (symmetric pencil, so phi_r^T is the left eigenvector), and R_{k+1} solves the
  linearised pole equations in least squares with the minimum-norm step, halving
  it while the squared pole error grows. From eq (18)'s poles it matches them
  to ~1e-15 in about five steps.

What it converges to, and what it cannot give
---------------------------------------------
The N poles are 2N real numbers, but not 2N independent functions of R: the 2N
roots of det(lambda^2 M + lambda R + K) multiply to det K / det M whatever R is,
so prod |lambda_r|^2 = det K / det M. The poles therefore carry 2N - 1 numbers
about R's N(N+1)/2 terms: 5 against 6 for N = 3, already underdetermined, and
ever more so for larger N. Besides that continuum there are discrete branches:
flipping the sign of a mode shape, R -> M Phi S Phi^T R Phi S Phi^T M with
S = diag(+-1), changes no pole (2^(N-1) such branches). So:

* the answer is the pole-consistent R reached from the start by minimum-norm
  Newton steps; it is not the R that produced the poles unless the start was
  already close to it (eq (18)'s poles from ``default_start`` give an R with
  R33 ~ 307 N s/m against eq (18)'s 2.75, with every pole matching to 1e-15);
* the classically damped estimate is a point where the pole sensitivity to the
  modal off-diagonals vanishes (they enter the poles squared), so Newton
  cannot leave it: ``default_start`` adds modal coupling of an arbitrary sign;
* noisy poles (or a stiffness error) break prod |lambda_r|^2 = det K / det M,
  and then no R matches them: the iteration stops at the least-squares R,
  which spreads the mismatch (``product_mismatch``) over the modes' |lambda|.

Why Lancaster's formula is not offered as a direct method
---------------------------------------------------------
R = -2 Re(M Psi Lambda^2 Psi^T M) (Lancaster; used by Adhikari for damping
identification) needs the complex modes Psi, properly scaled, at all N
coordinates, i.e. complex residues measured at N points (a row or column of the
FRF matrix). One tip accelerometer with the hammer at the tip measures one
element of each residue matrix, so Psi is not available.
"""

from __future__ import annotations

from typing import Any, Literal

import numpy as np

from analysis.damping.modal_estimate import match_modes, proportional_estimate, undamped_modes
from analysis.damping.params import matrix_to_theta, theta_to_matrix
from analysis.modal import damped_modes
from analysis.structure import StructuralModel

Update = Literal["newton", "lancaster"]


def _upper(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Row-major upper-triangle indices (R11, R12, ..., R1n, R22, ...)."""
    return np.triu_indices(n)


def _to_matrix(theta: np.ndarray, n: int) -> np.ndarray:
    rows, cols = _upper(n)
    r = np.zeros((n, n))
    r[rows, cols] = theta
    r[cols, rows] = theta
    return r


def _model_poles(model: StructuralModel, damping: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Oscillatory poles (N,) and shapes (N modes, N dof) of the current R (NaN if overdamped)."""
    modes = damped_modes(model, damping)
    return modes.poles, modes.shapes


def _pole_error(poles: np.ndarray, target: np.ndarray) -> float:
    """Largest relative pole error; inf when a paired mode is not oscillatory."""
    err = np.abs(poles - target) / np.abs(target)
    return float(np.max(err)) if np.all(np.isfinite(err)) else np.inf


def _cost(poles: np.ndarray, target: np.ndarray) -> float:
    """Sum of squared relative pole errors; inf when a paired mode is not oscillatory."""
    err = np.abs(poles - target) ** 2 / np.abs(target) ** 2
    return float(np.sum(err)) if np.all(np.isfinite(err)) else np.inf


def _newton_step(
    model: StructuralModel,
    damping: np.ndarray,
    idx: np.ndarray,
    target: np.ndarray,
    low: np.ndarray | None = None,
) -> np.ndarray:
    """Least-squares (minimum-norm) change of the parameters (the upper triangle of R,
    or the lower triangle of ``low`` = L when given, R = L L^T) towards the target poles."""
    n = model.n_dof
    poles, shapes = _model_poles(model, damping)
    lam, phi = poles[idx], shapes[idx]  # (m,), (m, N)
    denom = np.einsum("ri,rij,rj->r", phi, 2.0 * lam[:, None, None] * model.mass + damping, phi)
    if low is not None:
        # dR = dL L^T + L dL^T, so phi^T dR phi = 2 phi_i (L^T phi)_j for the term L_ij.
        rows, cols = np.tril_indices(n)
        quad = 2.0 * phi[:, rows] * (phi @ low)[:, cols]
    else:
        rows, cols = _upper(n)
        quad = phi[:, rows] * phi[:, cols] * np.where(rows == cols, 1.0, 2.0)  # phi^T dR phi per parameter
    jac = -(lam / denom)[:, None] * quad  # (m, P) complex
    # Relative pole errors so that every mode weighs alike, whatever its frequency.
    weight = 1.0 / np.abs(target)
    a = np.concatenate([jac.real, jac.imag]) * np.concatenate([weight, weight])[:, None]
    b = np.concatenate([(target - lam).real, (target - lam).imag]) * np.concatenate([weight, weight])
    # rcond drops the directions the poles cannot move (see the module docstring).
    step, *_ = np.linalg.lstsq(a, b, rcond=1e-10)
    return step


def _lancaster_step(
    model: StructuralModel, damping: np.ndarray, idx: np.ndarray, target: np.ndarray
) -> np.ndarray:
    """The literal substitution: current eigenvectors, measured poles, Lancaster's formula."""
    n = model.n_dof
    if idx.size != n:
        raise ValueError("the Lancaster update needs one identified pole per model mode")
    poles, shapes = _model_poles(model, damping)
    lam = poles[idx]
    phi = shapes[idx]  # (N modes, N dof)
    scale = np.einsum("ri,rij,rj->r", phi, 2.0 * lam[:, None, None] * model.mass + damping, phi)
    phi = phi / np.sqrt(scale)[:, None]
    m_phi = model.mass @ phi.T  # (dof, modes)
    new = -2.0 * ((m_phi * target**2) @ m_phi.T).real
    rows, cols = _upper(n)
    return new[rows, cols] - damping[rows, cols]


def default_start(model: StructuralModel, poles: np.ndarray, coupling: float = 0.5) -> np.ndarray:
    """The classically damped estimate with modal coupling added, (N, N) N s/m.

    In the modal basis D = Phi^T R Phi the proportional estimate is diagonal,
    and there the poles' sensitivity to the off-diagonal D_rs is zero (they
    enter the poles squared): Newton cannot leave it. Setting
    D_rs = coupling sqrt(D_rr D_ss) (all positive: an arbitrary choice, since
    the poles cannot tell the sign of D_rs, see the module docstring) breaks
    that symmetry.
    """
    target = np.asarray(poles, dtype=complex)
    r_prop, _ = proportional_estimate(model, np.abs(target) / (2 * np.pi), -target.real / np.abs(target))
    _, phi = undamped_modes(model)
    modal = phi.T @ r_prop @ phi
    d = np.sqrt(np.clip(np.diag(modal), 0.0, None))
    modal = np.diag(np.diag(modal)) + coupling * (np.outer(d, d) - np.diag(d * d))
    m_phi = model.mass @ phi
    return m_phi @ modal @ m_phi.T


def product_mismatch(model: StructuralModel, poles: np.ndarray) -> float:
    """Relative miss of prod |lambda_r|^2 against det K / det M; nan unless one pole per mode.

    For every R, the 2N poles of det(lambda^2 M + lambda R + K) multiply to
    det K / det M, so N identified poles consistent with the model must satisfy
    this; a nonzero value (noise, or a stiffness error) means no R matches them exactly.
    """
    target = np.asarray(poles, dtype=complex)
    if target.size != model.n_dof:
        return float("nan")
    sign_k, logdet_k = np.linalg.slogdet(model.stiffness)
    _, logdet_m = np.linalg.slogdet(model.mass)
    if sign_k <= 0:
        return float("nan")
    return float(np.expm1(2.0 * np.sum(np.log(np.abs(target))) - (logdet_k - logdet_m)))


def pilkey_inman(
    model: StructuralModel,
    poles: np.ndarray,
    start: np.ndarray | None = None,
    max_iter: int = 200,
    tol: float = 1e-10,
    update: Update = "newton",
    psd: bool = False,
) -> tuple[np.ndarray, dict[str, Any]]:
    """Symmetric R whose damped poles equal (or best fit) the identified ones (M, K known).

    Parameters
    ----------
    model : M and K (force and sensor vectors are not used).
    poles : (m,) complex, rad/s, m <= N: identified poles with positive imaginary
        part. Each is paired with the start model's mode nearest in natural
        frequency |lambda| (each mode once), and the pairing is kept.
    start : (N, N) N s/m, the first iterate; default ``default_start``. The
        Newton update moves it by minimum-norm steps, so the answer is a
        pole-consistent R near the start (pass e.g. a least-squares fit's R).
    max_iter : iteration limit.
    tol : the poles match when the largest relative pole error
        |lambda - lambda_id| / |lambda_id| is below it; the iteration also stops
        when the relative change of R falls below it (a least-squares solution
        when no R matches, e.g. noisy poles: see ``product_mismatch``).
    update : "newton" (default) or "lancaster"; see the module docstring.
    psd : Newton steps on the Cholesky factor L of R = L L^T, so that every iterate
        is positive semi-definite (dissipative); the start must be (``default_start``
        is). Only with the Newton update. The poles leave R underdetermined (2N - 1
        numbers for N (N + 1) / 2 terms), so a dissipative R matching them usually
        exists; where none does, the iteration stops at the best dissipative one.

    Returns
    -------
    damping : (N, N), N s/m.
    info : {"iterations": int, "converged": bool (poles matched, or stationary),
        "residual": largest relative pole error at the end, "match": (m,) model
        mode paired with each pole, "product_mismatch": see ``product_mismatch``}.
    """
    target = np.asarray(poles, dtype=complex)
    n = model.n_dof
    if target.ndim != 1 or not 1 <= target.size <= n:
        raise ValueError(f"poles must be a 1-D array of 1..{n} complex values")
    if not np.all(np.isfinite(target)) or np.any(target.imag <= 0):
        raise ValueError("poles must be finite with positive imaginary parts")
    if update not in ("newton", "lancaster"):
        raise ValueError(f"unknown update {update!r}; use 'newton' or 'lancaster'")
    if psd and update != "newton":
        raise ValueError("psd needs the Newton update (Lancaster's substitution has no factor to keep)")
    if start is None:
        start = default_start(model, target)
    damping = model.check_damping(start)
    if damping.shape != (n, n):
        raise ValueError(f"start must be one ({n}, {n}) matrix")
    damping = 0.5 * (damping + damping.T)

    start_poles, _ = _model_poles(model, damping)
    if not np.all(np.isfinite(start_poles)):
        raise ValueError("the start damping matrix has overdamped modes")
    idx = match_modes(np.abs(target), np.abs(start_poles))
    theta = matrix_to_theta(damping, psd)  # ValueError for an indefinite start with psd
    to_matrix = (lambda t: theta_to_matrix(t, n, psd=True)) if psd else (lambda t: _to_matrix(t, n))
    damping = to_matrix(theta)
    cost = _cost(start_poles[idx], target)
    converged = False
    iterations = 0
    for iterations in range(1, max_iter + 1):  # noqa: B007 - reported after the loop
        if update == "newton":
            low = None
            if psd:
                low = np.zeros((n, n))
                low[np.tril_indices(n)] = theta
            step = _newton_step(model, damping, idx, target, low)
            # Halve the step until the summed squared pole error does not grow.
            for _ in range(40):
                trial_cost = _cost(_model_poles(model, to_matrix(theta + step))[0][idx], target)
                if trial_cost <= cost:
                    break
                step = 0.5 * step
            else:
                break  # no descent: a (local) least-squares solution
            cost = trial_cost
        else:
            step = _lancaster_step(model, damping, idx, target)
        theta = theta + step
        damping = to_matrix(theta)
        residual = _pole_error(_model_poles(model, damping)[0][idx], target)
        stationary = np.linalg.norm(step) <= tol * np.linalg.norm(theta)
        if (update == "newton" and residual < tol) or stationary or not np.isfinite(residual):
            converged = bool(np.isfinite(residual))
            break
    residual = _pole_error(_model_poles(model, damping)[0][idx], target)
    info = {
        "iterations": iterations,
        "converged": converged or residual < tol,
        "residual": residual,
        "match": idx,
        "product_mismatch": product_mismatch(model, target),
    }
    return damping, info
