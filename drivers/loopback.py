"""A transport over an in-process link: anything with ``write(bytes)``,
``read(size, timeout_s)`` and ``clear()`` (the simulator's in-process front end).

Used for fast tests and for running the whole chain without a socket; the driver
cannot tell it from a wire.
"""

from __future__ import annotations

import time
from typing import Protocol

from drivers.errors import ConnectionLost, InstrumentTimeout
from drivers.transport import Transport


class Link(Protocol):
    def write(self, data: bytes) -> None: ...
    def read(self, size: int = -1, timeout_s: float = 1.0) -> bytes: ...
    def clear(self) -> None: ...


class LoopbackTransport(Transport):
    def __init__(self, link_factory, resource: str = "LOOPBACK", timeout_s: float = 5.0) -> None:
        """``link_factory()`` makes a fresh link; it is called again on reconnect."""
        super().__init__(resource, timeout_s, lock_file=False)
        self._factory = link_factory
        self._link: Link | None = None
        self._buffer = bytearray()

    def _open(self) -> None:
        self._link = self._factory()
        self._buffer.clear()

    def _close(self) -> None:
        self._link = None
        self._buffer.clear()

    def _get(self) -> Link:
        if self._link is None:
            raise ConnectionLost(f"{self.resource} is not open")
        return self._link

    def _write(self, message: bytes) -> None:
        try:
            self._get().write(message + b"\n")
        except ConnectionError as exc:
            raise ConnectionLost(f"{self.resource}: {exc}") from None

    def _fill(self, deadline: float) -> None:
        remaining = deadline - time.monotonic()
        if remaining <= 0:
            raise InstrumentTimeout(f"{self.resource}: no reply in time")
        try:
            self._buffer += self._get().read(-1, timeout_s=remaining)
        except TimeoutError:
            raise InstrumentTimeout(f"{self.resource}: no reply in time") from None
        except ConnectionError as exc:
            raise ConnectionLost(f"{self.resource}: {exc}") from None

    def _read_line(self) -> bytes:
        deadline = time.monotonic() + self.timeout_s
        while b"\n" not in self._buffer:
            self._fill(deadline)
        line, _, rest = bytes(self._buffer).partition(b"\n")
        self._buffer = bytearray(rest)
        return line.rstrip(b"\r")

    def _read_exact(self, count: int) -> bytes:
        deadline = time.monotonic() + self.timeout_s
        while len(self._buffer) < count:
            try:
                self._fill(deadline)
            except InstrumentTimeout:
                raise InstrumentTimeout(
                    f"{self.resource}: {len(self._buffer)} of {count} bytes arrived in time"
                ) from None
        data = bytes(self._buffer[:count])
        del self._buffer[:count]
        return data

    def _clear(self) -> None:
        self._buffer.clear()
        self._get().clear()
