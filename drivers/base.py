"""The driver of the HP dynamic signal analyzer family: what every dialect shares.

``SignalAnalyzer`` holds the link, the exchanges, the error queue and the settings
(configure and read-back, walked from the dialect's table of settings,
drivers/setting_table.py); a dialect's class (the HP mnemonics of the 35660A and 3562A
in drivers/hp_mnemonic.py, the SCPI of the 35665A/35670A in drivers/scpi_analyzer.py)
adds its commands. ``drivers.family.open_analyzer`` finds out what answers and returns
the right one.

Knows the analyzer's commands and replies, nothing of files or beams. Every
exchange runs under the transport's thread lock. A failed exchange that is safe
to repeat (a setting, a query, a dump) is retried a bounded number of times,
after a device clear (a timeout, a garbled or truncated reply) or a reconnect (a
lost link); what cannot be repeated, or keeps failing, ends in a clear error.
"""

from __future__ import annotations

import contextlib
import logging
import math
import threading
import time
from collections.abc import Callable
from typing import TypeVar

from drivers.detection import open_driver
from drivers.dialects import Dialect, Geometry, identity_mismatch
from drivers.errors import (
    ConnectionLost,
    DriverError,
    InstrumentError,
    InstrumentTimeout,
    Interrupted,
    ProtocolError,
    UnknownInstrument,
)
from drivers.messages import Status, ascii_message, decode_line
from drivers.setting_table import SettingsTable, read_fields, write_steps
from drivers.settings import ImpactSettings
from drivers.trace import Trace
from drivers.transport import Transport

log = logging.getLogger(__name__)
T = TypeVar("T")

#: How long a technician may take to hit once the analyzer is armed, s (default).
HIT_ALLOWANCE_S = 60.0
#: How long to wait for the probe's reply before calling the instrument silent, s.
PROBE_TIMEOUT_S = 0.5


class SignalAnalyzer:
    """Drive an analyzer of the family through a ``Transport``, in ``dialect``.

    retries : extra attempts for an exchange that failed but may be repeated.
    hit_allowance_s : how long to wait for the technician's hit before giving up.
    detection : how the dialect was chosen, one line (``daq identify`` prints it).
    forced : the dialect was given, not detected: ``identify`` then checks that the
        instrument's reply belongs to it.
    """

    def __init__(
        self,
        transport: Transport,
        dialect: Dialect,
        retries: int = 2,
        hit_allowance_s: float = HIT_ALLOWANCE_S,
        detection: str = "",
        forced: bool = False,
    ) -> None:
        if retries < 0:
            raise ValueError("retries must be >= 0")
        self.transport = transport
        self.dialect = dialect
        self.detection = detection or f"the {dialect.name} dialect was given"
        self.forced = forced
        #: The instrument's reply to its identity query, once ``identify`` has asked.
        self.identification: str | None = None
        self.retries = retries
        self.hit_allowance_s = hit_allowance_s
        #: Set from another thread to end the current and every later wait with Interrupted.
        self.interrupt = threading.Event()
        self._record_length_s: float | None = None
        self._recovery_error: DriverError | None = None

    #: The ``Dialect.family`` a dialect class drives (``hp``, ``scpi``).
    family: str = ""

    @classmethod
    def open(
        cls,
        resource: str,
        timeout_s: float = 5.0,
        lock_file: bool = True,
        dialect: Dialect | str | None = None,
        **kwargs: object,
    ) -> SignalAnalyzer:
        """Open ``resource`` and drive what answers with this class (its dialect detected,
        or ``dialect`` forced): UnknownInstrument if it speaks another family's. Any
        dialect of the family: ``drivers.family.open_analyzer``."""

        def this_class(found: Dialect) -> type[SignalAnalyzer]:
            if found.family != cls.family:
                raise UnknownInstrument(f"{resource}: the {found.name} dialect answers, not {cls.__name__}'s")
            return cls

        return open_driver(resource, this_class, timeout_s, lock_file, dialect, **kwargs)

    def close(self) -> None:
        self.transport.close()

    def __enter__(self) -> SignalAnalyzer:
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
                last.args = (f"{last.args[0]} (the instrument answers nothing, not even {self.probe})",)
            elif repeatable and self.retries:
                # An instrument that answers the probe but not this may have refused it:
                # the reason is in its error queue, left there for errors().
                hint = f"; it answers {self.probe}, errors() may say why" if alive else ""
                if isinstance(last, InstrumentTimeout):
                    last.instrument_answers = alive
                last.args = (f"{last.args[0]} (after {attempt + 1} attempt{'s' if attempt else ''}{hint})",)
            raise last

    @property
    def probe(self) -> str:
        """After a timeout, the query that tells a live instrument from a silent one: its
        identification, which changes nothing and leaves the error queue to errors()."""
        return self.dialect.identity_query

    def _instrument_answers(self) -> bool:
        """After a timeout: does the instrument answer the probe within a short
        timeout? Only that: an error it queued for the failed exchange stays queued
        for ``errors()``; popping it here would lose it and blame this exchange."""
        saved = self.transport.timeout_s
        self.transport.timeout_s = min(PROBE_TIMEOUT_S, saved)
        try:
            self.transport.write(self.probe.encode("ascii"))
            decode_line(self.transport.read_line(), self.probe)
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
        if answering := self.replies(text):
            raise ValueError(f"{text!r} answers ({answering[0]}): use query, or a fetch for a dump")
        repeatable = self.repeatable(text)
        self._exchange(text, lambda: self.transport.write(data), repeatable)

    def query(self, text: str) -> str:
        """Send a message whose one reply is one line; return it without CR LF."""
        data = ascii_message(text)
        kinds = self.replies(text)
        if kinds != ["line"]:
            what = "no reply" if not kinds else f"replies {' + '.join(kinds)}"
            raise ValueError(f"{text!r} {what}: query takes a message with one one-line reply")

        def ask() -> str:
            self.transport.write(data)
            return decode_line(self.transport.read_line(), text)

        return self._exchange(text, ask, self.repeatable(text))

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

    # ------------------------------------------------------------ the dialect's part
    def replies(self, text: str) -> list[str]:
        """The reply kind of each command of a message that answers: ``line`` for a
        one-line reply, ``block`` for a binary block, ``lines`` for an ASCII dump."""
        raise NotImplementedError

    def repeatable(self, text: str) -> bool:
        """False if any command of the message would change the outcome when sent twice."""
        raise NotImplementedError

    def identify(self) -> str:
        """The instrument's identification, as it replies to its identity query.

        With a forced dialect, UnknownInstrument if the reply is not one of that
        dialect's instruments, and a hint in a timeout: the dialect may be wrong."""
        if not self.forced:
            self.identification = self.query(self.dialect.identity_query)
            return self.identification
        hint = (
            f"; the {self.dialect.name} dialect was forced (--dialect or $DAQ_DIALECT): "
            "is it this analyzer's?"
        )
        try:
            reply = self.query(self.dialect.identity_query)
        except InstrumentTimeout as exc:
            exc.args = (f"{exc.args[0]}{hint}",)
            raise
        mismatch = identity_mismatch(self.dialect, reply)
        if mismatch:
            raise UnknownInstrument(f"{self.transport.resource}: {mismatch}{hint}")
        self.identification = reply
        return reply

    def reset(self) -> None:
        raise NotImplementedError

    def status(self) -> Status:
        raise NotImplementedError

    def errors(self) -> list[tuple[int, str]]:
        """Drain the instrument's error queue (``error_query`` until code 0), oldest first:
        (code, message)."""
        query = self.error_query
        found = []
        for _ in range(64):  # queues hold 32 at most; a queue that does not empty is a fault
            reply = self.query(query)
            code_text, comma, message = reply.partition(",")
            if (self.error_reply_needs_comma and not comma) or not code_text.strip().lstrip("+-").isdigit():
                raise ProtocolError(query, 'expected code,"message"', reply.encode())
            code = int(code_text)
            if code == 0:
                return found
            found.append((code, message.strip().strip('"')))
        raise ProtocolError(query, "the error queue does not empty")

    def check_errors(self) -> None:
        """Raise InstrumentError for the oldest queued instrument error, if any."""
        found = self.errors()
        if found:
            code, message = found[0]
            more = f" (and {len(found) - 1} more)" if len(found) > 1 else ""
            raise InstrumentError(code, message + more)

    def raise_if_error(self) -> None:
        """InstrumentError if the status says an error is queued (after a command that
        may be refused: start, accept, reject)."""
        if self.status().error:
            self.check_errors()

    # ------------------------------------------------------------ settings
    def configure(self, settings: ImpactSettings) -> ImpactSettings:
        """Apply ``settings`` (the rows of the dialect's ``settings_table``, in order) and
        return them as the analyzer holds them (span, lines and ranges as it made them).
        Settings naming no lines get the dialect's default; lines it does not offer are
        refused (ValueError)."""
        geometry = self.geometry_for(settings.lines)
        settings = settings.with_lines(geometry.lines)
        self.send(self.clear_errors_command)  # errors left by earlier commands are not these settings'
        up_to_span, rest = self.settings_table.split_at_span()
        self._write(up_to_span, settings, None)
        self.check_errors()
        # The analyzer rounds the span up; a baseband center follows the span it chose,
        # and the pre-trigger must fit the record of that span.
        span = float(self.read_setting("span_hz"))
        settings = self.fit_to_span(settings, geometry, span)
        self._write(rest, settings, span)
        self.check_errors()
        return self.read_settings()

    def read_settings(self) -> ImpactSettings:
        """The impact-test settings the analyzer holds now (the table's read-back)."""
        fields, channels = read_fields(self.settings_table, self._ask)
        settings = ImpactSettings.from_fields(
            fields, channels, self._keep_read(fields, channels), self.baseband
        )
        self._record_length_s = settings.record_length_s
        return settings

    def read_setting(self, name: str, ch: int | None = None) -> object:
        """One field of the settings table, read back (``read_setting("span_hz")``)."""
        row = self.settings_table.row(name)
        return row.to_ours(self._ask(row.query or row.command, ch))

    def _write(self, table: SettingsTable, settings: ImpactSettings, span: float | None) -> None:
        for command, value, ch in write_steps(table, *settings.wire_fields(span)):
            self._put(command, value, ch)

    # The dialect's part of the settings: its table, how it sends and asks one row.
    settings_table: SettingsTable
    clear_errors_command: str
    #: The query that pops the oldest error, and whether its reply must hold a comma.
    error_query: str
    error_reply_needs_comma = False

    def geometry_for(self, lines: int | None) -> Geometry:
        return self.dialect.geometry(lines)

    def _put(self, command: str, value: object, ch: int | None) -> None:
        raise NotImplementedError

    def _ask(self, query: str, ch: int | None) -> object:
        raise NotImplementedError

    def _keep_read(self, fields: dict, channels: dict[int, dict]) -> int:
        """What the dialect keeps of the settings just read (``read_fields``); their lines."""
        raise NotImplementedError

    @staticmethod
    def baseband(span: float, center: float) -> bool:
        """A center at span/2 is a baseband measurement; above it, a zoom."""
        return center <= span / 2 or math.isclose(center, span / 2, rel_tol=1e-9)

    @staticmethod
    def fit_to_span(settings: ImpactSettings, geometry: Geometry, span_hz: float) -> ImpactSettings:
        """``settings`` for the span the analyzer made of the one asked: windows and
        pre-trigger left to their defaults follow its record (a zoom center that does not
        fit it is left for the analyzer to refuse); ValueError if the pre-trigger is longer
        than that record."""
        with contextlib.suppress(ValueError):
            settings = settings.sized_for(geometry.lines, span_hz)
        record = geometry.record_length_s(span_hz)
        if settings.pre_trigger_s > record * (1 + 1e-9):
            raise ValueError(
                f"pre-trigger {settings.pre_trigger_s:g} s is longer than the {record:g} s record "
                f"of the {span_hz:g} Hz span the analyzer chose"
            )
        return settings

    def start(self) -> None:
        """Clear the average and arm the trigger; InstrumentError if it refuses."""
        raise NotImplementedError

    def accept(self) -> None:
        """Preview: put the pending hit into the average."""
        raise NotImplementedError

    def reject(self) -> None:
        """Preview: throw the pending hit away and re-arm."""
        raise NotImplementedError

    def averages_done(self) -> int:
        raise NotImplementedError

    def fetch_time_records(self) -> tuple[Trace, Trace]:
        """(force N, acceleration m/s^2) of the last hit: real records at baseband,
        complex (half as many points) in zoom."""
        raise NotImplementedError

    def fetch_frf(self) -> Trace:
        """The averaged frequency response ch2/ch1 (H1), lines + 1 complex points, (m/s^2)/N."""
        raise NotImplementedError

    def fetch_coherence(self) -> Trace:
        """The coherence of the average, lines + 1 real points."""
        raise NotImplementedError

    def fetch_linear_spectra(self) -> tuple[Trace, Trace]:
        """Averaged peak linear spectra of both channels, lines + 1 complex points."""
        raise NotImplementedError

    # ------------------------------------------------------------ measuring
    def _record_length(self) -> float:
        if self._record_length_s is None:
            self._record_length_s = self.read_settings().record_length_s
        return self._record_length_s

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
        """Wait until every average is in."""
        n = averages or 1
        timeout = (
            timeout_s
            if timeout_s is not None
            else n * (self.hit_allowance_s + 2 * self._record_length()) + 1.0
        )
        return self.wait_for(lambda s: s.done, "waiting for the measurement to finish", timeout)
