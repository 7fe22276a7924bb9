"""Least-squares frequency-domain (LSFD) estimation of modal constants for given poles.

Model, for each FRF o (every form uses the same pole-fraction terms):

    H_o(w) = sum_r [ A_or / (j w - lambda_r) + conj(A_or) / (j w - conj(lambda_r)) ]
             + LR_o * l(w) + UR_o * u(w),

A_or in the FRF's units times rad/s. The residual terms stand for the modes below
and above the band, whose receptance there is about -1/(w^2 M_LR) (mass line of the
modes below: they behave as masses) and 1/K_UR (stiffness line of the modes above):

    form          l(w)          u(w)      residual coefficients
    receptance    -1/w^2        1         LR = 1/M_LR,  UR = 1/K_UR
    mobility      1/(j w)       j w       (j w times receptance)
    accelerance   1             -w^2      (-w^2 times receptance: the lower residual
                                           is a constant 1/M_LR, the upper -w^2/K_UR)

LR and UR are fitted complex (their imaginary parts absorb the damping of the
out-of-band modes). A_r is complex and enters with its conjugate, so the problem is
linear in (Re A, Im A, Re LR, Im LR, Re UR, Im UR): one real least-squares solve for
all FRFs at once (they share the matrix). Lines at 0 Hz are skipped for receptance and
mobility, whose lower residual is infinite there.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

FORMS = ("receptance", "mobility", "accelerance")


@dataclass(frozen=True)
class LsfdResult:
    """modal_constants (n_modes, n_frf) complex; lower, upper (n_frf,) complex;
    synthesized (n_frf, n_lines); mode_terms (n_modes, n_frf, n_lines) and
    residual_terms (n_frf, n_lines): the pieces of the synthesis; relative_error:
    ||H - H_syn|| / ||H|| over all FRFs and the lines used."""

    modal_constants: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    synthesized: np.ndarray
    mode_terms: np.ndarray
    residual_terms: np.ndarray
    relative_error: float


def residual_bases(omega: np.ndarray, form: str) -> tuple[np.ndarray, np.ndarray]:
    """l(w), u(w) of the table in the module docstring, (n_lines,) complex."""
    jw = 1j * omega
    with np.errstate(all="ignore"):
        if form == "receptance":
            return -1.0 / omega**2 + 0j, np.ones_like(jw)
        if form == "mobility":
            return 1.0 / jw, jw
        if form == "accelerance":
            return np.ones_like(jw), -(omega**2) + 0j
    raise ValueError(f"form must be one of {', '.join(FORMS)}, got {form!r}")


def lsfd(
    frequency_hz: np.ndarray,
    frf: np.ndarray,
    poles: np.ndarray,
    form: str = "accelerance",
    lower_residual: bool = True,
    upper_residual: bool = True,
) -> LsfdResult:
    """Modal constants and residuals for fixed poles (rad/s, Im > 0).

    frequency_hz (n_lines,) Hz; frf (n_frf, n_lines) or (n_lines,) complex.
    """
    f = np.asarray(frequency_hz, dtype=float)
    h = np.atleast_2d(np.asarray(frf, dtype=complex))
    lam = np.asarray(poles, dtype=complex).ravel()
    omega = 2 * np.pi * f
    jw = 1j * omega[:, None]
    with np.errstate(all="ignore"):
        p_plus = 1.0 / (jw - lam[None, :])  # (F, R)
        p_minus = 1.0 / (jw - np.conj(lam)[None, :])
    # A = a + j b: A/(jw-l) + conj(A)/(jw-conj l) = a (p+ + p-) + b j (p+ - p-)
    cols = [p_plus + p_minus, 1j * (p_plus - p_minus)]
    low, up = residual_bases(omega, form)
    if lower_residual:
        cols += [low[:, None], 1j * low[:, None]]
    if upper_residual:
        cols += [up[:, None], 1j * up[:, None]]
    basis = np.concatenate(cols, axis=1)  # (F, n_unknowns), complex
    ok = np.all(np.isfinite(basis), axis=1)
    design = np.concatenate([basis[ok].real, basis[ok].imag], axis=0)
    target = np.concatenate([h[:, ok].real, h[:, ok].imag], axis=1).T  # (2F, n_frf)
    # Column scaling: the residual bases differ from the pole terms by orders of magnitude.
    norm = np.linalg.norm(design, axis=0)
    norm[norm == 0] = 1.0
    coef = np.linalg.lstsq(design / norm, target, rcond=None)[0] / norm[:, None]  # (n_unknowns, n_frf)
    n = lam.size
    a = coef[:n] + 1j * coef[n : 2 * n]  # (R, n_frf)
    rest = coef[2 * n :]
    lower = upper = np.zeros(h.shape[0], dtype=complex)
    if lower_residual:
        lower, rest = rest[0] + 1j * rest[1], rest[2:]
    if upper_residual:
        upper = rest[0] + 1j * rest[1]
    mode_terms = a[:, :, None] * p_plus.T[:, None, :] + np.conj(a)[:, :, None] * p_minus.T[:, None, :]
    mode_terms = np.where(ok[None, None, :], mode_terms, 0.0)
    residual_terms = np.where(ok, lower[:, None] * low + upper[:, None] * up, 0.0)
    synthesized = mode_terms.sum(axis=0) + residual_terms
    denom = np.linalg.norm(h[:, ok])
    error = float(np.linalg.norm(h[:, ok] - synthesized[:, ok]) / denom) if denom > 0 else np.inf
    return LsfdResult(a, lower, upper, synthesized, mode_terms, residual_terms, error)
