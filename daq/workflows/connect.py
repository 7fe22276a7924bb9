"""Connecting the application to an analyzer: a real one by resource name, or the
built-in simulator (resource ``sim``, ``sim:seed``, ``sim:realistic`` or ``sim:custom``),
its hammer and accelerometer anywhere on the beam."""

from __future__ import annotations

import contextlib
import os
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from drivers.analyzer import SignalAnalyzer

SIM_RESOURCES = ("sim", "sim:seed", "sim:realistic", "sim:custom")


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
    force_at_m: float | None = None,
    sensor_at_m: float | None = None,
    damping: Any = None,
) -> SignalAnalyzer:
    """An open driver, of the dialect detection finds (``dialect`` forces one): the one way
    the application opens an analyzer. ``sim`` runs the simulated analyzer in this
    process (scenario after the colon, ``seed`` by default), at ``time_scale`` (0: hits
    land at once), the hammer at ``force_at_m`` and the accelerometer at ``sensor_at_m``
    (m from the clamp, 0 < x <= L; None: the tip), and with ``damping`` ((3, 3) N s/m,
    symmetric positive semi-definite: the seed's Ritz beam with that matrix, scenario
    ``custom``). ``lock_file=False`` when the caller holds the resource's lock already
    (the service, for as long as it runs). A resource string that names nothing, or a
    position or damping matrix the simulator refuses, is a ValueError; positions or
    damping with a real analyzer too."""
    # The drivers (and numpy under them) load here, not with the command line.
    from drivers.family import connect
    from drivers.family import open_analyzer as open_resource
    from drivers.loopback import LoopbackTransport

    if is_simulated(resource):
        from sims.inprocess import InProcessConnection
        from sims.instrument import Analyzer

        _, _, scenario = resource.strip().lower().partition(":")
        source = simulator_source(scenario or "seed", seed, "", force_at_m, sensor_at_m, damping)
        analyzer = Analyzer(source, time_scale=time_scale)
        transport = LoopbackTransport(lambda: InProcessConnection(analyzer), resource, timeout_s)
        transport.open()
        try:
            return connect(transport, dialect, retries=retries)
        except BaseException:
            transport.close()
            raise
    if force_at_m is not None or sensor_at_m is not None or damping is not None:
        raise ValueError(
            "positions and a damping matrix are the simulator's: a real analyzer measures where it is put"
        )
    return open_resource(resource, timeout_s=timeout_s, dialect=dialect, retries=retries, lock_file=lock_file)


def fresh_seed() -> int:
    """A new random seed for the simulator, for a capture (or a simulator's start) given
    none: 0 <= seed < 2**32, from the operating system's entropy, so that two captures
    never play the same hits by accident. Printed and recorded, it replays them."""
    import secrets

    return secrets.randbits(32)


def simulator_source(
    scenario: str = "seed",
    seed: int = 0,
    hammer: str = "",
    force_at_m: float | None = None,
    sensor_at_m: float | None = None,
    damping: Any = None,
) -> Any:
    """The simulator's physics: ``scenario`` (seed, realistic, custom), random ``seed``,
    hammer adjustments (``k=v,...``, sims.hammer), hammer and accelerometer positions (m
    from the clamp, 0 < x <= L; None: the tip) and a damping matrix of your own ((3, 3)
    or 9 numbers row-major, N s/m, symmetric positive semi-definite; makes the scenario
    ``custom`` on the seed's Ritz beam). A ``sims.sources.PhysicsSource``; ValueError
    naming what is wrong."""
    from sims.hammer import HammerModel, adjusted
    from sims.sources import PhysicsSource

    hammer_model = adjusted(HammerModel(), hammer) if hammer else HammerModel()
    return PhysicsSource(
        scenario,
        hammer=hammer_model,
        seed=seed,
        force_at_m=force_at_m,
        sensor_at_m=sensor_at_m,
        damping=damping,
    )


def serve_simulator(
    stack: contextlib.ExitStack,
    source: Any,
    time_scale: float,
    model: str = "35660A",
    force_at_m: float | None = None,
    sensor_at_m: float | None = None,
) -> str:
    """Start the simulated analyzer (of ``model``) serving ``source`` on a loopback TCP
    socket for as long as ``stack`` lives; its VISA resource string. ``force_at_m`` and
    ``sensor_at_m`` (m from the clamp, 0 < x <= L), when given, move the source's hammer
    and accelerometer first (None leaves them where the source has them: the tip unless
    it was built otherwise, ``simulator_source``); ValueError off the beam."""
    from sims.instrument import Analyzer
    from sims.tcp_server import TcpServer

    if force_at_m is not None or sensor_at_m is not None:
        if not hasattr(source, "move"):
            raise ValueError("positions need the simulator's physics, not a replay")
        source.move(force_at_m, sensor_at_m)
    analyzer = Analyzer(source, time_scale=time_scale, model=model)
    server = stack.enter_context(TcpServer(analyzer))
    return server.resource
