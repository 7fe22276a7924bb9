"""The SCPI dialect of the family: the HP 35665A and 35670A (docs/instrument-scpi.md).

What it sends is spelled by its own table (drivers/scpi_commands.py, each entry
tagged peer/std/proj). It differs from the mnemonic dialect in form, not in what
the application sees: the same ``ImpactSettings`` in and out, the same ``Status``
bits, the same ``Trace``s. Where the HP dialect reads a dump with its header, this
one asks the analyzer's state and the trace's x values, and builds the header:

* traces are fetched through trace 1: ``CALC1:FEED``, ``CALC1:FORM NYQ`` (complex:
  FRF, linear spectra, zoom time records) or ``REAL`` (coherence, baseband time
  records), ``CALC1:DATA?`` and ``CALC1:X:DATA?``, IEEE 488.2 definite blocks of
  big-endian float64 (``FORM:DATA REAL,64``, sent by ``configure``);
* blocks are read by count: the header, exactly the payload, then the LF;
* one fetch is one exchange (state, feed, form, data and x), repeated as a whole
  after a failure, so that a retry never mixes two traces.
"""

from __future__ import annotations

import logging
import math

import numpy as np

from drivers.base import SignalAnalyzer
from drivers.blocks import decode_values, parse_block_header
from drivers.dialects import SCPI, SCPI_MODEL_LINES, Dialect, Geometry
from drivers.errors import DriverError, InstrumentTimeout, ProtocolError
from drivers.messages import Status, ascii_message, decode_line
from drivers.scpi_commands import (
    FEEDS,
    SETTINGS,
    STATE_QUERY,
    STATUS_MAP,
    STATUS_QUERY,
    command,
    parse_reply,
    readback,
    repeatable,
    replies,
)
from drivers.trace import Trace, TraceHeader
from drivers.transport import Transport

log = logging.getLogger(__name__)


class ScpiAnalyzer(SignalAnalyzer):
    """An HP 35665A or 35670A in SCPI (``dialect``: drivers.dialects.SCPI)."""

    family = "scpi"
    settings_table = SETTINGS
    clear_errors_command = "*CLS"
    error_query = "SYST:ERR?"
    error_reply_needs_comma = True

    def __init__(self, transport: Transport, dialect: Dialect = SCPI, **kwargs: object) -> None:
        if dialect.family != self.family:
            raise ValueError(f"the {dialect.name} dialect is not a SCPI dialect")
        super().__init__(transport, dialect, **kwargs)  # type: ignore[arg-type]
        self._lines: int | None = None
        #: Engineering units on, per channel, as last read (configure turns them on; the
        #: simulator presets them on, a real box off): the unit of the fetched data.
        self._eu = {1: True, 2: True}

    @property
    def geometry(self) -> Geometry:
        """The current lines and the records they make (asks the analyzer once)."""
        if self._lines is None:
            self._lines = self._read_lines()
        return self.dialect.geometry(self._lines)

    @property
    def model(self) -> str | None:
        """The model named by the identification (``35670A``), once ``identify`` asked."""
        fields = (self.identification or "").split(",")
        return fields[1].strip().upper() if len(fields) > 1 else None

    def replies(self, text: str) -> list[str]:
        return replies(text)

    def repeatable(self, text: str) -> bool:
        return repeatable(text)

    def read(self, header: str, n: int | None = None) -> float | int | bool | str:
        """A setting read back or a query, typed by the table: ``read("SENS:FREQ:SPAN")``
        asks ``SENS:FREQ:SPAN?`` and returns 200.0; ``read("SENS:WIND<n>:TYPE", 2)``."""
        query = readback(header, n)
        reply = self.query(query)
        try:
            return parse_reply(header, reply)
        except ValueError as exc:
            raise ProtocolError(query, str(exc), reply.encode()) from None

    def set(self, header: str, value: object = None, n: int | None = None) -> None:
        """Send one table entry, spelled by the table: ``set("SENS:FREQ:SPAN", 200.0)``
        sends ``SENS:FREQ:SPAN 200 HZ``."""
        self.send(command(header, value, n))

    # ------------------------------------------------------------ instrument
    def reset(self) -> None:
        """Preset (``*RST``) and clear the error queue and event registers (``*CLS``)."""
        self.send("*RST;*CLS")
        self._record_length_s = None
        self._lines = None

    def status(self) -> Status:
        """One message, one reply: the operation condition, the overloads and the
        status byte, mapped to Status."""
        reply = self.query(STATUS_QUERY)
        fields = reply.split(";")
        if len(fields) != 3 or not all(f.strip().isdigit() for f in fields):
            raise ProtocolError(STATUS_QUERY, "expected three NR1 numbers joined by ;", reply.encode())
        registers = dict(zip(("oper", "volt", "stb"), (int(f) for f in fields), strict=True))
        status = Status(0)
        for register, bit, name in STATUS_MAP:
            if registers[register] >> bit & 1:
                status |= Status[name.upper()]
        return status

    # ------------------------------------------------------------ settings
    def geometry_for(self, lines: int | None) -> Geometry:
        """Lines: the settings', or the dialect's default; a count the model (once
        identified) does not offer is refused (ValueError)."""
        geometry = self.dialect.geometry(lines)
        model = self.model
        if model in SCPI_MODEL_LINES and geometry.lines not in SCPI_MODEL_LINES[model]:
            offered = ", ".join(str(n) for n in SCPI_MODEL_LINES[model])
            raise ValueError(f"the {model} offers {offered} lines, not {geometry.lines}")
        return geometry

    def _put(self, command: str, value: object, ch: int | None) -> None:
        self.set(command, value, ch)

    def _ask(self, query: str, ch: int | None) -> object:
        if query == "SENS:FREQ:RES":
            return self._read_lines()
        return self.read(query, ch)

    def _keep_read(self, fields: dict, channels: dict[int, dict]) -> int:
        """Engineering units on or off, per channel: the unit of the data a fetch reads."""
        self._eu = {ch: bool(channels[ch]["engineering_units"]) for ch in (1, 2)}
        return int(fields["lines"])

    def _read_lines(self) -> int:
        lines = int(self.read("SENS:FREQ:RES"))
        if lines not in self.dialect.line_choices:
            raise ProtocolError("SENS:FREQ:RES?", f"{lines} lines is not one of {self.dialect.line_choices}")
        self._lines = lines
        return lines

    # ------------------------------------------------------------ measuring
    def _record_length(self) -> float:
        if self._record_length_s is None:
            span = float(self.read("SENS:FREQ:SPAN"))
            self._record_length_s = self.dialect.geometry(self._read_lines()).record_length_s(span)
        return self._record_length_s

    def start(self) -> None:
        """Clear the average and arm the trigger (``ABOR;INIT:IMM``, never repeated);
        InstrumentError if the analyzer refuses."""
        self._record_length()
        self.send("ABOR;INIT:IMM")
        self.raise_if_error()

    def accept(self) -> None:
        """Preview: put the pending hit into the average (never sent twice)."""
        self.send("SENS:AVER:PREV:ACC")
        self.raise_if_error()

    def reject(self) -> None:
        """Preview: throw the pending hit away and re-arm (never sent twice)."""
        self.send("SENS:AVER:PREV:REJ")
        self.raise_if_error()

    def averages_done(self) -> int:
        """Hits in the average so far."""
        return int(self.read("SENS:AVER:COUN:INT?"))

    # ------------------------------------------------------------ traces
    def fetch_time_records(self) -> tuple[Trace, Trace]:
        """(force N, acceleration m/s^2) of the last hit (in preview the pending one):
        2.56 x lines real samples, or 1.28 x lines complex in zoom."""
        force, accel = self.fetch_traces("TIM1", "TIM2")
        return force, accel

    def fetch_linear_spectra(self) -> tuple[Trace, Trace]:
        """Averaged peak linear spectra of both channels, lines + 1 complex points."""
        lsp1, lsp2 = self.fetch_traces("LSP1", "LSP2")
        return lsp1, lsp2

    def fetch_frf(self) -> Trace:
        """The averaged frequency response ch2/ch1 (H1), lines + 1 complex points, (m/s^2)/N."""
        return self.fetch_trace("FRSP")

    def fetch_coherence(self) -> Trace:
        """The coherence of the average, lines + 1 real points."""
        return self.fetch_trace("COHR")

    def fetch_trace(self, function: str) -> Trace:
        """One trace by our display function (FEEDS: TIM1 TIM2 LSP1 LSP2 FRSP COHR)."""
        return self.fetch_traces(function)[0]

    def fetch_traces(self, *functions: str) -> list[Trace]:
        """The traces of ``functions`` (FEEDS keys), in one repeatable exchange: the
        state (STATE_QUERY), then for each its feed, form, data and x."""
        for function in functions:
            if function not in FEEDS:
                raise ValueError(f"unknown display function {function!r}: one of {', '.join(FEEDS)}")
        what = "fetch of " + ", ".join(functions)
        return self._exchange(what, lambda: self._fetch(functions))

    def _fetch(self, functions: tuple[str, ...]) -> list[Trace]:
        self.transport.write(STATE_QUERY.encode("ascii"))
        state = self._read_state()
        return [self._fetch_one(function, *state) for function in functions]

    def _read_state(self) -> tuple[float, float, Geometry, int, int]:
        reply = decode_line(self.transport.read_line(), STATE_QUERY)
        fields = reply.split(";")
        try:
            if len(fields) != 5:
                raise ValueError(f"expected 5 answers, got {len(fields)}")
            span, center = (float(parse_reply("SENS:FREQ:SPAN", f)) for f in fields[:2])
            lines, count, overload = (int(parse_reply("SENS:FREQ:RES", f)) for f in fields[2:])
            geometry = self.dialect.geometry(lines)
        except ValueError as exc:
            raise ProtocolError(STATE_QUERY, str(exc), reply.encode()) from None
        if not span > 0 or center < 0:
            raise ProtocolError(STATE_QUERY, "span must be > 0 and center >= 0", reply.encode())
        self._lines = lines
        return span, center, geometry, count, overload

    def _fetch_one(
        self, function: str, span: float, center: float, g: Geometry, count: int, overload: int
    ) -> Trace:
        feed, channel, complex_data, eu_unit, volt_unit = FEEDS[function]
        zoom = not self.baseband(span, center)
        time_domain = complex_data is None
        is_complex = zoom if time_domain else bool(complex_data)
        points = g.time_points(zoom) if time_domain else g.spectrum_points
        message = f"CALC1:FEED '{feed}';:CALC1:FORM {'NYQ' if is_complex else 'REAL'};:CALC1:DATA?"
        self.transport.write(message.encode("ascii"))
        values = self._read_block(message, points * (2 if is_complex else 1))
        self.transport.write(b"CALC1:X:DATA?")
        x = self._read_block(f"CALC1:X:DATA? of {function}", points)
        delta = _uniform_step(x, f"CALC1:X:DATA? of {function}")
        rate = g.sample_rate_hz(span, zoom)
        expected_delta = 1.0 / rate if time_domain else span / g.lines
        start = float(x[0])
        if not math.isclose(delta, expected_delta, rel_tol=1e-6) or (
            not time_domain and abs(start - (center - span / 2 if zoom else 0.0)) > 1e-6 * delta
        ):
            raise ProtocolError(
                f"CALC1:X:DATA? of {function}",
                f"x from {start!r} by {delta!r} does not fit the {span:g} Hz span at {center:g} Hz",
            )
        data = np.empty(points, np.complex128) if is_complex else values
        if is_complex:  # re, im interleaved (NYQ)
            data.real, data.imag = values[0::2], values[1::2]
        header = TraceHeader(
            display_function=function,
            n_points=points,
            n_averages=count,
            channel=channel,
            overflow=bool(time_domain and overload >> (channel - 1) & 1),
            time_domain=time_domain,
            y_units=self._units(channel, eu_unit, volt_unit),
            x_units="s" if time_domain else "Hz",
            complex_data=is_complex,
            sample_rate_hz=rate,
            delta_x=delta,
            start_x=start,
        )
        return Trace(header, data)

    def _units(self, channel: int, eu_unit: str, volt_unit: str) -> str:
        eu = self._eu[1] and self._eu[2] if channel == 3 else self._eu[channel]
        if channel == 3 and self._eu[1] != self._eu[2] and eu_unit:
            raise DriverError("engineering units are on for one channel only: configure() sets both")
        return eu_unit if eu else volt_unit

    def query_block(self, text: str) -> np.ndarray:
        """Send a query that answers one IEEE 488.2 block (``CALC1:DATA?``) with the
        data format set to REAL,64 first; its values, float64 (n,)."""
        message = f"FORM:DATA REAL,64;:{ascii_message(text).decode()}"

        def ask() -> np.ndarray:
            self.transport.write(message.encode("ascii"))
            return self._read_block(text, None)

        return self._exchange(text, ask, self.repeatable(text))

    def _read_block(self, name: str, values: int | None) -> np.ndarray:
        """A definite block of ``values`` big-endian float64, read by count, then its LF."""
        head = self.transport.read_exact(2)
        if head[:1] != b"#" or not head[1:2].isdigit() or head[1:2] == b"0":
            raise ProtocolError(name, "expected a definite block '#<n><length>'", head)
        try:  # once a block has begun, whatever does not come is a truncated block
            head += self.transport.read_exact(int(head[1:2]))
            header = parse_block_header(head, name)
            if values is None:  # any whole number of values: the block says how many
                values = (header.payload_bytes or 0) // 8
            if header.payload_bytes != 8 * values:  # checked before waiting for a payload of that size
                raise ProtocolError(name, f"expected {values} float64 ({8 * values} bytes)", head)
            payload = self.transport.read_exact(header.payload_bytes)
            end = self.transport.read_exact(1)
            if end == b"\r":  # CR LF is tolerated (blocks.TRAILERS)
                end = self.transport.read_exact(1)
        except InstrumentTimeout as exc:
            raise ProtocolError(name, f"truncated block: {exc}", head) from None
        if end != b"\n":
            raise ProtocolError(name, "the block does not end with LF", head + end)
        return decode_values(payload, name, ">f8", values)


def _uniform_step(x: np.ndarray, name: str) -> float:
    """The step of evenly spaced x values (ProtocolError if they are not)."""
    if x.size < 2:
        raise ProtocolError(name, "fewer than 2 x values")
    steps = np.diff(x)
    step = float((x[-1] - x[0]) / (x.size - 1))
    if not (step > 0 and np.allclose(steps, step, rtol=1e-6, atol=0.0)):
        raise ProtocolError(name, "x values are not evenly spaced")
    return step
