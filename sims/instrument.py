"""The simulated HP 35660A: command interpreter, measurement state machine and traces.

Time: the measurement advances lazily, on each command, from a monotonic clock
scaled by ``time_scale`` (1.0 = real time, 0 = every hit lands and records at
once). Physics is drawn when the analyzer arms, so the data depend only on the
seed and the command sequence, never on timing.

Thread-safe: front ends serving several clients share one instrument, as clients
share one box on a GPIB bus; each message is executed under a lock.
"""

from __future__ import annotations

import math
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from sims import command_table as ct
from sims.acquisition import Record
from sims.command_table import BY_MNEMONIC, ERRORS, Command, split_message
from sims.dsp import Average, line_spectrum, peak_scale, window
from sims.encoding import ascii_dump, float_block, line
from sims.settings import MAX_SPAN_HZ, RANGES_V, AnalyzerSettings, check_center, coerce_range, coerce_span
from sims.sources import PhysicsSource, ReplaySource, SourceError
from sims.traces import NoData, active_trace_values
from sims.units import ArgumentError, format_number

IDENTITY = "HP35660A"
MAX_ERRORS = 32
MAX_COMMAND_CHARS = 4096

Source = PhysicsSource | ReplaySource


@dataclass(frozen=True)
class Reply:
    """Bytes the instrument has to send; ``binary`` for ``#A`` blocks."""

    data: bytes
    binary: bool = False


class CommandError(Exception):
    def __init__(self, code: int, detail: str) -> None:
        super().__init__(f"{ERRORS[code]}: {detail}")
        self.code = code
        self.detail = detail


class Analyzer:
    """One simulated instrument. ``execute(message)`` takes one or more commands
    separated by ``;`` or line ends and returns the replies of its queries."""

    def __init__(
        self,
        source: Source | None = None,
        time_scale: float = 0.0,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.source: Source = source if source is not None else PhysicsSource()
        self.time_scale = float(time_scale)
        self.clock = clock
        self.lock = threading.RLock()
        self.settings = AnalyzerSettings()
        self.errors: deque[tuple[int, str]] = deque()
        self.hardware_fault = False
        self._reset_measurement()

    # ------------------------------------------------------------------ state
    def _reset_measurement(self) -> None:
        self.state = "idle"  # idle, waiting, measuring, pending, done
        self.paused_at: float | None = None
        self.average = Average()
        self.last_record: Record | None = None
        self._next: Record | None = None
        self._trigger_at = math.inf
        self._done_at = math.inf
        self._never_hit = False

    def push_error(self, code: int, detail: str) -> None:
        if len(self.errors) >= MAX_ERRORS:
            self.errors.pop()
            code, detail = 8, "error queue overflow"
        self.errors.append((code, f"{ERRORS[code]}: {detail}"))

    def _target(self) -> int:
        return 1 if self.settings.averaging == "AVOF" else self.settings.n_averages

    def _arm(self, at: float) -> None:
        """Draw the next hit and schedule its trigger and end of record."""
        self.state = "waiting"
        if self._never_hit:
            self._next, self._trigger_at, self._done_at = None, math.inf, math.inf
            return
        try:
            timed = self.source.next_record(self.settings)
        except SourceError as exc:
            self.push_error(6, str(exc))
            self.state = "idle"
            return
        if timed is None:
            self._next, self._trigger_at, self._done_at = None, math.inf, math.inf
            return
        self._next = timed.record
        s = self.time_scale
        self._trigger_at = at + timed.trigger_after_s * s
        record_end = self.settings.trigger_delay_s + self.settings.record_length_s
        self._done_at = self._trigger_at + max(0.0, record_end) * s

    def _advance(self) -> None:
        if self.paused_at is not None:
            return
        now = self.clock()
        while True:
            if self.state == "waiting" and now >= self._trigger_at:
                self.state = "measuring"
            if self.state != "measuring" or now < self._done_at:
                return
            record = self._next
            assert record is not None
            done_at = self._done_at
            self.last_record = record
            if self._autorange(record):
                self._arm(done_at)
                continue
            if self.settings.preview:
                self.state = "pending"
                return
            self._accept(record, done_at)

    def _autorange(self, record: Record) -> bool:
        """Up-range an overloaded channel that has autorange on; True if the record is
        dropped for a new one. At the top range there is nowhere to go: the
        overloaded record stays, flagged."""
        dropped = False
        for ch in (1, 2):
            if record.overload[ch - 1] and self.settings.channel("autorange", ch):
                current = float(self.settings.channel("range", ch))  # type: ignore[arg-type]
                peak = record.peak_v[ch - 1]
                wanted = max(current, peak) * 1.2 if math.isfinite(peak) else current * 2
                new = coerce_range(min(wanted, RANGES_V[-1]))
                if new > current:
                    setattr(self.settings, f"range{ch}_v", new)
                    dropped = True
        return dropped

    def _accept(self, record: Record, at: float) -> None:
        s = self.settings
        fs, n = record.sample_rate_hz, record.force_n.size
        zoom = np.iscomplexobj(record.force_n)
        win1 = window(s.window1, n, fs, s.force_width1_s, s.exp_decay1_s)
        win2 = window(s.window2, n, fs, s.force_width2_s, s.exp_decay2_s)
        self.average.add(
            line_spectrum(record.force_n, win1),
            line_spectrum(record.acceleration_m_s2, win2),
            peak_scale(win1, zoom),
            peak_scale(win2, zoom),
            record.overload,
        )
        if self.average.count >= self._target():
            self.state = "done"
        else:
            self._arm(at)

    def status(self) -> int:
        bits = 0
        if self.state == "done":
            bits |= ct.STATUS_DONE
        if self.state == "waiting":
            bits |= ct.STATUS_WAITING_FOR_TRIGGER
        if self.last_record is not None:
            bits |= ct.STATUS_OVERLOAD_CH1 if self.last_record.overload[0] else 0
            bits |= ct.STATUS_OVERLOAD_CH2 if self.last_record.overload[1] else 0
        if self.errors or self.hardware_fault:
            bits |= ct.STATUS_ERROR
        if self.state == "pending":
            bits |= ct.STATUS_HIT_PENDING
        if self.state == "measuring":
            bits |= ct.STATUS_MEASURING
        if self.paused_at is not None:
            bits |= ct.STATUS_PAUSED
        return bits

    # -------------------------------------------------------------- commands
    def execute(self, message: str) -> list[Reply]:
        """Run every command in ``message``; replies of its queries, in order."""
        replies: list[Reply] = []
        with self.lock:
            self._advance()
            for text in split_message(message):
                if len(text) > MAX_COMMAND_CHARS:
                    self.push_error(8, f"command of {len(text)} characters")
                    continue
                try:
                    reply = self._execute_one(text)
                except CommandError as exc:
                    self.push_error(exc.code, exc.detail)
                    continue
                if reply is not None:
                    replies.append(reply)
                self._advance()
        return replies

    def start(self, never_hit: bool = False) -> None:
        """STRT; ``never_hit`` arms a hammer that never strikes (the trigger-timeout fault)."""
        with self.lock:
            try:
                self._start(never_hit)
            except CommandError as exc:
                self.push_error(exc.code, exc.detail)

    def enter_hardware_fault(self) -> None:
        with self.lock:
            self.hardware_fault = True
            self.push_error(7, "input A/D converter does not respond")

    def device_clear(self) -> None:
        """GPIB device clear: nothing persistent changes (buffers live in the front ends)."""

    def _start(self, never_hit: bool = False) -> None:
        if self.hardware_fault:
            raise CommandError(7, "input A/D converter does not respond")
        self._reset_measurement_data()
        self._never_hit = never_hit
        self._arm(self.clock())

    def _reset_measurement_data(self) -> None:
        self.average = Average()
        self.last_record = None
        self.paused_at = None

    def _execute_one(self, text: str) -> Reply | None:
        command, argument, is_query = _resolve(text)
        m = command.mnemonic
        if command.kind == "setting":
            if is_query:
                return Reply(line(self._format_setting(command)))
            if argument is None:
                raise CommandError(3, f"{m} needs a value")
            self._apply_setting(command, argument)
            return None
        if argument is not None:
            raise CommandError(3, f"{m} takes no value")
        if command.kind == "query":
            return self._query(m)
        self._action(command)
        return None

    def _action(self, command: Command) -> None:
        m, s = command.mnemonic, self.settings
        if m == "RST":
            self.settings = AnalyzerSettings()
            self.errors.clear()
            self.hardware_fault = False
            self._reset_measurement()
        elif m == "LCL":
            pass
        elif m == "STRT":
            self._start()
        elif m == "PAUS":
            if self.paused_at is None and self.state in ("waiting", "measuring"):
                self.paused_at = self.clock()
        elif m == "CONT":
            if self.paused_at is not None:
                shift = self.clock() - self.paused_at
                self._trigger_at += shift
                self._done_at += shift
                self.paused_at = None
        elif m in ("ACPT", "RJCT"):
            if self.state != "pending":
                raise CommandError(6, f"{m} with no hit waiting for preview")
            assert self.last_record is not None
            if m == "ACPT":
                self._accept(self.last_record, self.clock())
            else:
                self._arm(self.clock())
        elif command.attribute == "window":
            s.window1 = s.window2 = m
        elif command.attribute == "averaging":
            s.averaging = m
        elif command.attribute == "measurement":
            s.measurement = m
        elif command.attribute == "mode":
            s.mode = m
        elif command.attribute in ("autorange1", "autorange2"):
            setattr(s, command.attribute, 1)
        elif command.attribute == "trace":
            s.trace = m[-1]
        elif command.attribute == "display":
            s.display[s.trace] = m
        elif m == "CLER":
            self.errors.clear()
        else:  # pragma: no cover - every table entry is handled above
            raise CommandError(1, m)

    def _apply_setting(self, command: Command, text: str) -> None:
        arg, s, name = command.argument, self.settings, command.attribute
        assert arg is not None
        assert name is not None
        try:
            value = arg.parse(text)
        except ArgumentError as exc:
            raise CommandError(exc.code, f"{command.mnemonic}: {exc}") from None
        if arg.kind != "choice" and not (arg.low <= value <= arg.high):  # type: ignore[operator]
            raise CommandError(2, f"{command.mnemonic} {text.strip()}")
        try:
            if name == "span_hz":
                value = coerce_span(value)  # type: ignore[arg-type]
                baseband = not s.zoom
                s.span_hz = value  # type: ignore[assignment]
                # Baseband stays baseband; a zoom keeps its center, moved in if need be.
                s.center_hz = (
                    value / 2 if baseband else min(max(s.center_hz, value / 2), MAX_SPAN_HZ - value / 2)
                )
                self._check_delay()
                self._reset_measurement()  # new geometry: the measurement starts over
                return
            if name == "center_hz":
                value = check_center(value, s.span_hz)  # type: ignore[arg-type]
                s.center_hz = value
                self._check_delay()
                self._reset_measurement()  # new geometry: the measurement starts over
                return
            if name in ("range1_v", "range2_v"):
                value = coerce_range(value)  # type: ignore[arg-type]
                setattr(s, "autorange" + name[5], 0)
            elif name == "trigger_delay_s" and value < -s.record_length_s * (1 + 1e-9):  # type: ignore[operator]
                raise ValueError(f"pre-trigger is at most one record ({s.record_length_s:g} s)")
        except ValueError as exc:
            raise CommandError(2, f"{command.mnemonic} {text.strip()}: {exc}") from None
        setattr(s, name, value)

    def _check_delay(self) -> None:
        s = self.settings
        s.trigger_delay_s = max(s.trigger_delay_s, -s.record_length_s)

    def _format_setting(self, command: Command) -> str:
        value = getattr(self.settings, command.attribute)  # type: ignore[arg-type]
        arg = command.argument
        assert arg is not None
        if arg.kind == "quantity":
            return format_number(value)
        return str(value)

    def _query(self, m: str) -> Reply | None:
        s = self.settings
        if m == "ID?":
            return Reply(line(IDENTITY))
        if m == "SMSD":
            return Reply(line("1" if self.state == "done" else "0"))
        if m == "DISP?":
            return Reply(line(s.display[s.trace]))
        if m == "TRC?":
            return Reply(line(s.trace))
        if m == "STA?":
            return Reply(line(str(self.status())))
        if m == "ERR?":
            if not self.errors:
                return Reply(line('0,"No error"'))
            code, message = self.errors.popleft()
            return Reply(line(f'{code},"{message}"'))
        if m == "OVLD?":
            over = self.last_record.overload if self.last_record is not None else (False, False)
            return Reply(line(f"{int(over[0])},{int(over[1])}"))
        if m == "AVG?":
            return Reply(line(str(self.average.count)))
        if m == "AVMD?":
            return Reply(line(s.averaging))
        if m in ("AU1?", "AU2?"):
            return Reply(line(str(s.channel("autorange", int(m[2])))))
        if m in ("DSAN", "DSAS", "DDAN", "DDAS"):
            values = s.state_values() if m.startswith("DS") else self._trace_values()
            return Reply(float_block(values), True) if m.endswith("N") else Reply(ascii_dump(values))
        raise CommandError(1, m)  # pragma: no cover

    def _trace_values(self) -> np.ndarray:
        try:
            return active_trace_values(self.settings, self.average, self.last_record)
        except NoData as exc:
            raise CommandError(5, str(exc)) from None


def _resolve(text: str) -> tuple[Command, str | None, bool]:
    """(command, argument text or None, is a query of a setting)."""
    head, _, rest = text.partition(" ")
    head = head.upper()
    rest = rest.strip() or None
    if head in BY_MNEMONIC:
        return BY_MNEMONIC[head], rest, False
    if head.endswith("?") and head[:-1] in BY_MNEMONIC and BY_MNEMONIC[head[:-1]].kind == "setting":
        if rest is not None:
            raise CommandError(3, f"{head} takes no value")
        return BY_MNEMONIC[head[:-1]], None, True
    # A value fused to its mnemonic, as the 3562A accepts (C1AC1, FRS2KHZ, NAVG5).
    for size in range(len(head) - 1, 0, -1):
        prefix, tail = head[:size], head[size:]
        cmd = BY_MNEMONIC.get(prefix)
        if cmd is not None and cmd.kind == "setting" and (tail[0].isdigit() or tail[0] in "+-."):
            return cmd, tail + (" " + rest if rest else ""), False
    raise CommandError(1, head)
