"""Benchmark: identifying the seed's damping matrix from simulated hits, four ways.

Run: .venv/bin/python bench/bench_damping.py
Data: the seed model (Ritz N = 3) with the eq (18) damping, 5 half-sine hits of
2 ms, 1024 samples at 512 Hz, 1 % Gaussian noise on the acceleration. One core.

(a) the seed's GA budget (50 x 30 = 1,500 evaluations) with the batched Psi, each
    distinct member computed once (the default), and (a') every member computed;
(b) the same GA as a direct port would write it: per individual, build A, B, C, D
    and call scipy.signal.lsim per hit. Only 2 generations are run; the 30-generation
    time is extrapolated from them;
(c) differential evolution (vectorised) to scipy's convergence;
(d) least squares from a Rayleigh-proportional start (5 % at the first two modes).
"""

from __future__ import annotations

import os

# One BLAS/OpenMP thread, before numpy loads: the timings are per core.
for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_variable] = "1"

import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import scipy.linalg  # noqa: E402
import scipy.signal  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from analysis.damping.ga import fit_ga  # noqa: E402
from analysis.damping.local import fit_de, fit_least_squares  # noqa: E402
from analysis.damping.objective import TimeData, batched_residuals, psi, residuals  # noqa: E402
from analysis.modal import damped_modes  # noqa: E402
from analysis.response import time_response  # noqa: E402
from analysis.ritz import RitzBeam  # noqa: E402
from analysis.seed import eq18_damping_matrix  # noqa: E402

RATE_HZ = 512.0
N_SAMPLES = 1024
N_HITS = 5
LSIM_GENERATIONS = 2


def _half_sine(peak_n: float, start_s: float, width_s: float = 2e-3) -> np.ndarray:
    """Cell averages of a half-sine pulse over each sample, N."""
    edges = np.arange(N_SAMPLES + 1) / RATE_HZ
    a = np.clip(edges[:-1] - start_s, 0.0, width_s)
    b = np.clip(edges[1:] - start_s, 0.0, width_s)
    return peak_n * width_s / np.pi * (np.cos(np.pi * a / width_s) - np.cos(np.pi * b / width_s)) * RATE_HZ


def _data() -> tuple[TimeData, np.ndarray]:
    model = RitzBeam.build(n_functions=3).structure()
    r_true = eq18_damping_matrix()
    peaks = (100.0, 70.0, 130.0, 85.0, 115.0)
    force = np.array([_half_sine(p, (20 + 3 * i + 0.3) / RATE_HZ) for i, p in enumerate(peaks)])
    clean = time_response(model, np.broadcast_to(r_true, (N_HITS, 3, 3)), force, RATE_HZ)
    noisy = clean + 0.01 * clean.std() * np.random.default_rng(0).standard_normal(clean.shape)
    return TimeData(model, force, noisy, RATE_HZ), r_true


def _lsim_psi(data: TimeData, damping: np.ndarray) -> np.ndarray:
    """Eq (17) the direct way: one scipy.signal.lsim per individual and hit."""
    t = np.arange(data.n_samples) / data.sample_rate_hz
    out = np.empty(damping.shape[0])
    for i, r in enumerate(damping):
        a, b, c, d = data.model.state_space(r)
        sse = 0.0
        for force, measured in zip(data.force_n, data.response_m_s2, strict=True):
            with np.errstate(all="ignore"):  # unstable individuals overflow: Psi = inf
                _, yhat, _ = scipy.signal.lsim(
                    (a, b[:, None], c[None, :], d[None, None]), force, t, interp=False
                )
                sse += float(np.sum((measured - yhat) ** 2))
        out[i] = np.sqrt(sse) / (data.n_hits * data.n_samples) if np.isfinite(sse) else np.inf
    return out


def _rayleigh_start(data: TimeData, zeta: float = 0.05) -> np.ndarray:
    """alpha M + beta K with damping ratio zeta at the first two undamped modes."""
    w = np.sqrt(scipy.linalg.eigh(data.model.stiffness, data.model.mass, eigvals_only=True))[:2]
    alpha, beta = np.linalg.solve([[1 / (2 * w[0]), w[0] / 2], [1 / (2 * w[1]), w[1] / 2]], [zeta, zeta])
    return alpha * data.model.mass + beta * data.model.stiffness


def _timed(fn, repeat: int = 1):
    best, result = np.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        result = fn()
        best = min(best, time.perf_counter() - t0)
    return best, result


def main() -> None:
    data, r_true = _data()
    objective = lambda r: psi(data, r)  # noqa: E731
    psi(data, r_true[None])  # warm caches and imports
    t_ga, ga = _timed(lambda: fit_ga(objective, 3, seed=0), repeat=5)
    t_ga_all, ga_all = _timed(lambda: fit_ga(objective, 3, seed=0, cache=False), repeat=5)
    t_lsim, ga_lsim = _timed(
        lambda: fit_ga(lambda r: _lsim_psi(data, r), 3, seed=0, generations=LSIM_GENERATIONS, cache=False)
    )
    t_lsim_full = t_lsim * 30 / LSIM_GENERATIONS
    t_de, de = _timed(lambda: fit_de(objective, 3, seed=0))
    start = _rayleigh_start(data)
    t_ls, ls = _timed(
        lambda: fit_least_squares(
            lambda r: residuals(data, r), start, batched_residuals=lambda r: batched_residuals(data, r)
        ),
        repeat=5,
    )
    truth_psi = float(psi(data, r_true))
    same = np.allclose(ga_lsim.history, ga.history[:LSIM_GENERATIONS], rtol=1e-6)
    rows = [
        ("(a) GA 50 x 30, batched Psi, distinct members once", t_ga, ga),
        ("(a') GA 50 x 30, batched Psi, every member", t_ga_all, ga_all),
        (
            f"(b) GA 50 x 30, per-individual lsim (2 gens x {30 / LSIM_GENERATIONS:.0f}, extrapolated)",
            t_lsim_full,
            None,
        ),
        ("(c) DE vectorised, to convergence", t_de, de),
        ("(d) least squares, Rayleigh start", t_ls, ls),
    ]
    print(f"{N_HITS} hits x {N_SAMPLES} samples at {RATE_HZ:.0f} Hz, eq (18) truth, 1 % noise, one core")
    print(f"Psi of the true R on this data: {truth_psi:.6g} m/s^2; eq (18) ratios:", end=" ")
    print(" ".join(f"{z:.4f}" for z in damped_modes(data.model, r_true).damping_ratios))
    width = max(len(r[0]) for r in rows)
    print(f"{'method':<{width}}  {'time':>9}  {'x (a)':>7}  {'evals':>6}  {'Psi':>10}  damping ratios")
    for name, seconds, fit in rows:
        ratio = seconds / t_ga
        if fit is None:
            tail = f"{1500:>6}  {'(same GA)':>10}  (same GA)"
        else:
            z = damped_modes(data.model, fit.damping_matrix).damping_ratios
            tail = f"{fit.n_evaluations:>6}  {fit.psi:10.6g}  " + " ".join(f"{v:.4f}" for v in z)
        print(f"{name:<{width}}  {seconds * 1e3:7.1f}ms  {ratio:7.2f}  {tail}")
    print(
        f"lsim port: first {LSIM_GENERATIONS} generations identical to (a): {same}; "
        f"measured {t_lsim:.2f} s for {LSIM_GENERATIONS} generations"
    )
    print(f"(a): {ga.message}")


if __name__ == "__main__":
    main()
