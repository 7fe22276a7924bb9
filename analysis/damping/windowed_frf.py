"""The frequency-domain objective: the model's FRF against a measured one, with the
exponential window's effect on the measured FRF put into the model.

An exponential window exp(-t/tau) on the response (from the record's start) and a
force window that leaves the hammer pulse whole turn the FRF H(j omega) into

    H_w(j omega) = exp(-sigma t_p) H(j omega + sigma),   sigma = 1/tau,

t_p being the pulse's time after the record's start: every pole moves left by sigma
and the amplitude drops by the window's value at the pulse (checked against the
simulated analyzer in tests/test_sim_frf_with_impact_defaults.py). The model is
evaluated at s = j omega + sigma directly, so the fit's R is the beam's, not the
beam's plus the window's.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from analysis.structure import StructuralModel


@dataclass(frozen=True)
class WindowedFrfData:
    """model; frequency_hz : (n_lines,) Hz; frf : (n_lines,) complex measured
    accelerance, (m/s^2)/N; weights : (n_lines,) >= 0 (e.g. the coherence) or None;
    decay_1_s : sigma, 1/s (0 without an exponential window); pulse_s : t_p, s."""

    model: StructuralModel
    frequency_hz: np.ndarray
    frf: np.ndarray
    weights: np.ndarray | None = None
    decay_1_s: float = 0.0
    pulse_s: float = 0.0

    def __post_init__(self) -> None:
        f = np.asarray(self.frequency_hz, dtype=float)
        h = np.asarray(self.frf, dtype=complex)
        if f.ndim != 1 or h.shape != f.shape:
            raise ValueError(f"frequency_hz and frf must be matching 1-D arrays, got {f.shape} and {h.shape}")
        keep = (f > 0) & np.isfinite(h)
        w = np.ones_like(f) if self.weights is None else np.asarray(self.weights, dtype=float)
        keep &= np.isfinite(w) & (w > 0)
        if keep.sum() < 4:
            raise ValueError("fewer than 4 usable FRF lines")
        object.__setattr__(self, "frequency_hz", f[keep])
        object.__setattr__(self, "frf", h[keep])
        object.__setattr__(self, "weights", np.sqrt(w[keep]))


def model_frf(data: WindowedFrfData, damping: np.ndarray) -> np.ndarray:
    """(B, n_lines) the windowed model accelerance for damping matrices (B, N, N)."""
    m = data.model
    r = np.asarray(damping, dtype=float).reshape(-1, m.n_dof, m.n_dof)
    s = 2j * np.pi * data.frequency_hz + data.decay_1_s  # (F,)
    # D(s) = M s^2 + R s + K for every member and line: (B, F, N, N), solved for b.
    d = m.mass * (s**2)[None, :, None, None] + r[:, None] * s[None, :, None, None] + m.stiffness
    with np.errstate(all="ignore"):
        try:
            q = np.linalg.solve(d, np.broadcast_to(m.force_shape, (*d.shape[:2], m.n_dof))[..., None])[..., 0]
        except np.linalg.LinAlgError:
            return np.full((r.shape[0], s.size), np.nan + 0j)
        h = (s**2)[None] * (q @ m.sensor_shape)
    return h * np.exp(-data.decay_1_s * data.pulse_s)


def weighted_difference(measured: np.ndarray, model: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """(B, 2 n_lines): weighted real then imaginary parts of ``measured`` (n_lines,) minus
    ``model`` (B, n_lines), weights (n_lines,)."""
    diff = (measured[None] - model) * weights[None]
    return np.concatenate([diff.real, diff.imag], axis=1)


def psi_of(batched_residuals_of, damping: np.ndarray) -> np.ndarray:
    """eq (17)'s form on the FRF residual, (...,) for damping (..., N, N); invalid -> inf.
    batched_residuals_of: damping (B, N, N) -> residuals (B, n)."""
    r = np.asarray(damping, dtype=float)
    flat = r.reshape(-1, *r.shape[-2:])
    res = batched_residuals_of(flat)
    with np.errstate(all="ignore"):
        value = np.sqrt(np.sum(res**2, axis=1)) / res.shape[1]
    return np.where(np.isfinite(value), value, np.inf).reshape(r.shape[:-2])


def batched_residuals(data: WindowedFrfData, damping: np.ndarray) -> np.ndarray:
    """(B, 2 n_lines): weighted real then imaginary parts of measured minus model."""
    return weighted_difference(data.frf, model_frf(data, damping), data.weights)


def residuals(data: WindowedFrfData, damping: np.ndarray) -> np.ndarray:
    return batched_residuals(data, np.asarray(damping, dtype=float)[None])[0]


def psi(data: WindowedFrfData, damping: np.ndarray) -> np.ndarray:
    """eq (17)'s form on the FRF residual, (...,) for damping (..., N, N); invalid -> inf."""
    return psi_of(lambda r: batched_residuals(data, r), damping)
