"""Dumps: traces (DDAN binary, DDAS ASCII) and the instrument state (DSAN, DSAS).

A mixin of the HP mnemonic driver (drivers/hp_mnemonic.py), which provides
``transport``, ``_exchange`` (retries after a device clear) and ``geometry`` (the
model's lines and record length); kept apart so each module stays readable.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TypeVar

from drivers.blocks import decode_values, parse_block_header, read_ascii_dump
from drivers.commands import DISPLAY_FUNCTIONS, replies
from drivers.dialects import Dialect, Geometry
from drivers.errors import InstrumentTimeout, ProtocolError
from drivers.messages import ascii_message
from drivers.state import STATE_LENGTH, InstrumentState
from drivers.trace import HEADER_LENGTH, Trace
from drivers.transport import Transport

T = TypeVar("T")


class DumpsMixin:
    transport: Transport
    _exchange: Callable[..., object]
    geometry: Geometry
    dialect: Dialect

    @property
    def max_trace_values(self) -> int:
        """Values an ASCII trace dump may announce: the header and a whole record
        (real, or complex in zoom), so that a garbled count cannot make us wait long."""
        return HEADER_LENGTH + self.geometry.record_samples

    def fetch_trace(self, function: str, ascii: bool = False) -> Trace:
        """Select ``function`` on trace A and dump it: binary (DDAN) or ASCII (DDAS)."""
        if function not in DISPLAY_FUNCTIONS:
            raise ValueError(f"unknown display function {function!r}: one of {', '.join(DISPLAY_FUNCTIONS)}")
        dump = "DDAS" if ascii else "DDAN"
        return self._dump(f"TRCA;{function};{dump}", f"{dump} of {function}", function)

    def dump_trace(self, message: str) -> Trace:
        """Send ``message``, which must end in DDAN or DDAS (e.g. ``TRCB;COHR;DDAN``),
        and decode the dump."""
        last = message.strip().split(";")[-1].strip().upper()
        if last not in ("DDAN", "DDAS") or len(replies(message)) != 1:
            raise ValueError(f"{message!r} must end with DDAN or DDAS and ask nothing else")
        ascii_message(message)
        return self._dump(message.strip(), message.strip(), None)

    def read_state(self, ascii: bool = False) -> InstrumentState:
        """The instrument state (DSAN, or DSAS): 96 values, ours decoded (drivers/state.py)."""
        name = "DSAS" if ascii else "DSAN"

        def dump() -> InstrumentState:
            self.transport.write(name.encode("ascii"))
            values = self._read_values(name, ascii, STATE_LENGTH)
            return InstrumentState.decode(values, name)

        return self._exchange(name, dump)

    def _read_values(self, name: str, ascii: bool, max_values: int):
        if ascii:
            return read_ascii_dump(self.transport.read_line, name, max_values)
        return decode_values(self._read_block(name), name)

    def _dump(self, message: str, name: str, function: str | None) -> Trace:
        ascii = message.upper().endswith("DDAS")

        def dump() -> Trace:
            self.transport.write(ascii_message(message))
            trace = Trace.from_values(self._read_values(name, ascii, self.max_trace_values), name)
            self._check_shape(trace, function or trace.header.display_function, name)
            return trace

        return self._exchange(name, dump)

    def _check_shape(self, trace: Trace, function: str, name: str) -> None:
        h, g = trace.header, self.geometry
        if h.display_function != function:
            raise ProtocolError(name, f"asked for {function}, the dump holds {h.display_function}")
        if function.startswith("TIM"):
            if not h.time_domain or h.n_points != g.time_points(h.complex_data):
                raise ProtocolError(
                    name,
                    f"a {self.dialect.name} time record has {g.time_points(False)} real or "
                    f"{g.time_points(True)} complex points, got {h.n_points}",
                )
        elif h.time_domain or h.n_points != g.spectrum_points:
            raise ProtocolError(
                name, f"a {self.dialect.name} spectrum has {g.spectrum_points} points, got {h.n_points}"
            )

    def fetch_time_records(self) -> tuple[Trace, Trace]:
        """(force N, acceleration m/s^2) of the last hit: the model's record, real, or
        half as many complex points in zoom."""
        return self.fetch_trace("TIM1"), self.fetch_trace("TIM2")

    def fetch_linear_spectra(self) -> tuple[Trace, Trace]:
        """Averaged peak linear spectra of both channels, lines + 1 complex points."""
        return self.fetch_trace("LSP1"), self.fetch_trace("LSP2")

    def fetch_frf(self) -> Trace:
        """The averaged frequency response ch2/ch1 (H1), lines + 1 complex points, (m/s^2)/N."""
        return self.fetch_trace("FRSP")

    def fetch_coherence(self) -> Trace:
        """The coherence of the average, lines + 1 real points."""
        return self.fetch_trace("COHR")

    def _read_block(self, name: str) -> bytes:
        head = self.transport.read_exact(4)
        header = parse_block_header(head, name)
        if header.payload_bytes is None or header.kind != "A":
            raise ProtocolError(name, "expected an #A block", head)
        try:
            return self.transport.read_exact(header.payload_bytes)
        except InstrumentTimeout as exc:
            raise ProtocolError(name, f"truncated block: {exc}", head) from None
