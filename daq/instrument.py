"""Connecting the application to an analyzer: a real one by resource name, or the
built-in simulator (resource ``sim``, ``sim:seed`` or ``sim:realistic``)."""

from __future__ import annotations

from drivers.hp35660a import HP35660A
from drivers.loopback import LoopbackTransport

SIM_RESOURCES = ("sim", "sim:seed", "sim:realistic")


def is_simulated(resource: str) -> bool:
    return resource.strip().lower() in SIM_RESOURCES


def open_analyzer(resource: str, timeout_s: float = 5.0, seed: int = 0, time_scale: float = 0.0) -> HP35660A:
    """An open driver. ``sim`` runs the simulated analyzer in this process (scenario
    after the colon, ``seed`` by default), at ``time_scale`` (0: hits land at once)."""
    if is_simulated(resource):
        from sims.inprocess import InProcessConnection
        from sims.instrument import Analyzer
        from sims.sources import PhysicsSource

        _, _, scenario = resource.strip().lower().partition(":")
        analyzer = Analyzer(PhysicsSource(scenario or "seed", seed=seed), time_scale=time_scale)
        transport = LoopbackTransport(lambda: InProcessConnection(analyzer), resource, timeout_s)
        transport.open()
        return HP35660A(transport)
    return HP35660A.open(resource, timeout_s=timeout_s)
