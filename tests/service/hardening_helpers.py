"""Helpers of the hardening tests of `daq serve` (security, load, faults): raw HTTP
requests that no client library would normalise, a server-sent-events reader for
asyncio clients, what /proc says of a process, and a SIGKILL of a whole service.

Everything here talks to real processes over real sockets; nothing is mocked.
"""

from __future__ import annotations

import contextlib
import json
import os
import signal
import socket
import subprocess
from collections.abc import AsyncIterator, Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

import httpx

from tests.cli_helpers import DAQ
from tests.service.service_helpers import Served, wait_for


#: The banner line of a service bound beyond loopback (it does not print the token).
def free_port() -> int:
    """A TCP port of 127.0.0.1 that was free a moment ago (bound to port 0, then closed)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


@dataclass
class RawResponse:
    status: int
    headers: dict[str, str]
    body: bytes

    def json(self) -> object:
        return json.loads(self.body)


def raw_request(url: str, head: str, body: bytes = b"", timeout_s: float = 15.0) -> RawResponse:
    """Send ``head`` (request line and headers, without the blank line) and ``body``
    to the server of ``url`` exactly as given (no path normalisation, no added
    Content-Length), with ``Connection: close``; the response. The body may be cut
    short: the answer is read even if the server answers before the body is in."""
    parts = urlsplit(url)
    request = (head.rstrip("\r\n") + "\r\nConnection: close\r\n\r\n").encode("latin-1") + body
    with socket.create_connection((parts.hostname, parts.port), timeout=timeout_s) as sock:
        # The server may answer and close before taking everything: read its answer then.
        with contextlib.suppress(BrokenPipeError, ConnectionResetError):
            sock.sendall(request)
        chunks = []
        while True:
            try:
                chunk = sock.recv(65536)
            except ConnectionResetError:
                break
            if not chunk:
                break
            chunks.append(chunk)
    raw = b"".join(chunks)
    head_bytes, _, rest = raw.partition(b"\r\n\r\n")
    lines = head_bytes.decode("latin-1").split("\r\n")
    if not lines or not lines[0].startswith("HTTP/1.1 "):
        raise AssertionError(f"no HTTP response: {raw[:200]!r}")
    status = int(lines[0].split()[1])
    headers = {}
    for line in lines[1:]:
        name, _, value = line.partition(":")
        headers[name.strip().lower()] = value.strip()
    if headers.get("transfer-encoding") == "chunked":
        rest = _dechunk(rest)
    return RawResponse(status, headers, rest)


def _dechunk(data: bytes) -> bytes:
    out = []
    while data:
        size_line, _, data = data.partition(b"\r\n")
        size = int(size_line.split(b";")[0], 16)
        if size == 0:
            break
        out.append(data[:size])
        data = data[size + 2 :]
    return b"".join(out)


@dataclass(frozen=True)
class SseEvent:
    id: int | None
    kind: str
    data: dict


async def sse_events(response: httpx.Response) -> AsyncIterator[SseEvent]:
    """The events of an open text/event-stream response (comments skipped)."""
    event_id, kind, data = None, "message", []
    async for line in response.aiter_lines():
        if line == "":
            if data:
                yield SseEvent(event_id, kind, json.loads("\n".join(data)))
            event_id, kind, data = None, "message", []
        elif line.startswith("id: "):
            event_id = int(line[4:])
        elif line.startswith("event: "):
            kind = line[7:]
        elif line.startswith("data: "):
            data.append(line[6:])


# ---------------------------------------------------------------- /proc
def rss_kib(pid: int) -> int:
    """Resident set size of ``pid``, KiB (VmRSS)."""
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1])
    raise AssertionError(f"no VmRSS for pid {pid}")


def open_fds(pid: int) -> int:
    return len(os.listdir(f"/proc/{pid}/fd"))


def live_group_members(pgid: int) -> list[int]:
    """Processes of process group ``pgid`` that still run (zombies, which only wait
    for their parent to reap them, are not counted)."""
    members = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            stat = Path(f"/proc/{entry}/stat").read_text()
        except OSError:
            continue  # gone meanwhile
        # "pid (comm) state ppid pgrp ...": comm may hold spaces and parentheses.
        fields = stat[stat.rindex(")") + 2 :].split()
        if int(fields[2]) == pgid and fields[0] not in ("Z", "X"):
            members.append(int(entry))
    return members


def running(pid: int) -> bool:
    """Whether process ``pid`` exists and is not a zombie."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat[stat.rindex(")") + 2] not in "ZX"


def children_of(pid: int) -> list[int]:
    """Live processes whose parent is ``pid``."""
    out = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            stat = Path(f"/proc/{entry}/stat").read_text()
        except OSError:
            continue
        fields = stat[stat.rindex(")") + 2 :].split()
        if int(fields[1]) == pid and fields[0] not in ("Z", "X"):
            out.append(int(entry))
    return out


def kill_service(served: Served, timeout_s: float = 10.0) -> None:
    """SIGKILL the service and its process group (its workers): a power cut as far
    as the service can tell. Waits until no process of the group runs."""
    pgid = served.proc.pid  # started with start_new_session=True: its own group
    os.killpg(pgid, signal.SIGKILL)
    served.proc.wait(timeout_s)
    wait_for(lambda: not live_group_members(pgid), timeout_s, f"process group {pgid} to be gone")


# ---------------------------------------------------------------- the store
def unexpected_store_entries(store: Path) -> list[str]:
    """Entries of the store folder that are neither runs, nor results of a run
    present, nor the index cache, nor hidden temporaries (which the store never lists
    and `Store.clean_temporaries` removes)."""
    from daq.store.lock import STORE_LOCK_NAME
    from daq.store.store import is_run_file_name, is_temporary_name

    names = sorted(os.listdir(store))
    runs = {n[:-3] for n in names if is_run_file_name(n)}
    odd = []
    for name in names:
        # The store's lock (daq/store/lock.py) lives in the store by design.
        if is_run_file_name(name) or is_temporary_name(name) or name.startswith(".index.sqlite"):
            continue
        if name == STORE_LOCK_NAME:
            continue
        if name.endswith(".h5") and name[:29] in runs and name[29:30] == ".":
            continue  # <run_id>.<result name>.h5
        odd.append(name)
    return odd


def run_daq_env(env: dict[str, str], *args: str, timeout_s: float = 60.0) -> subprocess.CompletedProcess[str]:
    """The real console script in a subprocess with the service's environment."""
    return subprocess.run(
        [str(DAQ), *args], capture_output=True, text=True, env=env, timeout=timeout_s, check=False
    )


# ---------------------------------------------------------------- services
def first_event(served: Served, headers: dict[str, str] | None = None, **params: Any) -> SseEvent:
    """Open /api/events (with ``headers``, default the token's), read its first event
    (hello) and close; the event."""
    headers = {"Authorization": f"Bearer {served.token}"} if headers is None else headers
    with (
        httpx.Client(base_url=served.url, headers=headers, timeout=30) as client,
        client.stream("GET", "/api/events", params=params) as response,
    ):
        assert response.status_code == 200, response.status_code
        event_id, kind, data = None, "message", []
        for line in response.iter_lines():
            if line == "" and data:
                return SseEvent(event_id, kind, json.loads("\n".join(data)))
            if line.startswith("id: "):
                event_id = int(line[4:])
            elif line.startswith("event: "):
                kind = line[7:]
            elif line.startswith("data: "):
                data.append(line[6:])
    raise AssertionError("the event stream ended before its first event")


async def follow_until(
    client: httpx.AsyncClient, last: Callable[[SseEvent], bool], **kwargs: Any
) -> list[SseEvent]:
    """Follow /api/events (``kwargs`` go to the request: params, headers) until an
    event for which ``last`` is true; every event read, hello first."""
    events: list[SseEvent] = []
    async with client.stream("GET", "/api/events", **kwargs) as response:
        assert response.status_code == 200, response.status_code
        async for event in sse_events(response):
            events.append(event)
            if last(event):
                return events
    raise AssertionError(f"the event stream ended after {[(e.id, e.kind) for e in events]}")


def threads_of(pid: int) -> int:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("Threads:"):
            return int(line.split()[1])
    raise AssertionError(f"no Threads for pid {pid}")
