"""A long-lived hold on the analyzer, as the lab service keeps it: the lock for as long as the service runs, a
fresh connection for each capture (so that a dropped link is reconnected at the
next one), and what is known of its state.

With ``--sim`` the built-in simulator serves on a loopback TCP socket inside the
service, as ``daq capture --sim`` does, and the service talks to it through
pyvisa-py like to a real analyzer.
"""

from __future__ import annotations

import contextlib
import threading
from dataclasses import dataclass
from typing import Any

from daq.workflows.connect import open_analyzer, serve_simulator
from drivers.base import SignalAnalyzer
from drivers.errors import DriverError
from drivers.locking import ResourceLock
from drivers.resources import lock_key_of

#: A technician may take their time between hits; Stop on the page ends a wait.
SERVICE_HIT_ALLOWANCE_S = 24 * 3600.0
#: Per exchange with the analyzer.
IO_TIMEOUT_S = 5.0


@dataclass(frozen=True)
class SimSpec:
    """The built-in simulator's beam scenario, seed, time scale and hammer overrides."""

    scenario: str = "realistic"
    seed: int = 1
    time_scale: float = 0.05
    hammer: str = ""
    model: str = "35660A"

    def provenance(self) -> dict[str, Any]:
        return {
            "scenario": self.scenario,
            "seed": self.seed,
            "time_scale": self.time_scale,
            "hammer": self.hammer,
            "model": self.model,
        }


class InstrumentLink:
    """Owns the resource; ``open_driver()`` for each capture."""

    def __init__(
        self, resource: str | None, sim: SimSpec | None, holder: str, dialect: str | None = None
    ) -> None:
        if (resource is None) == (sim is None):
            raise ValueError("give a resource or a simulator, not both")
        self.resource = resource or ""
        self.sim = sim
        self.holder = holder
        self._stack = contextlib.ExitStack()
        self._lock: ResourceLock | None = None
        self._state_lock = threading.Lock()
        self.connected = False
        self.identification: str | None = None
        self.last_error: str | None = None
        self.transport_name = ""
        #: The dialect given (--dialect) or found at the first connection.
        self.dialect = dialect
        self.detection = f"the {dialect} dialect was forced (--dialect or $DAQ_DIALECT)" if dialect else ""

    def start(self) -> None:
        """Start the simulator if any, take the instrument's lock (ResourceBusy if
        another process has it) and probe the analyzer once (a failure is recorded,
        not raised: the service starts, and says so)."""
        if self.sim is not None:
            from sims.hammer import HammerModel, adjusted
            from sims.sources import PhysicsSource

            hammer = adjusted(HammerModel(), self.sim.hammer) if self.sim.hammer else HammerModel()
            source = PhysicsSource(self.sim.scenario, hammer=hammer, seed=self.sim.seed)
            self.resource = serve_simulator(self._stack, source, self.sim.time_scale, self.sim.model)
        lock = ResourceLock(lock_key_of(self.resource), self.resource, holder=self.holder)
        lock.acquire()
        self._lock = lock
        self._stack.callback(lock.release)
        try:
            with self.open_driver() as dsa:
                self.note_ok(dsa.identify())
        except DriverError as exc:
            self.note_error(str(exc))

    def open_driver(self) -> SignalAnalyzer:
        """A new connection (the lock is ours already: the driver does not take it). The
        dialect found at the first connection is kept, so later ones need not ask."""
        try:
            dsa = open_analyzer(self.resource, timeout_s=IO_TIMEOUT_S, dialect=self.dialect, lock_file=False)
        except DriverError as exc:
            self.note_error(str(exc))
            raise
        if self.dialect is None:
            self.dialect = dsa.dialect.name
            self.detection = dsa.detection
        dsa.hit_allowance_s = SERVICE_HIT_ALLOWANCE_S
        self.transport_name = type(dsa.transport).__name__
        return dsa

    def note_ok(self, identification: str | None = None) -> None:
        with self._state_lock:
            self.connected = True
            self.last_error = None
            if identification:
                self.identification = identification

    def note_error(self, message: str) -> None:
        with self._state_lock:
            self.connected = False
            self.last_error = message

    def status(self) -> dict[str, Any]:
        with self._state_lock:
            return {
                "resource": self.resource,
                "simulated": self.sim is not None,
                "connected": self.connected,
                "identification": self.identification,
                "dialect": self.dialect,
                "detection": self.detection or None,
                "last_error": self.last_error,
            }

    def close(self) -> None:
        self._stack.close()
