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
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import TypeVar

from drivers.blocks import decode_values, parse_block_header
from drivers.commands import COMMANDS, STATUS_BITS, replies
from drivers.errors import ConnectionLost, DriverError, InstrumentError, InstrumentTimeout, ProtocolError
from drivers.settings import ChannelSetup, ImpactSettings, Window
from drivers.trace import Trace
from drivers.transport import Transport

log = logging.getLogger(__name__)
T = TypeVar("T")

#: How long a technician may take to hit once the analyzer is armed, s (default).
HIT_ALLOWANCE_S = 60.0
#: How long to wait for ERR? after a timeout before calling the instrument silent, s.
PROBE_TIMEOUT_S = 0.5
#: The 35660A's record: 1024 real points at baseband, 512 complex in zoom; 401 lines.
TIME_POINTS = {False: 1024, True: 512}
SPECTRUM_LINES = 401


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


class HP35660A:
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
            silent = False
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
                    if (
                        isinstance(exc, InstrumentTimeout)
                        and what != "ERR?"
                        and not self._instrument_answers()
                    ):
                        silent = True  # another attempt would only wait out the timeout again
                        break
            assert last is not None
            # Leave the link clean for whoever talks next: a late or partial reply of
            # this failed exchange must never be read as the answer to another.
            self._recover(last)
            if isinstance(last, ConnectionLost) and self._recovery_error is not None:
                raise self._recovery_error  # "connection refused" says more than "not open"
            if silent:
                last.args = (f"{last.args[0]} (the instrument answers nothing, not even ERR?)",)
            elif repeatable and self.retries:
                last.args = (f"{last.args[0]} (after {attempt + 1} attempt{'s' if attempt else ''})",)
            raise last

    def _instrument_answers(self) -> bool:
        """After a timeout: ask ERR? with a short timeout. An instrument refuses a
        query by not answering it, and says why in its error queue: raise that.
        False if it does not even answer this."""
        saved = self.transport.timeout_s
        self.transport.timeout_s = min(PROBE_TIMEOUT_S, saved)
        try:
            self.transport.write(b"ERR?")
            reply = _decode_line(self.transport.read_line(), "ERR?")
        except DriverError as exc:
            self._recover(exc)
            return False
        finally:
            self.transport.timeout_s = saved
        code, _, message = reply.partition(",")
        if code.strip().isdigit() and int(code) != 0:
            raise InstrumentError(int(code), message.strip().strip('"'))
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
        data = _ascii(text)
        if answering := replies(text):
            raise ValueError(f"{text!r} answers ({answering[0]}): use query, or a fetch for a dump")
        repeatable = _repeatable(text)
        self._exchange(text, lambda: self.transport.write(data), repeatable)

    def query(self, text: str) -> str:
        """Send a message whose one reply is one line; return it without CR LF."""
        data = _ascii(text)
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

    def _read_block(self, name: str) -> bytes:
        head = self.transport.read_exact(4)
        header = parse_block_header(head, name)
        if header.payload_bytes is None or header.kind != "A":
            raise ProtocolError(name, "expected an #A block", head)
        try:
            return self.transport.read_exact(header.payload_bytes)
        except InstrumentTimeout as exc:
            raise ProtocolError(name, f"truncated block: {exc}", head) from None

    # ------------------------------------------------------------ instrument
    def identify(self) -> str:
        """The instrument's identification (``HP35660A``)."""
        return self.query("ID?")

    def reset(self) -> None:
        self.send("RST")
        self._record_length_s = None

    def status(self) -> Status:
        reply = self.query("STA?")
        if not reply.isdigit() or int(reply) > 255:
            raise ProtocolError("STA?", "expected a status byte", reply.encode())
        return Status(int(reply))

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
        actual_span = self.query_values("FRS?", 1)[0]
        if settings.pre_trigger_s > 400.0 / actual_span * (1 + 1e-9):
            record = 400.0 / actual_span
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

        def number(q: str) -> float:
            return self.query_values(q, 1)[0]

        def choice(q: str, allowed: tuple[str, ...]) -> str:
            reply = self.query(q)
            if reply not in allowed:
                raise ProtocolError(q, f"expected one of {', '.join(allowed)}", reply.encode())
            return reply

        def flag(q: str) -> bool:
            return bool(choice(q, ("0", "1")) == "1")

        span = number("FRS?")
        center = number("CF?")
        channels = []
        for ch in (1, 2):
            channels.append(
                ChannelSetup(
                    window=Window(choice(f"WIN{ch}?", tuple(w.value for w in Window))),
                    sensitivity_v_per_eu=number(f"SNS{ch}?"),
                    range_v=None if flag(f"AU{ch}?") else number(f"RNG{ch}?"),
                    force_width_s=number(f"FWD{ch}?"),
                    exp_decay_s=number(f"EXD{ch}?"),
                    ac_coupled=flag(f"C{ch}AC?"),
                )
            )
        source = choice("TSRC?", ("CH1", "CH2", "FREE"))
        level_v = number("TLVL?")
        trigger_channel = channels[1] if source == "CH2" else channels[0]
        averaging = choice("AVMD?", ("STBL", "AVOF"))
        settings = ImpactSettings(
            span_hz=span,
            center_hz=None if math.isclose(center, span / 2, rel_tol=1e-9) else center,
            hammer=channels[0],
            accelerometer=channels[1],
            trigger_source=source,
            trigger_level_eu=level_v / trigger_channel.sensitivity_v_per_eu,
            trigger_slope=choice("TSLP?", ("POS", "NEG")),
            pre_trigger_s=max(0.0, -number("TDLY?")),
            averages=1 if averaging == "AVOF" else int(number("NAVG?")),
            preview=flag("PRVW?"),
        )
        self._record_length_s = settings.record_length_s
        return settings

    # ------------------------------------------------------------ measuring
    def _record_length(self) -> float:
        if self._record_length_s is None:
            self._record_length_s = 400.0 / self.query_values("FRS?", 1)[0]
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
        reply = self.query("AVG?")
        if not reply.isdigit():
            raise ProtocolError("AVG?", "expected a count", reply.encode())
        return int(reply)

    def wait_for(self, done: Callable[[Status], bool], what: str, timeout_s: float | None = None) -> Status:
        """Poll the status until ``done(status)``; the default timeout is the hit
        allowance plus twice the record length. Polls back off from 5 ms to 0.2 s."""
        timeout = (
            timeout_s if timeout_s is not None else self.hit_allowance_s + 2 * self._record_length() + 1.0
        )
        deadline = time.monotonic() + timeout
        pause = 0.005
        while True:
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
            time.sleep(min(pause, max(0.0, deadline - time.monotonic())))
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

    # ------------------------------------------------------------ data
    def fetch_trace(self, function: str) -> Trace:
        """Select ``function`` on trace A and dump it in binary (DDAN)."""
        if function not in ("TIM1", "TIM2", "LSP1", "LSP2", "PSP1", "PSP2", "FRSP", "COHR"):
            raise ValueError(f"unknown display function {function!r}")
        return self._dump(b"TRCA;" + function.encode() + b";DDAN", f"DDAN of {function}", function)

    def fetch_active_trace(self) -> Trace:
        """Dump the active trace as the analyzer shows it (DDAN), changing nothing."""
        return self._dump(b"DDAN", "DDAN", None)

    def dump_trace(self, message: str) -> Trace:
        """Send ``message``, which must end in DDAN (e.g. ``TRCB;COHR;DDAN``), and decode the dump."""
        if replies(message) != ["block"] or message.strip().split(";")[-1].strip().upper() != "DDAN":
            raise ValueError(f"{message!r} must end with DDAN and ask nothing else")
        return self._dump(_ascii(message), message.strip(), None)

    def _dump(self, message: bytes, name: str, function: str | None) -> Trace:
        def dump() -> Trace:
            self.transport.write(message)
            payload = self._read_block(name)
            trace = Trace.from_values(decode_values(payload, name), name)
            self._check_shape(trace, function or trace.header.display_function, name)
            return trace

        return self._exchange(name, dump)

    @staticmethod
    def _check_shape(trace: Trace, function: str, name: str) -> None:
        h = trace.header
        if h.display_function != function:
            raise ProtocolError(name, f"asked for {function}, the dump holds {h.display_function}")
        if function.startswith("TIM"):
            if not h.time_domain or h.n_points != TIME_POINTS[h.complex_data]:
                raise ProtocolError(
                    name, f"a time record has 1024 real or 512 complex points, got {h.n_points}"
                )
        elif h.time_domain or h.n_points != SPECTRUM_LINES:
            raise ProtocolError(name, f"a spectrum has {SPECTRUM_LINES} lines, got {h.n_points}")

    def fetch_time_records(self) -> tuple[Trace, Trace]:
        """(force N, acceleration m/s^2) of the last hit: 1024 real points, or 512 complex in zoom."""
        return self.fetch_trace("TIM1"), self.fetch_trace("TIM2")

    def fetch_linear_spectra(self) -> tuple[Trace, Trace]:
        """Averaged peak linear spectra of both channels, 401 complex lines."""
        return self.fetch_trace("LSP1"), self.fetch_trace("LSP2")

    def fetch_frf(self) -> Trace:
        """The averaged frequency response ch2/ch1 (H1), 401 complex lines, (m/s^2)/N."""
        return self.fetch_trace("FRSP")

    def fetch_coherence(self) -> Trace:
        """The coherence of the average, 401 real lines."""
        return self.fetch_trace("COHR")


def _ascii(text: str) -> bytes:
    try:
        data = text.strip().encode("ascii")
    except UnicodeEncodeError:
        raise ValueError(f"commands are ASCII: {text!r}") from None
    if not data or b"\n" in data or b"\r" in data:
        raise ValueError("one command line, not empty")
    return data


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
