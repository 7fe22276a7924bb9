"""The bench of the fault tests (test_driver_faults.py, every dialect): a simulated
analyzer of one model, optionally measured already, behind a TCP server or the
Prologix pty with faults armed; and what the tests read off the driver's logging.

Where faults live: a TcpServer arms its ``faults=[...]`` on every new connection, and
the TCP driver reconnects to recover, so a one-shot fault (count=1) is armed in-band
on the current connection (``SIM:FAULT ...``) and a lasting one on the server. The pty
has one session for its life: in-band and server-wide are the same.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass

import pytest

from drivers.errors import DriverError
from sims.instrument import Analyzer
from sims.prologix import PrologixPty
from sims.sources import PhysicsSource
from sims.tcp_server import TcpServer

TRANSPORTS = ("tcp", "prologix")


@dataclass
class Bench:
    kind: str
    analyzer: Analyzer
    resource: str
    frontend: TcpServer | PrologixPty
    model: str = "35660A"

    def clear_server_faults(self) -> None:
        """New TCP connections stop getting the server-wide faults (the pty's session
        is cleared in-band, ``SIM:FAULT CLEAR``)."""
        if isinstance(self.frontend, TcpServer):
            self.frontend.faults = ()

    @property
    def connections(self) -> int:
        """TCP connections the server accepted (1 for the pty: it has one session)."""
        return self.frontend.connections_served if isinstance(self.frontend, TcpServer) else 1


@contextmanager
def bench_factory(model: str, measurement: str, settle_query: str) -> Iterator[Callable[..., Bench]]:
    """make(kind, faults=(), measured=True) -> Bench, its front end running until the
    ``with`` ends. Measured: ``measurement`` ran on the analyzer directly (time scale 0,
    2 averages; ``settle_query`` lets every hit in), so that a fault armed for every
    reply cannot stop the set-up and the driver only fetches."""
    frontends: list[TcpServer | PrologixPty] = []

    def make(kind: str, faults: Sequence[str] = (), measured: bool = True) -> Bench:
        analyzer = Analyzer(PhysicsSource("seed", seed=11), time_scale=0.0, model=model)
        if measured:
            analyzer.execute(measurement)
            analyzer.execute(settle_query)
            assert analyzer.state == "done"
            assert analyzer.average.count == 2
            assert not analyzer.errors
        if kind == "tcp":
            frontend: TcpServer | PrologixPty = TcpServer(analyzer, port=0, faults=list(faults)).start()
            resource = frontend.resource
        else:
            frontend = PrologixPty(analyzer, 11, faults=list(faults)).start()
            resource = f"PROLOGIX::{frontend.port}::11"
        frontends.append(frontend)
        return Bench(kind, analyzer, resource, frontend, model)

    try:
        yield make
    finally:
        for frontend in frontends:
            frontend.close()


def recoveries(caplog: pytest.LogCaptureFixture) -> list[str]:
    """The driver's 'recovering' warnings: one per retried exchange."""
    return [r.getMessage() for r in caplog.records if "recovering" in r.getMessage()]


def outcome_of(action: Callable[[], object]) -> object:
    """What ``action()`` returned, or the DriverError it raised (to show a wrong reply)."""
    try:
        return action()
    except DriverError as exc:
        return exc
