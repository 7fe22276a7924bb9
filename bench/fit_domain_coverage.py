"""Coverage of the stated uncertainty of the damping fit, time and frequency domain.

Input: simulated seed-scenario runs (Ritz N = 3, Table 1, eq (18)), one per seed,
made as a user makes them: daq capture --sim --scenario seed --seed S --hits 5 --yes
--time-scale 0, daq analyze, then daq fit --json in each domain. For every term of R:
z = (fitted - eq (18)) / u, u the printed ± (uncertainty.std).

Printed per domain: the share of |z| within 1 and 2 u (68 and 95 % for an exact
standard uncertainty), the largest |z|, the mean error of each term over the runs
(a bias shows as the same sign in every run), how many terms are marked determined
and how many fits carry a caution.

Run: .venv/bin/python bench/fit_domain_coverage.py [--seeds 11:21] [--store DIR]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from analysis.seed import eq18_damping_matrix  # noqa: E402


def _daq(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "daq", *args], capture_output=True, text=True, cwd=ROOT, check=False
    )


def _run_ids(store: Path) -> set[str]:
    listed = _daq("runs", "list", "--json", "--store", str(store))
    return {r["run_id"] for r in json.loads(listed.stdout or "[]")} if listed.returncode == 0 else set()


def _run(seed: int, store: Path) -> str:
    before = _run_ids(store)
    out = _daq("capture", "--sim", "--scenario", "seed", "--seed", str(seed), "--hits", "5", "--yes",
               "--time-scale", "0", "--store", str(store))  # fmt: skip
    if out.returncode:
        raise SystemExit(f"capture --seed {seed} failed: {out.stderr.strip()}")
    (run_id,) = _run_ids(store) - before
    analysed = _daq("analyze", run_id, "--store", str(store))
    if analysed.returncode:
        raise SystemExit(f"analyze {run_id} failed: {analysed.stderr.strip()}")
    return run_id


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--seeds", default="11:21", help="first:end (end excluded)")
    parser.add_argument(
        "--store", type=Path, default=None, help="a store to reuse (default: a temporary one)"
    )
    args = parser.parse_args(argv)
    first, end = (int(v) for v in args.seeds.split(":"))
    truth = eq18_damping_matrix()[np.triu_indices(3)]
    with tempfile.TemporaryDirectory() as tmp:
        store = args.store or Path(tmp)
        runs = [_run(seed, store) for seed in range(first, end)]
        for domain in ("time", "frequency"):
            z, errors, determined, cautioned, exits = [], [], 0, 0, []
            for run_id in runs:
                out = _daq("fit", run_id, "--domain", domain, "--json", "--store", str(store))
                exits.append(out.returncode)
                summary = json.loads(out.stdout)
                summary = summary[0] if isinstance(summary, list) else summary
                r = np.asarray(summary["damping_matrix"])[np.triu_indices(3)]
                u = np.asarray(summary["uncertainty"]["std"], dtype=float)
                z.extend((r - truth) / u)
                errors.append(r - truth)
                determined += sum(summary["uncertainty"]["determined"])
                cautioned += bool(summary["cautions"])
            z = np.abs(np.asarray(z))
            bias = np.mean(errors, axis=0)
            names = ("R11", "R12", "R13", "R22", "R23", "R33")
            print(
                f"{domain:9s}: {100 * np.mean(z <= 1):.0f} % within 1 u, "
                f"{100 * np.mean(z <= 2):.0f} % within 2 u, largest |z| {z.max():.3g}; "
                f"{determined} of {z.size} terms determined; "
                f"{cautioned} of {len(runs)} fits with a caution; exit codes {sorted(set(exits))}"
            )
            print(
                "           mean error (N s/m): "
                + ", ".join(f"{n} {b:+.3g}" for n, b in zip(names, bias, strict=True))
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
