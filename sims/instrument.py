"""The simulated analyzer: one instrument of a model (sims/models.py) speaking its
dialect, the 3562A-family mnemonics (35660A, 3562A; sims/hp_dialect.py) or SCPI
(35670A, 35665A; sims/scpi.py), over the measurement every model shares
(sims/measurement.py).

Time: the measurement advances lazily, on each command, from a monotonic clock
scaled by ``time_scale`` (1.0 = real time, 0 = every hit lands and records at
once). Physics is drawn when the analyzer arms, so the data depend only on the
seed and the command sequence, never on timing.

Thread-safe: front ends serving several clients share one instrument, as clients
share one box on a GPIB bus; each message is executed under a lock.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable

from sims.hp_dialect import CommandError, HpDialect
from sims.measurement import Measurement, Source
from sims.models import DEFAULT_MODEL, Model, get_model
from sims.reply import Reply
from sims.scpi import ScpiDialect
from sims.settings import AnalyzerSettings
from sims.sources import PhysicsSource

IDENTITY = DEFAULT_MODEL.identity

__all__ = ["Analyzer", "CommandError", "Reply"]


class Analyzer:
    """One simulated instrument. ``execute(message)`` takes one or more commands
    separated by ``;`` (and, in the mnemonic dialect, line ends) and returns the
    replies of its queries.

    model : "35660A" (default), "3562A", "35670A" or "35665A" (or a Model).
    """

    def __init__(
        self,
        source: Source | None = None,
        time_scale: float = 0.0,
        clock: Callable[[], float] = time.monotonic,
        model: Model | str = DEFAULT_MODEL,
    ) -> None:
        self.model = get_model(model)
        self.lock = threading.RLock()
        self.hardware_fault = False
        self.dialect: HpDialect | ScpiDialect = (
            HpDialect(self) if self.model.dialect == "hp" else ScpiDialect(self)
        )
        self.measurement = Measurement(
            AnalyzerSettings.preset(self.model),
            source if source is not None else PhysicsSource(),
            time_scale,
            clock,
            self._source_error,
        )
        if isinstance(self.dialect, ScpiDialect):
            self.dialect.preset()

    def _source_error(self, detail: str) -> None:
        self.dialect.source_error(detail)

    # ---------------------------------------------------- the measurement's state
    @property
    def settings(self) -> AnalyzerSettings:
        return self.measurement.settings

    @settings.setter
    def settings(self, value: AnalyzerSettings) -> None:
        self.measurement.settings = value

    @property
    def source(self) -> Source:
        return self.measurement.source

    @source.setter
    def source(self, value: Source) -> None:
        self.measurement.source = value

    @property
    def time_scale(self) -> float:
        return self.measurement.time_scale

    @time_scale.setter
    def time_scale(self, value: float) -> None:
        self.measurement.time_scale = float(value)

    @property
    def clock(self) -> Callable[[], float]:
        return self.measurement.clock

    @property
    def state(self) -> str:
        return self.measurement.state

    @property
    def average(self):
        return self.measurement.average

    @property
    def last_record(self):
        return self.measurement.last_record

    @property
    def errors(self):
        """The error queue, oldest first: (code, message) pairs."""
        return self.dialect.errors

    # -------------------------------------------------------------- commands
    def execute(self, message: str, on_start: Callable[[], bool] | None = None) -> list[Reply]:
        """Run every command in ``message``; replies of its queries, in order.

        ``on_start()``, if given, is asked at each start of a measurement (``STRT``,
        ``INIT``) whether the hammer never strikes (the no_hit fault).
        """
        with self.lock:
            return self.dialect.execute(message, on_start)

    def push_error(self, code: int, detail: str) -> None:
        """Queue an error by its mnemonic-dialect code (docs/instrument.md: 1 undefined
        command .. 8 input buffer overflow); a SCPI model queues its own equivalent."""
        with self.lock:
            self.dialect.push_error(code, detail)

    def start(self, never_hit: bool = False) -> None:
        """Start a measurement; ``never_hit`` arms a hammer that never strikes."""
        with self.lock:
            try:
                self.dialect.start(never_hit)
            except CommandError as exc:
                self.dialect.push_error(exc.code, exc.detail)

    def status(self) -> int:
        """The status the model reports on a serial poll: STA? bits, or SCPI's *STB."""
        with self.lock:
            self.measurement.advance()
            return self.dialect.serial_poll()

    serial_poll = status

    def measurement_pending(self) -> bool:
        """A started measurement is not finished yet (what SCPI's *OPC? waits for)."""
        with self.lock:
            self.measurement.advance()
            return self.measurement.state in ("waiting", "measuring", "pending")

    def enter_hardware_fault(self) -> None:
        with self.lock:
            self.hardware_fault = True
            self.dialect.hardware_fault()

    def device_clear(self) -> None:
        """GPIB device clear: nothing persistent changes (buffers live in the front ends)."""

    def go_to_local(self) -> None:
        """GPIB go-to-local: the simulator has no front panel to hand over."""
        with self.lock:
            self.measurement.advance()
