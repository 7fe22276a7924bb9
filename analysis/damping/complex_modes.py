"""The damping matrix from measured complex modes (poles and complex shapes at points).

A multi-point test identifies poles s_j (rad/s, s_j = -zeta_j omega_j + i omega_d,j,
upper half-plane) and complex mode shapes at n_points >= N measurement points. In the
Ritz model a shape at the points is B q with B (n_points, N) the Ritz functions at the
points (phi_i(x_p)), so the Ritz coordinates q (N,) of each mode are the least-squares
solution of B q = shape (``ritz_coordinates``). The methods then work with the known
Ritz mass M (and for Lancaster nothing else):

* ``adhikari_woodhouse`` -- the first-order method of S. Adhikari and J. Woodhouse,
  "Identification of damping: part 1, viscous damping", JSV 243(1) (2001) 43-61.
  Each mode's phase is set so that its real part u_j and imaginary part v_j are
  M-orthogonal (the M-weighted "most real" phase) and u_j^T M u_j = 1. To first order
  in the damping, v_j = sum_(k != j) A_kj u_k with A_kj = omega_j C'_kj / (omega_j^2 -
  omega_k^2), C' = U^T C U the damping in the basis of the undamped modes, and
  C'_jj = 2 zeta_j omega_j = -2 Re s_j. So A = U^-1 V, C'_kj = (omega_j^2 - omega_k^2)
  A_kj / omega_j, and C = U^-T C' U^-1 (omega_j = |s_j|). C is not symmetric in
  general (noise, and second-order terms).
* ``adhikari_woodhouse_symmetric`` -- the same with each pair C'_kj = C'_jk = c taken
  as the least-squares solution of both of its equations, c = (omega_j^2 - omega_k^2)
  A_kj / omega_j and c = (omega_k^2 - omega_j^2) A_jk / omega_k, each in C' units:
  their mean. C is symmetric by construction. (Weighting the equations as
  omega_j c = ... instead favours the higher mode and, on exact modes of the seed's
  3-function beam, doubled the error: 18 % against 10 %.)
* ``lancaster`` -- Lancaster's formula C = -M (sum_j s_j^2 q_j q_j^T + c.c.) M, exact
  for any viscous damping, when the shapes are scaled by their residues (the
  displacement FRF between points a and b has residue psi_aj psi_bj at s_j), as a
  multi-point test with a driving point gives them; the scaling through measured
  residues instead of the unknown C is what the "modified" Lancaster method of the
  damping-identification literature does. It needs all N modes, exactly scaled.

Assumptions: viscous damping; N modes identified (one per Ritz function); the
Ritz basis represents the measured shapes (``mapping_residual`` says how well);
for Adhikari-Woodhouse light damping, well-separated modes (the error is first
order in damping / frequency spacing).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

Method = Literal["adhikari_woodhouse", "adhikari_woodhouse_symmetric", "lancaster"]
METHODS: tuple[str, ...] = ("adhikari_woodhouse", "adhikari_woodhouse_symmetric", "lancaster")


@dataclass
class ComplexModeDamping:
    """R identified from complex modes.

    method : one of METHODS.
    damping_matrix : (N, N), N s/m (symmetric except for plain adhikari_woodhouse).
    modal_damping : (N, N) C' in the basis of the normalised real parts (N s/m per
        kg, i.e. 1/s), Adhikari-Woodhouse only (None for lancaster).
    ritz_modes : (N, m) complex Ritz coordinates of the modes as used (normalised
        for Adhikari-Woodhouse; residue-scaled, displacement, for lancaster).
    asymmetry : ||R - R^T|| / ||R|| (Frobenius).
    mapping_residual : (m,) ||B q - shape|| / ||shape|| of each mode's Ritz mapping.
    """

    method: str
    damping_matrix: np.ndarray
    modal_damping: np.ndarray | None
    ritz_modes: np.ndarray
    asymmetry: float
    mapping_residual: np.ndarray


def ritz_coordinates(
    shapes_at_points: np.ndarray, basis_at_points: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares Ritz coordinates of complex shapes measured at points.

    shapes_at_points : (n_points, m) complex, column j the shape of mode j (any units).
    basis_at_points : (n_points, N) real, phi_i(x_p): the Ritz functions at the points
        (analysis.ritz.RitzBeam.shapes(x).T); needs n_points >= N and full column rank.
    Returns q (N, m) complex and each mode's relative mapping residual (m,).
    """
    y = np.asarray(shapes_at_points, dtype=complex)
    b = np.asarray(basis_at_points, dtype=float)
    if y.ndim == 1:
        y = y[:, None]
    if b.ndim != 2 or y.ndim != 2 or b.shape[0] != y.shape[0]:
        raise ValueError(
            f"shapes (n_points, m) and basis (n_points, N) must share n_points, got {y.shape}, {b.shape}"
        )
    if b.shape[0] < b.shape[1]:
        raise ValueError(f"{b.shape[0]} points cannot fix {b.shape[1]} Ritz coordinates: need n_points >= N")
    if np.linalg.matrix_rank(b) < b.shape[1]:
        raise ValueError("the Ritz functions at these points are linearly dependent: choose other points")
    q, *_ = np.linalg.lstsq(b, y, rcond=None)
    with np.errstate(invalid="ignore", divide="ignore"):
        resid = np.linalg.norm(b @ q - y, axis=0) / np.linalg.norm(y, axis=0)
    return q, resid


def normalise_modes(q: np.ndarray, mass: np.ndarray) -> np.ndarray:
    """Rotate each complex mode (columns of q, (N, m)) to its M-weighted most-real phase
    (Re q^T M Im q = 0, larger real part) and scale to Re q^T M Re q = 1."""
    q = np.asarray(q, dtype=complex)
    m = np.asarray(mass, dtype=float)
    out = np.empty_like(q)
    for j in range(q.shape[1]):  # m modes, m <= 10
        z = q[:, j]
        theta = -0.5 * np.angle(z @ m @ z)
        z = z * np.exp(1j * theta)
        out[:, j] = z / np.sqrt(z.real @ m @ z.real)
    return out


def _check_poles(poles: np.ndarray, m: int) -> np.ndarray:
    s = np.asarray(poles, dtype=complex).ravel()
    if s.size != m:
        raise ValueError(f"{s.size} poles for {m} shapes")
    if not np.all(np.isfinite(s)) or np.any(s.imag <= 0):
        raise ValueError("poles must be finite with positive imaginary part (s = -zeta w + i w_d)")
    return s


def adhikari_woodhouse(
    poles: np.ndarray,
    shapes_at_points: np.ndarray,
    basis_at_points: np.ndarray,
    mass: np.ndarray,
    symmetric: bool = False,
) -> ComplexModeDamping:
    """Adhikari-Woodhouse (2001) first-order identification of R in the Ritz basis.

    poles : (N,) complex, rad/s, upper half-plane.
    shapes_at_points : (n_points, N) complex shapes (any scaling and phase).
    basis_at_points : (n_points, N) Ritz functions at the points, n_points >= N.
    mass : (N, N) Ritz mass matrix, kg.
    symmetric : the symmetry-preserving variant (module docstring).
    """
    mass = np.asarray(mass, dtype=float)
    n = mass.shape[0]
    q, resid = ritz_coordinates(shapes_at_points, basis_at_points)
    if q.shape != (n, n):
        raise ValueError(f"Adhikari-Woodhouse in the Ritz basis needs N = {n} modes, got {q.shape[1]}")
    s = _check_poles(poles, n)
    z = normalise_modes(q, mass)
    u, v = z.real, z.imag
    a = np.linalg.solve(u, v)
    w = np.abs(s)
    diff = w[None, :] ** 2 - w[:, None] ** 2  # (k, j): w_j^2 - w_k^2
    c_mod = diff * a / w[None, :]
    if symmetric:
        c_mod = 0.5 * (c_mod + c_mod.T)
    c_mod[np.diag_indices(n)] = -2.0 * s.real
    u_inv = np.linalg.inv(u)
    r = u_inv.T @ c_mod @ u_inv
    if symmetric:
        r = 0.5 * (r + r.T)
    return ComplexModeDamping(
        method="adhikari_woodhouse_symmetric" if symmetric else "adhikari_woodhouse",
        damping_matrix=r,
        modal_damping=c_mod,
        ritz_modes=z,
        asymmetry=_asymmetry(r),
        mapping_residual=resid,
    )


def lancaster(
    poles: np.ndarray,
    residue_shapes_at_points: np.ndarray,
    basis_at_points: np.ndarray,
    mass: np.ndarray,
    quantity: Literal["displacement", "acceleration"] = "displacement",
) -> ComplexModeDamping:
    """Lancaster's formula R = -M (sum_j s_j^2 q_j q_j^T + c.c.) M from residue-scaled modes.

    residue_shapes_at_points : (n_points, N) complex psi with residue_ab,j = psi_aj psi_bj
        of the FRF of ``quantity`` (m/N or (m/s^2)/N per unit force, poles in rad/s);
        an accelerance residue is s_j^2 times the receptance one, so acceleration
        shapes are divided by s_j. Sign of each column is irrelevant.
    Other inputs as ``adhikari_woodhouse``. Returns the real part (exact data give a
    real R; the imaginary part left over is round-off or inconsistency).
    """
    mass = np.asarray(mass, dtype=float)
    n = mass.shape[0]
    q, resid = ritz_coordinates(residue_shapes_at_points, basis_at_points)
    if q.shape != (n, n):
        raise ValueError(f"Lancaster's formula needs all N = {n} modes, got {q.shape[1]}")
    s = _check_poles(poles, n)
    if quantity == "acceleration":
        q = q / s[None, :]
    elif quantity != "displacement":
        raise ValueError("quantity must be 'displacement' or 'acceleration'")
    inner = (q * s**2) @ q.T
    r = -mass @ (2.0 * inner.real) @ mass
    return ComplexModeDamping(
        method="lancaster",
        damping_matrix=0.5 * (r + r.T),
        modal_damping=None,
        ritz_modes=q,
        asymmetry=_asymmetry(r),
        mapping_residual=resid,
    )


def identify(
    poles: np.ndarray,
    shapes_at_points: np.ndarray,
    basis_at_points: np.ndarray,
    mass: np.ndarray,
    method: Method = "adhikari_woodhouse_symmetric",
    quantity: Literal["displacement", "acceleration"] = "displacement",
) -> ComplexModeDamping:
    """Dispatch by method name (METHODS); ``quantity`` matters for lancaster only."""
    if method == "adhikari_woodhouse":
        return adhikari_woodhouse(poles, shapes_at_points, basis_at_points, mass)
    if method == "adhikari_woodhouse_symmetric":
        return adhikari_woodhouse(poles, shapes_at_points, basis_at_points, mass, symmetric=True)
    if method == "lancaster":
        return lancaster(poles, shapes_at_points, basis_at_points, mass, quantity)
    raise ValueError(f"unknown method {method!r}; use one of {', '.join(METHODS)}")


def _asymmetry(r: np.ndarray) -> float:
    norm = np.linalg.norm(r)
    return float(np.linalg.norm(r - r.T) / norm) if norm > 0 else 0.0
