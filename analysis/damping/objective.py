"""Objectives of the damping fit: how far a damping matrix's predicted response is from
the measured one, batched over damping matrices so that a whole GA/DE population is
one call of the response code.

Time domain, the seed's eq (17):

    Psi(R) = (1/n) sqrt( sum over hits and samples (y - yhat(R))^2 ),

with n the total number of samples (hits x samples per hit), y the measured tip
acceleration (m/s^2) and yhat the model's zero-order-hold response to the measured
force. This is not an RMS (that would be sqrt(sum / n)); it is what the paper writes,
and its minimiser is the same least-squares one. Psi = ||residuals|| / len(residuals).

Frequency domain: the same form on the complex accelerance residual, real and
imaginary parts counted as separate residuals (n = 2 x lines), each line weighted by
sqrt(w) (w e.g. the coherence) so that Psi^2 n^2 = sum w |H - Hhat|^2.

A damping matrix that is not positive semi-definite can make the model unstable:
its response overflows and its Psi is inf (never an exception), so a search moves away.

``psi`` never forms yhat. With the model's discrete impulse response written as
poles, h[0] = D, h[m] = sum_i c_i p_i^(m-1) (p_i = e^(lambda_i T), zero-order hold),
every term of sum (y - yhat)^2 is a polynomial in the p_i whose coefficients are
correlations of the measured force and response, summed over hits and computed
once (``TimeData``); the one exception, sum yhat^2, has a closed form per pole pair
(``_fast_sse``). A member then costs one 2N x 2N eigen-decomposition and a few
polynomial evaluations whatever the number of hits and samples: ~5x less than
convolving. Cancellation in y^2 - 2 y yhat + yhat^2 limits this to ~1e-12 of sum y^2,
so members near a perfect fit (and near-defective ones) are recomputed through
``time_response``; the two routes agree to ~1e-9 of Psi.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.fft

from analysis.response import frequency_response, time_response
from analysis.structure import StructuralModel

#: Damping entries beyond this (N s/m) are treated as invalid rather than handed to
#: LAPACK, whose eigen-solver refuses matrices that overflow.
MAX_ABS_DAMPING = 1e100


@dataclass(frozen=True)
class _Moments:
    """Sums over hits the fast Psi needs (u = force, y = response, n samples per hit).

    yy = sum y^2, yu = sum y u, uu = sum u^2.
    coefficients : (block, n_blocks * K) polynomial coefficients in p, laid out for
        p^j = p^(q block) p^r, j = q block + r: column group k of
        0: C_yu[j + 1], 1: C_uu[j + 1], 2: C_uu[j], 3..: u_h[n - 1 - j] per hit h,
        with C_ab[d] = sum_k a[k] b[k - d] (summed over hits).
    """

    yy: float
    yu: float
    uu: float
    block: int
    n_blocks: int
    coefficients: np.ndarray


def _moments(force: np.ndarray, response: np.ndarray, force_spectrum: np.ndarray, n_fft: int) -> _Moments:
    n_hits, n = force.shape
    conj_u = force_spectrum.conj()
    c_uu = scipy.fft.irfft((force_spectrum * conj_u).sum(axis=0), n_fft)[:n]
    c_yu = scipy.fft.irfft((scipy.fft.rfft(response, n_fft, axis=-1) * conj_u).sum(axis=0), n_fft)[:n]
    block = max(1, int(np.ceil(np.sqrt(n))))
    n_blocks = -(-n // block)
    k = 3 + n_hits
    coef = np.zeros((n_blocks * block, k))
    coef[: n - 1, 0] = c_yu[1:]
    coef[: n - 1, 1] = c_uu[1:]
    coef[:n, 2] = c_uu
    coef[:n, 3:] = force[:, ::-1].T
    coef = np.ascontiguousarray(coef.reshape(n_blocks, block, k).transpose(1, 0, 2).reshape(block, -1))
    return _Moments(
        yy=float(np.sum(response * response)),
        yu=float(np.sum(response * force)),
        uu=float(np.sum(force * force)),
        block=block,
        n_blocks=n_blocks,
        coefficients=coef,
    )


@dataclass(frozen=True)
class TimeData:
    """Measured hits the fit compares with.

    model : the structure (mass, stiffness, force and sensor shapes).
    force_n : (n_hits, n_samples) or (n_samples,), N: measured hammer force, raw
        records (not windowed), sample 0 = start of the record, model at rest there.
    response_m_s2 : same shape, m/s^2: measured tip acceleration.
    sample_rate_hz : samples per second.
    """

    model: StructuralModel
    force_n: np.ndarray
    response_m_s2: np.ndarray
    sample_rate_hz: float
    # rfft of each hit's force, padded for a linear convolution, and the correlations
    # the fast Psi needs: computed once here.
    _force_spectrum: np.ndarray = field(init=False, repr=False, compare=False)
    _moments: _Moments = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        force = np.atleast_2d(np.asarray(self.force_n, dtype=float))
        response = np.atleast_2d(np.asarray(self.response_m_s2, dtype=float))
        if force.ndim != 2 or force.shape != response.shape or force.shape[1] < 1:
            raise ValueError(
                f"force and response must both be (n_hits, n_samples), got {force.shape} and {response.shape}"
            )
        if not (np.all(np.isfinite(force)) and np.all(np.isfinite(response))):
            raise ValueError("force and response must be finite")
        rate = float(self.sample_rate_hz)
        if not (np.isfinite(rate) and rate > 0):
            raise ValueError(f"sample_rate_hz must be positive, got {self.sample_rate_hz!r}")
        object.__setattr__(self, "force_n", force)
        object.__setattr__(self, "response_m_s2", response)
        object.__setattr__(self, "sample_rate_hz", rate)
        n_fft = _fft_length(force.shape[1])
        object.__setattr__(self, "_force_spectrum", scipy.fft.rfft(force, n_fft, axis=-1))
        object.__setattr__(self, "_moments", _moments(force, response, self._force_spectrum, n_fft))

    @property
    def n_hits(self) -> int:
        return self.force_n.shape[0]

    @property
    def n_samples(self) -> int:
        return self.force_n.shape[1]


@dataclass(frozen=True)
class FrequencyData:
    """A measured FRF the fit compares with.

    frequency_hz : (n_lines,), Hz.
    frf : (n_lines,) complex accelerance, (m/s^2)/N.
    weights : (n_lines,) >= 0 (e.g. the coherence), or None for all ones.
    """

    model: StructuralModel
    frequency_hz: np.ndarray
    frf: np.ndarray
    weights: np.ndarray | None = None

    def __post_init__(self) -> None:
        f = np.asarray(self.frequency_hz, dtype=float)
        h = np.asarray(self.frf, dtype=complex)
        if f.ndim != 1 or h.shape != f.shape or f.size < 1:
            raise ValueError(f"frequency_hz and frf must be (n_lines,), got {f.shape} and {h.shape}")
        if not (np.all(np.isfinite(f)) and np.all(np.isfinite(h))):
            raise ValueError("frequency_hz and frf must be finite")
        w = np.ones(f.size) if self.weights is None else np.asarray(self.weights, dtype=float)
        if w.shape != f.shape or not np.all(np.isfinite(w)) or np.any(w < 0):
            raise ValueError("weights must be (n_lines,), finite and >= 0")
        object.__setattr__(self, "frequency_hz", f)
        object.__setattr__(self, "frf", h)
        object.__setattr__(self, "weights", w)


def _fft_length(n_samples: int) -> int:
    return scipy.fft.next_fast_len(2 * n_samples - 1, real=True)


def _split_valid(damping: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray, tuple[int, ...]]:
    """Flatten (..., N, N) to (B, N, N); members too large or non-finite are flagged and zeroed."""
    r = np.asarray(damping, dtype=float)
    if r.ndim < 2 or r.shape[-2:] != (n, n):
        raise ValueError(f"damping matrices must have shape (..., {n}, {n}), got {r.shape}")
    batch = r.shape[:-2]
    flat = r.reshape((-1, n, n))
    valid = np.all(np.isfinite(flat) & (np.abs(flat) < MAX_ABS_DAMPING), axis=(-2, -1))
    return np.where(valid[:, None, None], flat, 0.0), valid, batch


def batched_residuals(data: TimeData, damping: np.ndarray) -> np.ndarray:
    """y - yhat for each damping matrix, hits concatenated: (B, n_hits * n_samples), m/s^2.

    damping : (B, N, N), N s/m. One call of ``time_response`` for the whole batch:
    it gives each member's discrete (zero-order-hold) impulse response, and the
    response to each hit is its causal convolution with that hit's force. That is
    exactly what ``time_response`` would compute per hit, but needs one eigen-
    decomposition per member instead of one per member and hit. A member that is
    unstable or invalid gets non-finite residuals.
    """
    flat, valid, _ = _split_valid(damping, data.model.n_dof)
    n = data.n_samples
    impulse = np.zeros(n)
    impulse[0] = 1.0
    with np.errstate(all="ignore"):
        h = time_response(data.model, flat, impulse, data.sample_rate_hz, "acceleration")  # (B, n)
        spectrum_h = scipy.fft.rfft(h, _fft_length(n), axis=-1)
        yhat = scipy.fft.irfft(spectrum_h[:, None, :] * data._force_spectrum[None], _fft_length(n), axis=-1)[
            ..., :n
        ]  # (B, hits, n)
        res = (data.response_m_s2[None] - yhat).reshape(flat.shape[0], -1)
    res[~valid] = np.nan
    return res


def residuals(data: TimeData, damping: np.ndarray) -> np.ndarray:
    """y - yhat of one damping matrix (N, N), hits concatenated: (n_hits * n_samples,), m/s^2."""
    r = np.asarray(damping, dtype=float)
    if r.ndim != 2:
        raise ValueError(f"expected one (N, N) damping matrix, got shape {r.shape}")
    return batched_residuals(data, r[None])[0]


def _psi_from_residuals(res: np.ndarray, batch: tuple[int, ...]) -> np.ndarray:
    with np.errstate(all="ignore"):
        value = np.sqrt(np.einsum("bi,bi->b", res, res)) / res.shape[-1]
    return np.where(np.isfinite(value), value, np.inf).reshape(batch)


def psi(data: TimeData, damping: np.ndarray, exact: bool = False) -> np.ndarray:
    """Eq (17) for each damping matrix (..., N, N), N s/m: shape (...), m/s^2; inf if unstable.

    exact : form the residuals (``batched_residuals``) for every member instead of
        the correlation route (module docstring); same value to ~1e-9, ~5x slower.
    """
    flat, valid, batch = _split_valid(damping, data.model.n_dof)
    n_res = data.n_hits * data.n_samples
    if exact:
        return _psi_from_residuals(batched_residuals(data, flat), batch)
    sse = np.full(flat.shape[0], np.inf)
    redo = np.zeros(flat.shape[0], dtype=bool)
    if np.any(valid):
        sse[valid], redo[valid] = _fast_sse(data, flat[valid])
    if np.any(redo):
        res = batched_residuals(data, flat[redo])
        with np.errstate(all="ignore"):
            sse[redo] = np.einsum("bi,bi->b", res, res)
    with np.errstate(all="ignore"):
        value = np.sqrt(sse) / n_res
    return np.where(np.isfinite(value), value, np.inf).reshape(batch)


#: Above this condition number of the eigenvector matrix the pole expansion is unreliable.
_MAX_EIGVEC_CONDITION = 1e8
#: Below this fraction of sum y^2 the fast sum of squares is mostly cancellation error.
_CANCELLATION_FLOOR = 1e-6


#: Exponents below this real part are raised to it: e^-300 is 1e-130, negligible against
#: every other term, and it keeps powers and their products out of the subnormal range,
#: where arithmetic is ~100x slower (heavily damped members of a GA population go there).
_MIN_LOG_POWER = -300.0


def _exp_no_subnormals(exponent: np.ndarray) -> np.ndarray:
    return np.exp(np.maximum(exponent.real, _MIN_LOG_POWER) + 1j * exponent.imag)


def _fast_sse(data: TimeData, damping: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """sum (y - yhat)^2 (B,) by the correlation route, and a flag (B,) 'recompute exactly'.

    With s_i[k] = sum_(m<k) p_i^(k-1-m) u[m] and yhat = D u + sum_i c_i s_i (all 2N poles):
      y.s_i = P_yu(p_i) = sum_e C_yu[e+1] p_i^e,   u.s_i = sum_e C_uu[e+1] p_i^e,
      s_i.s_j = (P_uu(p_i) + P_uu(p_j) - C_uu[0] - sum_h G_h(p_i) G_h(p_j)) / (1 - p_i p_j),
    where P_uu(p) = sum_d C_uu[d] p^d and G_h(p) = sum_m u_h[m] p^(n-1-m): the geometric
    sum over k from max(m, m') to n - 1 splits into these (truncation at n gives the G terms).
    """
    mom = data._moments
    dt = 1.0 / data.sample_rate_hz
    a, b, c, d = data.model.state_space(damping, "acceleration")
    with np.errstate(all="ignore"):
        lam, vec = np.linalg.eig(a)
        inv = np.linalg.inv(vec)
        cond = np.abs(vec).sum(axis=-2).max(axis=-1) * np.abs(inv).sum(axis=-2).max(axis=-1)
        coef = np.einsum("bi,bij->bj", c, vec) * np.einsum("bij,bj->bi", inv, b)
        coef *= np.where(lam == 0, dt, np.expm1(lam * dt) / lam)  # zero-order hold
        # LAPACK lists each conjugate pair together, positive imaginary part first, and
        # the polynomials have real coefficients: evaluate on the upper half only.
        upper = lam.imag >= 0.0
        step = lam[upper] * dt
        fine = _exp_no_subnormals(step[:, None] * np.arange(mom.block))
        coarse = _exp_no_subnormals(step[:, None] * (mom.block * np.arange(mom.n_blocks)))
        stacked = np.concatenate([fine.real, fine.imag]) @ mom.coefficients
        # Assembled through .real/.imag: a complex product with an overflowed (unstable)
        # member's inf takes numpy's slow special-value path.
        inner = np.empty((step.size, stacked.shape[1]), dtype=complex)
        inner.real, inner.imag = stacked[: step.size], stacked[step.size :]
        inner = inner.reshape(step.size, mom.n_blocks, -1)
        vals = np.empty((*lam.shape, inner.shape[-1]), dtype=complex)
        vals[upper] = np.matmul(coarse[:, None, :], inner)[:, 0]
        lower = ~upper
        vals[lower] = np.roll(vals, 1, axis=1)[lower].conj()
        ys, us, pu, g = vals[..., 0], vals[..., 1], vals[..., 2], vals[..., 3:]
        p = np.exp(lam * dt)
        one_minus_q = 1.0 - p[:, :, None] * p[:, None, :]
        ss = (pu[:, :, None] + pu[:, None, :] - mom.uu - g @ np.swapaxes(g, 1, 2)) / one_minus_q
        y_yhat = d * mom.yu + np.einsum("bi,bi->b", coef, ys)
        yhat2 = d * d * mom.uu + 2.0 * d * np.einsum("bi,bi->b", coef, us)
        yhat2 = yhat2 + np.einsum("bi,bij,bj->b", coef, ss, coef)
        sse = (mom.yy - 2.0 * y_yhat + yhat2).real
        unstable = np.any(np.abs(p) > 1.0, axis=-1)
        redo = (
            ~(cond < _MAX_EIGVEC_CONDITION)
            | ~(np.min(np.abs(one_minus_q), axis=(-2, -1)) > 1e-12)
            | (~np.isfinite(sse) & ~unstable)
            | (sse < _CANCELLATION_FLOOR * mom.yy)
        )
    sse = np.where(np.isfinite(sse), sse, np.inf)
    return sse, redo


def batched_residuals_frf(data: FrequencyData, damping: np.ndarray) -> np.ndarray:
    """sqrt(w) (H - Hhat) as [real parts, imaginary parts]: (B, 2 n_lines), (m/s^2)/N.

    damping : (B, N, N), N s/m; one batched ``frequency_response`` call.
    """
    flat, valid, _ = _split_valid(damping, data.model.n_dof)
    with np.errstate(all="ignore"):
        hhat = frequency_response(data.model, flat, data.frequency_hz, "acceleration")
        diff = np.sqrt(data.weights) * (data.frf - hhat)
    res = np.concatenate([diff.real, diff.imag], axis=-1)
    res[~valid] = np.nan
    return res


def residuals_frf(data: FrequencyData, damping: np.ndarray) -> np.ndarray:
    """Weighted FRF residual of one damping matrix (N, N): (2 n_lines,), (m/s^2)/N."""
    r = np.asarray(damping, dtype=float)
    if r.ndim != 2:
        raise ValueError(f"expected one (N, N) damping matrix, got shape {r.shape}")
    return batched_residuals_frf(data, r[None])[0]


def psi_frf(data: FrequencyData, damping: np.ndarray) -> np.ndarray:
    """The eq (17) form on the FRF for each damping matrix (..., N, N): shape (...), (m/s^2)/N."""
    _, _, batch = _split_valid(damping, data.model.n_dof)
    n = data.model.n_dof
    res = batched_residuals_frf(data, np.reshape(damping, (-1, n, n)))
    return _psi_from_residuals(res, batch)
