"""Modal properties of a damped StructuralModel: poles, frequencies, damping ratios, shapes."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from analysis.structure import StructuralModel


@dataclass(frozen=True)
class DampedModes:
    """Oscillatory modes of each damping matrix in a batch, sorted by natural frequency.

    Every array has the batch shape (...) in front. A member with fewer than N
    oscillatory modes (a heavily damped member has real, overdamped poles) is
    padded with NaN; ``n_real_poles`` counts its real poles. A member whose
    damping matrix is indefinite can be unstable: ``n_unstable_poles`` counts
    poles with a positive real part (an oscillatory one shows a negative
    damping ratio).

    poles : (..., N) complex, rad/s; the pole of each pair with positive imaginary part.
    natural_frequencies_hz : (..., N), |lambda| / 2 pi.
    damped_frequencies_hz : (..., N), Im(lambda) / 2 pi.
    damping_ratios : (..., N), -Re(lambda) / |lambda| (dimensionless).
    shapes : (..., N, N) complex: shapes[..., k, :] is mode k in generalized
        coordinates, scaled so that its largest component is 1 + 0j.
    n_real_poles, n_unstable_poles : (...,) int.
    """

    poles: np.ndarray
    natural_frequencies_hz: np.ndarray
    damped_frequencies_hz: np.ndarray
    damping_ratios: np.ndarray
    shapes: np.ndarray
    n_real_poles: np.ndarray
    n_unstable_poles: np.ndarray


def damped_modes(model: StructuralModel, damping: np.ndarray) -> DampedModes:
    """Eigen-analysis of x' = A x for each damping matrix (..., N, N), N s/m."""
    r = model.check_damping(damping)
    batch = r.shape[:-2]
    n = model.n_dof
    flat = r.reshape((-1, n, n))
    a, _, _, _ = model.state_space(flat, "displacement")
    lam, vec = np.linalg.eig(a)
    # LAPACK gives exact conjugate pairs with imaginary part exactly 0 for real poles.
    upper = lam.imag > 0.0
    n_real = np.count_nonzero(lam.imag == 0.0, axis=-1)
    # Round-off puts the poles of an undamped mode at +-1e-15 off the axis: not unstable.
    n_unstable = np.count_nonzero(lam.real > 1e-10 * np.abs(lam), axis=-1)
    # Sort key: oscillatory poles by |lambda|, everything else to the end.
    key = np.where(upper, np.abs(lam), np.inf)
    order = np.argsort(key, axis=-1, kind="stable")[:, :n]
    valid = np.take_along_axis(upper, order, axis=-1)
    poles = np.where(valid, np.take_along_axis(lam, order, axis=-1), complex(np.nan, np.nan))
    shapes = np.take_along_axis(vec[:, :n, :], order[:, None, :], axis=-1)  # (P, N dof, N modes)
    shapes = np.swapaxes(shapes, -1, -2)  # (P, modes, dof)
    peak = np.take_along_axis(shapes, np.argmax(np.abs(shapes), axis=-1)[..., None], axis=-1)
    with np.errstate(all="ignore"):
        shapes = np.where(valid[..., None], shapes / peak, complex(np.nan, np.nan))
    magnitude = np.abs(poles)
    return DampedModes(
        poles=poles.reshape((*batch, n)),
        natural_frequencies_hz=(magnitude / (2 * np.pi)).reshape((*batch, n)),
        damped_frequencies_hz=(poles.imag / (2 * np.pi)).reshape((*batch, n)),
        damping_ratios=(-poles.real / magnitude).reshape((*batch, n)),
        shapes=shapes.reshape((*batch, n, n)),
        n_real_poles=n_real.reshape(batch),
        n_unstable_poles=n_unstable.reshape(batch),
    )
