"""The beam's own mode shapes at measurement points, scaled to unit modal mass, to set
beside measured shapes (analysis.modal_id.shapes) and compare by MAC (analysis.mac).

Unit modal mass: a mode shape u(x) (m of displacement per unit modal coordinate) with
int_0^L rho A u(x)^2 dx = 1 kg, so u is in 1/sqrt(kg), the unit of measured shapes
scaled through a driving point from SI FRFs.

* Exact cantilever: u_n(x) = phi_n(x) / sqrt(rho A L), phi_n the classical shape of
  analysis.exact_beam (int phi_n^2 dx = L).
* Ritz (N admissible functions f_i of eq (6)): K v = w^2 M v with v^T M v = 1 (M in kg,
  the functions dimensionless, so v is in 1/sqrt(kg)), u(x) = sum_i v_i f_i(x). The
  Ritz shape is exactly unit modal mass in the Ritz model's own mass matrix.

Sign: every shape is made positive at the free end (x = L), where a cantilever's modes
are all non-zero; a measured shape scaled through a driving point at the tip has the
same sign. Elsewhere, align the signs first (analysis.mac.align).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg

from analysis.beam import TABLE_1, BeamProperties, SectionSource
from analysis.exact_beam import ExactCantilever, cantilever_mode_shapes
from analysis.ritz import RitzBeam, admissible_functions


@dataclass(frozen=True)
class BeamShapes:
    """A model's modes at given points.

    model : "exact" or "ritz N=<n>". positions_m (n_points,) from the clamp, m.
    frequencies_hz (n_modes,) undamped natural frequencies, Hz, ascending.
    shapes (n_modes, n_points) real, unit modal mass, 1/sqrt(kg), positive at the tip.
    """

    model: str
    positions_m: np.ndarray
    frequencies_hz: np.ndarray
    shapes: np.ndarray


def _positions(positions_m: np.ndarray | float, length_m: float) -> np.ndarray:
    x = np.atleast_1d(np.asarray(positions_m, dtype=float))
    if x.ndim != 1 or x.size == 0:
        raise ValueError(f"positions must be a 1-D list of points, got shape {x.shape}")
    if not np.all(np.isfinite(x)) or np.any(x < 0.0) or np.any(x > length_m):
        raise ValueError(f"positions must lie on the beam, 0..{length_m:g} m")
    return x


def exact_shapes(
    positions_m: np.ndarray | float,
    n_modes: int,
    beam: BeamProperties = TABLE_1,
    section: SectionSource = "tabulated",
) -> BeamShapes:
    """The exact cantilever's first ``n_modes`` shapes at the positions (m from the
    clamp), unit modal mass (1/sqrt(kg)), positive at the tip; shapes (n_modes, n_points)."""
    model = ExactCantilever.build(beam, n_modes, section)
    x = _positions(positions_m, model.beam.length_m)
    phi = model.shapes(x) / np.sqrt(model.beam.mass_kg)
    # The classical phi_n(L) = 2 (-1)^(n+1): make every tip value positive.
    tip = cantilever_mode_shapes(model.beam.length_m, n_modes, model.beam.length_m)
    return BeamShapes("exact", x, model.frequencies_hz(), phi * np.sign(tip)[:, None])


def ritz_shapes(
    positions_m: np.ndarray | float,
    n_functions: int = 3,
    beam: BeamProperties = TABLE_1,
    section: SectionSource = "tabulated",
) -> BeamShapes:
    """The N-function Ritz model's N modes at the positions (m from the clamp), unit
    modal mass in the model's M (1/sqrt(kg)), positive at the tip; shapes (N, n_points)."""
    model = RitzBeam.build(beam, n_functions, section)
    length = model.beam.length_m
    x = _positions(positions_m, length)
    omega_sq, vectors = scipy.linalg.eigh(model.stiffness, model.mass)  # v^T M v = 1
    tip = vectors.T @ admissible_functions(length, n_functions, length)
    vectors = vectors * np.where(tip < 0, -1.0, 1.0)[None, :]
    shapes = vectors.T @ admissible_functions(x, n_functions, length)
    freqs = np.sqrt(np.maximum(omega_sq, 0.0)) / (2.0 * np.pi)
    return BeamShapes(f"ritz N={n_functions}", x, freqs, shapes)
