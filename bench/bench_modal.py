"""Our identify_modes vs sdypy-EMA's LSCF on the same FRFs, side by side.

3 FRFs x 1001 lines (0..200 Hz), accelerance of the paper's damped three-mode model
plus a lightly damped fourth mode, 0.5 % complex noise; LSCF orders up to 60 for both.
sdypy: get_poles (orders 1..60), select_closest_poles at the true frequencies (it needs
to be told; ours is not), get_constants (LSFD). Times are the best of 3 runs.

Run: .venv/bin/python bench/bench_modal.py
"""

from __future__ import annotations

import os

# One BLAS thread for both tools: on a small shared machine OpenBLAS threads fighting
# over the cores made every batched solve 10-100x slower and the timings meaningless.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import contextlib
import io
import time
import warnings

import numpy as np

from analysis.modal_id import identify_modes

FN = np.array([5.589, 36.09, 96.48, 160.0])
ZETA = np.array([0.0361, 0.2032, 0.1620, 0.005])
MAX_ORDER = 60


def synthetic_frfs(n_lines: int = 1001, noise: float = 0.005, seed: int = 0):
    """(f, H): accelerance (m/s^2)/N of real-mode shapes at 3 sensors, one force."""
    f = np.linspace(0.0, 200.0, n_lines)
    w = 2 * np.pi * f
    wn = 2 * np.pi * FN
    lam = -ZETA * wn + 1j * wn * np.sqrt(1 - ZETA**2)
    shapes = np.array([[1.0, -0.8, 0.6, 0.4], [0.7, 0.5, -1.0, -0.9], [0.3, 1.0, 0.8, 0.5]])
    force = shapes[0]
    modal_a = shapes * force / 1.0  # unit modal masses
    rd = modal_a / (2j * lam.imag)  # receptance residues (n_frf, n_modes)
    jw = 1j * w[None, None, :]
    h = -(w**2) * np.sum(
        rd[..., None] / (jw - lam[None, :, None])
        + np.conj(rd)[..., None] / (jw - np.conj(lam)[None, :, None]),
        axis=1,
    )
    rng = np.random.default_rng(seed)
    rms = np.sqrt(np.mean(np.abs(h) ** 2, axis=1, keepdims=True))
    h = h + noise * rms * (rng.standard_normal(h.shape) + 1j * rng.standard_normal(h.shape)) / np.sqrt(2)
    return f, h


def run_ours(f, h):
    return identify_modes(f, h, max_order=MAX_ORDER)


def run_sdypy(f, h):
    from sdypy import EMA

    # lower=1 Hz: with lower=0 its band-limited sums are wrong and every pole moves.
    model = EMA.Model(frf=h, freq=f, lower=1.0, upper=f[-1], pol_order_high=MAX_ORDER, pyfrf=False)
    with contextlib.redirect_stderr(io.StringIO()), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model.get_poles(show_progress=False)
        model.select_closest_poles(list(FN))
        model.get_constants()
    return model


def best_of(fn, *args, repeat: int = 3):
    best, out = np.inf, None
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn(*args)
        best = min(best, time.perf_counter() - t)
    return best, out


def main() -> None:
    f, h = synthetic_frfs()
    t_ours, ours = best_of(run_ours, f, h)
    t_sdy, sdy = best_of(run_sdypy, f, h)
    print(f"FRFs: {h.shape[0]} x {h.shape[1]} lines, LSCF orders up to {MAX_ORDER}")
    print(f"ours  identify_modes (automatic)   : {t_ours * 1e3:8.1f} ms")
    print(f"sdypy get_poles+select+constants   : {t_sdy * 1e3:8.1f} ms")
    print(f"speed ratio sdypy / ours           : {t_sdy / t_ours:8.1f} x")
    print("truth : " + ", ".join(f"{a:.3f} Hz {z * 100:.2f} %" for a, z in zip(FN, ZETA, strict=True)))
    print(
        "ours  : " + ", ".join(f"{m.frequency_hz:.3f} Hz {m.damping_ratio * 100:.2f} %" for m in ours.modes)
    )
    print(
        "sdypy : "
        + ", ".join(f"{a:.3f} Hz {z * 100:.2f} %" for a, z in zip(sdy.nat_freq, sdy.nat_xi, strict=True))
    )
    print(f"ours synthesis error {ours.synthesis_error:.2e}")


if __name__ == "__main__":
    main()
