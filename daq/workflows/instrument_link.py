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

from daq.workflows.connect import fresh_seed, open_analyzer, serve_simulator
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
    """The built-in simulator's beam scenario, seed, time scale and hammer overrides.
    The command line chooses the defaults (daq/cli/options.py). ``seed`` None: each
    capture plays a fresh random seed; a seed given: each capture plays that seed, so
    that every capture is the one ``daq capture --sim --seed N`` takes."""

    scenario: str
    seed: int | None
    time_scale: float
    hammer: str = ""
    model: str = "35660A"

    def provenance(self, seed: int) -> dict[str, Any]:
        """What a capture records of the simulator, ``seed`` the one it played."""
        return {
            "scenario": self.scenario,
            "seed": seed,
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
        #: The simulator's physics (with --sim), reseeded at each capture.
        self._source: Any = None

    def start(self) -> None:
        """Start the simulator if any, take the instrument's lock (ResourceBusy if
        another process has it) and probe the analyzer once (a failure is recorded,
        not raised: the service starts, and says so)."""
        if self.sim is not None:
            from sims.hammer import HammerModel, adjusted
            from sims.sources import PhysicsSource

            hammer = adjusted(HammerModel(), self.sim.hammer) if self.sim.hammer else HammerModel()
            seed = fresh_seed() if self.sim.seed is None else self.sim.seed
            source = PhysicsSource(self.sim.scenario, hammer=hammer, seed=seed)
            self._source = source
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

    def simulator_for_capture(self) -> dict[str, Any] | None:
        """Before a capture: restart the simulator's random stream on the capture's seed
        (--seed, else a fresh one) and return the simulator's provenance for the run,
        whose seed replays the capture's hits (``daq capture --sim --seed N``); None for
        a real analyzer."""
        if self.sim is None:
            return None
        seed = fresh_seed() if self.sim.seed is None else self.sim.seed
        self._source.reseed(seed)
        return self.sim.provenance(seed)

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
