"""Local least squares, differential evolution and multi-start fits of the damping matrix.

All work on the parameter vector theta of analysis.damping.params (``psd`` picks the
coding) and count model evaluations the same way: one damping matrix is one
evaluation, however it is batched.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import scipy.optimize

from analysis.damping.params import matrix_to_theta, n_params, theta_to_matrix
from analysis.damping.result import FitResult

ResidualFn = Callable[[np.ndarray], np.ndarray]
BatchedResidualFn = Callable[[np.ndarray], np.ndarray]


def _steps(theta: np.ndarray) -> np.ndarray:
    # Relative steps with an absolute floor: entries near zero still get a usable step.
    return np.sqrt(np.finfo(float).eps) * np.maximum(1.0, np.abs(theta))


def fit_least_squares(
    residual_fn: ResidualFn,
    start: np.ndarray,
    psd: bool = False,
    batched_residuals: BatchedResidualFn | None = None,
    method: str = "trf",
    max_nfev: int | None = None,
) -> FitResult:
    """Minimise ||residual_fn(R)||^2 from a start matrix with ``scipy.optimize.least_squares``.

    Parameters
    ----------
    residual_fn : (N, N) damping matrix, N s/m -> (n_res,) residuals.
    start : (N, N) symmetric start (positive semi-definite if psd).
    psd : fit the Cholesky factor, R = L L^T.
    batched_residuals : (B, N, N) -> (B, n_res). When given, the Jacobian is a
        forward difference with all P perturbed matrices in one call; the stored
        ``jacobian`` is a central difference at the solution (2P matrices, one call).
        Otherwise scipy's 2-point scheme calls residual_fn P times per Jacobian.
    method : "trf" or "lm".
    max_nfev : passed to scipy (counts residual_fn calls, not Jacobian ones).

    Returns
    -------
    FitResult with psi = ||r|| / n_res (eq (17) for time-domain residuals), the
    Jacobian d r / d theta (n_res, P) and the residual at the solution; history holds
    the best psi after each residual_fn call.
    """
    start = np.asarray(start, dtype=float)
    n = start.shape[0]
    x0 = matrix_to_theta(start, psd)
    count = [0]
    history: list[float] = []
    last: dict[str, np.ndarray] = {}

    def fun(theta: np.ndarray) -> np.ndarray:
        count[0] += 1
        r = np.asarray(residual_fn(theta_to_matrix(theta, n, psd)), dtype=float)
        value = float(np.linalg.norm(r) / r.size) if np.all(np.isfinite(r)) else np.inf
        history.append(min(value, history[-1]) if history else value)
        last["x"], last["r"] = theta.copy(), r
        return r

    def perturbed(theta: np.ndarray, central: bool) -> tuple[np.ndarray, np.ndarray]:
        h = _steps(theta)
        eye = np.diag(h)
        thetas = np.concatenate([theta + eye, theta - eye]) if central else theta + eye
        count[0] += thetas.shape[0]
        return np.asarray(batched_residuals(theta_to_matrix(thetas, n, psd)), dtype=float), h

    def jac(theta: np.ndarray) -> np.ndarray:
        r0 = last["r"] if "x" in last and np.array_equal(last["x"], theta) else fun(theta)
        r, h = perturbed(theta, central=False)
        return ((r - r0) / h[:, None]).T

    try:
        sol = scipy.optimize.least_squares(
            fun,
            x0,
            jac=jac if batched_residuals is not None else "2-point",
            method=method,
            x_scale="jac",
            max_nfev=max_nfev,
        )
    except ValueError as exc:  # e.g. non-finite residuals at the start
        return FitResult(
            "least_squares", start.copy(), x0, np.inf, count[0], np.array(history), False, str(exc), psd
        )
    theta = sol.x
    residual = np.asarray(sol.fun, dtype=float)
    if batched_residuals is not None:
        r, h = perturbed(theta, central=True)
        p = theta.size
        jacobian = ((r[:p] - r[p:]) / (2.0 * h[:, None])).T
    else:
        jacobian = np.asarray(sol.jac, dtype=float)
    return FitResult(
        method=f"least_squares_{method}",
        damping_matrix=theta_to_matrix(theta, n, psd),
        theta=theta,
        psi=float(np.linalg.norm(residual) / residual.size),
        n_evaluations=count[0],
        history=np.array(history),
        success=bool(sol.success),
        message=str(sol.message),
        psd=psd,
        jacobian=jacobian,
        residual=residual,
    )


def fit_de(
    objective: Callable[[np.ndarray], np.ndarray],
    n: int,
    seed: int = 0,
    bounds: tuple[float, float] = (-10.0, 10.0),
    psd: bool = False,
    maxiter: int = 1000,
    popsize: int = 15,
    tol: float = 1e-8,
    polish: bool = False,
) -> FitResult:
    """Minimise objective(R) with ``scipy.optimize.differential_evolution``, vectorised.

    objective : (B, N, N) -> (B,), e.g. ``lambda r: psi(data, r)``; each generation
        is one call (scipy's ``vectorized=True`` hands over a (P, S) array).
    bounds : the same (lo, hi) for every entry of theta.
    maxiter, popsize, tol : scipy's (population = popsize x P members).
    polish : let scipy finish with L-BFGS-B (many single evaluations); prefer
        ``fit_least_squares`` from the DE result.
    Non-finite objective values (unstable members) are replaced by 1e100, so that
    scipy's convergence test (spread of the population's values) stays defined.
    """
    p = n_params(n)
    count = [0]
    history: list[float] = []

    def func(x: np.ndarray) -> np.ndarray:
        thetas = np.asarray(x, dtype=float).T.reshape(-1, p)  # (S, P)
        count[0] += thetas.shape[0]
        values = np.asarray(objective(theta_to_matrix(thetas, n, psd)), dtype=float).reshape(-1)
        return np.where(np.isfinite(values), values, 1e100)

    def callback(intermediate_result: scipy.optimize.OptimizeResult) -> None:
        history.append(float(intermediate_result.fun))

    sol = scipy.optimize.differential_evolution(
        func,
        [tuple(map(float, bounds))] * p,
        seed=seed,
        maxiter=maxiter,
        popsize=popsize,
        tol=tol,
        polish=polish,
        vectorized=True,
        updating="deferred",
        callback=callback,
    )
    return FitResult(
        method="de",
        damping_matrix=theta_to_matrix(sol.x, n, psd),
        theta=np.asarray(sol.x, dtype=float),
        psi=float(sol.fun) if sol.fun < 1e100 else np.inf,
        n_evaluations=count[0],
        history=np.array(history),
        success=bool(sol.success),
        message=str(sol.message),
        psd=psd,
    )


def multi_start(
    residual_fn: ResidualFn,
    batched_residuals: BatchedResidualFn | None,
    n: int,
    starts: int = 8,
    seed: int = 0,
    scale: float | None = None,
    psd: bool = False,
) -> list[FitResult]:
    """Least-squares fits from random positive semi-definite starts, sorted by psi.

    Each start is R0 = L L^T with L's entries N(0, scale / N), so entries of R0 are
    of order ``scale`` (N s/m; default 5, the size of the seed's eq (18) entries).
    If all fits reach the same psi and R, the optimum is very likely global; a spread
    shows local minima or a flat (unidentifiable) direction.
    """
    rng = np.random.default_rng(seed)
    s = 5.0 if scale is None else float(scale)
    results = []
    for _ in range(starts):  # a handful of independent local fits: not a population loop
        low = np.tril(rng.normal(0.0, np.sqrt(s / n), size=(n, n)))
        results.append(fit_least_squares(residual_fn, low @ low.T, psd, batched_residuals))
    return sorted(results, key=lambda r: r.psi)
