"""Damping-matrix identification: the seed's GA (eq (17) objective), least squares,
differential evolution, the proportional estimate from identified modes, a
Pilkey-Inman-type iteration on the poles, the stiffness update, and what the data
determines (identifiability). Pure numerics (docs/damping.md)."""

from analysis.damping.ga import bits_per_variable, decode, fit_ga
from analysis.damping.identifiability import Identifiability, cramer_rao_frf, identifiability
from analysis.damping.local import fit_de, fit_least_squares, multi_start
from analysis.damping.modal_estimate import proportional_estimate, undamped_modes
from analysis.damping.objective import (
    FrequencyData,
    TimeData,
    batched_residuals,
    batched_residuals_frf,
    psi,
    psi_frf,
    residuals,
    residuals_frf,
)
from analysis.damping.params import matrix_to_theta, n_params, parameter_names, theta_to_matrix
from analysis.damping.pilkey_inman import pilkey_inman
from analysis.damping.result import FitResult
from analysis.damping.stiffness import frequency_errors, update_mode_frequencies, update_stiffness

__all__ = [
    "FitResult",
    "FrequencyData",
    "Identifiability",
    "TimeData",
    "batched_residuals",
    "batched_residuals_frf",
    "bits_per_variable",
    "cramer_rao_frf",
    "decode",
    "fit_de",
    "fit_ga",
    "fit_least_squares",
    "frequency_errors",
    "identifiability",
    "matrix_to_theta",
    "multi_start",
    "n_params",
    "parameter_names",
    "pilkey_inman",
    "proportional_estimate",
    "psi",
    "psi_frf",
    "residuals",
    "residuals_frf",
    "theta_to_matrix",
    "undamped_modes",
    "update_mode_frequencies",
    "update_stiffness",
]
