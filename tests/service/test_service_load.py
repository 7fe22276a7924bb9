"""`daq serve` under load: 50 clients follow the event stream and read runs while a
simulated capture runs. No hit is lost or duplicated, every client sees every event
in the same order, and memory, file descriptors and threads are flat afterwards. A
client that reconnects with ``since`` or ``Last-Event-ID`` gets what it missed and
nothing before. Real `daq serve`, real sockets (httpx.AsyncClient), no mocks."""

from __future__ import annotations

import asyncio
import statistics
import time
from dataclasses import dataclass, field

import httpx
import pytest

from daq.store import Store
from tests.service.hardening_helpers import (
    SseEvent,
    follow_until,
    open_fds,
    rss_kib,
    sse_events,
    threads_of,
)
from tests.service.service_helpers import EventReader, Served, serving, wait_for

pytestmark = pytest.mark.slow

N_CLIENTS = 50
HITS = 5
#: Seconds a load round may take at most (connections, the capture, the closing).
ROUND_TIMEOUT_S = 120.0


@dataclass
class ClientLog:
    events: list[SseEvent] = field(default_factory=list)
    requests: int = 0


@dataclass
class RoundResult:
    run_id: str
    logs: list[ClientLog]
    capture_s: float
    requests: int


async def _client(
    served: Served, read_id: str, log: ClientLog, connected: list[int], all_connected: asyncio.Event
) -> None:
    """One browser-like client: follows the events until the capture ends, and
    meanwhile reads the run list and a run's analysis, again and again."""
    auth = {"Authorization": f"Bearer {served.token}"}
    async with httpx.AsyncClient(base_url=served.url, headers=auth, timeout=60) as client:
        hello = asyncio.Event()
        finished = asyncio.Event()

        async def follow() -> None:
            try:
                async with client.stream("GET", "/api/events") as response:
                    assert response.status_code == 200, response.status_code
                    async for event in sse_events(response):
                        log.events.append(event)
                        if event.kind == "hello":
                            hello.set()
                            connected.append(1)
                            if len(connected) == N_CLIENTS:
                                all_connected.set()
                        elif event.kind == "capture_ended":
                            return
                raise AssertionError("the event stream ended before the capture did")
            finally:
                finished.set()

        async def read() -> None:
            await hello.wait()
            while not finished.is_set():
                runs = await client.get("/api/runs")
                assert runs.status_code == 200, runs.text
                assert read_id in [r["run_id"] for r in runs.json()]
                analysis = await client.get(f"/api/runs/{read_id}/analysis")
                assert analysis.status_code == 200, analysis.text
                assert analysis.json()["modes"], analysis.text
                log.requests += 2

        async with asyncio.TaskGroup() as group:
            group.create_task(follow())
            group.create_task(read())


async def _load_round(served: Served, read_id: str, hits: int) -> RoundResult:
    connected: list[int] = []
    all_connected = asyncio.Event()
    auth = {"Authorization": f"Bearer {served.token}"}
    logs = [ClientLog() for _ in range(N_CLIENTS)]
    async with asyncio.timeout(ROUND_TIMEOUT_S), asyncio.TaskGroup() as group:
        tasks = [group.create_task(_client(served, read_id, g, connected, all_connected)) for g in logs]
        await all_connected.wait()
        async with httpx.AsyncClient(base_url=served.url, headers=auth, timeout=60) as client:
            started = await client.post("/api/capture", json={"hits": hits, "auto": True})
        assert started.status_code == 202, started.text
        t0 = time.monotonic()
        before = sum(g.requests for g in logs)
        await asyncio.wait(tasks)
        capture_s = time.monotonic() - t0
    return RoundResult(started.json()["run_id"], logs, capture_s, sum(g.requests for g in logs) - before)


def _check_round(served: Served, result: RoundResult, hits: int) -> None:
    """Every client saw the same events, numbered without gap or repeat, every hit once."""
    reference = None
    for n, log in enumerate(result.logs):
        hello, *numbered = log.events
        assert hello.kind == "hello", (n, hello)
        ids = [e.id for e in numbered]
        assert None not in ids, (n, [(e.id, e.kind) for e in numbered])
        assert ids == list(range(ids[0], ids[0] + len(ids))), (n, ids)  # no gap, no repeat
        assert hello.data["last_id"] == ids[0] - 1, (n, hello.data, ids[0])  # nothing missed
        assert numbered[0].kind == "capture_started", (n, numbered[0])
        assert numbered[-1].kind == "capture_ended", (n, numbered[-1])
        if reference is None:
            reference = numbered
        else:
            assert numbered == reference, f"client {n} saw other events than client 0"
    assert reference is not None
    others = [e for e in reference if e.kind != "instrument" and e.data.get("run_id") != result.run_id]
    assert others == []  # nothing of another run came in between
    indices = [e.data["index"] for e in reference if e.kind == "hit"]
    assert indices == list(range(len(indices))), indices  # each hit once, in order
    decided = [e.data["index"] for e in reference if e.kind == "hit_decided"]
    assert decided == indices, decided
    (sealed,) = [e.data for e in reference if e.kind == "run_sealed"]
    assert sealed["n_hits"] == len(indices)
    assert sealed["n_accepted"] == hits
    assert reference[-1].data["outcome"] == "sealed", reference[-1].data
    run = Store(served.store).open(result.run_id)
    assert run.complete
    assert run.hits.n_hits == len(indices)
    assert int(run.hits.accepted.sum()) == hits
    accepted = [e.data["index"] for e in reference if e.kind == "hit_decided" and e.data["accepted"]]
    assert run.hits.accepted.nonzero()[0].tolist() == accepted


def _settled(served: Served, run_id: str) -> None:
    """Wait until no client is connected, nothing is queued or running and the run's
    fit is done: the service at rest."""

    def at_rest() -> bool:
        health = served.get("/api/health").json()
        jobs = health["jobs"]
        rows = {r["run_id"]: r for r in served.get("/api/runs").json()}
        return (
            health["clients"] == 0
            and health["capture"]["state"] == "idle"
            and jobs["queued"] == jobs["running"] == 0
            and rows[run_id]["fit"] == "done"
        )

    wait_for(at_rest, 120, "the service to settle")


def _figures(pid: int) -> dict[str, int]:
    return {"rss_kib": rss_kib(pid), "fds": open_fds(pid), "threads": threads_of(pid)}


def test_fifty_clients_follow_a_capture_and_read_runs_with_nothing_lost_and_nothing_leaked(tmp_path):
    with serving(tmp_path, "--sim", "--time-scale", "0.05", "--workers", "1") as served:
        pid = served.proc.pid
        events = EventReader(served)
        read_id = served.post("/api/capture", {"hits": 2, "auto": True}).json()["run_id"]
        events.wait_for_kind("fit_done", read_id, 120)
        events.close()

        warm = asyncio.run(_load_round(served, read_id, HITS))
        _check_round(served, warm, HITS)
        _settled(served, warm.run_id)
        before = _figures(pid)

        load = asyncio.run(_load_round(served, read_id, HITS))
        _check_round(served, load, HITS)
        _settled(served, load.run_id)
        after = _figures(pid)

        rate = load.requests / load.capture_s
        print(
            f"\n{N_CLIENTS} clients, {HITS}-hit auto capture: warm-up round {warm.requests} reads in "
            f"{warm.capture_s:.1f} s ({warm.requests / warm.capture_s:.0f}/s); load round {load.requests} "
            f"reads in {load.capture_s:.1f} s ({rate:.0f}/s), {len(load.logs[0].events) - 1} events to "
            f"each client\nservice after warm-up: RSS {before['rss_kib'] / 1024:.1f} MiB, "
            f"{before['fds']} fds, {before['threads']} threads; after load: RSS "
            f"{after['rss_kib'] / 1024:.1f} MiB, {after['fds']} fds, {after['threads']} threads"
        )
        assert load.requests > 0
        assert after["fds"] <= before["fds"] + 5, (before, after)
        # The request handlers' thread pool (anyio's, at most 40 threads) grows on demand
        # and keeps idle threads for a while: bounded, not flat.
        assert after["threads"] <= before["threads"] + 40, (before, after)
        assert after["rss_kib"] - before["rss_kib"] < 30 * 1024, (before, after)
        assert served.get("/api/health").json()["status"] == "ok"


def test_a_client_that_reconnects_gets_what_it_missed_and_nothing_before(tmp_path):
    with serving(tmp_path, "--sim", "--time-scale", "0.05", "--workers", "1") as served:
        # Responses on a kept-alive connection are not held back by Nagle's algorithm
        # waiting for the client's delayed ACK (that costs ~40 ms a request).
        with served.client() as client:
            times = []
            for _ in range(20):
                t0 = time.perf_counter()
                assert client.get("/api/health").status_code == 200
                times.append(time.perf_counter() - t0)
        print(f"\nGET /api/health on one connection: min {min(times) * 1e3:.1f} ms, "
              f"median {statistics.median(times) * 1e3:.1f} ms")  # fmt: skip
        assert min(times[1:]) < 0.02, times

        async def scenario() -> None:
            auth = {"Authorization": f"Bearer {served.token}"}
            async with httpx.AsyncClient(base_url=served.url, headers=auth, timeout=60) as client:
                await _reconnections(client)

        asyncio.run(asyncio.wait_for(scenario(), 120))


def _ended(event: SseEvent) -> bool:
    return event.kind == "capture_ended"


async def _reconnections(client: httpx.AsyncClient) -> None:
    steady = asyncio.create_task(follow_until(client, _ended))
    dropped = asyncio.create_task(follow_until(client, lambda e: e.kind == "hit"))
    await asyncio.sleep(0.5)  # both subscribed (hello comes at once)
    started = await client.post("/api/capture", json={"hits": 3, "auto": True})
    assert started.status_code == 202, started.text
    run_id = started.json()["run_id"]
    first_part = await dropped  # its connection closes after the first hit
    seen = first_part[-1].id
    assert seen is not None
    await asyncio.sleep(0.3)  # events go on meanwhile
    resumed = await follow_until(client, _ended, headers={"Last-Event-ID": str(seen)})
    full = await steady
    full_ids = [e.id for e in full[1:]]
    assert full_ids == list(range(full_ids[0], full_ids[0] + len(full_ids)))
    assert resumed[0].kind == "hello"
    assert all(e.id > seen for e in resumed[1:]), [e.id for e in resumed]
    assert first_part[1:] + resumed[1:] == full[1:]  # none lost, none twice

    # The service at rest (the run analysed and fitted): every event is numbered by now.
    async def fitted() -> None:
        while True:
            rows = {r["run_id"]: r for r in (await client.get("/api/runs")).json()}
            if (
                rows[run_id]["fit"] == "done"
                and (await client.get("/api/health")).json()["jobs"]["running"] == 0
            ):
                return
            await asyncio.sleep(0.1)

    await asyncio.wait_for(fitted(), 90)
    (hello,) = await follow_until(client, lambda e: True)
    last = hello.data["last_id"]
    everything = await follow_until(client, lambda e: e.id == last, params={"since": 0})
    assert [e.id for e in everything[1:]] == list(range(1, last + 1))
    assert everything[1 : len(full)] == full[1:]

    # since=<id> replays the events after it, none before.
    middle = last // 2
    replay = await follow_until(client, lambda e: e.id == last, params={"since": middle})
    assert replay[0].data == {"last_id": last}
    assert replay[1:] == [e for e in everything[1:] if e.id > middle]

    # Caught up, or a Last-Event-ID that is no number: nothing is replayed; the next
    # event is the next number.
    def numbered(event: SseEvent) -> bool:
        return event.id is not None

    followers = [asyncio.create_task(follow_until(client, numbered, params={"since": last}))]
    for garbled in (b"x", b"-1", b"1e3", b"\xb2", b"9" * 5000):  # \xb2: a digit to str.isdigit()
        headers = {"Last-Event-ID": garbled}
        followers.append(asyncio.create_task(follow_until(client, numbered, headers=headers)))
    await asyncio.sleep(0.5)
    second = await client.post("/api/capture", json={"hits": 1, "auto": True})
    assert second.status_code == 202, second.text
    for task in followers:
        hello, following = await task
        assert hello.data == {"last_id": last}
        assert (following.id, following.kind) == (last + 1, "capture_started"), following
    bad = await client.get("/api/events", params={"since": -1})
    assert bad.status_code == 422, bad.text
    while (await client.get("/api/capture")).json()["state"] != "idle":
        await asyncio.sleep(0.1)
