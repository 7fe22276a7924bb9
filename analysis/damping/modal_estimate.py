"""Classically damped estimate of the damping matrix from identified modal damping.

A modal fit of the tip accelerance gives, per mode, a natural frequency and a
damping ratio. The model's M and K fix the undamped modes Phi (mass-normalised,
Phi^T M Phi = I, Phi^T K Phi = diag(omega_r^2)). The damping matrix whose modal
damping is diag(2 zeta_r omega_r) in that basis is

    R = M Phi diag(2 zeta_r omega_r) Phi^T M,

because Phi^T M Phi = I gives Phi^-1 = Phi^T M, so Phi^T R Phi = diag(2 zeta_r omega_r).
This is the classical (proportional) damping matrix: it commutes with the modal
decomposition of (M, K), and its damped modes have exactly the given ratios.
It is the natural starting point for any non-proportional fit and the
direct estimate a single driving-point measurement supports without a search.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg
import scipy.optimize

from analysis.structure import StructuralModel


def undamped_modes(model: StructuralModel) -> tuple[np.ndarray, np.ndarray]:
    """Undamped modes of (M, K).

    Returns
    -------
    omega : (N,) natural frequencies, rad/s, ascending.
    phi : (N, N) mass-normalised mode shapes as columns (phi^T M phi = I).
    """
    omega_sq, phi = scipy.linalg.eigh(model.stiffness, model.mass)
    # A positive semi-definite K can give -1e-12 for a rigid-body mode: clip, not NaN.
    return np.sqrt(np.clip(omega_sq, 0.0, None)), phi


def match_modes(identified_hz: np.ndarray, model_hz: np.ndarray) -> np.ndarray:
    """Pair identified modes with model modes by nearest frequency, each used once.

    The pairing minimises the summed |log(f_identified / f_model)| (relative, so a
    10 Hz miss at 100 Hz weighs like a 1 Hz miss at 10 Hz) over one-to-one
    assignments (scipy's linear_sum_assignment).

    Parameters
    ----------
    identified_hz : (m,) Hz, positive.
    model_hz : (N,) Hz, positive.

    Returns
    -------
    (m,) int: the model mode of each identified mode, -1 where m > N left it unpaired.
    """
    f_id = np.asarray(identified_hz, dtype=float)
    f_mod = np.asarray(model_hz, dtype=float)
    if f_id.ndim != 1 or f_mod.ndim != 1:
        raise ValueError("frequencies must be 1-D arrays")
    if not (np.all(np.isfinite(f_id)) and np.all(f_id > 0) and np.all(f_mod > 0)):
        raise ValueError("frequencies must be finite and positive")
    cost = np.abs(np.log(f_id[:, None] / f_mod[None, :]))
    rows, cols = scipy.optimize.linear_sum_assignment(cost)
    match = np.full(f_id.size, -1, dtype=int)
    match[rows] = cols
    return match


def proportional_estimate(
    model: StructuralModel, frequency_hz: np.ndarray, damping_ratio: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Classically damped R whose modal damping equals the identified ratios.

    Parameters
    ----------
    model : M and K define the undamped modes.
    frequency_hz : (m,) identified natural frequencies, Hz; used only to pair each
        identified mode with a model mode (nearest frequency, each once; see
        ``match_modes``).
    damping_ratio : (m,) identified damping ratios (dimensionless).

    Returns
    -------
    damping : (N, N), N s/m: M Phi diag(2 zeta_r omega_r) Phi^T M.
    match : (m,) int, the model mode given to each identified mode (-1: unused,
        when there are more identified modes than model modes).

    Notes
    -----
    * The model's own omega_r goes into 2 zeta_r omega_r, not the identified
      frequency: the model's stiffness defines its modes, so this choice makes the
      damped model's ratios equal the identified ones exactly. (Using the
      identified omega would instead make the decay rate zeta omega match, and
      the two differ by the model's frequency error.)
    * A model mode no identified mode was paired with (a mode outside the
      measured band, or missed by the fit) takes the ratio of the identified mode
      nearest to it in frequency: a guess, flagged by its absence from ``match``.
    """
    f_id = np.asarray(frequency_hz, dtype=float)
    zeta_id = np.asarray(damping_ratio, dtype=float)
    if f_id.shape != zeta_id.shape or f_id.ndim != 1 or f_id.size == 0:
        raise ValueError("frequency_hz and damping_ratio must be 1-D arrays of the same, nonzero length")
    if not np.all(np.isfinite(zeta_id)) or np.any(zeta_id < 0):
        raise ValueError("damping ratios must be finite and non-negative")
    omega, phi = undamped_modes(model)
    model_hz = omega / (2.0 * np.pi)
    match = match_modes(f_id, model_hz)

    zeta = np.empty(model.n_dof)
    paired = match >= 0
    zeta[match[paired]] = zeta_id[paired]
    unpaired = np.setdiff1d(np.arange(model.n_dof), match[paired])
    for r in unpaired:
        zeta[r] = zeta_id[np.argmin(np.abs(np.log(f_id / model_hz[r])))]

    m_phi = model.mass @ phi
    damping = (m_phi * (2.0 * zeta * omega)) @ m_phi.T
    return 0.5 * (damping + damping.T), match
