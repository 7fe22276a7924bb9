"""Analysis and damping fit of every run as it lands, on the batch executor's queue.

The store is the queue: at start every readable run without its analysis or its
default (least-squares) fit is queued, so a run sealed while the service was down,
or whose analysis a crash interrupted, is done now. Results are written by the same
code as ``daq analyze`` and ``daq fit`` (the same tasks: daq/batch/tasks.py), so a
killed worker leaves no half result, only a run to do again at the next start.

The tasks run on daq/batch/queue_backend.py: separate worker processes (``spawn``),
so a long fit never stalls serving, or with a Dask scheduler the cluster.
"""

from __future__ import annotations

import logging
import os
import threading
import time
from collections import deque
from collections.abc import Callable, Sequence
from concurrent.futures import Future
from pathlib import Path
from typing import TYPE_CHECKING, Any

from daq.service.events import EventHub

if TYPE_CHECKING:
    from daq.batch.tasks import Task
    from daq.store import RunSummary
    from daq.workflows.outcome import RunOutcome

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


def task_for(store_dir: Path, run_id: str, stage: str) -> Task:
    """The task of ``stage`` (ANALYSIS, FIT) for ``run_id``: the default analysis, or
    the default (least-squares) fit, never recomputing an up-to-date result."""
    from daq.batch.tasks import AnalyseTask, FitTask

    return (AnalyseTask if stage == ANALYSIS else FitTask).default(store_dir, run_id)


def analysis_current(store_dir: Path, run_id: str) -> bool:
    """True if the run's stored analysis was made from the run file as it is now, by
    this software, with the options stored in it (``daq analyze`` before the service
    started, with or without options of its own): the service shows it at once and
    never computes it again (with the default options, which would replace the user's)."""
    from daq.store import Store, StoreError
    from daq.workflows.analysis import cache_key, stored_options

    store = Store(store_dir)
    try:
        options = stored_options(store, run_id)
        if options is None:
            return False
        stored = store.read_result(run_id, analysis_result_name())
        return stored.get("cache_key") == cache_key(store_dir / f"{run_id}.h5", options)
    except (StoreError, OSError, ValueError):
        return False


def fit_current(store_dir: Path, run_id: str) -> bool:
    """True if the run's stored default fit was made from the run file as it is now and
    from its stored analysis (``daq fit`` before the service started)."""
    from daq.store import Store, StoreError
    from daq.workflows.fit import FitOptions, fit_cache_key

    store = Store(store_dir)
    try:
        analysis_key = store.read_result(run_id, analysis_result_name()).get("cache_key")
        stored = store.read_result(run_id, fit_result_name())
        key = fit_cache_key(store_dir / f"{run_id}.h5", analysis_key, FitOptions())
        return stored.get("cache_key") == key
    except (StoreError, OSError, ValueError):
        return False


def analyse_in_worker(store_dir: Path, run_id: str) -> dict[str, Any] | str:
    """The run's analysis summary, or a one-line reason (as a worker computes it)."""
    outcome = task_for(store_dir, run_id, ANALYSIS).run()
    return outcome.summary if outcome.summary is not None else str(outcome.error)


def fit_in_worker(store_dir: Path, run_id: str) -> dict[str, Any] | str:
    """The run's default damping fit summary, or a one-line reason."""
    outcome = task_for(store_dir, run_id, FIT).run()
    return outcome.summary if outcome.summary is not None else str(outcome.error)


class JobRunner:
    """Queues runs for analysis then fit; ``state(run_id)`` says where each stands."""

    def __init__(
        self,
        store_dir: Path,
        hub: EventHub,
        workers: int = 1,
        scheduler: str | None = None,
        list_runs: Callable[[], Sequence[RunSummary]] | None = None,
    ) -> None:
        """list_runs: the store's runs for the backlog at start (the service lists
        regular files only); None: Store.list()."""
        from daq.batch.queue_backend import QueueBackend

        self.store_dir = store_dir
        self.hub = hub
        self.workers = max(1, workers)
        self.scheduler = scheduler
        self._list_runs = list_runs
        self._lock = threading.Lock()
        self._states: dict[str, dict[str, str]] = {}
        #: The one-line reason of each failed stage, (run_id, stage) -> text.
        self._errors: dict[tuple[str, str], str] = {}
        #: Runs whose stored analysis was up to date: only their fit is queued.
        self._fit_only: set[str] = set()
        self._counts = {"queued": 0, "running": 0, "done": 0, "failed": 0}
        self._queue = QueueBackend(self.workers, scheduler)
        self._closed = False
        self._waiting: deque[tuple[str, str]] = deque()
        self._inflight = 0
        #: Grows with every change of a run's state (a cache key for listings).
        self.version = 0

    # ------------------------------------------------------------ lifecycle
    def start(self) -> None:
        self._queue.start()
        threading.Thread(target=self._backlog, name="backlog", daemon=True).start()

    def close(self) -> None:
        with self._lock:
            self._closed = True
        self._queue.close()

    def _backlog(self) -> None:
        """Remove temporaries a crash left (older than an hour: a younger one may be
        another process's write in progress), then queue every run whose analysis or
        default fit is missing."""
        from daq.store import Store, StoreError

        try:
            removed = Store(self.store_dir).clean_temporaries()
            if removed:
                log.warning("removed %d stale temporary files from %s", len(removed), self.store_dir)
            # The service lists run files that are regular files only: a link may lead
            # anywhere, a FIFO would hang the listing (and a worker) for ever.
            summaries = self._list_runs() if self._list_runs is not None else Store(self.store_dir).list()
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
        """Analyse (unless its stored analysis is up to date) then fit ``run_id``."""
        with self._lock:
            if self._closed or self._busy(run_id):
                return
        # A run analysed from the command line before the service started reads
        # "done" with its numbers at once, not "queued" behind the other runs' work.
        current = self._on_disk(run_id, ANALYSIS) and analysis_current(self.store_dir, run_id)
        with self._lock:
            if self._closed or self._busy(run_id):
                return
            self._states[run_id] = {ANALYSIS: "done" if current else "queued", FIT: "queued"}
            self._errors.pop((run_id, ANALYSIS), None)
            self._errors.pop((run_id, FIT), None)
            self._counts["queued"] += 1
            if current:
                self._fit_only.add(run_id)
                self._waiting.append((run_id, FIT))
            else:
                self._fit_only.discard(run_id)
                self._waiting.append((run_id, ANALYSIS))
            self.version += 1
        self._pump()

    def _busy(self, run_id: str) -> bool:
        """True if a stage of ``run_id`` is queued or running (under the lock)."""
        return any(v in ("queued", "running") for v in self._states.get(run_id, {}).values())

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
        from daq.batch.queue_backend import outcome_of
        from daq.workflows.outcome import RunOutcome

        self._set(run_id, stage, "running")
        if stage == ANALYSIS:
            self.hub.publish("analysis_started", {"run_id": run_id})
        try:
            future: Future = self._queue.submit(task_for(self.store_dir, run_id, stage))
        except RuntimeError as exc:  # the pool is shut down, or broken by a killed worker
            self._finished(run_id, stage, RunOutcome.failed(run_id, f"cannot run: {exc}"))
            return
        future.add_done_callback(lambda f: self._finished(run_id, stage, outcome_of(f, run_id)))

    def _finished(self, run_id: str, stage: str, outcome: RunOutcome) -> None:
        failed = not outcome.ok
        summary = outcome.summary or {}
        with self._lock:
            if failed:
                self._errors[(run_id, stage)] = str(outcome.error)
            else:
                self._errors.pop((run_id, stage), None)
        self._set(run_id, stage, "failed" if failed else "done")
        with self._lock:
            self._inflight -= 1
        if stage == ANALYSIS:
            if failed:
                self.hub.publish("analysis_failed", {"run_id": run_id, "error": outcome.error})
                self._set(run_id, FIT, "none")
                self._count_end(failed=True)
            else:
                self.hub.publish(
                    "analysis_done", {"run_id": run_id, "n_modes": len(summary.get("modes", []))}
                )
                with self._lock:
                    self._waiting.appendleft((run_id, FIT))  # its fit before the next run's analysis
            self._pump()
            return
        if failed:
            self.hub.publish("fit_failed", {"run_id": run_id, "method": "ls", "error": outcome.error})
        else:
            self.hub.publish(
                "fit_done", {"run_id": run_id, "method": summary.get("method"), "psi": summary.get("psi")}
            )
        self._count_end(failed=failed)
        self._pump()

    def _set(self, run_id: str, stage: str, state: str) -> None:
        with self._lock:
            self.version += 1
            self._states.setdefault(run_id, {ANALYSIS: "none", FIT: "none"})[stage] = state
            first = stage == ANALYSIS or (stage == FIT and run_id in self._fit_only)
            if first and state == "running":
                self._fit_only.discard(run_id)
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

    def error(self, run_id: str, stage: str) -> str | None:
        """The one-line reason ``stage`` (ANALYSIS, FIT) of ``run_id`` failed, if it did."""
        with self._lock:
            if self._states.get(run_id, {}).get(stage) != "failed":
                return None
            return self._errors.get((run_id, stage))

    def current(self, run_id: str, stage: str) -> bool:
        """True if the stored result of ``stage`` is up to date with the run file (and,
        for the fit, with the stored analysis): shown while a recomputation waits."""
        if not self._on_disk(run_id, stage):
            return False
        return (analysis_current if stage == ANALYSIS else fit_current)(self.store_dir, run_id)

    def counts(self) -> dict[str, int]:
        with self._lock:
            return dict(self._counts)

    def idle(self) -> bool:
        with self._lock:
            return self._counts["queued"] == 0 and self._counts["running"] == 0
