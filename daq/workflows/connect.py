"""Connecting the application to an analyzer: a real one by resource name, or the
built-in simulator (resource ``sim``, ``sim:seed`` or ``sim:realistic``)."""

from __future__ import annotations

import contextlib
import os
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from drivers.analyzer import SignalAnalyzer

SIM_RESOURCES = ("sim", "sim:seed", "sim:realistic")


def configured_resource(option: str | None) -> str | None:
    """The analyzer to use: the --resource option, else $DAQ_RESOURCE, else the config
    file's ``resource`` (``daq config`` shows which); None when none names one."""
    if option:
        return option
    if os.environ.get("DAQ_RESOURCE"):
        return os.environ["DAQ_RESOURCE"]
    from daq.store.config import load_config

    return load_config().resource


def is_simulated(resource: str) -> bool:
    return resource.strip().lower() in SIM_RESOURCES


def open_analyzer(
    resource: str,
    timeout_s: float = 5.0,
    seed: int = 0,
    time_scale: float = 0.0,
    dialect: str | None = None,
    retries: int = 2,
    lock_file: bool = True,
) -> SignalAnalyzer:
    """An open driver, of the dialect detection finds (``dialect`` forces one): the one way
    the application opens an analyzer. ``sim`` runs the simulated analyzer in this
    process (scenario after the colon, ``seed`` by default), at ``time_scale`` (0: hits
    land at once). ``lock_file=False`` when the caller holds the resource's lock already
    (the service, for as long as it runs). A resource string that names nothing is a
    ValueError."""
    # The drivers (and numpy under them) load here, not with the command line.
    from drivers.family import connect
    from drivers.family import open_analyzer as open_resource
    from drivers.loopback import LoopbackTransport

    if is_simulated(resource):
        from sims.inprocess import InProcessConnection
        from sims.instrument import Analyzer
        from sims.sources import PhysicsSource

        _, _, scenario = resource.strip().lower().partition(":")
        analyzer = Analyzer(PhysicsSource(scenario or "seed", seed=seed), time_scale=time_scale)
        transport = LoopbackTransport(lambda: InProcessConnection(analyzer), resource, timeout_s)
        transport.open()
        try:
            return connect(transport, dialect, retries=retries)
        except BaseException:
            transport.close()
            raise
    return open_resource(resource, timeout_s=timeout_s, dialect=dialect, retries=retries, lock_file=lock_file)


def serve_simulator(
    stack: contextlib.ExitStack, source: Any, time_scale: float, model: str = "35660A"
) -> str:
    """Start the simulated analyzer (of ``model``) serving ``source`` on a loopback TCP
    socket for as long as ``stack`` lives; its VISA resource string."""
    from sims.instrument import Analyzer
    from sims.tcp_server import TcpServer

    analyzer = Analyzer(source, time_scale=time_scale, model=model)
    server = stack.enter_context(TcpServer(analyzer))
    return server.resource
