"""A Prologix GPIB-USB controller on a serial port, through pyserial.

Resource: ``PROLOGIX::<serial port>::<GPIB address>``, e.g.
``PROLOGIX::/dev/ttyUSB0::11``. Chosen over pyvisa-py's PRLGX resources because
its maintainers list binary and large transfers as untested; this one is proven
against the simulator's Prologix pty in the tests.

On open the controller is put in a known state (manual v6.1): ``++mode 1``
(controller), ``++auto 0`` (read only when asked), ``++eoi 1`` and ``++eos 3``
(messages end with EOI, nothing appended), ``++eot_enable 0`` (nothing appended
to binary data), ``++read_tmo_ms``, ``++addr``. Data bytes CR, LF, ESC and ``+``
are escaped with ESC. A reply is fetched with ``++read eoi``, once per message.
"""

from __future__ import annotations

import os
import re
import time

from drivers.errors import ConnectionFailed, ConnectionLost, DriverError, InstrumentTimeout, ProtocolError
from drivers.transport import Transport

ESC = b"\x1b"
_ESCAPED = {b"\r", b"\n", ESC, b"+"}
#: The controller's own wait for the instrument to talk, per read (max 3000 ms).
READ_TMO_MS = 500
MAX_LINE_BYTES = 65536


def escape(message: bytes) -> bytes:
    """ESC before CR, LF, ESC and '+' so the controller passes them as data."""
    return b"".join(ESC + bytes([b]) if bytes([b]) in _ESCAPED else bytes([b]) for b in message)


def parse_resource(resource: str) -> tuple[str, int]:
    """``PROLOGIX::<port>::<address>`` -> (port, address)."""
    parts = resource.split("::")
    if len(parts) != 3 or parts[0].upper() != "PROLOGIX" or not parts[1]:
        raise ValueError(
            f"not a Prologix resource: {resource!r} (expected PROLOGIX::<serial port>::<address>)"
        )
    if not re.fullmatch(r"[0-9]{1,2}", parts[2]) or not 0 <= int(parts[2]) <= 30:
        raise ValueError(f"GPIB address must be 0..30 in {resource!r}")
    return parts[1], int(parts[2])


class PrologixTransport(Transport):
    def __init__(
        self, resource: str, timeout_s: float = 5.0, lock_file: bool = True, baudrate: int = 115200
    ) -> None:
        self.port, self.address = parse_resource(resource)
        # One adapter carries one byte stream for every address on its bus: the lock
        # is the serial port's, whatever the address or spelling of the name.
        super().__init__(resource, timeout_s, lock_file, lock_key=f"SERIAL::{os.path.realpath(self.port)}")
        self.baudrate = baudrate
        self._serial = None
        self._talking = False  # ++read eoi already sent for the current reply
        self._read_sent = 0.0
        self._heard = True  # a byte arrived since the last ++read

    # ------------------------------------------------------------- lifecycle
    def _open(self) -> None:
        import serial

        try:
            self._serial = serial.Serial(self.port, self.baudrate, timeout=0.05, write_timeout=self.timeout_s)
        except (serial.SerialException, OSError, ValueError) as exc:
            raise ConnectionFailed(f"cannot open serial port {self.port}: {exc}") from None
        self._serial.reset_input_buffer()
        for command in (
            "++mode 1",
            "++auto 0",
            "++eoi 1",
            "++eos 3",
            "++eot_enable 0",
            f"++read_tmo_ms {READ_TMO_MS}",
            f"++addr {self.address}",
        ):
            self._controller(command)
        self._verify_controller()

    def _verify_controller(self) -> None:
        """Ask the adapter its version: proves a Prologix is on this port."""
        deadline = time.monotonic() + min(self.timeout_s, 2.0)
        line = b""
        try:
            self._controller("++ver")
            # A reply an earlier (killed) session asked for may still be on its way:
            # skip a few lines before the adapter's own answer.
            for _ in range(4):
                line = self._readline_raw(deadline=deadline, reissue=False)
                if b"Prologix" in line:
                    break
        except DriverError as exc:
            self._close()
            raise ConnectionFailed(f"no Prologix controller answers on {self.port} ({exc})") from None
        if b"Prologix" not in line:
            self._close()
            raise ConnectionFailed(f"no Prologix controller answers on {self.port} (got {line[:40]!r})")
        # Selected device clear: a reply the instrument still holds from an earlier
        # session must not be read as the answer to our first query.
        self._controller("++clr")

    def _close(self) -> None:
        if self._serial is not None:
            try:
                self._serial.close()
            finally:
                self._serial = None
        self._talking = False

    def _port(self):
        if self._serial is None:
            raise ConnectionLost(f"{self.port} is not open")
        return self._serial

    # ------------------------------------------------------------- bytes
    def _controller(self, command: str) -> None:
        self._send_raw(command.encode("ascii") + b"\n")

    def _send_raw(self, data: bytes) -> None:
        import serial

        try:
            self._port().write(data)
        except (serial.SerialException, OSError) as exc:
            raise ConnectionLost(f"{self.port}: write failed ({exc})") from None

    def _write(self, message: bytes) -> None:
        self._talking = False
        self._send_raw(escape(message) + b"\n")

    def _begin_read(self) -> None:
        if not self._talking:
            self._controller("++read eoi")
            self._talking = True
            self._read_sent = time.monotonic()
            self._heard = False

    def _keep_asking(self) -> None:
        """The adapter gives up a read after ++read_tmo_ms; a slower instrument is
        asked again until our own timeout (not the adapter's) runs out."""
        if time.monotonic() - self._read_sent > READ_TMO_MS / 1000 + 0.05:
            self._controller("++read eoi")
            self._read_sent = time.monotonic()
            self._heard = False

    def _read_some(self, size: int) -> bytes:
        import serial

        try:
            data = self._port().read(size)
            self._heard = self._heard or bool(data)
            return data
        except (serial.SerialException, OSError) as exc:
            raise ConnectionLost(f"{self.port}: read failed ({exc})") from None

    def _readline_raw(self, deadline: float, reissue: bool = True) -> bytes:
        line = bytearray()
        while not line.endswith(b"\n"):
            if reissue and not line:
                self._keep_asking()
            if time.monotonic() > deadline:
                raise InstrumentTimeout(
                    f"{self.resource}: no complete reply line in time (got {bytes(line)[:40]!r})"
                )
            if len(line) > MAX_LINE_BYTES:
                raise ProtocolError("read", "reply line without an end", bytes(line))
            line += self._read_until_lf()
        return bytes(line)

    def _read_until_lf(self) -> bytes:
        import serial

        try:
            # Returns at the LF or after the port's short timeout, whichever first.
            data = self._port().read_until(b"\n", MAX_LINE_BYTES)
            self._heard = self._heard or bool(data)
            return data
        except (serial.SerialException, OSError) as exc:
            raise ConnectionLost(f"{self.port}: read failed ({exc})") from None

    def _read_line(self) -> bytes:
        self._begin_read()
        line = self._readline_raw(time.monotonic() + self.timeout_s)
        self._talking = False
        return line.rstrip(b"\r\n")

    def _read_exact(self, count: int) -> bytes:
        self._begin_read()
        deadline = time.monotonic() + self.timeout_s
        data = bytearray()
        while len(data) < count:
            if not data:
                self._keep_asking()
            if time.monotonic() > deadline:
                raise InstrumentTimeout(f"{self.resource}: {len(data)} of {count} bytes arrived in time")
            data += self._read_some(count - len(data))
        return bytes(data)

    def _clear(self) -> None:
        """Selected device clear, then drop whatever the adapter still holds.

        An adapter still serving an earlier ``++read`` passes on what the instrument
        says until its read timeout ends: wait that out first, or a late reply would
        arrive after the drain and answer the next query.
        """
        import serial

        self._talking = False
        if not self._heard:  # nothing came since the last ++read: it may still be waiting
            in_flight_until = self._read_sent + READ_TMO_MS / 1000 + 0.1
            time.sleep(max(0.0, in_flight_until - time.monotonic()))
        self._controller("++clr")
        port = self._port()
        give_up = time.monotonic() + max(1.0, self.timeout_s)
        quiet_until = time.monotonic() + 0.1
        try:
            while time.monotonic() < quiet_until:
                if time.monotonic() > give_up:
                    raise ConnectionLost(f"{self.port}: the adapter does not stop sending")
                if port.in_waiting:
                    port.reset_input_buffer()
                    quiet_until = time.monotonic() + 0.1
                else:
                    time.sleep(0.01)
        except (serial.SerialException, OSError) as exc:
            raise ConnectionLost(f"{self.port}: {exc}") from None

    def _apply_timeout(self) -> None:
        if self._serial is not None:
            self._serial.write_timeout = self.timeout_s
