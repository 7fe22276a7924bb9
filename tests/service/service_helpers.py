"""Start the real `daq serve` (a subprocess, real sockets) and talk to it over HTTP.

``serving(tmp_path, *args)`` starts ``daq serve --port 0 --store <tmp>/store ...``
with its own token file, lock directory and config, waits for the line with the
address, and stops it with SIGINT at the end (SIGKILL if it hangs).
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import signal
import subprocess
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import httpx

from tests.cli_helpers import DAQ, ENV

ADDRESS_LINE = re.compile(r"open (http://[^/\s]+)/#token=([0-9a-f]+)")
BEYOND_LOOPBACK_LINE = re.compile(r"listening on (\S+), .*open http://\S+:(\d+)/#token=")


@dataclass
class Served:
    url: str
    token: str
    proc: subprocess.Popen
    store: Path
    env: dict[str, str]
    stderr_lines: list[str] = field(default_factory=list)

    #: Seconds a request may wait for its answer: a report draws a dozen figures, which
    #: took over 30 s with one more pytest worker than cores and the browser tests beside it.
    TIMEOUT_S = 120.0

    def client(self, token: bool = True, timeout: float = TIMEOUT_S) -> httpx.Client:
        headers = {"Authorization": f"Bearer {self.token}"} if token else {}
        return httpx.Client(base_url=self.url, headers=headers, timeout=timeout)

    def get(self, path: str, **kwargs: Any) -> httpx.Response:
        with self.client() as c:
            return c.get(path, **kwargs)

    def post(self, path: str, body: dict | None = None, **kwargs: Any) -> httpx.Response:
        with self.client() as c:
            return c.post(path, json=body if body is not None else {}, **kwargs)


def service_env(tmp_path: Path) -> dict[str, str]:
    env = {**os.environ, **ENV}
    env.pop("DAQ_DEBUG", None)
    env.pop("DAQ_SCHEDULER", None)
    env.update(
        DAQ_TOKEN_FILE=str(tmp_path / "token"),
        DAQ_LOCK_DIR=str(tmp_path / "locks"),
        DAQ_CONFIG=str(tmp_path / "no-config.toml"),
    )
    # A decision held for undo would add seconds to every test's hit; the tests of undo
    # set their own window.
    env.setdefault("DAQ_UNDO_WINDOW_S", "0")
    return env


def _default_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def stop_service(served: Served, timeout_s: float = 30.0) -> int:
    """SIGINT (Ctrl-C), as a technician stops it; the exit status."""
    if served.proc.poll() is None:
        served.proc.send_signal(signal.SIGINT)
        try:
            served.proc.wait(timeout_s)
        except subprocess.TimeoutExpired:
            os.killpg(served.proc.pid, signal.SIGKILL)
            served.proc.wait(10)
            raise AssertionError("daq serve did not stop on SIGINT") from None
    return served.proc.returncode


@contextlib.contextmanager
def serving(
    tmp_path: Path, *args: str, host: str | None = None, store: Path | None = None, timeout_s: float = 60.0
) -> Iterator[Served]:
    """`daq serve --port 0 --store <store> ...` with its own token file, lock
    directory and config, until the block ends (SIGINT; SIGKILL of its process group
    if it hangs). ``host`` may be beyond loopback: the service is then reached through
    127.0.0.1, and the token, which its banner does not print, is read from the token
    file as `daq serve --show-token` would. The thread that drains its stderr is joined
    before the pipe is closed (a test may SIGKILL the service at any moment)."""
    store = store or tmp_path / "store"
    env = service_env(tmp_path)
    where = ("--host", host) if host else ()
    proc = subprocess.Popen(
        [str(DAQ), "serve", *where, "--port", "0", "--store", str(store), *args],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
        start_new_session=True,  # its own process group: a SIGKILL of the group takes its workers
        # pytest-xdist's workers ignore SIGINT, and a child inherits that: the service
        # would ignore a Ctrl-C that lands before uvicorn installs its own handler.
        preexec_fn=_default_sigint,
    )
    lines: list[str] = []
    drain = None
    try:
        deadline = time.monotonic() + timeout_s
        url = token = None
        while url is None and time.monotonic() < deadline:
            line = proc.stderr.readline()
            if not line:
                raise AssertionError(f"daq serve exited ({proc.wait(10)}): {''.join(lines)}")
            lines.append(line)
            if match := ADDRESS_LINE.search(line):
                url, token = match.group(1), match.group(2)
            elif match := BEYOND_LOOPBACK_LINE.search(line):
                url = f"http://127.0.0.1:{match.group(2)}"
                token = Path(env["DAQ_TOKEN_FILE"]).read_text().strip()
        if url is None or token is None:
            raise AssertionError(f"daq serve printed no address in {timeout_s} s: {''.join(lines)}")
        served = Served(url, token, proc, store, env, lines)
        drain = threading.Thread(target=lambda: lines.extend(proc.stderr), daemon=True)
        drain.start()
        yield served
    finally:
        try:
            if proc.poll() is None:
                stop_service(Served("", "", proc, store, env))
        finally:
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGKILL)
            proc.wait(10)
            if drain is not None:
                drain.join(10)
            proc.stderr.close()


def wait_for(predicate: Callable[[], Any], timeout_s: float = 60.0, what: str = "the condition") -> Any:
    """Poll ``predicate`` until it returns something truthy; that value."""
    deadline = time.monotonic() + timeout_s
    while True:
        value = predicate()
        if value:
            return value
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout_s} s waiting for {what}")
        time.sleep(0.05)


class EventReader:
    """Follows /api/events in a thread; ``events`` is the list of (id, kind, data)."""

    def __init__(self, served: Served, since: int | None = None) -> None:
        self.served = served
        self.events: list[tuple[int | None, str, dict]] = []
        self._stop = threading.Event()
        self._connected = threading.Event()
        self.error: BaseException | None = None
        params = {} if since is None else {"since": since}
        self._thread = threading.Thread(target=self._run, args=(params,), daemon=True)
        self._thread.start()
        if not self._connected.wait(15):
            raise AssertionError("the event stream did not open")

    def _run(self, params: dict) -> None:
        try:
            with self.served.client(timeout=None) as c, c.stream("GET", "/api/events", params=params) as r:
                assert r.status_code == 200, r.status_code
                event_id, kind, data = None, "message", []
                for line in r.iter_lines():
                    if self._stop.is_set():
                        return
                    if line == "":
                        if data:
                            self.events.append((event_id, kind, json.loads("\n".join(data))))
                            if kind == "hello":
                                self._connected.set()
                        event_id, kind, data = None, "message", []
                    elif line.startswith("id: "):
                        event_id = int(line[4:])
                    elif line.startswith("event: "):
                        kind = line[7:]
                    elif line.startswith("data: "):
                        data.append(line[6:])
        except BaseException as exc:
            if not self._stop.is_set():
                self.error = exc
            self._connected.set()

    def kinds(self, run_id: str | None = None) -> list[str]:
        return [k for _, k, d in self.events if run_id is None or d.get("run_id") == run_id]

    def wait_for_kind(self, kind: str, run_id: str | None = None, timeout_s: float = 60.0) -> dict:
        def found() -> dict | None:
            for _, k, d in list(self.events):
                if k == kind and (run_id is None or d.get("run_id") == run_id):
                    return d
            return None

        return wait_for(found, timeout_s, f"event {kind}")

    def close(self) -> None:
        self._stop.set()


@contextlib.contextmanager
def sim_server(*args: str, port: int = 0) -> Iterator[tuple[subprocess.Popen, str]]:
    """A `daq sim serve --tcp <port>` subprocess (a separate analyzer the service
    connects to, that a test can kill to drop the link); (process, VISA resource)."""
    env = {**os.environ, **ENV}
    proc = subprocess.Popen(
        [str(DAQ), "sim", "serve", "--tcp", str(port), *args],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
        start_new_session=True,
    )
    try:
        resource = proc.stdout.readline().strip()
        if not resource.startswith("TCPIP::"):
            proc.kill()
            raise AssertionError(f"daq sim serve printed {resource!r}: {proc.stderr.read()}")
        yield proc, resource
    finally:
        if proc.poll() is None:
            proc.kill()
        proc.wait(10)
        proc.stdout.close()
        proc.stderr.close()


def import_noise_frf(tmp_path: Path, store: Path, seed: int = 1) -> str:
    """`daq import` of a UFF 58 FRF of pure complex noise (1-800 Hz) into ``store``: a
    run whose analysis finds no mode and says so in its cautions; the new run's id."""
    import gc
    import warnings

    import numpy as np
    import pyuff

    from daq.store import Store
    from tests.cli_helpers import invoke_daq

    rng = np.random.default_rng(seed)
    x = np.arange(1, 801, dtype=float)
    dset = pyuff.prepare_58(
        binary=1, id1="noise", func_type=4, rsp_node=2, rsp_dir=3, ref_node=1, ref_dir=3,
        abscissa_spacing=1, abscissa_spec_data_type=18, ordinate_spec_data_type=12,
        orddenom_spec_data_type=13, z_axis_spec_data_type=0,
        data=rng.normal(size=x.size) + 1j * rng.normal(size=x.size), x=x,
    )  # fmt: skip
    dset.update(abscissa_axis_units_lab="Hz", ordinate_axis_units_lab="m/s^2", orddenom_axis_units_lab="N")
    path = tmp_path / f"noise-{seed}.uff"
    with warnings.catch_warnings():  # pyuff leaves its file for the collector to close
        warnings.simplefilter("ignore", ResourceWarning)
        pyuff.UFF(str(path)).write_sets([dset], mode="add")
        gc.collect()
    before = {s.run_id for s in Store(store).list()} if store.is_dir() else set()
    result = invoke_daq("import", str(path), "--store", str(store))
    assert result.returncode == 0, result.stderr
    (run_id,) = {s.run_id for s in Store(store).list()} - before
    return run_id
