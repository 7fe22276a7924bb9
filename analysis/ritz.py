"""Ritz assumed-modes model of a cantilever with the seed's admissible functions, eq (6).

phi_i(x) = 1 - cos(i pi x / L) + (-1)^(i+1) (i pi x / L)^2 / 2,  i = 1..N

Each phi_i satisfies the geometric boundary conditions at the clamp (phi = phi' = 0)
and, by the choice of the quadratic term, zero bending moment at the free end.
M_ij = rho A int phi_i phi_j dx and K_ij = E I int phi_i'' phi_j'' dx.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
import scipy.linalg

from analysis.beam import TABLE_1, BeamProperties, SectionSource
from analysis.structure import StructuralModel

MatrixMethod = Literal["quadrature", "closed_form"]


def admissible_functions(
    x_m: np.ndarray | float, n_functions: int, length_m: float, derivative: int = 0
) -> np.ndarray:
    """Values of phi_1..phi_N of eq (6) (or their 1st/2nd x-derivative) at positions x.

    Parameters
    ----------
    x_m : positions along the beam from the clamp, m; any shape S.
    n_functions : N >= 1.
    length_m : beam length L, m.
    derivative : 0, 1 or 2 (d^k/dx^k, units 1/m^k).

    Returns
    -------
    Array of shape (N, *S).
    """
    _check_n(n_functions)
    x = np.asarray(x_m, dtype=float)
    i = np.arange(1, n_functions + 1, dtype=float).reshape((-1,) + (1,) * x.ndim)
    k = i * np.pi / length_m  # wavenumber of each cosine, 1/m
    sign = np.where(i % 2 == 1, 1.0, -1.0)  # (-1)^(i+1)
    if derivative == 0:
        return 1.0 - np.cos(k * x) + 0.5 * sign * (k * x) ** 2
    if derivative == 1:
        return k * np.sin(k * x) + sign * k**2 * x
    if derivative == 2:
        return k**2 * (np.cos(k * x) + sign)
    raise ValueError(f"derivative must be 0, 1 or 2, got {derivative}")


def _check_n(n_functions: int) -> None:
    if not isinstance(n_functions, (int, np.integer)) or n_functions < 1:
        raise ValueError(
            f"the number of admissible functions must be a positive integer, got {n_functions!r}"
        )


def _gauss_points(n_functions: int, length_m: float) -> tuple[np.ndarray, np.ndarray]:
    # The integrands are products of cosines up to wavenumber 2 N pi / L with
    # polynomials of degree <= 4; a generous fixed rule resolves them to round-off.
    n_points = 40 + 8 * n_functions
    xi, w = np.polynomial.legendre.leggauss(n_points)
    return 0.5 * length_m * (xi + 1.0), 0.5 * length_m * w


def ritz_matrices(
    beam: BeamProperties = TABLE_1, n_functions: int = 3, method: MatrixMethod = "quadrature"
) -> tuple[np.ndarray, np.ndarray]:
    """Mass and stiffness matrices of the assumed-modes model.

    Returns ``(M, K)``, each (N, N): M in kg, K in N/m (the eq (6) functions are
    dimensionless, so the generalized coordinates q are in m).

    ``method="closed_form"`` evaluates the seed's eqs (10)-(11) with the leading
    ``rho L`` read as rho*A*L (mass per length times length); ``"quadrature"``
    integrates eq (6) by Gauss-Legendre quadrature. They agree to round-off.
    """
    _check_n(n_functions)
    length = beam.length_m
    if method == "quadrature":
        x, w = _gauss_points(n_functions, length)
        phi = admissible_functions(x, n_functions, length)
        phi2 = admissible_functions(x, n_functions, length, derivative=2)
        mass = beam.mass_per_length_kg_m * (phi * w) @ phi.T
        stiffness = beam.flexural_rigidity_n_m2 * (phi2 * w) @ phi2.T
    elif method == "closed_form":
        i = np.arange(1, n_functions + 1, dtype=float)[:, None]
        j = i.T
        sij = (-1.0) ** (i + j)
        si = (-1.0) ** (i + 1)
        sj = (-1.0) ** (j + 1)
        delta = np.eye(n_functions)
        pi2 = np.pi**2
        mass = beam.mass_kg * (
            1.0
            + sij * ((i / j) ** 2 + (j / i) ** 2)
            + 0.5 * delta
            + si * i**2 * pi2 / 6.0
            + sj * j**2 * pi2 / 6.0
            + sij * i**2 * j**2 * pi2**2 / 20.0
        )
        stiffness = beam.flexural_rigidity_n_m2 * (sij + 0.5 * delta) * i**2 * j**2 * pi2**2 / length**3
    else:
        raise ValueError(f"unknown method {method!r}; use 'quadrature' or 'closed_form'")
    # Symmetrise: quadrature round-off would otherwise leave ~1e-16 asymmetry.
    return 0.5 * (mass + mass.T), 0.5 * (stiffness + stiffness.T)


def ritz_frequencies_hz(
    beam: BeamProperties = TABLE_1, n_functions: int = 3, method: MatrixMethod = "quadrature"
) -> np.ndarray:
    """Undamped natural frequencies of the N-function Ritz model, Hz, ascending, shape (N,)."""
    mass, stiffness = ritz_matrices(beam, n_functions, method)
    omega_sq = scipy.linalg.eigh(stiffness, mass, eigvals_only=True)
    return np.sqrt(omega_sq) / (2.0 * np.pi)


@dataclass(frozen=True)
class RitzBeam:
    """The assumed-modes cantilever: properties, N, and the derived M and K."""

    beam: BeamProperties
    n_functions: int
    mass: np.ndarray
    stiffness: np.ndarray

    @classmethod
    def build(
        cls,
        beam: BeamProperties = TABLE_1,
        n_functions: int = 3,
        section: SectionSource = "tabulated",
        method: MatrixMethod = "quadrature",
    ) -> RitzBeam:
        beam = beam.with_section(section)
        mass, stiffness = ritz_matrices(beam, n_functions, method)
        return cls(beam, n_functions, mass, stiffness)

    def shapes(self, x_m: np.ndarray | float, derivative: int = 0) -> np.ndarray:
        """Admissible functions at x, shape (N, *x.shape)."""
        self._check_position(x_m)
        return admissible_functions(x_m, self.n_functions, self.beam.length_m, derivative)

    def frequencies_hz(self) -> np.ndarray:
        """Undamped natural frequencies, Hz, shape (N,)."""
        omega_sq = scipy.linalg.eigh(self.stiffness, self.mass, eigvals_only=True)
        return np.sqrt(omega_sq) / (2.0 * np.pi)

    def structure(self, force_at_m: float | None = None, sensor_at_m: float | None = None) -> StructuralModel:
        """The second-order model with a point force at ``force_at_m`` and a sensor at
        ``sensor_at_m`` (both default to the tip, as in the seed's setup)."""
        length = self.beam.length_m
        x_f = length if force_at_m is None else force_at_m
        x_s = length if sensor_at_m is None else sensor_at_m
        return StructuralModel(
            mass=self.mass,
            stiffness=self.stiffness,
            force_shape=self.shapes(x_f),
            sensor_shape=self.shapes(x_s),
        )

    def _check_position(self, x_m: np.ndarray | float) -> None:
        x = np.asarray(x_m, dtype=float)
        if not np.all(np.isfinite(x)) or np.any(x < 0.0) or np.any(x > self.beam.length_m):
            raise ValueError(f"positions must lie on the beam, 0..{self.beam.length_m} m")
