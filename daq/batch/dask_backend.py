"""Batch analyses and fits on a Dask cluster (dask.distributed, the optional extra
``cantilever-daq[dask]``): ``daq analyze|fit --scheduler tcp://HOST:PORT``.

The workers of a real cluster run on other machines and cannot see the store folder.
So this process, the client, does everything that touches the store: it resolves
the runs, checks the caches, reads each run file's bytes and sends them with the
options; a worker decodes the run in memory (refusing what daq.store.reader refuses
in a file on disk), computes it (daq.workflows.analysis.compute_analysis,
daq.workflows.fit.fit_run) and sends back the summary and arrays; the client writes them
beside the run with the cache key, file name and content the local pool would
write, so that a later local run is a cache hit. A fit whose run has no up-to-date
analysis (default options) gets it computed in the same task, first, and the client
stores both, as ``daq fit`` does locally.

distributed is imported only inside functions: without the extra, daq works and only
--scheduler says what to install. The API a service can use: scheduler_address and
run_on_cluster.
"""

from __future__ import annotations

import contextlib
import io
import logging
import os
import re
import threading
import time
import uuid
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from daq.errors import UserError

#: Bounds every wait for the cluster: connecting, and finding a worker.
CONNECT_TIMEOUT_S = 10.0
KINDS = ("analyze", "fit")
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


def scheduler_address(option: str | None, env: Mapping[str, str] | None = None) -> str | None:
    """The Dask scheduler to use: ``option`` (--scheduler), else $DAQ_SCHEDULER (an
    empty one counts as unset), else None for the local pool. UserError (exit status
    2) unless it reads tcp://HOST:PORT or tls://HOST:PORT."""
    env = os.environ if env is None else env
    if option is not None:
        text, origin = option, "--scheduler"
    elif env.get("DAQ_SCHEDULER"):
        text, origin = env["DAQ_SCHEDULER"], "$DAQ_SCHEDULER"
    else:
        return None
    match = _ADDRESS.fullmatch(text)
    if match is None or not 1 <= int(match.group(3)) <= 65535:
        raise UserError(
            f"{origin} {text!r}: give the Dask scheduler's address as tcp://HOST:PORT or tls://HOST:PORT, "
            "e.g. tcp://10.0.0.9:8786",
            exit_code=2,
        )
    return text


def run_on_cluster(
    address: str,
    store_dir: Path | str,
    ids: Iterable[str],
    options: Any,
    force: bool,
    kind: str,
    on_done: Callable[[str, dict | str], None],
) -> None:
    """Analyse (``kind`` "analyze", AnalysisOptions) or fit (``kind`` "fit",
    FitOptions) the runs ``ids`` of the store on the Dask cluster at ``address``,
    storing each result beside its run as the local path does.

    ``on_done(run_id, outcome)`` is called in this process, in this thread, as each
    run finishes, in the order they finish: outcome is the summary dict (with
    ``cached``) or a one-line reason the run failed, the same reasons the local pool
    gives. Up-to-date results are read here and never sent.

    Blocking: call it from a thread without a running event loop (a service:
    ``await asyncio.to_thread(run_on_cluster, ...)``). UserError (one line) when
    distributed is not installed, the scheduler cannot be reached or has no worker,
    the workers cannot run daq's tasks, or the connection is lost.
    """
    from daq.store import Store

    if kind not in KINDS:
        raise ValueError(f"kind must be one of {', '.join(KINDS)}, got {kind!r}")
    distributed = _import_distributed()
    with _logging_as_the_root_says():
        _probe(address)
        client = _connect(distributed, address)
        try:
            _check_workers(client, address)
            ids = list(dict.fromkeys(ids))  # one task per run
            _run(distributed, client, address, Store(store_dir), ids, options, force, kind, on_done)
        finally:
            client.close()


def run_from_bytes(data: bytes, name: str) -> Any:
    """The Run whose file content is ``data``, decoded as daq.store.open_run decodes a
    file on disk: links and data outside the file refused, checksums verified, every
    failure one StoreError naming ``name`` (the file's path where it was read)."""
    import h5py

    from daq.store import StoreError
    from daq.store.decode import decode_run
    from daq.store.h5io import refuse_outside_references

    try:
        with h5py.File(io.BytesIO(data), "r") as f:
            refuse_outside_references(f)
            return decode_run(f)
    except StoreError as exc:
        raise StoreError(f"{name}: {exc}") from None
    except Exception as exc:
        # As daq.store.reader.open_h5: h5py reports damage in many exception types.
        text = " ".join(str(exc).split()) or type(exc).__name__
        text = text if len(text) <= 160 else text[:157] + "..."
        raise StoreError(f"{name}: damaged or not an HDF5 run file ({text})") from None


def failure_reason(exc: BaseException) -> str | None:
    """The one-line reason a run failed with ``exc``, as `daq analyze` and `daq fit`
    report it; None when ``exc`` is no failure of the run but a bug."""
    import numpy as np

    from daq.store import StoreError

    if isinstance(exc, (StoreError, ValueError)):
        return " ".join(str(exc).split())
    if isinstance(exc, (np.linalg.LinAlgError, FloatingPointError, ZeroDivisionError)):
        return f"numerical failure ({type(exc).__name__}: {' '.join(str(exc).split())})"
    return None


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


def _analyze_task(data: bytes, name: str, options: Any, software: str) -> tuple[dict, dict] | str:
    """(summary, arrays) of the analysis of the run file ``data``, or why not."""
    from daq.workflows.analysis import compute_analysis

    wrong = _prepare_worker(software)
    if wrong:
        return wrong
    try:
        return compute_analysis(run_from_bytes(data, name), options)
    except Exception as exc:
        reason = failure_reason(exc)
        if reason is None:
            raise
        return reason


def _fit_task(
    data: bytes, name: str, options: Any, analysis: dict | None, fit: bool, software: str
) -> dict[str, Any] | str:
    """The fit of the run file ``data``: {"analysis": (summary, arrays) computed here,
    or None when ``analysis`` (the stored one: summary, ``cached``, ``arrays``) was
    given; "fit": (summary, arrays) or None; "failure": why the run failed or None}.
    ``fit`` False: only the analysis (the fit's result is up to date)."""
    from analysis.run_analysis import AnalysisOptions
    from daq.workflows.analysis import compute_analysis
    from daq.workflows.fit import fit_run

    wrong = _prepare_worker(software)
    if wrong:
        return wrong
    out: dict[str, Any] = {"analysis": None, "fit": None, "failure": None}
    try:
        run = run_from_bytes(data, name)
        if analysis is None:
            info, arrays = compute_analysis(run, AnalysisOptions())
            out["analysis"] = (info, arrays)
            # As fit_stored: the fresh summary, and the arrays as they are stored.
            analysis = {**info, "cached": False, "arrays": dict(arrays)}
        if fit:
            out["fit"] = fit_run(run, analysis, options)
    except Exception as exc:
        reason = failure_reason(exc)
        if reason is None:
            raise
        if out["analysis"] is None:
            return reason
        out["failure"] = reason  # the analysis is stored all the same, as locally
    return out


# --- in the client ----------------------------------------------------------------------


def _import_distributed() -> Any:
    try:
        import distributed
    except ImportError:
        raise UserError(EXTRA_HINT) from None
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
    """UserError unless a Dask scheduler answers at ``address`` within the timeout.

    Asked by hand rather than by distributed.Client, which waits past its timeout
    for some peers (a web server, say) and leaves a half-made client behind whose
    clean-up prints tracebacks at exit.
    """
    import asyncio

    from distributed.comm import connect
    from distributed.security import Security

    args = Security().get_connection_args("client")
    if address.startswith("tls://") and args.get("ssl_context") is None:
        raise UserError(
            f"{address}: tls:// needs this client's certificate in Dask's configuration "
            "(distributed.comm.tls.ca-file, .client.cert and .client.key)"
        )

    async def identity() -> Any:
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
        raise UserError(f"{cannot} ({why})") from None
    except Exception as exc:
        raise UserError(f"{cannot} (something else answers there: {type(exc).__name__})") from None
    kind = reply.get("type") if isinstance(reply, dict) else None
    if kind != "Scheduler":
        raise UserError(f"{address} is not a Dask scheduler (it answers as {kind or 'something else'})")


def _connect(distributed: Any, address: str) -> Any:
    try:
        return distributed.Client(address, timeout=CONNECT_TIMEOUT_S, set_as_default=False)
    except (TimeoutError, OSError) as exc:
        raise UserError(
            f"cannot reach the Dask scheduler at {address} ({' '.join(str(exc).split())})"
        ) from None


def _check_workers(client: Any, address: str) -> None:
    """UserError unless a worker joins within the timeout and every worker runs this
    version of daq (it must import daq to decode a run)."""
    try:
        client.wait_for_workers(1, timeout=CONNECT_TIMEOUT_S)
    except TimeoutError:
        raise UserError(
            f"the Dask scheduler at {address} has no worker (waited {CONNECT_TIMEOUT_S:g} s); "
            f"start some with: dask worker {address}"
        ) from None
    try:
        versions = client.run(_software)
    except Exception as exc:
        raise UserError(
            f"the Dask workers of {address} cannot run daq's tasks ({type(exc).__name__}: "
            f"{' '.join(str(exc).split())}); install cantilever-daq on them, the version this client runs"
        ) from None
    here = _software()
    wrong = sorted(f"{worker} runs {there}" for worker, there in versions.items() if there != here)
    if wrong:
        raise UserError(f"this client runs {here} but {', '.join(wrong)}: install the same version on all")


@dataclass
class _Task:
    """A run to send: the worker function, its arguments, and what to do with its
    return value here (store it; the outcome for on_done)."""

    function: Callable[..., Any]
    args: tuple[Any, ...]
    finish: Callable[[Any], dict | str]


def _resolve(store: Any, run_id: str) -> Path:
    """store.resolve(run_id), without listing the folder for a complete run id (the
    usual case: run_batch resolved the names already). Listing a store of thousands
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


def _plan_analysis(store: Any, run_id: str, options: Any, force: bool) -> dict | _Task:
    """The cached summary, or the task that analyses the run (as analyze_stored)."""
    from daq.workflows.analysis import cache_key, cached_analysis, store_analysis

    path = _resolve(store, run_id)
    key = cache_key(path, options)
    if not force:
        stored = cached_analysis(store, path.stem, key)
        if stored is not None:
            return {**stored["summary"], "cached": True}
    data = _read(path)

    def finish(result: tuple[dict, dict] | str) -> dict | str:
        if isinstance(result, str):
            return result
        info, arrays = result
        store_analysis(store, info["run_id"], key, info, arrays)
        return {**info, "cached": False}

    return _Task(_analyze_task, (data, str(path), options, _software()), finish)


def _plan_fit(store: Any, run_id: str, options: Any, force: bool) -> dict | _Task:
    """The cached summary, or the task that fits the run (as fit_stored): with the
    stored analysis when it is up to date, else computing it first."""
    import numpy as np

    from analysis.run_analysis import AnalysisOptions
    from daq.workflows.analysis import cache_key, cached_analysis, store_analysis
    from daq.workflows.fit import cached_fit, fit_cache_key, store_fit

    path = _resolve(store, run_id)
    analysis_key = cache_key(path, AnalysisOptions())
    stored_analysis = cached_analysis(store, path.stem, analysis_key)  # never forced, as fit_stored
    key = fit_cache_key(path, analysis_key, options)
    cached = None if force else cached_fit(store, path.stem, options, key)
    if stored_analysis is not None and cached is not None:
        return {**cached, "cached": True}
    analysis = None
    if stored_analysis is not None:
        arrays = {k: v for k, v in stored_analysis.items() if isinstance(v, np.ndarray)}
        analysis = {**stored_analysis["summary"], "cached": True, "arrays": arrays}
    data = _read(path)

    def finish(result: dict[str, Any] | str) -> dict | str:
        if isinstance(result, str):
            return result
        if result["analysis"] is not None:
            info, arrays = result["analysis"]
            store_analysis(store, info["run_id"], analysis_key, info, arrays)
        if result["failure"] is not None:
            return result["failure"]
        if cached is not None:
            return {**cached, "cached": True}
        summary, arrays = result["fit"]
        store_fit(store, summary["run_id"], options, key, summary, arrays, analysis_key)
        return {**summary, "cached": False}

    args = (data, str(path), options, analysis, cached is None, _software())
    return _Task(_fit_task, args, finish)


def _run(
    distributed: Any,
    client: Any,
    address: str,
    store: Any,
    ids: list[str],
    options: Any,
    force: bool,
    kind: str,
    on_done: Callable[[str, dict | str], None],
) -> None:
    """Send the runs that need computing, a window at a time, and finish each here."""
    plan = _plan_analysis if kind == "analyze" else _plan_fit
    batch = uuid.uuid4().hex[:8]
    queue = iter(ids)
    pending: dict[Any, tuple[str, Callable[[Any], dict | str]]] = {}
    finished = distributed.as_completed(loop=client.loop)
    window, checked = _window(client), time.monotonic()

    def settle(run_id: str, step: Callable[..., dict | str | _Task], *args: Any) -> _Task | None:
        """``step(*args)`` here: a task to send, or None once on_done has the outcome."""
        try:
            outcome = step(*args)
        except Exception as exc:
            reason = failure_reason(exc)
            if reason is None:
                raise
            outcome = reason
        if isinstance(outcome, _Task):
            return outcome
        on_done(run_id, outcome)
        return None

    def feed() -> None:
        while len(pending) < window:
            run_id = next(queue, None)
            if run_id is None:
                return
            task = settle(run_id, plan, store, run_id, options, force)
            if task is None:
                continue
            args = list(task.args)
            if len(args[0]) > SCATTER_BYTES:
                args[0] = client.scatter(args[0], hash=False)
            future = client.submit(task.function, *args, key=f"daq-{kind}-{run_id}-{batch}", pure=False)
            pending[future] = (run_id, task.finish)
            finished.add(future)

    feed()
    for future in finished:
        run_id, finish = pending.pop(future)
        result = _result(distributed, future, address)
        settle(run_id, finish, result)
        if time.monotonic() - checked > 5:  # workers may join (or leave) during a batch
            window, checked = _window(client), time.monotonic()
        feed()


def _window(client: Any) -> int:
    threads = sum(client.nthreads().values())
    return max(4, TASKS_PER_THREAD * threads)


def _result(distributed: Any, future: Any, address: str) -> Any:
    """The task's return value; a one-line reason (a str, as the task returns) when
    the cluster lost it; UserError when the scheduler is gone. A task's own exception is
    a bug and is raised, as the local pool raises it."""
    if future.status == "error":
        exc = future.exception()
        if isinstance(exc, distributed.KilledWorker):
            return f"lost on the cluster: the Dask workers running it died ({' '.join(str(exc).split())})"
        raise exc
    if future.status == "cancelled":  # by the client, when it lost the scheduler
        raise UserError(f"lost the connection to the Dask scheduler at {address}")
    if future.status != "finished":
        return f"lost on the cluster (the task ended {future.status})"
    return future.result()
