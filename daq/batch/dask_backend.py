"""Batch analyses and fits on a Dask cluster (dask.distributed, the optional extra
``cantilever-daq[dask]``): ``daq analyze|fit --scheduler tcp://HOST:PORT``, the
executor's DaskCluster backend (daq/batch/executor.py) and the service's queue.

The workers of a real cluster run on other machines and cannot see the store folder.
So this process, the client, does everything that touches the store: it resolves
the runs, checks the caches, reads each run file's bytes and sends them with the
options; a worker decodes the run in memory with the store's own decoder
(daq.store.open_run_bytes: it refuses what daq.store.open_run refuses in a file on
disk), computes it (daq.workflows.analysis.compute_analysis,
daq.workflows.fit.fit_run) and sends back the summary and arrays; the client writes
them beside the run with the cache key, file name and content the local pool would
write, so that a later local run is a cache hit. A fit whose run has no up-to-date
analysis (default options) gets it computed in the same task, first, and the client
stores both, as ``daq fit`` does locally.

distributed is imported only inside functions: without the extra, daq works and only
--scheduler says what to install. The API: scheduler_address and run_on_cluster.
"""

from __future__ import annotations

import contextlib
import logging
import os
import re
import threading
import time
import uuid
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any, TypeAlias

from daq.batch.tasks import AnalyseTask, FitTask, Task
from daq.workflows.errors import WorkflowError
from daq.workflows.outcome import RunOutcome, failure_reason

if TYPE_CHECKING:
    import numpy as np
    from distributed import Client, Future

    from analysis.run_analysis import AnalysisOptions
    from daq.store import Store
    from daq.workflows.fit import FitOptions

#: Bounds every wait for the cluster: connecting, and finding a worker.
CONNECT_TIMEOUT_S = 10.0
EXTRA_HINT = "--scheduler needs the optional extra: pip install 'cantilever-daq[dask]'"
#: A run file bigger than this goes to the cluster on its own (scatter) rather than
#: inside its task: distributed warns about task graphs over 10 MB.
SCATTER_BYTES = 4 * 2**20
#: Tasks in flight per worker thread: enough to keep every worker busy while the
#: client stores results, few enough that the run files sent stay a small share of
#: the memory (a batch of 1,000 runs is never sent at once).
TASKS_PER_THREAD = 2

_ADDRESS = re.compile(
    r"(tcp|tls)://(\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9](?:[A-Za-z0-9.-]*[A-Za-z0-9])?):([0-9]{1,5})"
)

#: A result's summary (JSON-able) and its arrays, as the result file stores them.
Summary: TypeAlias = dict[str, Any]
Arrays: TypeAlias = "dict[str, np.ndarray]"
#: What a worker computed, or the one-line reason it could not.
Computed: TypeAlias = "tuple[Summary, Arrays] | str"


def scheduler_address(option: str | None, env: Mapping[str, str] | None = None) -> str | None:
    """The Dask scheduler to use: ``option`` (--scheduler), else $DAQ_SCHEDULER (an
    empty one counts as unset), else None for the local pool. WorkflowError (exit
    status 2) unless it reads tcp://HOST:PORT or tls://HOST:PORT."""
    env = os.environ if env is None else env
    if option is not None:
        text, origin = option, "--scheduler"
    elif env.get("DAQ_SCHEDULER"):
        text, origin = env["DAQ_SCHEDULER"], "$DAQ_SCHEDULER"
    else:
        return None
    match = _ADDRESS.fullmatch(text)
    if match is None or not 1 <= int(match.group(3)) <= 65535:
        raise WorkflowError(
            f"{origin} {text!r}: give the Dask scheduler's address as tcp://HOST:PORT or tls://HOST:PORT, "
            "e.g. tcp://10.0.0.9:8786",
            exit_code=2,
        )
    return text


def run_on_cluster(address: str, tasks: Sequence[Task], on_done: Callable[[Task, RunOutcome], None]) -> None:
    """Run ``tasks`` (AnalyseTask, FitTask) on the Dask cluster at ``address``, storing
    each result beside its run as the local path does.

    ``on_done(task, outcome)`` is called in this process, in this thread, as each
    run finishes, in the order they finish, with the outcomes the local pool gives
    (the same summaries, the same one-line reasons). Up-to-date results are read here
    and never sent. A run named twice is done once.

    Blocking: call it from a thread without a running event loop (a service:
    ``await asyncio.to_thread(run_on_cluster, ...)``). WorkflowError (one line) when
    distributed is not installed, the scheduler cannot be reached or has no worker,
    the workers cannot run daq's tasks, or the connection is lost.
    """
    distributed = _import_distributed()
    with _logging_as_the_root_says():
        _probe(address)
        client = _connect(distributed, address)
        try:
            _check_workers(client, address)
            once = list({(t.store_dir, t.run_id): t for t in tasks}.values())
            _run(distributed, client, address, once, on_done)
        finally:
            client.close()


# --- on the workers ---------------------------------------------------------------------


def _software() -> str:
    from daq.store.model import SOFTWARE

    return SOFTWARE


def _prepare_worker(expected: str) -> str | None:
    """Ready this worker process for a task: None, or why it must not run it (it
    runs another version of daq than the client, ``expected``).

    As daq's own worker processes do, it keeps freed memory (daq/batch/memory_tuning.py):
    Dask's workers ask glibc for the opposite (MALLOC_TRIM_THRESHOLD_=65536), and
    every fit then faults its temporaries in again page by page, twice the time."""
    from daq.batch.memory_tuning import keep_freed_memory

    keep_freed_memory()
    here = _software()
    if here == expected:
        return None
    return f"the Dask worker runs {here}, this client {expected}: install the same version on both"


def _analyze_task(data: bytes, name: str, options: AnalysisOptions, software: str) -> Computed:
    """(summary, arrays) of the analysis of the run file ``data``, or why not."""
    from daq.store import open_run_bytes
    from daq.workflows.analysis import compute_analysis

    wrong = _prepare_worker(software)
    if wrong:
        return wrong
    try:
        return compute_analysis(open_run_bytes(data, name), options)
    except Exception as exc:
        reason = failure_reason(exc)
        if reason is None:
            raise
        return reason


@dataclass(frozen=True)
class _FitComputed:
    """What a fit's task sends back: ``analysis`` the run's analysis computed there
    (None when the stored one was sent), ``fit`` the fit (None when only the analysis
    was asked for, or the run failed), ``failure`` why the run failed after its
    analysis (which is stored all the same, as locally)."""

    analysis: tuple[Summary, Arrays] | None = None
    fit: tuple[Summary, Arrays] | None = None
    failure: str | None = None


def _fit_task(
    data: bytes, name: str, options: FitOptions, analysis: Summary | None, fit: bool, software: str
) -> _FitComputed | str:
    """The fit of the run file ``data``, with ``analysis`` (the stored one: summary,
    ``cached``, ``arrays``) or, None, computing it first; ``fit`` False: only the
    analysis (the fit's result is up to date). A str: why the run failed before any
    result."""
    from analysis.run_analysis import AnalysisOptions
    from daq.store import open_run_bytes
    from daq.workflows.analysis import compute_analysis
    from daq.workflows.fit import fit_run

    wrong = _prepare_worker(software)
    if wrong:
        return wrong
    computed = None
    try:
        run = open_run_bytes(data, name)
        if analysis is None:
            info, arrays = compute_analysis(run, AnalysisOptions())
            computed = (info, arrays)
            # As fit_stored: the fresh summary, and the arrays as they are stored.
            analysis = {**info, "cached": False, "arrays": dict(arrays)}
        return _FitComputed(computed, fit_run(run, analysis, options) if fit else None)
    except Exception as exc:
        reason = failure_reason(exc)
        if reason is None:
            raise
        if computed is None:
            return reason
        return _FitComputed(computed, None, reason)


# --- in the client ----------------------------------------------------------------------


def _import_distributed() -> ModuleType:
    try:
        import distributed
    except ImportError:
        raise WorkflowError(EXTRA_HINT) from None
    return distributed


_logging_lock = threading.Lock()
_logging_users = 0
_logging_saved: dict[str, int] = {}


@contextlib.contextmanager
def _logging_as_the_root_says() -> Iterator[None]:
    """Hold distributed's (and tornado's) loggers to the root logger's level meanwhile.

    distributed sets its own levels on import (INFO, WARNING for its client), and its
    records pass any handler on the root: `daq`, which shows only CRITICAL unless
    -v, would print its connection chatter and retries beside its one error line.
    Batches at the same time (threads of a service) share one change.
    """
    global _logging_users
    with _logging_lock:
        if _logging_users == 0:
            floor = logging.getLogger().getEffectiveLevel()
            tops = ("distributed", "tornado")
            known = list(logging.root.manager.loggerDict.items())
            below = sorted(n for n, node in known if isinstance(node, logging.Logger) and "." in n)
            for name in [*tops, *(n for n in below if n.split(".")[0] in tops)]:
                logger = logging.getLogger(name)
                # The tops always; below them only those with a level of their own.
                if (name in tops or logger.level != logging.NOTSET) and logger.level < floor:
                    _logging_saved[name] = logger.level
                    logger.setLevel(floor)
        _logging_users += 1
    try:
        yield
    finally:
        with _logging_lock:
            _logging_users -= 1
            if _logging_users == 0:
                for name, level in _logging_saved.items():
                    logging.getLogger(name).setLevel(level)
                _logging_saved.clear()


def _probe(address: str) -> None:
    """WorkflowError unless a Dask scheduler answers at ``address`` within the timeout.

    Asked by hand rather than by distributed.Client, which waits past its timeout
    for some peers (a web server, say) and leaves a half-made client behind whose
    clean-up prints tracebacks at exit.
    """
    import asyncio

    from distributed.comm import connect
    from distributed.security import Security

    args = Security().get_connection_args("client")
    if address.startswith("tls://") and args.get("ssl_context") is None:
        raise WorkflowError(
            f"{address}: tls:// needs this client's certificate in Dask's configuration "
            "(distributed.comm.tls.ca-file, .client.cert and .client.key)"
        )

    async def identity() -> object:
        comm = await connect(address, timeout=CONNECT_TIMEOUT_S, **args)
        try:
            await comm.write({"op": "identity", "reply": True})
            return await comm.read()
        finally:
            comm.abort()

    cannot = f"cannot reach the Dask scheduler at {address}"
    try:
        reply = asyncio.run(asyncio.wait_for(identity(), CONNECT_TIMEOUT_S))
    except (TimeoutError, OSError) as exc:
        timed_out = isinstance(exc, TimeoutError) or "Timed out" in str(exc)
        why = f"timed out after {CONNECT_TIMEOUT_S:g} s" if timed_out else " ".join(str(exc).split())
        raise WorkflowError(f"{cannot} ({why})") from None
    except Exception as exc:
        raise WorkflowError(f"{cannot} (something else answers there: {type(exc).__name__})") from None
    kind = reply.get("type") if isinstance(reply, dict) else None
    if kind != "Scheduler":
        raise WorkflowError(f"{address} is not a Dask scheduler (it answers as {kind or 'something else'})")


def _connect(distributed: ModuleType, address: str) -> Client:
    try:
        return distributed.Client(address, timeout=CONNECT_TIMEOUT_S, set_as_default=False)
    except (TimeoutError, OSError) as exc:
        raise WorkflowError(
            f"cannot reach the Dask scheduler at {address} ({' '.join(str(exc).split())})"
        ) from None


def _check_workers(client: Client, address: str) -> None:
    """WorkflowError unless a worker joins within the timeout and every worker runs
    this version of daq (it must import daq to decode a run)."""
    try:
        client.wait_for_workers(1, timeout=CONNECT_TIMEOUT_S)
    except TimeoutError:
        raise WorkflowError(
            f"the Dask scheduler at {address} has no worker (waited {CONNECT_TIMEOUT_S:g} s); "
            f"start some with: dask worker {address}"
        ) from None
    try:
        versions = client.run(_software)
    except Exception as exc:
        raise WorkflowError(
            f"the Dask workers of {address} cannot run daq's tasks ({type(exc).__name__}: "
            f"{' '.join(str(exc).split())}); install cantilever-daq on them, the version this client runs"
        ) from None
    here = _software()
    wrong = sorted(f"{worker} runs {there}" for worker, there in versions.items() if there != here)
    if wrong:
        raise WorkflowError(
            f"this client runs {here} but {', '.join(wrong)}: install the same version on all"
        )


#: What the client makes of a worker's return value: it stores the results and
#: gives the run's outcome.
Finish: TypeAlias = Callable[[Any], RunOutcome]


@dataclass(frozen=True)
class _Remote:
    """A run to send: the worker function, its arguments (the run file's bytes first),
    and what to do with its return value here."""

    function: Callable[..., Computed | _FitComputed]
    args: tuple[object, ...]
    finish: Finish


def _resolve(store: Store, run_id: str) -> Path:
    """store.resolve(run_id), without listing the folder for a complete run id (the
    usual case: the batch resolved the names already). Listing a store of thousands
    of runs for each of them would make the client the batch's bottleneck."""
    from daq.store.ids import is_run_id

    path = store.path / f"{run_id}.h5"
    return path if is_run_id(run_id) and path.is_file() else store.resolve(run_id)


def _read(path: Path) -> bytes:
    from daq.store import StoreError

    try:
        return path.read_bytes()
    except FileNotFoundError:
        raise StoreError(f"{path}: no such run file") from None
    except OSError as exc:
        raise StoreError(f"{path}: cannot read it ({exc.strerror or exc})") from None


def _plan_analysis(store: Store, task: AnalyseTask) -> RunOutcome | _Remote:
    """The cached outcome, or the work that analyses the run (as analyze_stored)."""
    from daq.workflows.analysis import cache_key, cached_analysis, store_analysis

    path = _resolve(store, task.run_id)
    key = cache_key(path, task.options)
    if not task.recompute:
        stored = cached_analysis(store, path.stem, key)
        if stored is not None:
            return RunOutcome.done(task.run_id, {**stored["summary"], "cached": True})
    data = _read(path)

    def finish(result: Computed) -> RunOutcome:
        if isinstance(result, str):
            return RunOutcome.failed(task.run_id, result)
        info, arrays = result
        store_analysis(store, info["run_id"], key, info, arrays)
        return RunOutcome.done(task.run_id, {**info, "cached": False})

    return _Remote(_analyze_task, (data, str(path), task.options, _software()), finish)


def _plan_fit(store: Store, task: FitTask) -> RunOutcome | _Remote:
    """The cached outcome, or the work that fits the run (as fit_stored): with the
    stored analysis when it is up to date, else computing it first."""
    import numpy as np

    from analysis.run_analysis import AnalysisOptions
    from daq.workflows.analysis import cache_key, cached_analysis, store_analysis
    from daq.workflows.fit import cached_fit, fit_cache_key, store_fit

    options = task.options
    path = _resolve(store, task.run_id)
    analysis_key = cache_key(path, AnalysisOptions())
    stored_analysis = cached_analysis(store, path.stem, analysis_key)  # never recomputed, as fit_stored
    key = fit_cache_key(path, analysis_key, options)
    cached = None if task.recompute else cached_fit(store, path.stem, options, key)
    if stored_analysis is not None and cached is not None:
        return RunOutcome.done(task.run_id, {**cached, "cached": True})
    analysis = None
    if stored_analysis is not None:
        arrays = {k: v for k, v in stored_analysis.items() if isinstance(v, np.ndarray)}
        analysis = {**stored_analysis["summary"], "cached": True, "arrays": arrays}
    data = _read(path)

    def finish(result: _FitComputed | str) -> RunOutcome:
        if isinstance(result, str):
            return RunOutcome.failed(task.run_id, result)
        if result.analysis is not None:
            info, arrays = result.analysis
            store_analysis(store, info["run_id"], analysis_key, info, arrays)
        if result.failure is not None:
            return RunOutcome.failed(task.run_id, result.failure)
        if cached is not None:
            return RunOutcome.done(task.run_id, {**cached, "cached": True})
        assert result.fit is not None
        summary, arrays = result.fit
        store_fit(store, summary["run_id"], options, key, summary, arrays, analysis_key)
        return RunOutcome.done(task.run_id, {**summary, "cached": False})

    args = (data, str(path), options, analysis, cached is None, _software())
    return _Remote(_fit_task, args, finish)


def _plan(store: Store, task: Task) -> RunOutcome | _Remote:
    if isinstance(task, AnalyseTask):
        return _plan_analysis(store, task)
    return _plan_fit(store, task)


def _run(
    distributed: ModuleType,
    client: Client,
    address: str,
    tasks: list[Task],
    on_done: Callable[[Task, RunOutcome], None],
) -> None:
    """Send the runs that need computing, a window at a time, and finish each here."""
    from daq.store import Store

    stores: dict[Path, Store] = {}
    batch = uuid.uuid4().hex[:8]
    queue = iter(tasks)
    pending: dict[Future, tuple[Task, Finish]] = {}
    finished = distributed.as_completed(loop=client.loop)
    window, checked = _window(client), time.monotonic()

    def settle(task: Task, step: Callable[..., RunOutcome | _Remote], *args: object) -> _Remote | None:
        """``step(*args)`` here: work to send, or None once on_done has the outcome."""
        try:
            outcome = step(*args)
        except Exception as exc:
            reason = failure_reason(exc)
            if reason is None:
                raise
            outcome = RunOutcome.failed(task.run_id, reason)
        if isinstance(outcome, _Remote):
            return outcome
        on_done(task, outcome)
        return None

    def feed() -> None:
        while len(pending) < window:
            task = next(queue, None)
            if task is None:
                return
            store = stores.setdefault(Path(task.store_dir), Store(task.store_dir))
            remote = settle(task, _plan, store, task)
            if remote is None:
                continue
            args = list(remote.args)
            if len(args[0]) > SCATTER_BYTES:  # type: ignore[arg-type]
                args[0] = client.scatter(args[0], hash=False)
            key = f"daq-{task.command}-{task.run_id}-{batch}"
            future = client.submit(remote.function, *args, key=key, pure=False)
            pending[future] = (task, remote.finish)
            finished.add(future)

    feed()
    for future in finished:
        task, finish = pending.pop(future)
        result = _result(distributed, future, address)
        settle(task, finish, result)
        if time.monotonic() - checked > 5:  # workers may join (or leave) during a batch
            window, checked = _window(client), time.monotonic()
        feed()


def _window(client: Client) -> int:
    threads = sum(client.nthreads().values())
    return max(4, TASKS_PER_THREAD * threads)


def _result(distributed: ModuleType, future: Future, address: str) -> object:
    """The task's return value; a one-line reason (a str, as the task returns) when
    the cluster lost it; WorkflowError when the scheduler is gone. A task's own
    exception is a bug and is raised, as the local pool raises it."""
    if future.status == "error":
        exc = future.exception()
        if isinstance(exc, distributed.KilledWorker):
            return f"lost on the cluster: the Dask workers running it died ({' '.join(str(exc).split())})"
        raise exc
    if future.status == "cancelled":  # by the client, when it lost the scheduler
        raise WorkflowError(f"lost the connection to the Dask scheduler at {address}")
    if future.status != "finished":
        return f"lost on the cluster (the task ended {future.status})"
    return future.result()
