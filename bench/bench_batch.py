"""Benchmark: the batch analysis and least-squares fit of a store of runs (`daq analyze
--all` then `daq fit --all`) on one core, on every core, and on a 2-worker Dask
LocalCluster (`--scheduler`).

Run: .venv/bin/python bench/bench_batch.py [FOLDER] [--runs N]
FOLDER (default /tmp/daq-bench-batch) holds the store; a store of N runs (default
1,000) there is reused, else made: a few 5-hit captures of the simulated analyzer
(realistic scenario, different seeds), sealed again under new ids until there are N
(the analysis does not care that records repeat; every run is analysable). Before
each configuration every result file is deleted, so each computes everything.
Timings are wall-clock, one pass each.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import logging
import os
import time
import warnings
from pathlib import Path

# As `daq` itself does (daq/cli/app.py), before numpy loads: one BLAS thread per process.
for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")

DEFAULT_FOLDER = Path("/tmp/daq-bench-batch")
CAPTURES = 4


def make_store(store_dir: Path, n_runs: int) -> None:
    """Top ``store_dir`` up to ``n_runs`` runs: captures first, then copies of them."""
    from daq.cli.app import main
    from daq.store import Store, new_run_id

    store = Store(store_dir)
    have = len(store.list())
    for seed in range(have + 1, min(CAPTURES, n_runs) + 1):
        argv = ["capture", "--sim", "--yes", "--scenario", "realistic", "--hits", "5", "--time-scale", "0"]
        with contextlib.redirect_stdout(io.StringIO()):  # the capture's hit-by-hit account
            status = main([*argv, "--seed", str(seed), "--store", str(store_dir)])
        if status != 0:
            raise SystemExit("capture failed")
    summaries = store.list()
    originals = [store.open(s.run_id) for s in summaries[:CAPTURES]]
    for k in range(len(summaries), n_runs):
        run = originals[k % len(originals)]
        run.run_id = new_run_id()
        store.seal(run)


def clear_results(store_dir: Path) -> None:
    for path in store_dir.glob("*.h5"):
        if path.name.count(".") == 3:  # <run id>.<result>.h5 (a run id holds one dot)
            path.unlink()


def run_tasks(tasks: list, jobs: int | None, scheduler: str | None):
    """The executor (daq/batch/executor.py) on ``tasks``, as `daq analyze|fit` runs them."""
    from daq.batch.executor import BackendChoice, execute

    return execute(tasks, BackendChoice(jobs, scheduler).backend(len(tasks)))


def batch(store_dir: Path, ids: list[str], jobs: int | None, scheduler: str | None) -> tuple[float, float]:
    """Seconds of (analyse all, then fit all) from a store without results."""
    from daq.batch.tasks import AnalyseTask, FitTask

    clear_results(store_dir)
    times = []
    for kind, label in ((AnalyseTask, "analysing"), (FitTask, "fitting")):
        start = time.perf_counter()
        report = run_tasks([kind.default(store_dir, i) for i in ids], jobs, scheduler)
        times.append(time.perf_counter() - start)
        summaries = report.summaries(ids)
        if report.failures or len(summaries) != len(ids) or any(r["cached"] for r in summaries):
            raise SystemExit(f"{label}: {len(report.failures)} failures, {len(summaries)} results")
    return times[0], times[1]


def cached(store_dir: Path, ids: list[str], scheduler: str | None) -> float:
    """Seconds of both passes again, every result up to date (nothing computed)."""
    from daq.batch.tasks import AnalyseTask, FitTask

    start = time.perf_counter()
    for kind in (AnalyseTask, FitTask):
        report = run_tasks([kind.default(store_dir, i) for i in ids], None, scheduler)
        assert all(r["cached"] for r in report.summaries(ids))
    return time.perf_counter() - start


def main_bench(folder: Path, n_runs: int) -> None:
    import distributed

    from daq.store import Store

    store_dir = folder / "store"
    start = time.perf_counter()
    make_store(store_dir, n_runs)
    made = time.perf_counter() - start
    ids = [s.run_id for s in Store(store_dir).list()][:n_runs]
    cores = os.cpu_count() or 1
    rows = []
    for name, jobs in (("1 core (--jobs 1)", 1), (f"all cores ({cores} processes)", None)):
        analyse, fit = batch(store_dir, ids, jobs, None)
        rows.append((name, analyse, fit))
    again_local = cached(store_dir, ids, None)
    # The LocalCluster's scheduler and nannies live in this process; under load they
    # log that workers were slow to stop, which is not what is measured here.
    logging.getLogger("distributed").setLevel(logging.ERROR)
    with warnings.catch_warnings():
        # distributed may warn at shutdown about connections it closes; not ours.
        warnings.simplefilter("ignore", ResourceWarning)
        with distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=None,
            scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},
        ) as cluster:  # fmt: skip
            analyse, fit = batch(store_dir, ids, None, cluster.scheduler_address)
            rows.append(("2-worker LocalCluster (--scheduler)", analyse, fit))
            again_cluster = cached(store_dir, ids, cluster.scheduler_address)
    print(f"{len(ids)} runs (5 hits each) in {store_dir}; store made or topped up in {made:.1f} s")
    width = max(len(r[0]) for r in rows)
    print(f"{'where':<{width}}  {'analyse':>9}  {'fit':>9}  {'total':>9}  {'per run':>8}")
    print(f"{'-' * width}  {'-' * 9}  {'-' * 9}  {'-' * 9}  {'-' * 8}")
    for name, analyse, fit in rows:
        total = analyse + fit
        print(
            f"{name:<{width}}  {analyse:>7.1f} s  {fit:>7.1f} s  {total:>7.1f} s  "
            f"{total / len(ids) * 1e3:>5.0f} ms"
        )
    print(f"again, all cached: local {again_local:.1f} s, cluster client {again_cluster:.1f} s")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", nargs="?", type=Path, default=DEFAULT_FOLDER)
    parser.add_argument("--runs", type=int, default=1000)
    args = parser.parse_args()
    main_bench(args.folder, args.runs)
