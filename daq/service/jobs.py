"""Analysis and damping fit of every run as it lands, in worker processes.

The store is the queue: at start every readable run without its analysis or its
default (least-squares) fit is queued, so a run sealed while the service was down,
or whose analysis a crash interrupted, is done now. Results are written by the same
code as ``daq analyze`` and ``daq fit`` (atomically, beside the run), so a killed
worker leaves no half result, only a run to do again at the next start.

Workers are separate processes (``spawn``: the service's threads must not be
forked), so a long fit never stalls serving. With a Dask scheduler the work goes to
the cluster instead (daq/batch/dask_backend.py).
"""

from __future__ import annotations

import logging
import multiprocessing
import os
import threading
import time
from collections import deque
from collections.abc import Callable
from concurrent.futures import Future, ProcessPoolExecutor, ThreadPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path
from typing import Any

from daq.service.events import EventHub

log = logging.getLogger(__name__)

ANALYSIS, FIT = "analysis", "fit"
#: Seconds between looks for runs sealed into the store by other processes.
WATCH_S = 2.0


def analysis_result_name() -> str:
    from daq.workflows.analysis import RESULT_NAME

    return RESULT_NAME


def fit_result_name() -> str:
    from daq.workflows.fit import FitOptions

    return FitOptions().result_name


def analyse_in_worker(store_dir: Path, run_id: str) -> dict[str, Any] | str:
    """The run's analysis summary, or a one-line reason (runs in a worker process)."""
    from analysis.run_analysis import AnalysisOptions
    from daq.cli.commands.analyze import analyze_one

    return analyze_one(store_dir, run_id, AnalysisOptions(), False)


def fit_in_worker(store_dir: Path, run_id: str) -> dict[str, Any] | str:
    """The run's default damping fit summary, or a one-line reason."""
    from daq.cli.commands.fit import fit_one
    from daq.workflows.fit import FitOptions

    return fit_one(store_dir, run_id, FitOptions(), False)


def on_cluster(address: str, store_dir: Path, run_id: str, kind: str) -> dict[str, Any] | str:
    """Analyse ("analyze") or fit ("fit") one run on the Dask cluster at ``address``
    (daq/batch/dask_backend.py: the run's bytes go to a worker, the result comes back and is
    stored here); the summary or a one-line reason."""
    from analysis.run_analysis import AnalysisOptions
    from daq.batch.dask_backend import run_on_cluster
    from daq.errors import UserError
    from daq.workflows.fit import FitOptions

    outcomes: dict[str, dict[str, Any] | str] = {}
    options = AnalysisOptions() if kind == "analyze" else FitOptions()
    try:
        run_on_cluster(address, store_dir, [run_id], options, False, kind, outcomes.__setitem__)
    except UserError as exc:
        return str(exc)
    return outcomes.get(run_id, "the cluster returned no result")


def _init_worker() -> None:
    from daq.batch.memory_tuning import keep_freed_memory

    keep_freed_memory()
    threading.Thread(target=_exit_with_parent, args=(os.getppid(),), name="parent-watch", daemon=True).start()


def _exit_with_parent(parent: int) -> None:
    """End this worker when the service is gone (SIGKILL leaves no one to stop it):
    an orphan would finish its run and then wait under init for ever."""
    while os.getppid() == parent:
        time.sleep(1.0)
    os._exit(0)


class JobRunner:
    """Queues runs for analysis then fit; ``state(run_id)`` says where each stands."""

    def __init__(
        self, store_dir: Path, hub: EventHub, workers: int = 1, scheduler: str | None = None
    ) -> None:
        self.store_dir = store_dir
        self.hub = hub
        self.workers = max(1, workers)
        self.scheduler = scheduler
        self._lock = threading.Lock()
        self._states: dict[str, dict[str, str]] = {}
        self._counts = {"queued": 0, "running": 0, "done": 0, "failed": 0}
        self._pool: ProcessPoolExecutor | None = None
        self._cluster_calls: ThreadPoolExecutor | None = None
        self._closed = False
        self._waiting: deque[tuple[str, str]] = deque()
        self._inflight = 0
        #: Grows with every change of a run's state (a cache key for listings).
        self.version = 0

    # ------------------------------------------------------------ lifecycle
    def start(self) -> None:
        if self.scheduler is None:
            self._pool = self._new_pool()
        else:  # each call blocks until the cluster has done the run: one thread per slot
            self._cluster_calls = ThreadPoolExecutor(self.workers, thread_name_prefix="dask")
        threading.Thread(target=self._backlog, name="backlog", daemon=True).start()

    def close(self) -> None:
        with self._lock:
            self._closed = True
        if self._pool is not None:
            self._pool.shutdown(wait=False, cancel_futures=True)
        if self._cluster_calls is not None:
            self._cluster_calls.shutdown(wait=False, cancel_futures=True)

    def _backlog(self) -> None:
        """Remove temporaries a crash left (older than an hour: a younger one may be
        another process's write in progress), then queue every run whose analysis or
        default fit is missing."""
        from daq.store import Store, StoreError

        try:
            removed = Store(self.store_dir).clean_temporaries()
            if removed:
                log.warning("removed %d stale temporary files from %s", len(removed), self.store_dir)
            # Run files that are regular files only: a link may lead anywhere, a FIFO
            # would hang the listing (and a worker) for ever.
            from daq.service.service import list_regular_runs

            summaries = list_regular_runs(Store(self.store_dir))
        except StoreError as exc:
            log.error("cannot list the store for its backlog: %s", exc)
            return
        seen = set()
        for summary in summaries:
            seen.add(summary.run_id)
            if summary.error is None and not self._on_disk(summary.run_id, FIT):
                self.submit(summary.run_id)
        self._watch(seen)

    def _watch(self, seen: set[str]) -> None:
        """Runs that other processes seal into the store (daq capture, daq import
        beside the service) are queued too, within WATCH_S."""
        from daq.store.store import is_run_file_name

        while not self._closed:
            time.sleep(WATCH_S)
            try:
                with os.scandir(self.store_dir) as it:
                    names = [
                        e.name for e in it if is_run_file_name(e.name) and e.is_file(follow_symlinks=False)
                    ]
            except OSError:
                continue
            for name in names:
                run_id = name.removesuffix(".h5")
                if run_id not in seen:
                    seen.add(run_id)
                    if not self._on_disk(run_id, FIT):
                        self.submit(run_id)

    # ------------------------------------------------------------ queueing
    def submit(self, run_id: str) -> None:
        """Analyse (unless already done) then fit ``run_id``."""
        with self._lock:
            if self._closed or self._states.get(run_id, {}).get(ANALYSIS) in ("queued", "running"):
                return
            self._states[run_id] = {ANALYSIS: "queued", FIT: "queued"}
            self._counts["queued"] += 1
            self._waiting.append((run_id, ANALYSIS))
        self._pump()

    def _pump(self) -> None:
        """Hand waiting work to free workers. Only as much as there are workers is in
        the pool at a time, so that "running" and analysis_started mean running."""
        while True:
            with self._lock:
                if self._closed or self._inflight >= self.workers or not self._waiting:
                    return
                run_id, stage = self._waiting.popleft()
                self._inflight += 1
            self._dispatch(run_id, stage)

    def _dispatch(self, run_id: str, stage: str) -> None:
        worker: Callable[[Path, str], dict | str] = analyse_in_worker if stage == ANALYSIS else fit_in_worker
        self._set(run_id, stage, "running")
        if stage == ANALYSIS:
            self.hub.publish("analysis_started", {"run_id": run_id})
        try:
            future = self._submit(worker, run_id)
        except RuntimeError as exc:  # the pool is shut down, or broken by a killed worker
            self._finished(run_id, stage, f"cannot run: {exc}")
            return
        future.add_done_callback(lambda f: self._finished(run_id, stage, _outcome(f)))

    def _submit(self, worker: Callable[[Path, str], dict | str], run_id: str) -> Future:
        if self.scheduler is not None:
            kind = "analyze" if worker is analyse_in_worker else "fit"
            assert self._cluster_calls is not None
            return self._cluster_calls.submit(on_cluster, self.scheduler, self.store_dir, run_id, kind)
        assert self._pool is not None
        try:
            return self._pool.submit(worker, self.store_dir, run_id)
        except BrokenProcessPool:  # a worker was killed: later runs get a new pool
            with self._lock:
                if self._closed:
                    raise
                self._pool = self._new_pool()
            return self._pool.submit(worker, self.store_dir, run_id)

    def _new_pool(self) -> ProcessPoolExecutor:
        return ProcessPoolExecutor(
            max_workers=self.workers,
            mp_context=multiprocessing.get_context("spawn"),
            initializer=_init_worker,
        )

    def _finished(self, run_id: str, stage: str, outcome: dict[str, Any] | str) -> None:
        failed = isinstance(outcome, str)
        self._set(run_id, stage, "failed" if failed else "done")
        with self._lock:
            self._inflight -= 1
        if stage == ANALYSIS:
            if failed:
                self.hub.publish("analysis_failed", {"run_id": run_id, "error": outcome})
                self._set(run_id, FIT, "none")
                self._count_end(failed=True)
            else:
                self.hub.publish(
                    "analysis_done", {"run_id": run_id, "n_modes": len(outcome.get("modes", []))}
                )
                with self._lock:
                    self._waiting.appendleft((run_id, FIT))  # its fit before the next run's analysis
            self._pump()
            return
        if failed:
            self.hub.publish("fit_failed", {"run_id": run_id, "method": "ls", "error": outcome})
        else:
            self.hub.publish(
                "fit_done", {"run_id": run_id, "method": outcome.get("method"), "psi": outcome.get("psi")}
            )
        self._count_end(failed=failed)
        self._pump()

    def _set(self, run_id: str, stage: str, state: str) -> None:
        with self._lock:
            self.version += 1
            self._states.setdefault(run_id, {ANALYSIS: "none", FIT: "none"})[stage] = state
            if stage == ANALYSIS and state == "running":
                self._counts["queued"] -= 1
                self._counts["running"] += 1

    def _count_end(self, failed: bool) -> None:
        with self._lock:
            self._counts["running"] -= 1
            self._counts["failed" if failed else "done"] += 1

    # ------------------------------------------------------------ reading
    def _on_disk(self, run_id: str, stage: str) -> bool:
        name = analysis_result_name() if stage == ANALYSIS else fit_result_name()
        return (self.store_dir / f"{run_id}.{name}.h5").is_file()

    def state(self, run_id: str) -> dict[str, str]:
        """{"analysis": ..., "fit": ...}, each done, queued, running, failed or none."""
        with self._lock:
            known = dict(self._states.get(run_id, {}))
        for stage in (ANALYSIS, FIT):
            if known.get(stage) in (None, "none") or known.get(stage) == "done":
                known[stage] = "done" if self._on_disk(run_id, stage) else known.get(stage, "none")
        return known

    def counts(self) -> dict[str, int]:
        with self._lock:
            return dict(self._counts)

    def idle(self) -> bool:
        with self._lock:
            return self._counts["queued"] == 0 and self._counts["running"] == 0


def _outcome(future: Future) -> dict[str, Any] | str:
    try:
        return future.result()
    except Exception as exc:  # a worker died (BrokenProcessPool) or a bug
        return f"worker failed: {type(exc).__name__}: {' '.join(str(exc).split()) or 'no message'}"
