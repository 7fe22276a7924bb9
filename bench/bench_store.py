"""Run store timings (not a test): seal, list cold/warm, open and verify.

    .venv/bin/python bench/bench_store.py [--runs 1000] [--keep DIR]

Prints a small table. The store is built in a temporary folder and removed afterwards
(--keep DIR: built in DIR/many and kept; given again, the runs kept there are timed
again, e.g. to time other code on the same runs).

"cold" means without the index cache (.index.sqlite removed before each timing; the
files themselves are in the page cache, as they are after any recent use). The cold
`daq runs list` is timed as a whole process, interpreter start and imports included,
with /usr/bin/time when it exists (its "elapsed" figure), else with a wall clock here.
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from daq.store import Hits, Instrument, Run, Sample, Store, new_run_id, open_run, seal, verify


def make_run(n_hits: int, n_samples: int, seed: int) -> Run:
    rng = np.random.default_rng(seed)
    t = np.arange(n_samples) / 2560.0
    # Decaying sines with noise: compresses like real records, unlike pure noise.
    response = np.sin(2 * np.pi * 27.3 * t) * np.exp(-t / 0.4) * 20 + rng.normal(0, 0.05, (n_hits, n_samples))
    force = np.zeros((n_hits, n_samples))
    force[:, 32:40] = 150.0
    force += rng.normal(0, 0.01, force.shape)
    return Run(
        run_id=new_run_id(),
        kind="simulated",
        complete=True,
        start_time="2026-11-23T10:15:03.123Z",
        end_time="2026-11-23T10:16:03.123Z",
        operator="bench",
        note=f"bench run {seed}",
        instrument=Instrument(
            "HP 35660A", "HEWLETT-PACKARD,35660A", "sim", "tcp", "35660A", {"span_hz": 1000.0}
        ),
        sample=Sample(2700.0, 69e9, 0.025, 0.003, 0.3, 7.5e-5, 5.625e-11),
        hits=Hits(
            force_n=force,
            response_m_s2=response,
            sample_rate_hz=2560.0,
            start_s=-32 / 2560.0,
            center_hz=0.0,
            accepted=np.ones(n_hits, bool),
            reject_reason=[""] * n_hits,
            overload=np.zeros((n_hits, 2), bool),
            peak_force_n=force.max(axis=1),
            timestamp_utc=["2026-11-23T10:15:03.123Z"] * n_hits,
            checks=[{"double_hit": False}] * n_hits,
        ),
    )


def best_of(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return min(times)


def remove_index(store_dir: Path) -> None:
    for suffix in ("", "-wal", "-shm", "-journal"):
        (store_dir / f".index.sqlite{suffix}").unlink(missing_ok=True)


def timed_process(argv: list[str]) -> float:
    """Seconds the process ``argv`` took, as /usr/bin/time reports them when it exists."""
    repo = Path(__file__).resolve().parent.parent
    env = {**os.environ, "PYTHONPATH": str(repo)}
    if Path("/usr/bin/time").exists():
        done = subprocess.run(
            ["/usr/bin/time", "-f", "elapsed %e", *argv],
            cwd=repo,
            env=env,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
        )
        if done.returncode != 0:
            raise SystemExit(f"{' '.join(argv)} failed:\n{done.stderr[-2000:]}")
        return float(done.stderr.strip().splitlines()[-1].split()[-1])
    start = time.perf_counter()
    subprocess.run(argv, cwd=repo, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
    return time.perf_counter() - start


def cold_cli_list(store_dir: Path, *options: str) -> float:
    remove_index(store_dir)
    return timed_process([sys.executable, "-m", "daq", "runs", "list", *options, "--store", str(store_dir)])


def cli_help() -> float:
    return timed_process([sys.executable, "-m", "daq", "--help"])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=1000)
    parser.add_argument("--keep", type=Path, default=None, help="build the stores here and keep them")
    parser.add_argument("--repeat", type=int, default=5, help="cold timings to take the median of")
    args = parser.parse_args()
    root = args.keep if args.keep is not None else Path(tempfile.mkdtemp(prefix="bench-store-"))
    root.mkdir(parents=True, exist_ok=True)
    rows: list[tuple[str, str]] = []
    try:
        one = root / "one"
        seal_times = []
        for i in range(20):
            run = make_run(10, 1024, seed=i)
            start = time.perf_counter()
            path = seal(run, one)
            seal_times.append(time.perf_counter() - start)
        raw_bytes = 2 * 10 * 1024 * 8
        size = path.stat().st_size
        rows.append(
            ("seal 10 hits x 1024 samples (median of 20)", f"{statistics.median(seal_times) * 1e3:.1f} ms")
        )
        rows.append(
            ("  size on disk (raw records 160 KiB)", f"{size / 1024:.1f} KiB ({size / raw_bytes:.0%})")
        )
        rows.append(
            ("open_run of that run (best of 10)", f"{best_of(lambda: open_run(path), 10) * 1e3:.1f} ms")
        )
        rows.append(("verify of that run (best of 10)", f"{best_of(lambda: verify(path), 10) * 1e3:.1f} ms"))

        many = root / "many"
        kept = sorted(many.glob("*.h5")) if many.is_dir() else []
        if kept:  # --keep of an earlier run: time the same runs again
            args.runs = len(kept)
            rows.append((f"seal {args.runs} runs (10 x 1024 each)", "kept from an earlier run"))
        else:
            start = time.perf_counter()
            for i in range(args.runs):
                seal(make_run(10, 1024, seed=i), many)
            filling = time.perf_counter() - start
            rows.append((f"seal {args.runs} runs (10 x 1024 each)", f"{filling:.1f} s"))
        store = Store(many)
        colds = []
        for _ in range(args.repeat):
            remove_index(many)
            start = time.perf_counter()
            listing = store.list()
            colds.append(time.perf_counter() - start)
        assert len(listing) == args.runs
        assert all(s.error is None for s in listing)
        rows.append(
            (
                f"Store.list() of {args.runs} runs cold (no index; builds it; median of {args.repeat})",
                f"{statistics.median(colds) * 1e3:.0f} ms (min {min(colds) * 1e3:.0f})",
            )
        )
        cli = [cold_cli_list(many) for _ in range(args.repeat)]
        rows.append(
            (
                f"`daq runs list` of {args.runs} runs cold, whole process (median of {args.repeat})",
                f"{statistics.median(cli):.2f} s (min {min(cli):.2f})",
            )
        )
        cli = [cold_cli_list(many, "--json") for _ in range(args.repeat)]
        rows.append(
            (
                f"`daq runs list --json` of {args.runs} runs cold, whole process (median of {args.repeat})",
                f"{statistics.median(cli):.2f} s (min {min(cli):.2f})",
            )
        )
        rows.append(
            (
                "`python -m daq --help`, whole process (best of 3)",
                f"{min(cli_help() for _ in range(3)):.2f} s",
            )
        )
        warm = best_of(store.list, 5)
        rows.append((f"list {args.runs} runs warm (index present, best of 5)", f"{warm * 1e3:.0f} ms"))
        start = time.perf_counter()
        store.resolve(listing[-1].run_id[:22])
        rows.append(("resolve a prefix among them", f"{(time.perf_counter() - start) * 1e3:.1f} ms"))
    finally:
        if args.keep is None:
            shutil.rmtree(root, ignore_errors=True)
    width = max(len(label) for label, _ in rows)
    print(f"{'what':<{width}}  value")
    print(f"{'-' * width}  ------")
    for label, value in rows:
        print(f"{label:<{width}}  {value}")


if __name__ == "__main__":
    main()
