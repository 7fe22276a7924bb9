"""The parts of ``daq serve`` and their life: the instrument link, the capture
controller, the analysis workers, the event hub, and a cache of stored results."""

from __future__ import annotations

import asyncio
import concurrent.futures
import contextlib
import json
import os
import queue
import stat
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from daq.service.capture_control import CaptureController, Conflict
from daq.service.events import EventHub, plain
from daq.service.jobs import JobRunner, analysis_result_name, fit_result_name
from daq.store import Store, StoreError
from daq.store.lock import store_lock
from daq.workflows.instrument_link import InstrumentLink, SimSpec


@dataclass
class ServiceConfig:
    """store_dir : the run store. resource / sim : the analyzer (one of them).
    host, port : where HTTP is served. token : the access token.
    workers : analysis worker processes. scheduler : a Dask scheduler instead.
    dialect : the analyzer's dialect, forced (None: found out at the first connection).
    undo_window_s : seconds a decision is held before it goes to the analyzer, so that
        the page can undo it (default 3 s, else ``$DAQ_UNDO_WINDOW_S``; 0: none).
    setup : the named setup (or a setup file) captures use when a request names none;
        None: the service's own settings, no setup recorded (the snapshot's
        ``next_setup`` is then null). Requests may name stored setups only, never a file."""

    store_dir: Path
    resource: str | None
    sim: SimSpec | None
    host: str
    port: int
    token: str
    reads_need_token: bool
    workers: int = field(default_factory=lambda: max(1, (os.cpu_count() or 2) - 1))
    scheduler: str | None = None
    dialect: str | None = None
    undo_window_s: float = field(default_factory=lambda: _undo_window_from_env())
    setup: str | None = None

    @property
    def url(self) -> str:
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"http://{host}:{self.port}"


def _undo_window_from_env() -> float:
    """``$DAQ_UNDO_WINDOW_S`` when set to a number >= 0, else the default (3 s)."""
    from daq.service.capture_control import UNDO_WINDOW_S

    text = os.environ.get("DAQ_UNDO_WINDOW_S", "").strip()
    try:
        value = float(text) if text else UNDO_WINDOW_S
    except ValueError:
        return UNDO_WINDOW_S
    return value if 0 <= value <= 600 else UNDO_WINDOW_S


class Service:
    def __init__(self, config: ServiceConfig) -> None:
        self.config = config
        self.store = Store(config.store_dir)
        self.hub = EventHub()
        self.link = InstrumentLink(
            config.resource, config.sim, holder=f"daq serve at {config.url}", dialect=config.dialect
        )
        self.jobs = JobRunner(
            config.store_dir, self.hub, config.workers, config.scheduler,
            list_runs=lambda: list_regular_runs(Store(config.store_dir)),
        )  # fmt: skip
        self.capture = CaptureController(
            self.link,
            config.store_dir,
            self.hub,
            on_sealed=self.jobs.submit,
            undo_window_s=config.undo_window_s,
        )
        self._results = _ResultCache(self.store)
        # The lock lives in the store: every process finds it whatever its environment.
        self._store_lock = store_lock(config.store_dir, holder=f"daq serve at {config.url}")
        self._store_claimed = False
        self._reports: dict[str, tuple[Any, str]] = {}
        self._reports_lock = threading.Lock()
        self._listing_lock = threading.Lock()
        self._listing: tuple[Any, bytes] | None = None
        self.reads = BoundedReads()

    def claim_store(self) -> None:
        """Check that the store is writable and take its lock (StoreError if another
        service holds it): quick, so that a refusal comes before anything slow starts."""
        if self._store_claimed:
            return
        self.store.ensure_writable()
        # One service per store: two would analyse every run twice.
        self._store_lock.acquire()
        self._store_claimed = True

    def start(self) -> None:
        """Claim the store (claim_store), take the instrument (ResourceBusy if someone
        has it), start the workers and queue the store's backlog."""
        self.claim_store()
        self.link.start()
        try:
            self.jobs.start()
        except BaseException:
            self.link.close()
            raise

    def close(self) -> None:
        # Workers first: a run sealed now is analysed at the next start (the store is
        # the queue), and the stop waits only for the analysis already running.
        self.jobs.close()
        with contextlib.suppress(Conflict):  # nothing running is the usual case
            self.capture.stop("stop")  # a running capture seals what it has
        self.capture.wait_idle(10.0)
        self.link.close()
        self._store_lock.release()

    # ------------------------------------------------------------ results
    def analysis(self, run_id: str) -> dict[str, Any] | None:
        return self._results.get(run_id, analysis_result_name())

    def fits(self, run_id: str) -> dict[str, dict[str, Any]]:
        out = {}
        for path in sorted(self.store.path.glob(f"{run_id}.fit-*.h5")):
            if not is_regular(path):
                continue
            name = path.name[len(run_id) + 1 : -3]
            payload = self._results.get(run_id, name)
            if payload is not None:
                out[name] = payload
        return out

    def default_fit(self, run_id: str) -> dict[str, Any] | None:
        return self._results.get(run_id, fit_result_name())

    def report_html(self, run_id: str) -> str:
        """The run's report page, built again only when the run or a result changed
        (building takes seconds: figures for every hit, the fit's response)."""
        from daq.report.build import build_report

        def key() -> tuple:
            files = sorted(self.store.path.glob(f"{run_id}.*h5"))
            return tuple((p.name, *_size_mtime_path(p)) for p in files)

        before = key()
        odd = [name for name, *_ in before if not is_regular(self.store.path / name)]
        if odd:  # the report would read them: a link may lead anywhere, a FIFO hangs the read
            raise StoreError(f"{odd[0]} is not a regular file; refused")
        with self._reports_lock:
            cached = self._reports.get(run_id)
        if cached is not None and cached[0] == before:
            return cached[1]
        html, _ = build_report(self.store.path, run_id)
        with self._reports_lock:
            if len(self._reports) >= 32:
                self._reports.pop(next(iter(self._reports)))
            self._reports[run_id] = (key(), html)  # after: the build may have fitted the run
        return html

    def summary_json(self, run_id: str, name: str) -> bytes | None:
        """The stored result's summary as JSON bytes, encoded once per file version."""
        return self._results.summary_json(run_id, name)

    def runs_json(self, row: Callable[[Any], dict[str, Any]]) -> bytes:
        """GET /api/runs as JSON bytes: ``row(summary)`` for every run, recomputed only
        when a file of the store or a run's job state changed (50 clients polling a
        1,000-run store must not re-read it 50 times)."""
        try:
            with os.scandir(self.store.path) as it:
                files = sorted((e.name, *_size_mtime(e)) for e in it if e.name.endswith(".h5"))
        except FileNotFoundError:
            files = []
        key = (tuple(files), self.jobs.version)
        with self._listing_lock:
            if self._listing is not None and self._listing[0] == key:
                return self._listing[1]
            data = json.dumps([row(s) for s in self.list_runs()], separators=(",", ":")).encode()
            self._listing = (key, data)
            return data

    def list_runs(self) -> list[Any]:
        """Store.list(), of the run files that are regular files only."""
        return list_regular_runs(self.store)

    def public(self, text: str) -> str:
        """``text`` (an error's message) without the store's path: a client learns
        nothing of the server's folders."""
        where = str(self.store.path)
        return " ".join(text.replace(where + os.sep, "").replace(where, "the store").split())


def is_regular(path: Path) -> bool:
    """True if ``path`` is a regular file itself: not a symbolic link (which may lead
    anywhere: /etc/passwd, the token file), nor a FIFO or a device (whose reading may
    never end)."""
    try:
        return stat.S_ISREG(os.lstat(path).st_mode)
    except OSError:
        return False


def regular_run_names(store_dir: Path) -> list[tuple[str, int, int]]:
    """(name, size, mtime_ns) of the store's run files that are regular files."""
    from daq.store.store import is_run_file_name

    out = []
    try:
        with os.scandir(store_dir) as it:
            for entry in it:
                if not is_run_file_name(entry.name):
                    continue
                try:
                    st = entry.stat(follow_symlinks=False)
                except OSError:
                    continue
                if stat.S_ISREG(st.st_mode):
                    out.append((entry.name, st.st_size, st.st_mtime_ns))
    except FileNotFoundError:
        return []
    except OSError as exc:
        raise StoreError(f"cannot read the store folder: {os.strerror(exc.errno or 0)}") from None
    return sorted(out)


def list_regular_runs(store: Store) -> list[Any]:
    """As Store.list(), but a run file that is a link, a FIFO or a device is not
    listed (Store.list would read it: a FIFO would hang the listing for ever)."""
    from daq.store.index import cached_summaries
    from daq.store.store import _summary_or_error

    return cached_summaries(store.path, regular_run_names(store.path), _summary_or_error)


# ---------------------------------------------------------------- bounded reads
#: Threads that read run files for requests, at most: a damaged file whose reading
#: takes for ever holds one of them, never the server's request threads.
READ_THREADS = 8
#: Different reads of one run in progress at most (identical ones are shared).
READS_PER_RUN = 3
#: Reads in progress or waiting at most, all runs together.
MAX_READS = 64
#: Seconds a request waits for its read before it is answered 503.
READ_TIMEOUT_S = 60.0


class ReadRefused(Exception):
    """Too many reads, or this one took too long: the request gets 503."""


class _Job:
    __slots__ = ("args", "fn", "future", "waiters")

    def __init__(self, fn: Callable[..., Any], args: tuple) -> None:
        self.fn = fn
        self.args = args
        self.future: concurrent.futures.Future = concurrent.futures.Future()
        self.waiters = 0


class BoundedReads:
    """Long reads of run files (opening a run, its results, its report, the listing)
    run here, off the event loop and outside the server's thread pool, so that a file
    that is slow or impossible to read cannot starve the other requests: at most
    READ_THREADS threads, at most READS_PER_RUN different reads per run (the same read
    asked again waits for the one in progress; more wait their turn), a request waits
    READ_TIMEOUT_S at most. A read that never ends keeps its thread: the process does not wait for it
    when it stops."""

    def __init__(
        self,
        threads: int = READ_THREADS,
        per_run: int = READS_PER_RUN,
        max_reads: int = MAX_READS,
        timeout_s: float = READ_TIMEOUT_S,
    ) -> None:
        self.threads = threads
        self.per_run = per_run
        self.max_reads = max_reads
        self.timeout_s = timeout_s
        self._lock = threading.Lock()
        self._jobs: dict[tuple[str, str], _Job] = {}
        self._queue: queue.SimpleQueue = queue.SimpleQueue()
        self._started = 0
        self._running = 0

    async def run(self, key: tuple[str, str], fn: Callable[..., Any], *args: Any) -> Any:
        """``fn(*args)``'s value, read in one of the threads; ``key`` is (what, run id).
        ReadRefused if too many reads wait, or this one takes too long."""
        deadline = time.monotonic() + self.timeout_s
        while True:
            with self._lock:
                job = self._jobs.get(key)
                if job is None and len(self._jobs) >= self.max_reads:
                    raise ReadRefused("the service is busy reading runs; try again later")
                if job is None and sum(1 for k in self._jobs if k[1] == key[1]) < self.per_run:
                    job = self._jobs[key] = _Job(fn, args)
                    self._queue.put((key, job))
                    if self._started < self.threads:
                        self._started += 1
                        threading.Thread(target=self._work, name="daq-read", daemon=True).start()
                if job is not None:
                    job.waiters += 1
                    break
            if time.monotonic() > deadline:  # the run's other reads hold their places
                raise ReadRefused(f"run {key[1]} is still being read for earlier requests; try again later")
            await asyncio.sleep(0.05)
        try:
            left = max(0.0, deadline - time.monotonic())
            return await asyncio.wait_for(asyncio.shield(asyncio.wrap_future(job.future)), left)
        except TimeoutError:
            raise ReadRefused(f"reading run {key[1]} takes too long; try again later") from None
        finally:
            with self._lock:
                job.waiters -= 1
                # Nobody waits for it and it has not started: it never will.
                if job.waiters == 0 and job.future.cancel() and self._jobs.get(key) is job:
                    del self._jobs[key]

    def busy(self) -> bool:
        """True while a read is running."""
        with self._lock:
            return self._running > 0

    def _work(self) -> None:
        while True:
            key, job = self._queue.get()
            if not job.future.set_running_or_notify_cancel():
                continue
            with self._lock:
                self._running += 1
            try:
                job.future.set_result(job.fn(*job.args))
            except BaseException as exc:  # handed to the requests that wait
                job.future.set_exception(exc)
            finally:
                with self._lock:
                    self._running -= 1
                    if self._jobs.get(key) is job:
                        del self._jobs[key]


class _ResultCache:
    """Stored results read once per version of the file (keyed by its size and mtime):
    listing 1,000 runs with their modes must not open 2,000 HDF5 files each time."""

    MAX_ENTRIES = 4096

    def __init__(self, store: Store) -> None:
        self.store = store
        self._lock = threading.Lock()
        self._entries: dict[tuple[str, str], tuple[tuple[int, int], dict[str, Any]]] = {}
        self._encoded: dict[int, tuple[dict[str, Any], bytes]] = {}

    def summary_json(self, run_id: str, name: str) -> bytes | None:
        payload = self.get(run_id, name)
        if payload is None:
            return None
        with self._lock:
            cached = self._encoded.get(id(payload))
            if cached is not None and cached[0] is payload:
                return cached[1]
        data = json.dumps(plain(payload["summary"]), separators=(",", ":")).encode()
        with self._lock:
            if len(self._encoded) >= self.MAX_ENTRIES:
                self._encoded.pop(next(iter(self._encoded)))
            self._encoded[id(payload)] = (payload, data)
        return data

    def get(self, run_id: str, name: str) -> dict[str, Any] | None:
        """The result's payload (summary and arrays), or None if absent or unreadable."""
        path = self.store.path / f"{run_id}.{name}.h5"
        try:
            st = os.lstat(path)
        except OSError:
            return None
        if not stat.S_ISREG(st.st_mode):
            return None  # a link may lead anywhere; a FIFO would hang the read
        version = (st.st_size, st.st_mtime_ns)
        with self._lock:
            hit = self._entries.get((run_id, name))
        if hit is not None and hit[0] == version:
            return hit[1]
        try:
            payload = self.store.read_result(run_id, name)
        except StoreError:
            return None
        with self._lock:
            if len(self._entries) >= self.MAX_ENTRIES:
                self._entries.pop(next(iter(self._entries)))
            self._entries[(run_id, name)] = (version, payload)
        return payload


def _size_mtime(entry: os.DirEntry) -> tuple[int, int]:
    try:
        st = entry.stat()
    except OSError:  # removed meanwhile
        return (-1, -1)
    return (st.st_size, st.st_mtime_ns)


def _size_mtime_path(path: Path) -> tuple[int, int]:
    try:
        st = path.stat()
    except OSError:
        return (-1, -1)
    return (st.st_size, st.st_mtime_ns)
