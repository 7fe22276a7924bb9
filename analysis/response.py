"""Frequency and time responses of a StructuralModel, batched over damping matrices.

Both go through the eigen-decomposition of the state matrix A = V diag(lambda) V^-1,
computed once per damping matrix for the whole batch in one LAPACK call:

* H(j w) = sum_i r_i / (j w - lambda_i) + D, with residues r_i = (C V)_i (V^-1 B)_i.
* The time response holds the force constant over each sample (zero-order hold),
  which is exact for x' = A x + B f with piecewise-constant f: each mode obeys
  z[k+1] = e^(lambda T) z[k] + (e^(lambda T) - 1) / lambda * g u[k]. The response is
  the causal convolution of the force with that discrete impulse response.

Where V is too ill-conditioned for the modal route (repeated poles, e.g. critical
damping), a member falls back to a direct solve (frequency response) or the matrix
exponential (time response); the result is the same to round-off, only slower.
"""

from __future__ import annotations

import numpy as np
import scipy.fft
import scipy.linalg

from analysis.structure import QUANTITY_ORDER, Quantity, StructuralModel

#: Above this condition number of the eigenvector matrix, a member leaves the modal route.
MAX_EIGVEC_CONDITION = 1e8


def _flatten_batch(damping: np.ndarray) -> tuple[np.ndarray, tuple[int, ...]]:
    batch = damping.shape[:-2]
    n = damping.shape[-1]
    return damping.reshape((-1, n, n)), batch


def _modal_terms(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Poles (P, 2N), residues (P, 2N) and a per-member 'modal route is safe' flag (P,)."""
    lam, vec = np.linalg.eig(a)
    with np.errstate(all="ignore"):
        cond = np.linalg.cond(vec)
        g = np.linalg.solve(vec, b[..., None].astype(complex))[..., 0]
    cv = np.einsum("pi,pij->pj", c, vec)
    ok = np.isfinite(cond) & (cond < MAX_EIGVEC_CONDITION)
    return lam, cv * g, ok


def _upper_half(lam: np.ndarray, res: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Keep one pole of each conjugate pair (weight 2) and every real pole (weight 1).

    LAPACK returns the poles of a real matrix as exact conjugate pairs, so the
    response is the real part of the sum over the kept poles: half the work.
    """
    keep = lam.imag >= 0.0
    weight = np.where(lam.imag > 0.0, 2.0, 1.0) * keep
    order = np.argsort(~keep, axis=-1, kind="stable")[..., : int(keep.sum(axis=-1).max())]
    lam_kept = np.take_along_axis(lam, order, axis=-1)
    res_kept = np.take_along_axis(res * weight, order, axis=-1)
    return lam_kept, res_kept


def frequency_response(
    model: StructuralModel,
    damping: np.ndarray,
    frequencies_hz: np.ndarray,
    output: Quantity = "acceleration",
) -> np.ndarray:
    """H(j w) from the force at x_f to the chosen quantity at x_s.

    Parameters
    ----------
    damping : (..., N, N), N s/m.
    frequencies_hz : (F,), Hz.
    output : "displacement" (m/N), "velocity" (m/s/N) or "acceleration" (m/s^2/N).

    Returns
    -------
    (..., F) complex.
    """
    r = model.check_damping(damping)
    flat, batch = _flatten_batch(r)
    f = np.asarray(frequencies_hz, dtype=float)
    if f.ndim != 1 or not np.all(np.isfinite(f)):
        raise ValueError("frequencies_hz must be a finite 1-D array")
    s = 2j * np.pi * f
    if flat.shape[0] == 0:
        return np.zeros((*batch, f.size), dtype=complex)
    a, b, c, d = model.state_space(flat, output)
    lam, res, ok = _modal_terms(a, b, c)
    with np.errstate(all="ignore"):
        h = _sum_of_poles(res, lam, 2.0 * np.pi * f) + d[:, None]
    if not np.all(ok):
        h[~ok] = _direct_frequency_response(model, flat[~ok], s, output)
    return h.reshape((*batch, f.size))


def _sum_of_poles(res: np.ndarray, lam: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """sum_i res_i / (j omega - lambda_i), (P, F) complex, from (P, W) and (F,).

    This is the hot loop of a fit, so it avoids numpy's slow complex division and
    keeps the (P, W, F) temporaries to three: each fresh ~1 MB temporary costs
    page faults that dwarf the arithmetic. Frequency is the innermost axis.
    """
    x = -lam.real  # (P, W)
    y = omega - lam.imag[:, :, None]  # (P, W, F): w - Im(lambda)
    inv = y * y
    inv += (x * x)[:, :, None]
    np.reciprocal(inv, out=inv)  # 1 / |j w - lambda|^2
    y *= inv
    # r / (x + j y) = (r_re x + r_im y) / |.|^2 + j (r_im x - r_re y) / |.|^2
    real = np.matmul((res.real * x)[:, None, :], inv) + np.matmul(res.imag[:, None, :], y)
    imag = np.matmul((res.imag * x)[:, None, :], inv) - np.matmul(res.real[:, None, :], y)
    return real[:, 0] + 1j * imag[:, 0]


def _direct_frequency_response(
    model: StructuralModel, damping: np.ndarray, s: np.ndarray, output: Quantity
) -> np.ndarray:
    """H(s) = s^k c^T (s^2 M + s R + K)^-1 b by a direct solve, (P, F)."""
    z = (
        s[None, :, None, None] ** 2 * model.mass
        + s[None, :, None, None] * damping[:, None, :, :]
        + model.stiffness
    )
    rhs = np.broadcast_to(model.force_shape.astype(complex), z.shape[:-1])[..., None]
    q = np.linalg.solve(z, rhs)[..., 0]
    return (q @ model.sensor_shape) * s[None, :] ** QUANTITY_ORDER[output]


def _expm1_over(lam: np.ndarray, dt: float) -> np.ndarray:
    """(e^(lambda dt) - 1) / lambda without cancellation; dt where lambda == 0."""
    x, y = lam.real * dt, lam.imag * dt
    # e^(x+jy) - 1 = (expm1(x) cos y - 2 sin^2(y/2)) + j e^x sin y, all terms accurate.
    num = (np.expm1(x) * np.cos(y) - 2.0 * np.sin(0.5 * y) ** 2) + 1j * np.exp(x) * np.sin(y)
    with np.errstate(all="ignore"):
        out = num / lam
    return np.where(lam == 0, dt, out)


def _modal_impulse_response(lam: np.ndarray, coef: np.ndarray, dt: float, n_samples: int) -> np.ndarray:
    """Re(sum_i coef_i e^(lambda_i dt m)) for m = 0..n_samples-1, shape (P, n_samples).

    Powers are formed as e^(lambda dt q B) e^(lambda dt r) with m = q B + r, which
    needs 2 sqrt(n) exponentials per pole instead of n, at one rounding of extra error.
    """
    block = max(1, int(np.ceil(np.sqrt(n_samples))))
    n_blocks = -(-n_samples // block)
    step = lam * dt
    fine = np.exp(step[..., None] * np.arange(block))  # (P, W, B)
    coarse = np.exp(step[..., None] * (block * np.arange(n_blocks)))  # (P, W, Q)
    weighted = coef[..., None] * coarse
    h = np.matmul(np.swapaxes(weighted, -1, -2), fine)  # (P, Q, B)
    return h.real.reshape(h.shape[0], -1)[:, :n_samples]


def _expm_impulse_response(
    a: np.ndarray, b: np.ndarray, c: np.ndarray, dt: float, n_samples: int
) -> np.ndarray:
    """C Ad^m Bd for m = 0..n_samples-1 through the matrix exponential, (n_samples,)."""
    n = a.shape[0]
    aug = np.zeros((n + 1, n + 1))
    aug[:n, :n] = a * dt
    aug[:n, n] = b * dt
    phi = scipy.linalg.expm(aug)
    ad, x = phi[:n, :n], phi[:n, n]
    out = np.empty(n_samples)
    for m in range(n_samples):
        out[m] = c @ x
        x = ad @ x
    return out


def time_response(
    model: StructuralModel,
    damping: np.ndarray,
    force_n: np.ndarray,
    sample_rate_hz: float,
    output: Quantity = "acceleration",
) -> np.ndarray:
    """Response at the sensor to a sampled force held constant over each sample.

    Starts from rest. Matches ``scipy.signal.cont2discrete(..., method="zoh")``
    followed by ``dlsim`` to round-off.

    Parameters
    ----------
    damping : (..., N, N), N s/m.
    force_n : (n_samples,) shared by the whole batch, or (..., n_samples)
        broadcastable against the batch shape; newtons.
    sample_rate_hz : samples per second.
    output : "displacement" (m), "velocity" (m/s) or "acceleration" (m/s^2).

    Returns
    -------
    (..., n_samples) float. An unstable member (a damping matrix that is not
    positive semi-definite can make one) may overflow to inf/nan without
    affecting the others.
    """
    r = model.check_damping(damping)
    flat, batch = _flatten_batch(r)
    force = np.asarray(force_n, dtype=float)
    if force.ndim < 1 or force.shape[-1] < 1 or not np.all(np.isfinite(force)):
        raise ValueError("force_n must be a finite array with samples along its last axis")
    try:
        sample_rate_hz = float(sample_rate_hz)
    except (TypeError, ValueError):
        raise ValueError(f"sample_rate_hz must be a number, got {sample_rate_hz!r}") from None
    if not (np.isfinite(sample_rate_hz) and sample_rate_hz > 0):
        raise ValueError(f"sample_rate_hz must be positive, got {sample_rate_hz!r}")
    n_samples = force.shape[-1]
    try:
        force_b = np.broadcast_to(force, (*batch, n_samples)).reshape(-1, n_samples)
    except ValueError:
        raise ValueError(
            f"force_n of shape {force.shape} does not broadcast against the batch {batch}"
        ) from None
    dt = 1.0 / sample_rate_hz
    if flat.shape[0] == 0:
        return np.zeros((*batch, n_samples))

    a, b, c, d = model.state_space(flat, output)
    lam, res, ok = _modal_terms(a, b, c)
    lam_k, res_k = _upper_half(lam, res)
    h = np.empty((flat.shape[0], n_samples))
    h[:, 0] = d
    with np.errstate(all="ignore"):
        if n_samples > 1:
            coef = res_k * _expm1_over(lam_k, dt)
            h[:, 1:] = _modal_impulse_response(lam_k, coef, dt, n_samples - 1)
        for p in np.flatnonzero(~ok):
            h[p, 1:] = _expm_impulse_response(a[p], b[p], c[p], dt, n_samples - 1)
        y = _causal_convolution(h, force_b, shared_input=force.ndim == 1)
    return y.reshape((*batch, n_samples))


def _causal_convolution(h: np.ndarray, u: np.ndarray, shared_input: bool) -> np.ndarray:
    """y[p, k] = sum_{m<=k} h[p, k-m] u[p, m], by FFT, (P, n)."""
    n = h.shape[-1]
    n_fft = scipy.fft.next_fast_len(2 * n - 1, real=True)
    spectrum_h = scipy.fft.rfft(h, n_fft, axis=-1)
    spectrum_u = scipy.fft.rfft(u[:1] if shared_input else u, n_fft, axis=-1)
    return scipy.fft.irfft(spectrum_h * spectrum_u, n_fft, axis=-1)[:, :n]
