"""Three close modes whose middle one LSCF misses: how often the added-mode step finds it
(analysis/modal_id/refine.py, missing) and the coverage of the stated uncertainties.

Input: simulated impact hits without windows (tests/analysis/impact_synth.py): 150, 152 and
154.5 Hz at 0.5, 0.8 and 0.6 % (amplitudes 1, 0.8, 0.7) and 400 Hz at 1 %; 2048 Hz, 1 s
records, --hits hits, response noise --noise of its RMS. One draw per seed, analysed by
analysis.run_analysis.analyze_hits with its defaults. For the three close modes of each
draw that finds four modes: z = (value - truth) / u.

Printed: the draws that found all four modes, and the share of |z| within 1 and 2 for the
frequency and the damping (68 % and 95 % for an honest standard uncertainty), over the three
close modes and over the added middle one alone.

Run: .venv/bin/python bench/close_triple_coverage.py [--seeds 20] [--hits 5] [--noise 0.02]
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import numpy as np

from analysis.run_analysis import analyze_hits
from analysis.windows import WindowSpec
from tests.analysis.impact_synth import impact_hits

FN_HZ = [150.0, 152.0, 154.5, 400.0]
ZETA = [0.005, 0.008, 0.006, 0.01]
AMP = [1.0, 0.8, 0.7, 1.0]
RATE_HZ = 2048.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=20)
    parser.add_argument("--hits", type=int, default=5)
    parser.add_argument("--noise", type=float, default=0.02)
    args = parser.parse_args()
    uniform = WindowSpec("uniform")
    z_f, z_zeta, found = [], [], 0
    for seed in range(args.seeds):
        force, response = impact_hits(FN_HZ, ZETA, AMP, RATE_HZ, 1.0, args.hits, args.noise, 1.5e-3, seed)
        result = analyze_hits(force, response, RATE_HZ, np.ones(args.hits, bool), uniform, uniform)
        if len(result.modes) != 4:
            print(f"seed {seed}: {[round(m.frequency_hz, 2) for m in result.modes]} Hz")
            continue
        found += 1
        for mode, f, zeta in zip(result.modes[:3], FN_HZ, ZETA, strict=False):
            z_f.append(abs(mode.frequency_hz - f) / mode.frequency_u_hz)
            z_zeta.append(abs(mode.damping_ratio - zeta) / mode.damping_u)
    print(f"draws that found all four modes: {found} of {args.seeds}")
    if not found:
        return
    z_f, z_zeta = np.array(z_f).reshape(-1, 3), np.array(z_zeta).reshape(-1, 3)
    for label, cols in (("the three close modes", slice(None)), ("the added middle mode", 1)):
        f, z = z_f[:, cols].ravel(), z_zeta[:, cols].ravel()
        print(
            f"{label}: frequency within 1 u / 2 u {np.mean(f <= 1):.0%} / {np.mean(f <= 2):.0%}, "
            f"damping {np.mean(z <= 1):.0%} / {np.mean(z <= 2):.0%}"
        )


if __name__ == "__main__":
    main()
