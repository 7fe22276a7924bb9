"""The parts of ``daq serve`` and their life: the instrument link, the capture
controller, the analysis workers, the event hub, and a cache of stored results."""

from __future__ import annotations

import contextlib
import json
import os
import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from daq.service.capture_control import CaptureController, Conflict
from daq.service.events import EventHub, plain
from daq.service.instrument_link import InstrumentLink, SimSpec
from daq.service.jobs import JobRunner, analysis_result_name, fit_result_name
from daq.store import Store, StoreError
from drivers.locking import ResourceLock


@dataclass
class ServiceConfig:
    """store_dir : the run store. resource / sim : the analyzer (one of them).
    host, port : where HTTP is served. token : the access token.
    workers : analysis worker processes. scheduler : a Dask scheduler instead.
    dialect : the analyzer's dialect, forced (None: found out at the first connection)."""

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

    @property
    def url(self) -> str:
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"http://{host}:{self.port}"


class Service:
    def __init__(self, config: ServiceConfig) -> None:
        self.config = config
        self.store = Store(config.store_dir)
        self.hub = EventHub()
        self.link = InstrumentLink(
            config.resource, config.sim, holder=f"daq serve at {config.url}", dialect=config.dialect
        )
        self.jobs = JobRunner(config.store_dir, self.hub, config.workers, config.scheduler)
        self.capture = CaptureController(self.link, config.store_dir, self.hub, on_sealed=self.jobs.submit)
        self._results = _ResultCache(self.store)
        where = os.path.realpath(config.store_dir)
        self._store_lock = ResourceLock(
            f"STORE::{where}", f"store {where}", holder=f"daq serve at {config.url}"
        )
        self._reports: dict[str, tuple[Any, str]] = {}
        self._reports_lock = threading.Lock()
        self._listing_lock = threading.Lock()
        self._listing: tuple[Any, bytes] | None = None

    def start(self) -> None:
        """Take the instrument (ResourceBusy if someone has it), start the workers and
        queue the store's backlog."""
        self.store.ensure_writable()
        # One service per store: two would analyse every run twice.
        self._store_lock.acquire()
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
        with os.scandir(self.store.path) as it:
            files = sorted((e.name, *_size_mtime(e)) for e in it if e.name.endswith(".h5"))
        key = (tuple(files), self.jobs.version)
        with self._listing_lock:
            if self._listing is not None and self._listing[0] == key:
                return self._listing[1]
            data = json.dumps([row(s) for s in self.store.list()], separators=(",", ":")).encode()
            self._listing = (key, data)
            return data


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
            st = path.stat()
        except OSError:
            return None
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
