"""Coverage of the stated uncertainties on heavily damped modes among small ones.

Input: the tool-holder-like FRFs of tests/analysis/modal_id/test_heavily_damped_modes.py
(five roving-hammer accelerances, 0-5000 Hz on 1 Hz lines; three main modes at 1070,
1965 and 2610 Hz with 3.3, 4.5 and 2.5 % damping among eleven small ones; noise of RMS
NOISE x the FRF's RMS x (f / 2 kHz)^2), one draw per seed. Each is analysed by
analysis.run_analysis.analyze_frfs with its defaults (the bootstrap over lines gives the
uncertainties). For every main mode found within a quarter of its half-power half-width:
z = (value - truth) / u, for the frequency and the damping.

Printed: modes found, how many were read with the second LSCF normalisation (alpha_0 = 1),
the share of |z| within 1, 2 and 3, and the rms of z (1 for an honest standard uncertainty).

Run: .venv/bin/python bench/heavy_damping_coverage.py [--noise 0.4] [--seeds 30]
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import numpy as np

from analysis.run_analysis import analyze_frfs
from tests.analysis.modal_id.test_heavily_damped_modes import MAIN_HZ, MAIN_ZETA, tool_holder_like


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--noise", type=float, default=0.4)
    parser.add_argument("--seeds", type=int, default=30, help="noise draws, seeds 3.. (0-2 are the test's)")
    args = parser.parse_args(argv)
    z_f, z_zeta, lowest, missed = [], [], [], 0
    for seed in range(3, 3 + args.seeds):
        f, h = tool_holder_like(seed, args.noise)
        result = analyze_frfs(f, h, None, "file")
        for f_true, zeta_true in zip(MAIN_HZ, MAIN_ZETA, strict=True):
            near = [m for m in result.modes if abs(m.frequency_hz - f_true) <= 0.25 * zeta_true * f_true]
            if len(near) != 1:
                missed += 1
                continue
            (mode,) = near
            z_f.append((mode.frequency_hz - f_true) / mode.frequency_u_hz)
            z_zeta.append((mode.damping_ratio - zeta_true) / mode.damping_u)
            lowest.append(mode.quality["normalisation"] == "lowest")
    found = len(z_f)
    print(
        f"noise {args.noise:g}: {found} of {found + missed} main modes found, "
        f"{sum(lowest)} read with alpha_0 = 1"
    )
    for name, z in (("frequency", np.abs(z_f)), ("damping", np.abs(z_zeta))):
        shares = ", ".join(f"{100 * np.mean(z <= k):.0f} % within {k} u" for k in (1, 2, 3))
        print(f"  {name:9s}: {shares}; rms z {np.sqrt(np.mean(z**2)):.2f}")
        if any(lowest):
            mine = z[np.array(lowest)]
            print(
                f"    alpha_0 = 1 only: {100 * np.mean(mine <= 1):.0f} % within 1 u, "
                f"{100 * np.mean(mine <= 2):.0f} % within 2 u"
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
