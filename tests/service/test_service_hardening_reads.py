"""BoundedReads, which every read of a run file of `daq serve` goes through: reads that
never end hold at most their own threads, identical reads are shared, a request waits
a bounded time (then ReadRefused, a 503), and other runs are read meanwhile."""

from __future__ import annotations

import asyncio
import threading

import pytest

from daq.service.service import BoundedReads, ReadRefused


def test_reads_that_never_end_starve_neither_other_runs_nor_the_server():
    release = threading.Event()
    started = []

    def stuck(name: str) -> str:
        started.append(name)
        release.wait(30)
        return name

    async def scenario() -> None:
        reads = BoundedReads(threads=4, per_run=2, max_reads=64, timeout_s=1.0)
        # 45 requests for one bad run, two kinds of read: two threads at most.
        flood = [asyncio.ensure_future(reads.run((f"what{i % 2}", "bad"), stuck, "bad")) for i in range(45)]
        await asyncio.sleep(0.2)
        assert len(started) == 2, started
        # Another run is read meanwhile: while the flood still waits for its timeout.
        assert await reads.run(("run", "good"), lambda: "good") == "good"
        assert not any(f.done() for f in flood)
        # The flood gets 503s after its timeout, not a thread each.
        outcomes = await asyncio.gather(*flood, return_exceptions=True)
        assert all(isinstance(o, ReadRefused) for o in outcomes), outcomes
        assert len(started) == 2, started
        assert reads.busy()
        release.set()
        await asyncio.sleep(0.2)
        assert not reads.busy()

    asyncio.run(scenario())


@pytest.mark.timeout(20)
def test_too_many_reads_are_refused_at_once():
    release = threading.Event()

    async def scenario() -> None:
        # A request's wait is an hour: refused by waiting, it would hang the test.
        reads = BoundedReads(threads=2, per_run=1, max_reads=3, timeout_s=3600.0)
        held = [asyncio.ensure_future(reads.run(("run", f"r{i}"), release.wait, 30)) for i in range(3)]
        await asyncio.sleep(0.1)
        with pytest.raises(ReadRefused, match="busy reading runs"):  # the cap's refusal, not a timeout's
            await reads.run(("run", "another"), lambda: None)
        release.set()
        assert await asyncio.gather(*held) == [True, True, True]

    asyncio.run(scenario())
