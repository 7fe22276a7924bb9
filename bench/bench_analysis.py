"""Benchmark: analysing stored runs (daq analyze), one run in-process and a batch of
200 runs with one worker process and with one per core.

Run: .venv/bin/python bench/bench_analysis.py [n_runs]
A 5-hit run is captured from the simulated analyzer (realistic scenario), then sealed
again under new ids to make the batch (the analysis does not care that the records
repeat). Timings are wall-clock, best of 3 for the single run.
"""

from __future__ import annotations

import os
import sys
import tempfile
import time
from pathlib import Path

# As `daq` itself does (daq/cli/app.py), before numpy loads: one BLAS thread per process.
for _variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_variable, "1")

from analysis.run_analysis import AnalysisOptions
from daq.batch.executor import BackendChoice, execute
from daq.batch.tasks import AnalyseTask
from daq.cli.app import main
from daq.store import Store, new_run_id
from daq.workflows.analysis import analyze


def main_bench(n_runs: int = 200) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        store_dir = Path(tmp) / "store"
        argv = ["capture", "--sim", "--yes", "--scenario", "realistic", "--hits", "5", "--time-scale", "0"]
        if main([*argv, "--store", str(store_dir)]) != 0:
            raise SystemExit("capture failed")
        store = Store(store_dir)
        run = store.open(store.list()[0].run_id)
        options = AnalysisOptions()
        analyze(run, options)  # imports and caches warm
        best = min(_timed(lambda: analyze(run, options)) for _ in range(3))
        no_scatter = min(_timed(lambda: analyze(run, AnalysisOptions(per_hit=False))) for _ in range(3))
        for _ in range(n_runs - 1):
            run.run_id = new_run_id()
            store.seal(run)
        ids = [s.run_id for s in store.list()]
        one = _timed(lambda: run_all(store_dir, ids, options, True, 1))
        cores = os.cpu_count() or 1
        many = _timed(lambda: run_all(store_dir, ids, options, True, cores))
        cached = _timed(lambda: run_all(store_dir, ids, options, False, cores))
    rows = [
        ("analyse one 5-hit run (with per-hit scatter)", f"{best * 1e3:.0f} ms"),
        ("  without the per-hit scatter", f"{no_scatter * 1e3:.0f} ms"),
        (f"analyse {n_runs} runs, 1 worker", f"{one:.1f} s ({one / n_runs * 1e3:.0f} ms/run)"),
        (f"analyse {n_runs} runs, {cores} workers", f"{many:.1f} s ({many / n_runs * 1e3:.0f} ms/run)"),
        (f"{n_runs} runs again, all cached", f"{cached:.2f} s"),
    ]
    width = max(len(r[0]) for r in rows)
    print(f"{'what':<{width}}  value\n{'-' * width}  -----")
    for what, value in rows:
        print(f"{what:<{width}}  {value}")


def run_all(store_dir: Path, ids: list[str], options: AnalysisOptions, recompute: bool, jobs: int) -> None:
    """Analyse ``ids`` on the executor with ``jobs`` worker processes, as `daq analyze`."""
    tasks = [AnalyseTask(store_dir, run_id, options, recompute) for run_id in ids]
    execute(tasks, BackendChoice(jobs).backend(len(tasks)))


def _timed(job) -> float:
    start = time.perf_counter()
    job()
    return time.perf_counter() - start


if __name__ == "__main__":
    main_bench(int(sys.argv[1]) if len(sys.argv) > 1 else 200)
