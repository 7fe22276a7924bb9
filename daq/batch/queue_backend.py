"""The executor's backend for a long-running queue (the service's analysis workers,
daq/service/jobs.py): tasks come one at a time, each gets a Future of its outcome.

Locally the tasks run in worker processes started with ``spawn`` (the service's
threads must not be forked), so that a long fit never stalls serving; a pool that a
killed worker broke is replaced for the tasks after. With a Dask scheduler each task
goes to the cluster instead (daq/batch/dask_backend.py), from one of ``workers``
threads here (each call blocks until the cluster has done the run).

The Future never raises: a worker that died, a cluster that could not be reached or
a bug give a failed :class:`RunOutcome` with the one line the service reports.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import threading
import time
from concurrent.futures import Future, ProcessPoolExecutor, ThreadPoolExecutor
from concurrent.futures.process import BrokenProcessPool

from daq.batch.tasks import Task, run_task
from daq.workflows.outcome import RunOutcome


def _init_worker() -> None:
    """Keep freed memory (memory_tuning) and end with the service. Not
    memory_tuning.die_with_parent: its prctl(PR_SET_PDEATHSIG) fires when the *thread*
    that started the worker ends, and the service starts workers from passing threads
    (a capture's, a request's)."""
    from daq.batch.memory_tuning import keep_freed_memory

    # Ctrl-C in the terminal reaches the whole process group: the service stops its
    # workers itself (close), and a worker interrupted mid-run would send a
    # KeyboardInterrupt back through the pool as a traceback. SIGINT came blocked
    # from the spawning thread (submit), so none lands before this line.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
    keep_freed_memory()
    threading.Thread(target=_exit_with_parent, args=(os.getppid(),), name="parent-watch", daemon=True).start()


def _exit_with_parent(parent: int) -> None:
    """End this worker when the service is gone (SIGKILL leaves no one to stop it):
    an orphan would finish its run and then wait under init for ever."""
    while os.getppid() == parent:
        time.sleep(1.0)
    os._exit(0)


def on_cluster(address: str, task: Task) -> RunOutcome:
    """``task`` on the Dask cluster at ``address`` (the run's bytes go to a worker, the
    result comes back and is stored here); a failed outcome, the error's line, when the
    cluster cannot take it."""
    from daq.batch.dask_backend import run_on_cluster
    from daq.store import StoreError
    from daq.workflows.errors import WorkflowError

    outcomes: dict[str, RunOutcome] = {}
    try:
        run_on_cluster(address, [task], lambda t, outcome: outcomes.__setitem__(t.run_id, outcome))
    except (WorkflowError, StoreError) as exc:
        return RunOutcome.failed(task.run_id, str(exc))
    return outcomes.get(task.run_id, RunOutcome.failed(task.run_id, "the cluster returned no result"))


class QueueBackend:
    """``workers`` tasks at a time, in spawned worker processes, or (``scheduler``, a
    Dask scheduler's address) on that cluster. start(), submit(task), close()."""

    def __init__(self, workers: int = 1, scheduler: str | None = None) -> None:
        self.workers = max(1, workers)
        self.scheduler = scheduler
        self._lock = threading.Lock()
        self._closed = False
        self._pool: ProcessPoolExecutor | None = None
        self._cluster_calls: ThreadPoolExecutor | None = None

    def start(self) -> None:
        if self.scheduler is None:
            self._pool = self._new_pool()
        else:  # each call blocks until the cluster has done the run: one thread per slot
            self._cluster_calls = ThreadPoolExecutor(self.workers, thread_name_prefix="dask")

    def close(self) -> None:
        with self._lock:
            self._closed = True
        if self._pool is not None:
            # A run half analysed is analysed again at the next start (results are
            # written atomically), so the workers end now instead of keeping the
            # service's process alive until their runs are done.
            workers = list((getattr(self._pool, "_processes", None) or {}).values())
            self._pool.shutdown(wait=False, cancel_futures=True)
            for worker in workers:
                worker.terminate()
        if self._cluster_calls is not None:
            self._cluster_calls.shutdown(wait=False, cancel_futures=True)

    def submit(self, task: Task) -> Future:
        """A Future of ``task``'s RunOutcome (outcome_of reads it, never raising).
        RuntimeError when the backend is closed."""
        if self.scheduler is not None:
            assert self._cluster_calls is not None
            return self._cluster_calls.submit(on_cluster, self.scheduler, task)
        assert self._pool is not None
        try:
            # A worker is spawned by the submitting thread and inherits its signal
            # mask: SIGINT stays blocked in it until its initializer ignores it.
            blocked = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
            try:
                return self._pool.submit(run_task, task)
            finally:
                signal.pthread_sigmask(signal.SIG_SETMASK, blocked)
        except BrokenProcessPool:  # a worker was killed: later runs get a new pool
            with self._lock:
                if self._closed:
                    raise
                self._pool = self._new_pool()
            return self._pool.submit(run_task, task)

    def _new_pool(self) -> ProcessPoolExecutor:
        return ProcessPoolExecutor(
            max_workers=self.workers,
            mp_context=multiprocessing.get_context("spawn"),
            initializer=_init_worker,
        )


def outcome_of(future: Future, run_id: str) -> RunOutcome:
    """The outcome a submitted task's Future holds; a failed one when the worker died
    (BrokenProcessPool) or the task raised (a bug)."""
    try:
        return future.result()
    except Exception as exc:
        why = " ".join(str(exc).split()) or "no message"
        return RunOutcome.failed(run_id, f"worker failed: {type(exc).__name__}: {why}")
