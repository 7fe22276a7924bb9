"""Modes found in pure noise by the defaults of identify_modes: the false-mode rate.

One FRF of complex white noise, moving-averaged over W lines (W = 1: white; 5-40: noise
whose bumps are as broad as a damped mode's), on 800 lines of 0.5 Hz, 3000 and 5000 lines
of 1 Hz, four draws each. Printed: draws with a mode, and the modes, per W.
``--noise-factor K`` sets the spurious-pole test's threshold (identify.NOISE_FACTOR, the
times the misfit around it a mode's term must peak; 3 by default) to try another.

Run: .venv/bin/python bench/noise_false_modes.py [--noise-factor 2]
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import numpy as np

from analysis.modal_id import identify, identify_modes

GRIDS = ((800, 0.5), (3000, 1.0), (5000, 1.0))
WIDTHS = (1, 5, 15, 40)
DRAWS = 4


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--noise-factor", type=float, help="identify.NOISE_FACTOR to try (default: as set)")
    args = parser.parse_args(argv)
    if args.noise_factor is not None:
        identify.NOISE_FACTOR = args.noise_factor
    for width in WIDTHS:
        draws_with, modes = 0, 0
        for n_lines, step_hz in GRIDS:
            f = np.arange(1, n_lines + 1) * step_hz
            for seed in range(DRAWS):
                rng = np.random.default_rng(seed)
                h = rng.standard_normal(n_lines) + 1j * rng.standard_normal(n_lines)
                h = np.convolve(h, np.ones(width) / width, mode="same")[np.newaxis, :]
                found = len(identify_modes(f, h).modes)
                draws_with += found > 0
                modes += found
        draws = len(GRIDS) * DRAWS
        print(f"noise averaged over {width:2d} lines: {draws_with} of {draws} with a mode, {modes} modes")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
