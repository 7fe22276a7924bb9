"""The exact Euler-Bernoulli cantilever: frequencies, mode shapes and a modal model.

beta_n L solves 1 + cos(beta L) cosh(beta L) = 0 (1.8751041, 4.6940911, ...), and
omega_n = (beta_n L)^2 sqrt(E I / (rho A L^4)). Mode shapes are the classical

    phi_n(x) = cosh(b x) - cos(b x) - sigma_n (sinh(b x) - sin(b x)),
    sigma_n = (cosh(b L) + cos(b L)) / (sinh(b L) + sin(b L)),

normalised so that int_0^L phi_n^2 dx = L (|phi_n(L)| = 2); the modal mass is
then rho A L for every mode.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.optimize

from analysis.beam import TABLE_1, BeamProperties, SectionSource
from analysis.structure import StructuralModel


def cantilever_roots(n_modes: int) -> np.ndarray:
    """beta_n L for n = 1..n_modes, shape (n_modes,), to full double precision."""
    if not isinstance(n_modes, (int, np.integer)) or n_modes < 1:
        raise ValueError(f"the number of modes must be a positive integer, got {n_modes!r}")

    # cos(x) + sech(x) has the same roots and stays O(1) for large x; sech is
    # written with e^-x so that it never overflows.
    def f(x: float) -> float:
        e = np.exp(-x)
        return np.cos(x) + 2.0 * e / (1.0 + e * e)

    return np.array(
        [
            scipy.optimize.brentq(f, (n - 1) * np.pi, n * np.pi, xtol=1e-15, rtol=4 * np.finfo(float).eps)
            for n in range(1, n_modes + 1)
        ]
    )


def cantilever_frequencies_hz(beam: BeamProperties = TABLE_1, n_modes: int = 3) -> np.ndarray:
    """Natural frequencies of the exact clamped-free beam, Hz, shape (n_modes,)."""
    beta_l = cantilever_roots(n_modes)
    scale = np.sqrt(beam.flexural_rigidity_n_m2 / (beam.mass_per_length_kg_m * beam.length_m**4))
    return beta_l**2 * scale / (2.0 * np.pi)


def cantilever_mode_shapes(x_m: np.ndarray | float, n_modes: int, length_m: float) -> np.ndarray:
    """phi_n(x) for n = 1..n_modes, shape (n_modes, *x.shape), dimensionless.

    Written in decaying exponentials so that high modes do not cancel catastrophically.
    """
    x = np.asarray(x_m, dtype=float)
    beta_l = cantilever_roots(n_modes).reshape((-1,) + (1,) * x.ndim)
    u = beta_l * x / length_m
    e_l = np.exp(-beta_l)
    sin_l, cos_l = np.sin(beta_l), np.cos(beta_l)
    # sigma = (cosh bL + cos bL) / (sinh bL + sin bL), times 2 e^-bL above and below.
    sigma = (1.0 + 2.0 * cos_l * e_l + e_l**2) / (1.0 - e_l**2 + 2.0 * sin_l * e_l)
    # (1 - sigma) e^u, with 1 - sigma and e^u / sinh(bL) each formed without overflow.
    one_minus_sigma_e_u = (
        (sin_l - cos_l - e_l) * 2.0 * np.exp(u - beta_l) / (1.0 - e_l**2 + 2.0 * sin_l * e_l)
    )
    cosh_minus_sigma_sinh = 0.5 * (one_minus_sigma_e_u + (1.0 + sigma) * np.exp(-u))
    return cosh_minus_sigma_sinh - np.cos(u) + sigma * np.sin(u)


@dataclass(frozen=True)
class ExactCantilever:
    """The continuous cantilever truncated to its first ``n_modes`` modes."""

    beam: BeamProperties
    n_modes: int

    @classmethod
    def build(
        cls, beam: BeamProperties = TABLE_1, n_modes: int = 6, section: SectionSource = "tabulated"
    ) -> ExactCantilever:
        cantilever_roots(n_modes)  # validates n_modes
        return cls(beam.with_section(section), n_modes)

    def frequencies_hz(self) -> np.ndarray:
        """Undamped natural frequencies, Hz, shape (n_modes,)."""
        return cantilever_frequencies_hz(self.beam, self.n_modes)

    def shapes(self, x_m: np.ndarray | float) -> np.ndarray:
        """Mode shapes at x (m from the clamp), shape (n_modes, *x.shape)."""
        x = np.asarray(x_m, dtype=float)
        if not np.all(np.isfinite(x)) or np.any(x < 0.0) or np.any(x > self.beam.length_m):
            raise ValueError(f"positions must lie on the beam, 0..{self.beam.length_m} m")
        return cantilever_mode_shapes(x, self.n_modes, self.beam.length_m)

    def modal_damping_matrix(self, damping_ratios: np.ndarray | float) -> np.ndarray:
        """Diagonal R = rho A L diag(2 zeta_n omega_n) for ratios zeta, shape (..., n, n).

        ``damping_ratios`` is a scalar, (n_modes,) or (..., n_modes).
        """
        zeta = np.asarray(damping_ratios, dtype=float)
        if zeta.ndim > 0 and zeta.shape[-1] != self.n_modes:
            raise ValueError(f"expected {self.n_modes} damping ratios, got {zeta.shape[-1]}")
        zeta = zeta * np.ones(self.n_modes)
        if not np.all(np.isfinite(zeta)) or np.any(zeta < 0):
            raise ValueError("damping ratios must be finite and non-negative")
        omega = 2.0 * np.pi * self.frequencies_hz()
        diag = self.beam.mass_kg * 2.0 * zeta * omega
        return diag[..., :, None] * np.eye(self.n_modes)

    def structure(self, force_at_m: float | None = None, sensor_at_m: float | None = None) -> StructuralModel:
        """Modal model: M = rho A L I, K = rho A L diag(omega^2), force and sensor at
        the given positions (default: the tip)."""
        length = self.beam.length_m
        omega = 2.0 * np.pi * self.frequencies_hz()
        modal_mass = self.beam.mass_kg
        return StructuralModel(
            mass=modal_mass * np.eye(self.n_modes),
            stiffness=np.diag(modal_mass * omega**2),
            force_shape=self.shapes(length if force_at_m is None else force_at_m),
            sensor_shape=self.shapes(length if sensor_at_m is None else sensor_at_m),
        )
