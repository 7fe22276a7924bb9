"""The one executor of batch analyses and fits: typed tasks in, typed outcomes out,
on one of three backends.

- :class:`InProcess` runs the tasks one after the other here (one run, or --jobs 1);
- :class:`ProcessPool` runs them in worker processes, as many as --jobs (default: the
  cores), each tuned to keep freed memory and to die with this process
  (daq/batch/memory_tuning.py);
- :class:`DaskCluster` sends them to the Dask cluster of --scheduler or
  $DAQ_SCHEDULER (daq/batch/dask_backend.py).

The service's queue (daq/batch/queue_backend.py) takes the same tasks one at a time,
for as long as the service runs.

:func:`choose_backend` applies the rules of --jobs and --scheduler;
:func:`execute` runs the tasks on a backend and reports each outcome as it comes
(``on_outcome``), in the order the runs finish. A backend calls ``on_done`` in the
calling thread. Everything heavy (numpy, the workflows, distributed) is imported
when a task runs, not when this module is.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Protocol

from daq.batch.tasks import Task, run_task
from daq.workflows.errors import WorkflowError
from daq.workflows.outcome import RunOutcome

#: Called as each task ends: the task and what it came to.
OnDone = Callable[[Task, RunOutcome], None]


class Backend(Protocol):
    """Where tasks run. ``run`` returns once every task has ended; ``on_done`` is
    called in the calling thread for each, as it ends. A task's exception (a bug, not
    a failure of its run) is raised."""

    def run(self, tasks: Sequence[Task], on_done: OnDone) -> None: ...


class InProcess:
    """The tasks one after the other, in this process, in their order."""

    def run(self, tasks: Sequence[Task], on_done: OnDone) -> None:
        for task in tasks:
            on_done(task, run_task(task))


@dataclass(frozen=True)
class ProcessPool:
    """The tasks in ``workers`` worker processes (forked), which keep freed memory and
    die when this process dies, even by SIGKILL (memory_tuning.worker_setup)."""

    workers: int

    def run(self, tasks: Sequence[Task], on_done: OnDone) -> None:
        from concurrent.futures import ProcessPoolExecutor, as_completed

        from daq.batch.memory_tuning import worker_setup

        # Workers die with this process: killed, it must not leave them running for good.
        pool = ProcessPoolExecutor(
            max_workers=self.workers, initializer=worker_setup, initargs=(os.getpid(),)
        )
        with pool:
            futures = {pool.submit(run_task, task): task for task in tasks}
            for future in as_completed(futures):
                on_done(futures[future], future.result())


@dataclass(frozen=True)
class DaskCluster:
    """The tasks on the Dask cluster whose scheduler is at ``address``: the run files
    are read here and sent, the results come back and are stored here."""

    address: str

    def run(self, tasks: Sequence[Task], on_done: OnDone) -> None:
        from daq.batch.dask_backend import run_on_cluster

        run_on_cluster(self.address, tasks, on_done)


@dataclass(frozen=True)
class BackendChoice:
    """Where a batch runs, as the options chose: ``address`` a Dask scheduler, else a
    local pool of ``jobs`` processes (None: one per core)."""

    jobs: int | None = None
    address: str | None = None

    def backend(self, n_tasks: int) -> Backend:
        """The backend for ``n_tasks`` tasks: the cluster, else one process here when
        one worker would do, else a pool of at most one worker per task."""
        if self.address is not None:
            return DaskCluster(self.address)
        workers = min(self.jobs or os.cpu_count() or 1, n_tasks)
        return InProcess() if workers <= 1 else ProcessPool(workers)


def choose_backend(
    jobs: int | None, scheduler: str | None, env: Mapping[str, str] | None = None
) -> BackendChoice:
    """The rules of --jobs and --scheduler: --jobs at least 1; not both; an explicit
    --jobs asks for the local pool whatever $DAQ_SCHEDULER says; else --scheduler,
    else $DAQ_SCHEDULER (dask_backend.scheduler_address), else the local pool.
    WorkflowError with exit status 2 for bad usage."""
    from daq.batch.dask_backend import scheduler_address

    if jobs is not None and jobs < 1:
        raise WorkflowError("--jobs must be at least 1", exit_code=2)
    if jobs is not None and scheduler is not None:
        raise WorkflowError(
            "give --jobs (local worker processes) or --scheduler (a Dask cluster), not both", exit_code=2
        )
    return BackendChoice(jobs, None if jobs is not None else scheduler_address(scheduler, env))


def select_runs(store_dir: Path, names: Sequence[str] | None, all_runs: bool) -> list[str]:
    """The run ids a batch works on: every run file of the store with ``all_runs``
    (damaged ones too, so that they fail with a line, never silently), else ``names``
    resolved (ids or unique prefixes), each once, in the order given. WorkflowError
    when the store cannot be listed or a name matches no run or several."""
    from daq.store import Store, StoreError

    store = Store(store_dir)
    try:
        if all_runs:
            return [s.file_name.removesuffix(".h5") for s in store.list()]
        return list(dict.fromkeys(store.resolve(name).stem for name in names or []))
    except StoreError as exc:
        raise WorkflowError(str(exc)) from None


@dataclass
class BatchReport:
    """What a batch came to: every outcome by run id, and the failed ones in the order
    they ended (skipped runs are neither done nor failed)."""

    outcomes: dict[str, RunOutcome] = field(default_factory=dict)
    failures: list[RunOutcome] = field(default_factory=list)

    def summaries(self, ids: Sequence[str]) -> list[dict]:
        """The summaries of the runs that succeeded, in the order of ``ids``."""
        return [o.summary for i in ids if (o := self.outcomes.get(i)) is not None and o.summary is not None]


def execute(
    tasks: Sequence[Task],
    backend: Backend,
    *,
    skip_empty: bool = False,
    on_outcome: OnDone | None = None,
) -> BatchReport:
    """Run ``tasks`` on ``backend``. skip_empty: a run with nothing to analyse (spectra
    alone: daq.workflows.analysis.nothing_to_identify) is "skipped", not failed.
    ``on_outcome(task, outcome)`` is called as each ends, after that choice."""
    report = BatchReport()

    def done(task: Task, outcome: RunOutcome) -> None:
        if outcome.status == "failed" and skip_empty and _nothing_to_identify(outcome.error or ""):
            outcome = replace(outcome, status="skipped")
        report.outcomes[task.run_id] = outcome
        if outcome.status == "failed":
            report.failures.append(outcome)
        if on_outcome is not None:
            on_outcome(task, outcome)

    backend.run(tasks, done)
    return report


def _nothing_to_identify(reason: str) -> bool:
    from daq.workflows.analysis import nothing_to_identify

    return nothing_to_identify(reason)


__all__ = [
    "Backend", "BackendChoice", "BatchReport", "DaskCluster", "InProcess", "OnDone", "ProcessPool",
    "choose_backend", "execute", "select_runs",
]  # fmt: skip
