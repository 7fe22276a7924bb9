"""A linear structure M q'' + R q' + K q = b f(t), observed as y = c^T q (or q', q'').

This is the seed's model with the signs right (docs/method.md): its eqs (13)
and (16) drop the minus signs. The state x = [q, q'] obeys x' = A x + B f with

    A = [[0, I], [-M^-1 K, -M^-1 R]],   B = [0; M^-1 b],

where b holds the shape functions at the force position (F_i = phi_i(x_f) f) and
c those at the sensor. The acceleration output has a direct feed-through,
y = c^T q'' = c^T M^-1 (b f - K q - R q').

Damping matrices may carry any leading batch shape (..., N, N): a genetic
algorithm evaluates a whole population in one call.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

Quantity = Literal["displacement", "velocity", "acceleration"]
QUANTITIES: tuple[Quantity, ...] = ("displacement", "velocity", "acceleration")
#: Power of (j omega) relating each quantity to displacement.
QUANTITY_ORDER = {"displacement": 0, "velocity": 1, "acceleration": 2}


@dataclass(frozen=True)
class StructuralModel:
    """Mass, stiffness, force and sensor vectors of an N-DOF structure.

    mass : (N, N), kg (generalized); symmetric positive definite.
    stiffness : (N, N), N/m (generalized); symmetric positive semi-definite.
    force_shape : (N,), generalized force per newton at the force position.
    sensor_shape : (N,), physical displacement per unit generalized coordinate at
        the sensor.
    """

    mass: np.ndarray
    stiffness: np.ndarray
    force_shape: np.ndarray
    sensor_shape: np.ndarray

    def __post_init__(self) -> None:
        mass = np.asarray(self.mass, dtype=float)
        n = mass.shape[0] if mass.ndim == 2 else -1
        if mass.ndim != 2 or mass.shape != (n, n) or n < 1:
            raise ValueError(f"mass matrix must be square, got shape {mass.shape}")
        for name, shape in (
            ("stiffness", (n, n)),
            ("force_shape", (n,)),
            ("sensor_shape", (n,)),
        ):
            value = np.asarray(getattr(self, name), dtype=float)
            if value.shape != shape:
                raise ValueError(f"{name} must have shape {shape}, got {value.shape}")
            if not np.all(np.isfinite(value)):
                raise ValueError(f"{name} holds non-finite values")
            object.__setattr__(self, name, value)
        if not np.all(np.isfinite(mass)):
            raise ValueError("mass holds non-finite values")
        if not np.allclose(mass, mass.T, rtol=1e-10, atol=0.0):
            raise ValueError("mass matrix must be symmetric")
        try:
            np.linalg.cholesky(mass)
        except np.linalg.LinAlgError:
            raise ValueError("mass matrix must be positive definite") from None
        object.__setattr__(self, "mass", mass)

    @property
    def n_dof(self) -> int:
        return self.mass.shape[0]

    def check_damping(self, damping: np.ndarray) -> np.ndarray:
        """Validate damping matrices of shape (..., N, N) and return them as float."""
        r = np.asarray(damping, dtype=float)
        n = self.n_dof
        if r.ndim < 2 or r.shape[-2:] != (n, n):
            raise ValueError(f"damping matrices must have shape (..., {n}, {n}), got {r.shape}")
        if not np.all(np.isfinite(r)):
            raise ValueError("damping matrices hold non-finite values")
        return r

    def state_space(
        self, damping: np.ndarray, output: Quantity = "acceleration"
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Continuous state-space matrices for each damping matrix.

        Parameters
        ----------
        damping : (..., N, N) viscous damping, N s/m (generalized).
        output : quantity measured at the sensor.

        Returns
        -------
        A : (..., 2N, 2N), B : (..., 2N), C : (..., 2N), D : (...,)
            Units of y per newton: m, m/s or m/s^2.
        """
        r = self.check_damping(damping)
        batch = r.shape[:-2]
        n = self.n_dof
        minv_k = np.linalg.solve(self.mass, self.stiffness)
        # One factorisation of M for the whole batch (a broadcast solve would factor it
        # once per member): the members' columns side by side as right-hand sides.
        columns = np.moveaxis(r, -2, 0).reshape(n, -1)
        minv_r = np.moveaxis(np.linalg.solve(self.mass, columns).reshape(n, *batch, n), 0, -2)
        minv_b = np.linalg.solve(self.mass, self.force_shape)

        a = np.zeros((*batch, 2 * n, 2 * n))
        a[..., :n, n:] = np.eye(n)
        a[..., n:, :n] = -minv_k
        a[..., n:, n:] = -minv_r
        b = np.zeros((*batch, 2 * n))
        b[..., n:] = minv_b
        c = np.zeros((*batch, 2 * n))
        d = np.zeros(batch)
        if output == "displacement":
            c[..., :n] = self.sensor_shape
        elif output == "velocity":
            c[..., n:] = self.sensor_shape
        elif output == "acceleration":
            c[..., :n] = -self.sensor_shape @ minv_k
            c[..., n:] = -np.einsum("i,...ij->...j", self.sensor_shape, minv_r)
            d[...] = self.sensor_shape @ minv_b
        else:
            raise ValueError(f"unknown output {output!r}; use one of {', '.join(QUANTITIES)}")
        return a, b, c, d
