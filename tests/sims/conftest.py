"""Fixtures for the simulator's tests: an in-process analyzer, noise off unless asked."""

from __future__ import annotations

import pytest

from sims.inprocess import InProcessConnection
from sims.instrument import Analyzer
from sims.sources import PhysicsSource


@pytest.fixture
def make_analyzer():
    """make_analyzer(scenario="seed", seed=0, noise=False, time_scale=0.0, clock=None)."""

    def make(scenario: str = "seed", seed: int = 0, noise: bool = False, time_scale: float = 0.0, clock=None):
        source = PhysicsSource(scenario, seed=seed)
        source.set_noise(noise)
        kwargs = {"clock": clock} if clock is not None else {}
        return Analyzer(source, time_scale=time_scale, **kwargs)

    return make


@pytest.fixture
def connect(make_analyzer):
    """connect(analyzer=None, faults=()) -> an in-process connection with .query(text)."""

    def make(analyzer: Analyzer | None = None, faults=()):
        conn = InProcessConnection(analyzer if analyzer is not None else make_analyzer(), faults)

        def query(text: str, timeout_s: float = 1.0) -> bytes:
            conn.write(text.encode("ascii") + b"\n")
            return conn.read(timeout_s=timeout_s)

        conn.query = query  # type: ignore[attr-defined]
        return conn

    return make
