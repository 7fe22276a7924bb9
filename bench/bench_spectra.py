"""Benchmark of the FRF estimators (not a test): `python bench/bench_spectra.py [--repeat N]`.

Times H1, H2 and coherence from the time records, ours (analysis.spectra:
linear_spectra + frf_estimate, which also forms Hv) against pyFRF on the same data
with uniform windows:
  * one 51,200-sample hit at 51.2 kHz (a modern DAQ's 1 s record);
  * 5 hits of 1024 samples (the HP analyzer's baseband records).
Best of N rounds with time.perf_counter. pyFRF keeps every FFT line (n/2 + 1) and its
FFT uses all cores (workers=-1); ours keeps the alias-free lines (fs / 2.56) on one.
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import numpy as np
import pyFRF

from analysis.spectra import frf_estimate, linear_spectra
from analysis.windows import WindowSpec

UNIFORM = WindowSpec("uniform")


def _best(fn, repeat: int, number: int) -> float:
    """Best seconds per call over ``repeat`` rounds of ``number`` calls."""
    fn()  # warm-up
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(number):
            fn()
        best = min(best, (time.perf_counter() - t0) / number)
    return best


def _ours(force: np.ndarray, response: np.ndarray, rate: int):
    est = frf_estimate(linear_spectra(force, response, float(rate), UNIFORM, UNIFORM))
    return est.h1, est.h2, est.coherence


def _pyfrf(force: np.ndarray, response: np.ndarray, rate: int):
    frf = pyFRF.FRF(rate, force, response, exc_type="f", resp_type="a", window="none")
    return (
        frf.get_FRF("H1", frf_form="accelerance"),
        frf.get_FRF("H2", frf_form="accelerance"),
        frf.get_coherence(),
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args()

    rng = np.random.default_rng(0)
    cases = []
    for label, n_hits, n, rate, number in (
        ("1 hit x 51200 @ 51.2 kHz", 1, 51200, 51200, 5),
        ("5 hits x 1024 @ 2.56 kHz", 5, 1024, 2560, 50),
    ):
        force = rng.normal(size=(n_hits, n))
        response = np.roll(force, 3, axis=1) + 0.1 * rng.normal(size=(n_hits, n))
        force -= force.mean(axis=1, keepdims=True)  # pyFRF detrends; keep DC out of it
        response -= response.mean(axis=1, keepdims=True)
        ours = _best(lambda f=force, a=response, r=rate: _ours(f, a, r), args.repeat, number)
        theirs = _best(lambda f=force, a=response, r=rate: _pyfrf(f, a, r), args.repeat, number)
        # Same numbers on the shared lines, or the timing compares different work.
        h1 = _ours(force, response, rate)[0]
        h1_theirs = _pyfrf(force, response, rate)[0][0, 0, 1 : h1.size]
        agree = float(np.max(np.abs(h1[1:] - h1_theirs) / np.abs(h1_theirs)))
        cases.append((label, ours, theirs, agree))

    print(
        f"Python {platform.python_version()}, numpy {np.__version__}, pyFRF {pyFRF.__version__}, "
        f"{os.cpu_count()} CPUs; best of {args.repeat}"
    )
    print(f"{'case':<28}{'ours ms':>10}{'pyFRF ms':>10}{'speed-up':>10}{'H1 max rel diff':>18}")
    for label, ours, theirs, agree in cases:
        print(f"{label:<28}{ours * 1e3:>10.3f}{theirs * 1e3:>10.3f}{theirs / ours:>9.1f}x{agree:>18.1e}")


if __name__ == "__main__":
    main()
