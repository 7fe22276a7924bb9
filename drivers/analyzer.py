"""The HP 35660A Dynamic Signal Analyzer driver.

Knows the analyzer's commands and replies, nothing of files or beams. Every
exchange runs under the transport's thread lock. A failed exchange that is safe
to repeat (a setting, a query, a dump) is retried a bounded number of times,
after a device clear (a timeout, a garbled or truncated reply) or a reconnect (a
lost link); what cannot be repeated, or keeps failing, ends in a clear error.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import TypeVar

from drivers.commands import COMMANDS, STATUS_BITS, ascii_message, command, parse_reply, replies
from drivers.dumps import DumpsMixin
from drivers.errors import (
    ConnectionLost,
    DriverError,
    InstrumentError,
    InstrumentTimeout,
    Interrupted,
    ProtocolError,
)
from drivers.record import record_length_s
from drivers.settings import ChannelSetup, ImpactSettings, Window
from drivers.transport import Transport

log = logging.getLogger(__name__)
T = TypeVar("T")

#: How long a technician may take to hit once the analyzer is armed, s (default).
HIT_ALLOWANCE_S = 60.0
#: After a timeout, the query that tells a live instrument from a silent one: it
#: changes nothing, and leaves the error queue to whoever asks ERR?.
PROBE = "ID?"
#: How long to wait for the probe's reply before calling the instrument silent, s.
PROBE_TIMEOUT_S = 0.5


@dataclass(frozen=True)
class Status:
    """The analyzer's status bits (STA?)."""

    bits: int

    def __getattr__(self, name: str) -> bool:
        if name in STATUS_BITS:
            return bool(self.bits & STATUS_BITS[name])
        raise AttributeError(name)

    def __str__(self) -> str:
        names = [n for n, b in STATUS_BITS.items() if self.bits & b]
        return ", ".join(names) or "idle"


class HP35660A(DumpsMixin):
    """Drive an HP 35660A through a ``Transport``.

    retries : extra attempts for an exchange that failed but may be repeated.
    hit_allowance_s : how long to wait for the technician's hit before giving up.
    """

    def __init__(
        self, transport: Transport, retries: int = 2, hit_allowance_s: float = HIT_ALLOWANCE_S
    ) -> None:
        if retries < 0:
            raise ValueError("retries must be >= 0")
        self.transport = transport
        self.retries = retries
        self.hit_allowance_s = hit_allowance_s
        #: Set from another thread to end the current and every later wait with Interrupted.
        self.interrupt = threading.Event()
        self._record_length_s: float | None = None
        self._recovery_error: DriverError | None = None

    @classmethod
    def open(
        cls, resource: str, timeout_s: float = 5.0, lock_file: bool = True, **kwargs: object
    ) -> HP35660A:
        from drivers.resources import open_transport

        transport = open_transport(resource, timeout_s, lock_file)
        try:
            return cls(transport, **kwargs)  # type: ignore[arg-type]
        except BaseException:
            transport.close()  # a bad argument must not leave the link (and its lock) held
            raise

    def close(self) -> None:
        self.transport.close()

    def __enter__(self) -> HP35660A:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ------------------------------------------------------------ exchanges
    def _exchange(self, what: str, action: Callable[[], T], repeatable: bool = True) -> T:
        # The lock covers the retries and the recovery too: between a timed-out
        # attempt and its clean-up no other thread may read the late reply.
        with self.transport.lock:
            last: DriverError | None = None
            silent = alive = False
            self._recovery_error = None
            for attempt in range(self.retries + 1):
                try:
                    return action()
                except (InstrumentTimeout, ProtocolError, ConnectionLost) as exc:
                    last = exc
                    if not repeatable or attempt == self.retries:
                        break
                    log.warning(
                        "%s: %s; recovering, attempt %d of %d", what, exc, attempt + 2, self.retries + 1
                    )
                    self._recover(exc)
                    if isinstance(exc, InstrumentTimeout):
                        alive = self._instrument_answers()
                        if not alive:
                            silent = True  # another attempt would only wait out the timeout again
                            break
            assert last is not None
            # Leave the link clean for whoever talks next: a late or partial reply of
            # this failed exchange must never be read as the answer to another.
            self._recover(last)
            if isinstance(last, ConnectionLost) and self._recovery_error is not None:
                raise self._recovery_error  # "connection refused" says more than "not open"
            if silent:
                last.instrument_answers = False  # type: ignore[attr-defined]
                last.args = (f"{last.args[0]} (the instrument answers nothing, not even {PROBE})",)
            elif repeatable and self.retries:
                # An instrument that answers the probe but not this may have refused it:
                # the reason is in its error queue, left there for errors().
                hint = f"; it answers {PROBE}, errors() may say why" if alive else ""
                if isinstance(last, InstrumentTimeout):
                    last.instrument_answers = alive
                last.args = (f"{last.args[0]} (after {attempt + 1} attempt{'s' if attempt else ''}{hint})",)
            raise last

    def _instrument_answers(self) -> bool:
        """After a timeout: does the instrument answer the probe (ID?) within a short
        timeout? Only that: an error it queued for the failed exchange stays queued
        for ``errors()``; popping it here would lose it and blame this exchange."""
        saved = self.transport.timeout_s
        self.transport.timeout_s = min(PROBE_TIMEOUT_S, saved)
        try:
            self.transport.write(PROBE.encode("ascii"))
            _decode_line(self.transport.read_line(), PROBE)
        except DriverError as exc:
            self._recover(exc)
            return False
        finally:
            self.transport.timeout_s = saved
        return True

    def _recover(self, exc: DriverError) -> None:
        try:
            if isinstance(exc, ConnectionLost):
                self.transport.reconnect()
            else:
                self.transport.clear()
        except DriverError as again:
            log.warning("recovery failed: %s", again)
            self._recovery_error = again

    def send(self, text: str) -> None:
        """Send a command as typed; it must not be one that answers (use ``query``)."""
        data = ascii_message(text)
        if answering := replies(text):
            raise ValueError(f"{text!r} answers ({answering[0]}): use query, or a fetch for a dump")
        repeatable = _repeatable(text)
        self._exchange(text, lambda: self.transport.write(data), repeatable)

    def query(self, text: str) -> str:
        """Send a message whose one reply is one line; return it without CR LF."""
        data = ascii_message(text)
        kinds = replies(text)
        if kinds != ["line"]:
            what = "no reply" if not kinds else f"replies {' + '.join(kinds)}"
            raise ValueError(f"{text!r} {what}: query takes a message with one one-line reply")

        def ask() -> str:
            self.transport.write(data)
            return _decode_line(self.transport.read_line(), text)

        return self._exchange(text, ask, _repeatable(text))

    def query_values(self, text: str, expected: int | None = None) -> list[float]:
        """A query whose reply is comma-separated numbers."""
        reply = self.query(text)
        try:
            values = [float(v) for v in reply.split(",")]
        except ValueError:
            raise ProtocolError(text, "expected numbers", reply.encode()) from None
        if expected is not None and len(values) != expected:
            raise ProtocolError(text, f"expected {expected} numbers, got {len(values)}", reply.encode())
        if not all(math.isfinite(v) for v in values):
            raise ProtocolError(text, "non-finite number in the reply", reply.encode())
        return values

    def read(self, mnemonic: str) -> float | int | bool | str:
        """A setting read back (``read("FRS")`` asks FRS?) or a one-line query
        (``read("AVMD?")``), typed by the command table: float (SI), int, bool or str."""
        entry = COMMANDS.get(mnemonic)
        if entry is None:
            raise KeyError(f"{mnemonic} is not in the driver's command table")
        query = entry.readback or mnemonic
        reply = self.query(query)
        try:
            return parse_reply(query, reply)
        except ValueError as exc:
            raise ProtocolError(query, str(exc), reply.encode()) from None

    def set(self, mnemonic: str, value: object = None) -> None:
        """Send one table entry with its argument, spelled by the table:
        ``set("FRS", 200.0)`` sends ``FRS 200 HZ``."""
        self.send(command(mnemonic, value).decode("ascii"))

    # ------------------------------------------------------------ instrument
    def identify(self) -> str:
        """The instrument's identification (``HP35660A``)."""
        return self.query("ID?")

    def reset(self) -> None:
        self.send("RST")
        self._record_length_s = None

    def status(self) -> Status:
        bits = self.read("STA?")
        if not 0 <= bits <= 255:  # type: ignore[operator]
            raise ProtocolError("STA?", "expected a status byte", str(bits).encode())
        return Status(int(bits))

    def errors(self) -> list[tuple[int, str]]:
        """Drain the instrument's error queue, oldest first."""
        found = []
        for _ in range(64):
            reply = self.query("ERR?")
            code_text, _, message = reply.partition(",")
            if not code_text.strip().lstrip("+-").isdigit():
                raise ProtocolError("ERR?", 'expected code,"message"', reply.encode())
            code = int(code_text)
            if code == 0:
                return found
            found.append((code, message.strip().strip('"')))
        raise ProtocolError("ERR?", "the error queue does not empty")

    def check_errors(self) -> None:
        """Raise InstrumentError for the oldest queued instrument error, if any."""
        found = self.errors()
        if found:
            code, message = found[0]
            more = f" (and {len(found) - 1} more)" if len(found) > 1 else ""
            raise InstrumentError(code, message + more)

    # ------------------------------------------------------------ settings
    def configure(self, settings: ImpactSettings) -> ImpactSettings:
        """Apply ``settings`` and return them as the analyzer holds them (span and
        ranges rounded up to what it offers)."""
        self.send("CLER")  # errors left by earlier commands must not be blamed on these settings
        messages = settings.commands()
        for message in messages[:3]:  # up to the span
            self.send(message.decode())
        self.check_errors()
        # The analyzer rounds the span up; the baseband center follows the span it chose,
        # and the pre-trigger must fit the record of that span.
        actual_span = float(self.read("FRS"))
        record = record_length_s(actual_span)
        if settings.pre_trigger_s > record * (1 + 1e-9):
            raise ValueError(
                f"pre-trigger {settings.pre_trigger_s:g} s is longer than the {record:g} s record "
                f"of the {actual_span:g} Hz span the analyzer chose"
            )
        for message in settings.commands(actual_span_hz=actual_span)[3:]:
            self.send(message.decode())
        self.check_errors()
        actual = self.read_settings()
        self._record_length_s = actual.record_length_s
        return actual

    def read_settings(self) -> ImpactSettings:
        """The impact-test settings the analyzer holds now."""

        # The order of the queries is the golden transcripts' (tests/drivers/test_protocol.py).
        span = float(self.read("FRS"))
        center = float(self.read("CF"))
        channels = []
        for ch in (1, 2):
            channels.append(
                ChannelSetup(
                    window=Window(self.read(f"WIN{ch}")),
                    sensitivity_v_per_eu=float(self.read(f"SNS{ch}")),
                    range_v=None if self.read(f"AU{ch}?") else float(self.read(f"RNG{ch}")),
                    force_width_s=float(self.read(f"FWD{ch}")),
                    exp_decay_s=float(self.read(f"EXD{ch}")),
                    ac_coupled=bool(self.read(f"C{ch}AC")),
                )
            )
        source = str(self.read("TSRC"))
        level_v = float(self.read("TLVL"))
        trigger_channel = channels[1] if source == "CH2" else channels[0]
        averaging = self.read("AVMD?")
        settings = ImpactSettings(
            span_hz=span,
            center_hz=None if math.isclose(center, span / 2, rel_tol=1e-9) else center,
            hammer=channels[0],
            accelerometer=channels[1],
            trigger_source=source,
            trigger_level_eu=level_v / trigger_channel.sensitivity_v_per_eu,
            trigger_slope=str(self.read("TSLP")),
            pre_trigger_s=max(0.0, -float(self.read("TDLY"))),
            averages=1 if averaging == "AVOF" else int(self.read("NAVG")),
            preview=bool(self.read("PRVW")),
        )
        self._record_length_s = settings.record_length_s
        return settings

    # ------------------------------------------------------------ measuring
    def _record_length(self) -> float:
        if self._record_length_s is None:
            self._record_length_s = record_length_s(float(self.read("FRS")))
        return self._record_length_s

    def start(self) -> None:
        """Clear the average and arm the trigger (STRT); InstrumentError if it refuses."""
        self._record_length()
        self.send("STRT")
        if self.status().error:
            self.check_errors()

    def accept(self) -> None:
        """Preview: put the pending hit into the average."""
        self._exchange("ACPT", lambda: self.transport.write(b"ACPT"), repeatable=False)
        self._raise_if_error()

    def reject(self) -> None:
        """Preview: throw the pending hit away and re-arm."""
        self._exchange("RJCT", lambda: self.transport.write(b"RJCT"), repeatable=False)
        self._raise_if_error()

    def _raise_if_error(self) -> None:
        if self.status().error:
            self.check_errors()

    def averages_done(self) -> int:
        return int(self.read("AVG?"))

    def wait_for(self, done: Callable[[Status], bool], what: str, timeout_s: float | None = None) -> Status:
        """Poll the status until ``done(status)``; the default timeout is the hit
        allowance plus twice the record length. Polls back off from 5 ms to 0.2 s."""
        timeout = (
            timeout_s if timeout_s is not None else self.hit_allowance_s + 2 * self._record_length() + 1.0
        )
        deadline = time.monotonic() + timeout
        pause = 0.005
        while True:
            if self.interrupt.is_set():
                raise Interrupted(f"{what}: interrupted")
            status = self.status()
            if status.error:
                self.check_errors()
            if done(status):
                return status
            if time.monotonic() >= deadline:
                hint = (
                    " (no trigger: is the hammer connected, is the trigger level right?)"
                    if status.waiting_for_trigger
                    else ""
                )
                raise InstrumentTimeout(f"{what}: not within {timeout:.3g} s; status {status}{hint}")
            self.interrupt.wait(min(pause, max(0.0, deadline - time.monotonic())))
            pause = min(pause * 1.5, 0.2)

    def wait_for_hit(self, timeout_s: float | None = None) -> Status:
        """Wait until the current hit is recorded: pending (preview) or in the average."""
        before = self.averages_done()
        return self.wait_for(
            lambda s: s.hit_pending or s.done or self.averages_done() > before, "waiting for a hit", timeout_s
        )

    def wait_until_done(self, timeout_s: float | None = None, averages: int | None = None) -> Status:
        """Wait until every average is in (SMSD-equivalent done bit)."""
        n = averages or 1
        timeout = (
            timeout_s
            if timeout_s is not None
            else n * (self.hit_allowance_s + 2 * self._record_length()) + 1.0
        )
        return self.wait_for(lambda s: s.done, "waiting for the measurement to finish", timeout)


def _repeatable(text: str) -> bool:
    """False if any command in the message would change the outcome when sent twice."""
    for part in text.replace(";", " ; ").split(";"):
        head = part.strip().split(" ")[0].upper()
        if head in COMMANDS and not COMMANDS[head].idempotent:
            return False
    return True


def _decode_line(raw: bytes, command_text: str) -> str:
    try:
        text = raw.decode("ascii")
    except UnicodeDecodeError:
        raise ProtocolError(command_text, "reply is not ASCII", raw) from None
    if any(ch < " " for ch in text):
        raise ProtocolError(command_text, "control characters in the reply", raw)
    return text
