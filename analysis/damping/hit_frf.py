"""The frequency-domain objective for runs that hold their hits: the FRF of the hits
against the FRF the model's response to the same hits would give through the same
windows.

``windowed_frf`` models a windowed FRF as exp(-sigma t_p) H(j omega + sigma), which is
exact for an ideal impulse and a continuous record only. The analysed FRF is made of
sampled, band-limited records: the anti-alias filter spreads the pulse and the
accelerance's direct term over several samples, and the exponential window weighs
those samples differently from the one at t_p. On simulated seed-beam hits with no
noise at all that model leaves 0.2-0.4 % errors on every line, and R's poorly
determined terms absorb them: eq (18)'s R23 = 1.99 came out at 0.0 and R33 = 2.75 at
5.4 N s/m, the same way in every run.

Here the model's FRF is made the way the measured one is: the model's band-limited
response (analysis/damping/bandlimited.py) to each accepted hit's force, as the force
window leaves it, through the response window, and both combined over the hits by the
H1 estimator, sum Y_k conj(F_k) / sum |F_k|^2. Noise-free hits then give eq (18) back
to the solver's tolerance, whatever the windows.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from analysis.damping.bandlimited import BandLimitedData, model_response
from analysis.damping.windowed_frf import psi_of, weighted_difference
from analysis.spectra import ALIAS_FREE_FACTOR
from analysis.structure import StructuralModel


@dataclass(frozen=True)
class HitFrfData:
    """model; force_n, response_m_s2 : (n_hits, n_samples) N and m/s^2, raw baseband
    records of the accepted hits; sample_rate_hz : Hz; force_window, response_window :
    (n_samples,) the windows the analysis applies (analysis.windows.window).

    Derived: frequency_hz (n_lines,) the lines 0 < f <= fs / 2.56; frf (n_lines,) the
    H1 estimate of the hits; weights (n_lines,) the square root of its coherence (1 for
    one hit), as windowed_frf weights its lines."""

    model: StructuralModel
    force_n: np.ndarray
    response_m_s2: np.ndarray
    sample_rate_hz: float
    force_window: np.ndarray
    response_window: np.ndarray

    def __post_init__(self) -> None:
        force = np.atleast_2d(np.asarray(self.force_n, dtype=float))
        response = np.atleast_2d(np.asarray(self.response_m_s2, dtype=float))
        n = force.shape[1]
        if force.shape != response.shape:
            raise ValueError(
                f"force and response must both be (n_hits, n_samples), got {force.shape}, {response.shape}"
            )
        w_f = np.broadcast_to(np.asarray(self.force_window, dtype=float), (n,))
        w_r = np.broadcast_to(np.asarray(self.response_window, dtype=float), (n,))
        f = np.fft.rfftfreq(n, 1.0 / self.sample_rate_hz)
        lines = np.flatnonzero((f > 0) & (f <= self.sample_rate_hz / ALIAS_FREE_FACTOR * (1 + 1e-12)))
        windowed_force = force * w_f
        f_k = np.fft.rfft(windowed_force, axis=1)[:, lines]
        y_k = np.fft.rfft(response * w_r, axis=1)[:, lines]
        g_ff = np.sum(np.abs(f_k) ** 2, axis=0)
        g_fy = np.sum(y_k * f_k.conj(), axis=0)
        g_yy = np.sum(np.abs(y_k) ** 2, axis=0)
        with np.errstate(all="ignore"):
            frf = g_fy / g_ff
            coherence = np.abs(g_fy) ** 2 / (g_ff * g_yy)
        keep = np.isfinite(frf) & np.isfinite(coherence) & (coherence > 0)
        if keep.sum() < 4:
            raise ValueError("fewer than 4 usable FRF lines")
        lines = lines[keep]
        for name, value in (
            ("force_n", force), ("response_m_s2", response), ("force_window", w_f), ("response_window", w_r),
            ("frequency_hz", f[lines]), ("frf", frf[keep]), ("weights", np.sqrt(coherence[keep])),
            ("_lines", lines), ("_force_lines", f_k[:, keep]), ("_g_ff", g_ff[keep]),
            # The model is driven by the force as the force window leaves it (noise outside it
            # is the sensor's, not a force on the beam).
            ("_driving", BandLimitedData(self.model, windowed_force, windowed_force, self.sample_rate_hz)),
        ):  # fmt: skip
            object.__setattr__(self, name, value)

    @property
    def n_hits(self) -> int:
        return int(self.force_n.shape[0])

    def hit(self, k: int) -> HitFrfData:
        """The data of hit ``k`` alone (its own FRF, coherence 1)."""
        return HitFrfData(
            self.model, self.force_n[k : k + 1], self.response_m_s2[k : k + 1], self.sample_rate_hz,
            self.force_window, self.response_window,
        )  # fmt: skip


#: Damping matrices whose responses are computed at once (memory: B x hits x 8n complex).
_MEMBERS_PER_CHUNK = 8


def model_frf(data: HitFrfData, damping: np.ndarray) -> np.ndarray:
    """(B, n_lines) the H1 estimate the model's response to the hits would give, for
    damping matrices (B, N, N)."""
    m = data.model
    r = np.asarray(damping, dtype=float).reshape(-1, m.n_dof, m.n_dof)
    out = np.empty((r.shape[0], data.frequency_hz.size), dtype=complex)
    with np.errstate(all="ignore"):
        for i in range(0, r.shape[0], _MEMBERS_PER_CHUNK):
            y = model_response(data._driving, r[i : i + _MEMBERS_PER_CHUNK])  # (b, hits, n)
            y_k = np.fft.rfft(y * data.response_window, axis=2)[:, :, data._lines]
            out[i : i + _MEMBERS_PER_CHUNK] = (
                np.sum(y_k * data._force_lines.conj()[None], axis=1) / data._g_ff
            )
    return out


def batched_residuals(data: HitFrfData, damping: np.ndarray) -> np.ndarray:
    """(B, 2 n_lines): weighted real then imaginary parts of measured minus model."""
    return weighted_difference(data.frf, model_frf(data, damping), data.weights)


def residuals(data: HitFrfData, damping: np.ndarray) -> np.ndarray:
    return batched_residuals(data, np.asarray(damping, dtype=float)[None])[0]


def psi(data: HitFrfData, damping: np.ndarray) -> np.ndarray:
    """eq (17)'s form on the FRF residual, (...,) for damping (..., N, N); invalid -> inf."""
    return psi_of(lambda r: batched_residuals(data, r), damping)
