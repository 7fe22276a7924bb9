"""Least-squares complex frequency-domain (LSCF) estimator, common-denominator z-domain form.

Model (Guillaume, Verboven, Vanlanduit, Van der Auweraer, Peeters, IMAC 2003): every
FRF o shares one denominator,

    H_o(w) ~ N_o(z) / D(z),   z = exp(j w Ts),   N_o(z) = sum_j beta_oj z^j,
    D(z) = sum_j alpha_j z^j,  j = 0..p,   real coefficients, alpha_p = 1,

fitted by linear least squares on sum_k |N_o(z_k) - H_o(w_k) D(z_k)|^2. Eliminating
the numerators gives the reduced normal equations M alpha = 0 with
M = sum_o (T_o - S_o^T R^-1 S_o). R, S_o, T_o are Toeplitz (their entries depend on
j - i only), so one matrix product over the lines gives them for the highest order and
every lower order uses their leading blocks.

Model order: ``order`` n is the number of pole PAIRS; the denominator polynomial has
degree p = 2 n (the same count as sdypy-EMA's ``pol_order_high``). Orders 1..max_order
are solved together (padded, batched linear algebra; no loop over lines).

Sampling time: Ts = pi / w_max with w_max the highest line used, so the lines map
onto the upper half of the unit circle [0, pi] (real coefficients make the lower half
the mirror image); this is the best-conditioned choice when the band starts near 0 Hz.

Each FRF is divided by its RMS over the lines first, so every FRF weighs the same in
the common denominator whatever its units or level.

Zoomed form (``basis="complex"``), for a band [f1, f2] away from 0 Hz: the lines map
onto the unit circle around the band's centre, z = exp(j (w - w_c) Ts) with
Ts = 0.8 / (f2 - f1), so the band fills 80 % of the circle instead of the sliver
[pi f1/f2, pi] that the real form gives it (a polynomial basis on a short arc is
ill-conditioned: at order 30 on an arc of pi/8 the normal equations lose every
digit). The coefficients are then complex and each root is one pole (no conjugate
pairs: the negative-frequency poles are smooth over the band and the numerators take
them up), so ``order`` n is a denominator of degree n. Frequency-domain zooming of
this kind is how commercial LSCF (PolyMAX) handles narrow bands.

Normalisation: the denominator is defined up to a factor, so one coefficient is fixed.
``"highest"`` fixes alpha_p = 1 (a monic polynomial); ``"lowest"`` fixes alpha_0 = 1, as
sdypy-EMA and PolyMAX do. They weigh the noise differently. With alpha_p = 1 the poles of
well-resolved, lightly damped modes converge fastest with the order (modelab-beam's
974 Hz at 0.0103 % from order 20, against 0.016-0.018 % with alpha_0 = 1). But on noisy
data the noise poles stay among the modes in the stable half-plane, and a heavily damped
mode's pole wanders from one order to the next: on the measured tool holder of
tests/data/README.md (200-3500 Hz), 2612 Hz went 1.8-3.0 % over orders 14-39. With alpha_0 = 1 the
noise poles move to negative damping and the same mode holds 2.36-2.51 %.
analysis.modal_id.identify fits both.

Kept poles: roots with a non-zero imaginary part (one of each conjugate pair, the one
with Im s > 0), a negative real part (|z| < 1), natural frequency inside the band.
Discarded: real roots (over-damped or numerical, no oscillation), unstable roots
(|z| >= 1, Re s >= 0) and out-of-band roots (they model what lies outside the band).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg

#: Orders are grouped in this many size buckets for the batched eigenvalue solve, so
#: zero padding costs little (a single bucket would pad every companion matrix to 2N).
_EIG_BUCKETS = 12


@dataclass(frozen=True)
class LscfPoles:
    """Physical poles of each model order.

    orders : (n_orders,) int, pole pairs of the model (polynomial degree 2 n).
    poles : list over orders of (n_r,) complex, rad/s, Im > 0, Re < 0.
    residues : list over orders of (n_r, n_frf) complex, the residue of N_o/D at each
        pole in the FRF's units times rad/s (H ~ A / (j w - lambda) near lambda);
        a modal participation vector for the stability test.
    sampling_time : Ts, s.
    """

    orders: np.ndarray
    poles: list[np.ndarray]
    residues: list[np.ndarray]
    sampling_time: float


def _toeplitz_terms(omega_ts: np.ndarray, h: np.ndarray, p_max: int, real: bool = True, weights=None):
    """r(m), s_o(m), t(m) for lags m = -p_max..p_max: sums over the lines, each line
    counted ``weights`` times (default once); their real parts for the real-coefficient
    form, where each line stands for itself and its mirror."""
    lags = np.arange(-p_max, p_max + 1)
    # z^m by repeated products, not exp(j m theta) for every lag: the exponentials were
    # most of the cost on 51,201 lines (the rounding grows as m eps, 1e-14 at m = 120).
    z = np.exp(1j * omega_ts)
    positive = np.cumprod(np.broadcast_to(z[:, None], (z.size, p_max)), axis=1)  # z^1..z^P
    zpow = np.concatenate([np.conj(positive[:, ::-1]), np.ones((z.size, 1)), positive], axis=1)  # (F, 2P+1)
    w = np.ones(omega_ts.size) if weights is None else np.asarray(weights, dtype=float)
    r = w @ zpow
    s = -((h * w) @ zpow)  # (n_frf, 2P+1)
    t = ((np.abs(h) ** 2).sum(axis=0) * w) @ zpow
    if real:
        return lags, r.real, s.real, t.real
    return lags, r, s, t


def _toeplitz_from_lags(values: np.ndarray, p_max: int) -> np.ndarray:
    """Matrix X[..., i, j] = values[..., (j - i) + p_max], i, j = 0..p_max."""
    idx = np.arange(p_max + 1)
    return values[..., (idx[None, :] - idx[:, None]) + p_max]


def _cholesky(r: np.ndarray) -> np.ndarray:
    """Lower Cholesky factor; a tiny ridge rescues the rank loss of a narrow zoom band."""
    try:
        return np.linalg.cholesky(r)
    except np.linalg.LinAlgError:
        ridge = 1e-10 * np.trace(r) / r.shape[0]
        return np.linalg.cholesky(r + ridge * np.eye(r.shape[0]))


def lscf_poles(
    frequency_hz: np.ndarray,
    frf: np.ndarray,
    max_order: int,
    band: tuple[float, float] | None = None,
    orders: tuple[int, ...] | None = None,
    basis: str = "real",
    weights: np.ndarray | None = None,
    normalisation: str = "highest",
) -> LscfPoles:
    """Poles of LSCF models of order 1..max_order fitted to the lines inside ``band``.

    frequency_hz : (n_lines,) Hz, increasing. frf : (n_frf, n_lines) complex.
    band : (f1, f2) Hz; default the whole line range. Returns :class:`LscfPoles`.
    orders : only these orders get their poles (the others come back empty): the
        denominators of every order cost little, their roots most of the time.
    basis : "real" (lines on [0, pi], order n = n pole pairs) or "complex" (the band
        zoomed onto the circle, order n = n poles; see the module docstring).
    weights : (n_lines,) how many times each line counts (a bootstrap over the lines).
    normalisation : "highest" (alpha_p = 1) or "lowest" (alpha_0 = 1): which coefficient
        of the denominator is fixed (see the module docstring).
    """
    if normalisation not in ("highest", "lowest"):
        raise ValueError(f"normalisation must be 'highest' or 'lowest', got {normalisation!r}")
    if basis not in ("real", "complex"):
        raise ValueError(f"basis must be 'real' or 'complex', got {basis!r}")
    real = basis == "real"
    f = np.asarray(frequency_hz, dtype=float)
    h = np.atleast_2d(np.asarray(frf, dtype=complex))
    f1, f2 = (f[0], f[-1]) if band is None else band
    use = (f >= f1) & (f <= f2)
    f, h = f[use], h[:, use]
    weights = None if weights is None else np.asarray(weights, dtype=float)[use]
    n_orders = int(max_order)
    step = 2 if real else 1  # polynomial degree per order
    p_max = step * n_orders
    if n_orders < 1 or f.size < p_max + 2:
        raise ValueError(f"LSCF needs max_order >= 1 and more than {p_max + 1} lines, got {f.size}")
    if real:
        ts, f_centre = 0.5 / f[-1], 0.0
    else:
        ts, f_centre = 0.8 / max(f[-1] - f[0], 1e-300), 0.5 * (f[0] + f[-1])
    omega_ts = 2 * np.pi * (f - f_centre) * ts
    scale = np.sqrt(np.mean(np.abs(h) ** 2, axis=1))
    scale[scale == 0] = 1.0
    hn = h / scale[:, None]
    n_frf = h.shape[0]

    _, r_lag, s_lag, t_lag = _toeplitz_terms(omega_ts, hn, p_max, real, weights)
    r_full = _toeplitz_from_lags(r_lag, p_max)
    s_full = _toeplitz_from_lags(s_lag, p_max)  # (n_frf, P+1, P+1)
    t_full = _toeplitz_from_lags(t_lag, p_max)
    # R_p = L_p L_p^H with L_p the leading block of the full factor, and the first p+1
    # rows of L^-1 S depend only on L_p: one triangular solve serves every order.
    chol = _cholesky(r_full)
    y = scipy.linalg.solve_triangular(chol, s_full.transpose(1, 0, 2).reshape(p_max + 1, -1), lower=True)
    y = y.reshape(p_max + 1, -1, p_max + 1).transpose(1, 0, 2)  # (n_frf, P+1, P+1)
    # S_p^H R_p^-1 S_p = sum over rows k <= p of y[k]^H y[k]. Order n adds the rows of
    # degrees step*(n-1)+1 .. step*n: one batched matmul per order, then a cumulative sum.
    degrees = step * np.arange(1, n_orders + 1)
    rows = y[:, 1:, :].reshape(n_frf, n_orders, step, p_max + 1).transpose(1, 0, 2, 3)
    rows = rows.reshape(n_orders, step * n_frf, p_max + 1)
    gram = np.cumsum(np.matmul(rows.conj().transpose(0, 2, 1), rows), axis=0)
    gram += y[:, 0, :].conj().T @ y[:, 0, :]
    m = t_full[None] - gram  # (n_orders, P+1, P+1), order n uses its leading (p+1) block
    wanted = np.arange(n_orders) if orders is None else np.array(sorted(orders), dtype=int) - 1
    if wanted.size == 0 or wanted.min() < 0 or wanted.max() >= n_orders:
        raise ValueError(f"orders must lie in 1..{n_orders}, got {orders}")
    # Only the orders wanted are solved: the batched solve is the costly step at high order.
    m, deg_w = m[wanted], degrees[wanted]
    idx = np.arange(p_max)
    alpha = np.zeros((n_orders, p_max + 1), dtype=m.dtype)
    if normalisation == "highest":
        # alpha_p = 1: M[:p, :p] alpha[:p] = -M[:p, p]; pad each order to p_max with identity.
        inside = idx[None, :] < deg_w[:, None]  # (n_wanted, P)
        a_mat = np.where(inside[:, :, None] & inside[:, None, :], m[:, :p_max, :p_max], 0.0)
        a_mat += np.eye(p_max) * ~inside[:, :, None]
        rhs = -np.take_along_axis(m[:, :p_max, :], deg_w[:, None, None], axis=2)[..., 0] * inside
        alpha[wanted, :p_max] = np.linalg.solve(a_mat, rhs[..., None])[..., 0]
        alpha[wanted, deg_w] = 1.0
    else:
        # alpha_0 = 1: M[1:p+1, 1:p+1] alpha[1:p+1] = -M[1:p+1, 0], then made monic for the roots.
        inside = idx[None, :] < deg_w[:, None]  # unknowns alpha_1..alpha_p
        a_mat = np.where(inside[:, :, None] & inside[:, None, :], m[:, 1:, 1:], 0.0)
        a_mat += np.eye(p_max) * ~inside[:, :, None]
        rhs = -m[:, 1:, 0] * inside
        alpha[wanted, 0] = 1.0
        alpha[wanted, 1:] = np.linalg.solve(a_mat, rhs[..., None])[..., 0]
        lead = alpha[wanted, deg_w]
        lead = np.where(np.abs(lead) > 0, lead, 1e-300)
        alpha[wanted] /= lead[:, None]
    # Numerators beta_o = -R_p^-1 S_o,p alpha = -L_p^-H (L_p^-1 S_o,p) alpha. Padding the
    # right-hand side with zeros beyond p makes the full upper-triangular L^H solve return
    # the order-p answer (zeros below), so one solve serves all orders and FRFs.
    y_alpha = np.einsum("okj,nj->kno", y, alpha[wanted]) * (
        np.arange(p_max + 1)[:, None, None] <= deg_w[None, :, None]
    )
    beta = np.zeros((n_orders, p_max + 1, n_frf), dtype=y.dtype)
    solved = -scipy.linalg.solve_triangular(chol.conj().T, y_alpha.reshape(p_max + 1, -1), lower=False)
    beta[wanted] = solved.reshape(p_max + 1, wanted.size, n_frf).transpose(1, 0, 2)

    roots: list[np.ndarray] = [np.empty(0, complex)] * n_orders
    for k, r in zip(wanted, _batched_roots(alpha[wanted], degrees[wanted]), strict=True):
        roots[k] = r
    poles, residues = [], []
    w_centre = 2 * np.pi * f_centre
    with np.errstate(all="ignore"):
        for k in range(n_orders):  # per order: a handful of poles, bookkeeping only
            z = roots[k]
            if z.size == 0:
                poles.append(np.empty(0, complex))
                residues.append(np.empty((0, n_frf), complex))
                continue
            s = np.log(z) / ts + 1j * w_centre
            keep = (s.imag > 0) & (np.abs(z) < 1.0)
            if real:  # a real root stands for no oscillation; one of each conjugate pair is kept
                keep &= np.abs(z.imag) > 1e-12 * np.abs(z)
            fn = np.abs(s) / (2 * np.pi)
            keep &= (fn >= f1) & (fn <= f2)
            z, s = z[keep], s[keep]
            deg = degrees[k]
            powers = z[:, None] ** np.arange(deg + 1)  # (n_r, p+1)
            num = powers @ beta[k, : deg + 1]  # (n_r, n_frf)
            dden = powers[:, :deg] @ (np.arange(1, deg + 1) * alpha[k, 1 : deg + 1])
            # H(s) = N(z) / D(z), z = e^((s - j w_c) Ts): dD/ds = D'(z) z Ts at the pole.
            res = num / (dden * z * ts)[:, None] * scale[None, :]
            order = np.argsort(s.imag)
            poles.append(s[order])
            residues.append(res[order])
    return LscfPoles(np.arange(1, n_orders + 1), poles, residues, ts)


def _batched_roots(alpha: np.ndarray, degrees: np.ndarray) -> list[np.ndarray]:
    """Roots of each monic polynomial alpha[k, :deg_k+1] (ascending powers), batched.

    Companion matrices are zero-padded to the largest degree in their bucket; the
    padding adds exact zero eigenvalues, which are dropped.
    """
    out: list[np.ndarray] = [np.empty(0, complex)] * len(degrees)
    for bucket in np.array_split(np.arange(len(degrees)), min(_EIG_BUCKETS, len(degrees))):
        size = int(degrees[bucket].max())
        comp = np.zeros((bucket.size, size, size), dtype=alpha.dtype)
        for row, k in enumerate(bucket):  # fills a (p, p) block per order
            p = degrees[k]
            comp[row, 0, :p] = -alpha[k, p - 1 :: -1][:p]
            comp[row, np.arange(1, p), np.arange(p - 1)] = 1.0
        eig = np.linalg.eigvals(comp)
        for row, k in enumerate(bucket):
            e = eig[row]
            # Keep the p eigenvalues of largest modulus: the padding contributed exact zeros.
            out[k] = e[np.argsort(-np.abs(e))[: degrees[k]]]
    return out
