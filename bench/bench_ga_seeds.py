"""The seed's GA as it comes out: one simulated capture of the seed beam (eq (18)
truth), the GA run with 10 seeds, the damping ratios and Psi of each, their spread,
and least squares beside it. Run: .venv/bin/python bench/bench_ga_seeds.py"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

# As `daq` itself does (daq/cli/app.py): one BLAS thread per process, set before numpy loads.
for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")

import numpy as np

from daq.cli.app import main
from daq.store import Store
from daq.workflows.fit import FitOptions, fit_stored

TRUTH = (0.036058, 0.203226, 0.161986)  # eq (18), docs/method.md


def run() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        store_dir = Path(tmp)
        argv = ["capture", "--sim", "--yes", "--scenario", "seed", "--hits", "5", "--time-scale", "0"]
        if main([*argv, "--seed", "5", "--store", str(store_dir)]) != 0:
            raise SystemExit("capture failed")
        run_id = Store(store_dir).list()[0].run_id
        rows = []
        for seed in range(10):
            info = fit_stored(store_dir, run_id, FitOptions(method="ga", seed=seed), recompute=True)
            rows.append((seed, info["psi"], [m["damping_ratio"] for m in info["modes"]], info["seconds"]))
        ls = fit_stored(store_dir, run_id, FitOptions(method="ls"), recompute=True)
    print(f"truth (eq 18): {' '.join(f'{100 * z:6.2f}' for z in TRUTH)} %")
    print("seed        Psi   damping ratios (%)        time")
    for seed, psi, zetas, seconds in rows:
        print(f"{seed:4d}  {psi:9.5f}   {_pct(zetas)}   {seconds:5.2f} s")
    z = np.array([r[2] for r in rows])
    print(f"GA mean     {np.mean([r[1] for r in rows]):9.5f}   {_pct(z.mean(0))}")
    print(f"GA std                 {_pct(z.std(0, ddof=1))}")
    zl = [m["damping_ratio"] for m in ls["modes"]]
    print(f"least sq.   {ls['psi']:9.5f}   {_pct(zl)}   {ls['seconds']:5.2f} s")


def _pct(values) -> str:
    return " ".join(f"{100 * v:6.2f}" for v in values)


if __name__ == "__main__":
    run()
