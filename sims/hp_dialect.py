"""The 3562A-family mnemonic dialect of the simulated 35660A and 3562A
(docs/instrument.md): the command interpreter, its error queue and status bits.

The commands come from the simulator's own table (sims/command_table.py); what
differs between the two models (identity, lines, spans) comes from the Model.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from sims import command_table as ct
from sims.command_table import BY_MNEMONIC, ERRORS, Command, split_message
from sims.encoding import ascii_dump, float_block, line
from sims.reply import Reply
from sims.settings import AnalyzerSettings, check_center, coerce_range, coerce_span
from sims.traces import NoData, active_trace_values
from sims.units import ArgumentError, format_number

if TYPE_CHECKING:
    from sims.instrument import Analyzer

MAX_ERRORS = 32
MAX_COMMAND_CHARS = 4096


class CommandError(Exception):
    def __init__(self, code: int, detail: str) -> None:
        super().__init__(f"{ERRORS[code]}: {detail}")
        self.code = code
        self.detail = detail


class HpDialect:
    """Interprets mnemonic messages for ``analyzer``; errors as ``code,"Message: detail"``."""

    def __init__(self, analyzer: Analyzer) -> None:
        self.analyzer = analyzer
        self.errors: deque[tuple[int, str]] = deque()

    @property
    def m(self):
        return self.analyzer.measurement

    # --------------------------------------------------------------- errors
    def push_error(self, code: int, detail: str) -> None:
        """Queue error ``code`` (ERRORS); a full queue's last entry becomes code 8."""
        if len(self.errors) >= MAX_ERRORS:
            self.errors.pop()
            code, detail = 8, "error queue overflow"
        self.errors.append((code, f"{ERRORS[code]}: {detail}"))

    def source_error(self, detail: str) -> None:
        self.push_error(6, detail)

    def hardware_fault(self) -> None:
        self.push_error(7, "input A/D converter does not respond")

    def status(self) -> int:
        """STA?: the project's status bits (command_table.STATUS_*)."""
        m, bits = self.m, 0
        if m.state == "done":
            bits |= ct.STATUS_DONE
        if m.state == "waiting":
            bits |= ct.STATUS_WAITING_FOR_TRIGGER
        if m.last_record is not None:
            bits |= ct.STATUS_OVERLOAD_CH1 if m.last_record.overload[0] else 0
            bits |= ct.STATUS_OVERLOAD_CH2 if m.last_record.overload[1] else 0
        if self.errors or self.analyzer.hardware_fault:
            bits |= ct.STATUS_ERROR
        if m.state == "pending":
            bits |= ct.STATUS_HIT_PENDING
        if m.state == "measuring":
            bits |= ct.STATUS_MEASURING
        if m.paused_at is not None:
            bits |= ct.STATUS_PAUSED
        return bits

    serial_poll = status

    # -------------------------------------------------------------- commands
    def execute(self, message: str, on_start: Callable[[], bool] | None = None) -> list[Reply]:
        """Run every command in ``message``; replies of its queries, in order.
        ``on_start()`` is asked at each STRT whether the hammer never strikes."""
        replies: list[Reply] = []
        self.m.advance()
        for text in split_message(message):
            if len(text) > MAX_COMMAND_CHARS:
                self.push_error(8, f"command of {len(text)} characters")
                continue
            try:
                reply = self._execute_one(text, on_start)
            except CommandError as exc:
                self.push_error(exc.code, exc.detail)
                continue
            if reply is not None:
                replies.append(reply)
            self.m.advance()
        return replies

    def start(self, never_hit: bool = False) -> None:
        if self.analyzer.hardware_fault:
            raise CommandError(7, "input A/D converter does not respond")
        self.m.start(never_hit)

    def _execute_one(self, text: str, on_start: Callable[[], bool] | None) -> Reply | None:
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
        self._action(command, on_start)
        return None

    def _action(self, command: Command, on_start: Callable[[], bool] | None) -> None:
        m, meas = command.mnemonic, self.m
        s = meas.settings
        if m == "RST":
            meas.settings = AnalyzerSettings.preset(self.analyzer.model)
            self.errors.clear()
            self.analyzer.hardware_fault = False
            meas.reset()
        elif m == "LCL":
            pass
        elif m == "STRT":
            never_hit = bool(on_start()) if on_start is not None else False
            self.start(never_hit)
        elif m == "PAUS":
            meas.pause()
        elif m == "CONT":
            meas.resume()
        elif m in ("ACPT", "RJCT"):
            if meas.state != "pending":
                raise CommandError(6, f"{m} with no hit waiting for preview")
            if m == "ACPT":
                meas.accept_pending()
            else:
                meas.reject_pending()
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
        arg, name = command.argument, command.attribute
        s = self.m.settings
        model = self.analyzer.model
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
                value = coerce_span(value, model)  # type: ignore[arg-type]
                baseband = not s.zoom
                s.span_hz = value  # type: ignore[assignment]
                # Baseband stays baseband; a zoom keeps its center, moved in if need be.
                top = model.top_span_hz
                s.center_hz = value / 2 if baseband else min(max(s.center_hz, value / 2), top - value / 2)
                self._check_delay()
                self.m.reset()  # new geometry: the measurement starts over
                return
            if name == "center_hz":
                value = check_center(value, s.span_hz, model)  # type: ignore[arg-type]
                s.center_hz = value
                self._check_delay()
                self.m.reset()  # new geometry: the measurement starts over
                return
            if name in ("range1_v", "range2_v"):
                value = coerce_range(value, model)  # type: ignore[arg-type]
                setattr(s, "autorange" + name[5], 0)
            elif name == "trigger_delay_s" and value < -s.record_length_s * (1 + 1e-9):  # type: ignore[operator]
                raise ValueError(f"pre-trigger is at most one record ({s.record_length_s:g} s)")
        except ValueError as exc:
            raise CommandError(2, f"{command.mnemonic} {text.strip()}: {exc}") from None
        setattr(s, name, value)

    def _check_delay(self) -> None:
        s = self.m.settings
        s.trigger_delay_s = max(s.trigger_delay_s, -s.record_length_s)

    def _format_setting(self, command: Command) -> str:
        value = getattr(self.m.settings, command.attribute)  # type: ignore[arg-type]
        arg = command.argument
        assert arg is not None
        if arg.kind == "quantity":
            return format_number(value)
        return str(value)

    def _query(self, name: str) -> Reply | None:
        meas = self.m
        s = meas.settings
        if name == "ID?":
            return Reply(line(self.analyzer.model.identity))
        if name == "SMSD":
            return Reply(line("1" if meas.state == "done" else "0"))
        if name == "DISP?":
            return Reply(line(s.display[s.trace]))
        if name == "TRC?":
            return Reply(line(s.trace))
        if name == "STA?":
            return Reply(line(str(self.status())))
        if name == "ERR?":
            if not self.errors:
                return Reply(line('0,"No error"'))
            code, message = self.errors.popleft()
            return Reply(line(f'{code},"{message}"'))
        if name == "OVLD?":
            over = meas.overload
            return Reply(line(f"{int(over[0])},{int(over[1])}"))
        if name == "AVG?":
            return Reply(line(str(meas.average.count)))
        if name == "AVMD?":
            return Reply(line(s.averaging))
        if name in ("AU1?", "AU2?"):
            return Reply(line(str(s.channel("autorange", int(name[2])))))
        if name in ("DSAN", "DSAS", "DDAN", "DDAS"):
            values = s.state_values() if name.startswith("DS") else self._trace_values()
            return Reply(float_block(values), True) if name.endswith("N") else Reply(ascii_dump(values))
        raise CommandError(1, name)  # pragma: no cover

    def _trace_values(self) -> np.ndarray:
        meas = self.m
        try:
            return active_trace_values(meas.settings, meas.average, meas.last_record)
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
