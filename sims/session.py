"""One client's connection to the simulated analyzer: framing, simulator control, faults.

Front ends (TCP, the Prologix pty, in-process) own the bytes; a Session turns
complete messages into instrument commands and the instrument's replies into
``Chunk``s to send, with the faults armed on this connection applied.

Simulator control travels in-band, in a namespace no instrument command uses
(on a SCPI model too: its commands go to the instrument together, SIM: apart):

| command                 | effect                                                        |
|-------------------------|---------------------------------------------------------------|
| ``SIM:FAULT spec``      | arm a fault on this connection (see sims.faults)              |
| ``SIM:FAULT CLEAR``     | disarm every fault on this connection                         |
| ``SIM:FAULT?``          | the armed faults, ``;``-separated, or NONE                    |
| ``SIM:NOISE 0|1``       | sensor noise off/on (physics source)                          |
| ``SIM:SEED n``          | restart the physics random stream                             |
| ``SIM:SCEN name``       | switch the specimen (seed, realistic; custom after SIM:DAMP), |
|                         | the hammer and the accelerometer staying where they are       |
| ``SIM:FORCE x``         | move the hammer to x metres from the clamp (0 < x <= L)       |
| ``SIM:SENSOR x``        | move the accelerometer to x metres from the clamp             |
| ``SIM:FORCE?``          | the hammer's position, m from the clamp (L: the tip)          |
| ``SIM:SENSOR?``         | the accelerometer's position, m from the clamp                |
| ``SIM:DAMP c11,...,c33``| scenario custom: the seed's Ritz N=3 beam with this damping   |
|                         | matrix, 9 numbers row by row, N s/m, symmetric PSD            |
| ``SIM:DAMP?``           | the damping matrix now simulated, N x N numbers row by row    |
| ``SIM:TIME scale``      | time scale: 1 real time, 0 instant                            |
| ``SIM:HAMMER k=v,...``  | peak_force_n, pulse_width_s, double_hit_probability, rel_spread |
| ``SIM:HITS?``           | hits the hammer has struck so far                             |

Positions and damping take effect from the next hit drawn (the analyzer draws a hit
when it arms: ``STRT``, or the next average); a position off the beam or a matrix
that is not symmetric positive semi-definite changes nothing and queues an error.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

from sims.faults import Fault, garbage_bytes, parse_fault
from sims.hammer import adjusted
from sims.instrument import Analyzer, Reply
from sims.scenarios import CUSTOM, build_specimen, parse_damping_matrix
from sims.scpi_table import split_units
from sims.sources import PhysicsSource

#: A client that sends this much without a line end is not talking to us.
MAX_PENDING_BYTES = 65536


@dataclass(frozen=True)
class Chunk:
    """Bytes to send after waiting ``delay_s``; ``close`` ends the connection after them.
    ``until``, if given, holds them back until it returns True (SCPI's ``*OPC?``)."""

    data: bytes
    delay_s: float = 0.0
    close: bool = False
    until: Callable[[], bool] | None = None


class Session:
    def __init__(self, analyzer: Analyzer, faults: list[str] | tuple[str, ...] = ()) -> None:
        self.analyzer = analyzer
        self.faults: list[Fault] = []
        self.closed = False
        self._pending = b""
        for spec in faults:
            self.arm(spec)

    # ------------------------------------------------------------- faults
    def arm(self, spec: str) -> None:
        fault = parse_fault(spec)
        if fault.name == "error":
            self.analyzer.enter_hardware_fault()
            return
        self.faults.append(fault)

    def _fault(self, name: str) -> Fault | None:
        """The first armed fault of this name that acts on the current event."""
        for fault in self.faults:
            if fault.name == name and fault.fires():
                return fault
        return None

    # ------------------------------------------------------------- framing
    def feed(self, data: bytes) -> list[Chunk]:
        """Bytes from the client; replies to every message they complete (LF ends one)."""
        if self.closed:
            return []
        self._pending += data
        out: list[Chunk] = []
        while b"\n" in self._pending:
            message, _, self._pending = self._pending.partition(b"\n")
            out += self.message(message)
        if len(self._pending) > MAX_PENDING_BYTES:
            self._pending = b""
            with self.analyzer.lock:
                self.analyzer.push_error(8, "message too long")
        return out

    def end_of_message(self) -> list[Chunk]:
        """GPIB EOI: whatever is buffered is a complete message."""
        message, self._pending = self._pending, b""
        return self.message(message) if message.strip() else []

    def clear(self) -> None:
        """Device clear: drop any partial input."""
        self._pending = b""
        self.analyzer.device_clear()

    def message(self, raw: bytes) -> list[Chunk]:
        """One complete message: commands separated by ``;``."""
        # Bytes that are not ASCII become '?': they must not reach a reply undecodable.
        text = raw.decode("ascii", errors="replace").replace("\ufffd", "?")
        if self.analyzer.model.dialect == "scpi":
            return self._scpi_message(text)
        out: list[Chunk] = []
        for part in text.replace("\r", "").split(";"):
            part = part.strip()
            if not part:
                continue
            if part.upper().startswith("SIM:"):
                reply = self._control(part)
                replies = [Reply(reply.encode("ascii") + b"\r\n")] if reply is not None else []
            elif part.upper() == "STRT" and self._fault("no_hit"):
                self.analyzer.start(never_hit=True)
                replies = []
            else:
                replies = self.analyzer.execute(part)
            for reply in replies:
                out += self._deliver(reply)
                if self.closed:
                    return out
        return out

    def _scpi_message(self, text: str) -> list[Chunk]:
        """A SCPI message: the instrument's commands go to it together (SCPI's path
        rule spans a message), SIM: controls apart; replies end with LF."""
        out: list[Chunk] = []
        batch: list[str] = []

        def flush() -> bool:
            replies = self.analyzer.execute(";".join(batch), on_start=self._no_hit) if batch else []
            batch.clear()
            for reply in replies:
                out.extend(self._deliver(reply))
                if self.closed:
                    return False
            return True

        for unit in split_units(text):
            if not unit.upper().startswith("SIM:"):
                batch.append(unit)
                continue
            if not flush():
                return out
            answer = self._control(unit)
            if answer is not None:
                out.extend(self._deliver(Reply(answer.encode("ascii") + b"\n")))
        flush()
        return out

    def _no_hit(self) -> bool:
        return self._fault("no_hit") is not None

    def _deliver(self, reply: Reply) -> list[Chunk]:
        delay = 0.0
        slow = self._fault("slow")
        if slow:
            delay = slow.params["delay"]
        data = reply.data
        garbage = self._fault("garbage")
        if garbage:
            data = garbage_bytes(garbage) + data
        if reply.binary:
            drop = self._fault("drop")
            if drop:
                self.closed = True
                return [Chunk(data[: int(len(data) * drop.params["keep"])], delay, close=True)]
            truncate = self._fault("truncate")
            if truncate:
                return [Chunk(data[: int(len(data) * truncate.params["keep"])], delay, until=reply.ready)]
        return [Chunk(data, delay, until=reply.ready)]

    # ------------------------------------------------------------- control
    def _control(self, text: str) -> str | None:
        head, _, arg = text.partition(" ")
        head, arg = head.upper(), arg.strip()
        analyzer = self.analyzer
        try:
            if head == "SIM:FAULT?":
                live = [f.describe() for f in self.faults if not f.exhausted]
                return ";".join(live) if live else "NONE"
            if head == "SIM:FAULT":
                if arg.upper() == "CLEAR":
                    self.faults.clear()
                else:
                    self.arm(arg)
                return None
            if head == "SIM:HITS?":
                return str(getattr(analyzer.source, "hits_drawn", 0))
            if head == "SIM:TIME?":
                return repr(analyzer.time_scale)
            if head == "SIM:TIME":
                scale = float(arg)
                if not (math.isfinite(scale) and scale >= 0):
                    raise ValueError("time scale must be >= 0")
                analyzer.time_scale = scale
                return None
            source = analyzer.source
            if not isinstance(source, PhysicsSource):
                raise ValueError(f"{head} needs the physics source, not a replay")
            if head == "SIM:NOISE?":
                return "1" if source.noise.enabled else "0"
            if head == "SIM:NOISE":
                if arg not in ("0", "1"):
                    raise ValueError("SIM:NOISE takes 0 or 1")
                source.set_noise(arg == "1")
            elif head == "SIM:SEED":
                source.reseed(int(arg))
            elif head == "SIM:SCEN?":
                return source.specimen.name
            elif head == "SIM:SCEN":
                name, spec = arg.lower(), source.specimen
                analyzer.source = PhysicsSource(
                    name,
                    source.hammer,
                    source.noise,
                    source.seed,
                    force_at_m=spec.force_at_m,
                    sensor_at_m=spec.sensor_at_m,
                    damping=spec.damping if name == CUSTOM and spec.name == CUSTOM else None,
                )
            elif head in ("SIM:FORCE?", "SIM:SENSOR?"):
                spec = source.specimen
                return repr(spec.force_at_m if head == "SIM:FORCE?" else spec.sensor_at_m)
            elif head == "SIM:FORCE":
                source.move(force_at_m=_metres(head, arg))
            elif head == "SIM:SENSOR":
                source.move(sensor_at_m=_metres(head, arg))
            elif head == "SIM:DAMP?":
                return ",".join(repr(float(v)) for v in source.specimen.damping.ravel())
            elif head == "SIM:DAMP":
                spec = source.specimen
                damping = parse_damping_matrix(arg)
                source.use(build_specimen(CUSTOM, spec.force_at_m, spec.sensor_at_m, damping=damping))
            elif head == "SIM:HAMMER":
                source.hammer = adjusted(source.hammer, arg)
            else:
                raise ValueError(f"unknown simulator command {head}")
        except ValueError as exc:
            with analyzer.lock:
                analyzer.push_error(3, str(exc))
        return None


def _metres(head: str, arg: str) -> float:
    """A position as ``SIM:FORCE``/``SIM:SENSOR`` take it: metres, a bare number or one
    followed by ``M``; ValueError naming the command otherwise (the beam checks the range)."""
    text = arg.strip().upper()
    if text.endswith("M"):
        text = text[:-1].strip()
    try:
        return float(text)
    except ValueError:
        raise ValueError(f"{head} takes a position in metres from the clamp, got {arg!r}") from None
