"""The outcome of a damping fit, shared by every method (GA, DE, least squares, modal)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class FitResult:
    """An identified damping matrix and how it was found.

    method : short name ("ga", "de", "least_squares", ...).
    damping_matrix : (N, N), N s/m, symmetric.
    theta : (P,), the parameter vector of ``damping_matrix`` in the coding the fit
        used (analysis.damping.params; ``psd`` says which).
    psi : objective value reached (eq (17) or its FRF form; units of the data).
    n_evaluations : model evaluations (one damping matrix = one evaluation, however
        many hits or matrices a batched call holds).
    history : (n_iterations,), best psi after each generation / iteration, for a
        convergence plot; non-increasing only where the method keeps its best.
    success, message : the optimiser's own verdict.
    psd : True if theta is a Cholesky factor (R = L L^T).
    jacobian : (n_res, P) d(residual)/d(theta) at the solution, least squares only.
    residual : (n_res,) residual vector at the solution, least squares only.
    """

    method: str
    damping_matrix: np.ndarray
    theta: np.ndarray
    psi: float
    n_evaluations: int
    history: np.ndarray
    success: bool
    message: str
    psd: bool = False
    jacobian: np.ndarray | None = field(default=None, repr=False)
    residual: np.ndarray | None = field(default=None, repr=False)
