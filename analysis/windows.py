"""Time windows of an impact test and the damping an exponential window adds. Pure numpy/scipy.

Windows are applied to a record from its first sample (t = 0 at the record start),
as the analyzer applies them (sims/dsp.py plays the analyzer; this module matches
its definitions so that an FRF computed here from a capture agrees with the
analyzer's own):

- "uniform": 1 everywhere.
- "hann", "flattop": periodic (DFT-even) windows, scipy's ``hann`` and 5-term
  ``flattop`` with ``sym=False``, as a spectrum analyzer applies them.
- "force": 1 for t < ``force_width_s``, then, if ``taper_s`` > 0, a half-cosine
  falling from 1 to 0 over ``taper_s``; 0 after. ``taper_s`` = 0 is the HP
  analyzer's rectangular force window (the strict ``t < width`` is the analyzer's).
- "exponential": exp(-t / tau), tau = ``exp_decay_s``. It forces a response to
  decay within the record (no leakage) at the price of extra damping: every pole's
  decay rate grows by exactly 1/tau (see :func:`correct_pole`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.signal

#: The window kinds :class:`WindowSpec` accepts.
KINDS = ("uniform", "hann", "flattop", "force", "exponential")


@dataclass(frozen=True)
class WindowSpec:
    """One channel's window.

    kind : one of KINDS.
    force_width_s : force window only (required there): the window is 1 for record
        times t < force_width_s, s.
    taper_s : force window only: length of the half-cosine taper after the width, s;
        0 (default) is rectangular, as on the HP analyzer.
    exp_decay_s : exponential window only (required there): time constant tau of
        w = exp(-t / tau), s.
    """

    kind: str
    force_width_s: float | None = None
    taper_s: float = 0.0
    exp_decay_s: float | None = None

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"unknown window kind {self.kind!r}; expected one of {', '.join(KINDS)}")
        if self.kind == "force":
            if self.force_width_s is None or not (
                math.isfinite(self.force_width_s) and self.force_width_s > 0
            ):
                raise ValueError(
                    f"a force window needs a finite force_width_s > 0 s, got {self.force_width_s}"
                )
            if not (math.isfinite(self.taper_s) and self.taper_s >= 0):
                raise ValueError(f"a force window's taper_s must be finite and >= 0 s, got {self.taper_s}")
        else:
            # Parameters of another kind are a caller's mix-up, not something to ignore.
            if self.force_width_s is not None or self.taper_s != 0.0:
                raise ValueError(
                    f"force_width_s and taper_s apply to the force window only, not {self.kind!r}"
                )
        if self.kind == "exponential":
            if self.exp_decay_s is None or not (math.isfinite(self.exp_decay_s) and self.exp_decay_s > 0):
                raise ValueError(
                    f"an exponential window needs a finite exp_decay_s > 0 s, got {self.exp_decay_s}"
                )
        elif self.exp_decay_s is not None:
            raise ValueError(f"exp_decay_s applies to the exponential window only, not {self.kind!r}")


def window(spec: WindowSpec, n_samples: int, sample_rate_hz: float) -> np.ndarray:
    """The window over a record of ``n_samples`` at ``sample_rate_hz`` (Hz), (n_samples,) float64.

    Sample i sits at t = i / sample_rate_hz from the record start. For a zoom record
    (complex envelope) the same real window multiplies the complex samples.
    """
    if isinstance(n_samples, bool) or not isinstance(n_samples, (int, np.integer)) or n_samples < 1:
        raise ValueError(f"n_samples must be a positive integer, got {n_samples!r}")
    if not (math.isfinite(sample_rate_hz) and sample_rate_hz > 0):
        raise ValueError(f"sample_rate_hz must be finite and > 0 Hz, got {sample_rate_hz}")
    n = int(n_samples)
    if spec.kind == "uniform":
        return np.ones(n)
    if spec.kind == "hann":
        return scipy.signal.windows.hann(n, sym=False)
    if spec.kind == "flattop":
        return scipy.signal.windows.flattop(n, sym=False)
    if spec.kind == "force":
        assert spec.force_width_s is not None  # checked by WindowSpec
        t = np.arange(n) / sample_rate_hz  # computed as sims/dsp.py does, so the edge sample agrees
        w = (t < spec.force_width_s).astype(np.float64)
        if spec.taper_s > 0:
            in_taper = (t >= spec.force_width_s) & (t < spec.force_width_s + spec.taper_s)
            phase = (t[in_taper] - spec.force_width_s) / spec.taper_s
            w[in_taper] = 0.5 * (1.0 + np.cos(np.pi * phase))
        return w
    # exponential: scipy's exponential window from the first sample, tau in samples,
    # exactly the simulated analyzer's call (same rounding).
    assert spec.exp_decay_s is not None
    decay_samples = spec.exp_decay_s * sample_rate_hz
    return scipy.signal.windows.exponential(n, center=0, tau=decay_samples, sym=False)


def added_decay_rate(spec: WindowSpec) -> float:
    """The decay rate the window adds to every pole, 1/s: 1/tau for an exponential window, else 0.0.

    Multiplying x(t) = sum_r A_r exp(lambda_r t) by exp(-t/tau) gives
    sum_r A_r exp((lambda_r - 1/tau) t): each pole moves left by 1/tau. Other windows
    do not multiply by an exponential; their effect is leakage, not a pole shift.
    """
    if spec.kind == "exponential":
        assert spec.exp_decay_s is not None
        return 1.0 / spec.exp_decay_s
    return 0.0


def correct_pole(
    frequency_hz: np.ndarray | float, damping_ratio: np.ndarray | float, added_decay_1_s: float
) -> tuple[np.ndarray, np.ndarray]:
    """Remove an exponential window's added damping from measured modes; vectorised.

    frequency_hz : undamped natural frequency f_n of each measured mode, Hz, any shape.
    damping_ratio : measured viscous damping ratio zeta, same shape (broadcast), 0 <= zeta < 1.
    added_decay_1_s : the window's added decay rate 1/tau, 1/s (:func:`added_decay_rate`), >= 0.
    Returns (frequency_hz, damping_ratio) of the true modes, float64 arrays of the
    broadcast shape.

    Derivation. A mode with natural angular frequency w_n = 2 pi f_n and damping ratio
    zeta has the pole lambda = -sigma + j w_d with sigma = zeta w_n and
    w_d = w_n sqrt(1 - zeta^2) (so |lambda| = w_n, zeta = sigma / |lambda|). The window
    multiplies the free decay by exp(-t/tau), which moves every pole to
    lambda - 1/tau: sigma_meas = sigma_true + 1/tau, w_d unchanged. Hence

        sigma_true = zeta_m w_n,m - 1/tau,   w_d = w_n,m sqrt(1 - zeta_m^2),
        w_n,true = sqrt(sigma_true^2 + w_d^2),   zeta_true = sigma_true / w_n,true.

    The natural frequency changes too (|lambda| shrinks with sigma), slightly for light damping.
    Where sigma_true < 0 the window took out more damping than was measured (a bad fit,
    or a wrong tau): zeta is returned as NaN for that mode rather than a negative ratio;
    its frequency is still sqrt(sigma_true^2 + w_d^2) / 2 pi (w_d is unaffected by the window).
    NaN inputs give NaN outputs.
    """
    f_m, zeta_m = np.broadcast_arrays(
        np.asarray(frequency_hz, dtype=np.float64), np.asarray(damping_ratio, dtype=np.float64)
    )
    if not (math.isfinite(added_decay_1_s) and added_decay_1_s >= 0):
        raise ValueError(f"added_decay_1_s must be finite and >= 0 1/s, got {added_decay_1_s}")
    known = ~np.isnan(f_m) & ~np.isnan(zeta_m)
    if np.any(~(f_m[known] > 0)) or np.any(~np.isfinite(f_m[known])):
        raise ValueError("frequency_hz must be finite and > 0 Hz (NaN allowed for missing modes)")
    if np.any(~((zeta_m[known] >= 0) & (zeta_m[known] < 1))):
        raise ValueError("damping_ratio must be in [0, 1) for an underdamped mode (NaN allowed)")
    omega_n = 2.0 * np.pi * f_m
    sigma = zeta_m * omega_n - added_decay_1_s
    omega_d = omega_n * np.sqrt(1.0 - zeta_m**2)
    omega_true = np.hypot(sigma, omega_d)
    with np.errstate(invalid="ignore"):
        zeta_true = np.where(sigma >= 0, sigma / omega_true, np.nan)
    return omega_true / (2.0 * np.pi), zeta_true
