"""The transport interface: one instrument's byte stream, whatever carries it.

Subclasses implement ``_open``, ``_close``, ``_write``, ``_read_line``,
``_read_exact`` and ``_clear``; this base adds what every transport needs:
timeouts in seconds, a re-entrant thread lock (``with transport.lock:`` around a
write and its read, so two threads never interleave on one instrument), an
optional lock file against other processes, and DEBUG logging of every message
on the wire with binary payloads summarised.
"""

from __future__ import annotations

import logging
import threading
from abc import ABC, abstractmethod

from drivers.errors import summarize
from drivers.locking import ResourceLock

wire_log = logging.getLogger("drivers.wire")


def describe(data: bytes) -> str:
    """A wire log entry: text lines as text, binary blocks as their size."""
    if data.startswith(b"#"):
        return f"<binary {len(data)} bytes: {summarize(data, 12)}>"
    return summarize(data, 120)


class Transport(ABC):
    """Bytes to and from one instrument."""

    def __init__(
        self, resource: str, timeout_s: float = 5.0, lock_file: bool = True, lock_key: str | None = None
    ) -> None:
        """``lock_key`` names the physical link for the lock file (default: the resource)."""
        if not timeout_s > 0:
            raise ValueError("timeout_s must be positive")
        self.resource = resource
        self._timeout_s = float(timeout_s)
        self.lock = threading.RLock()
        self.lock_key = lock_key or resource
        self._file_lock = ResourceLock(self.lock_key, resource) if lock_file else None
        self.is_open = False

    # ------------------------------------------------------------- lifecycle
    def open(self) -> None:
        with self.lock:
            if not self.is_open:
                self._open_locked()
                wire_log.debug("%s: opened", self.resource)

    def _open_locked(self) -> None:
        """Take the lock file (a no-op if held) and open; a failed open frees the lock,
        since close() will not run for a transport that is not open."""
        if self._file_lock is not None:
            self._file_lock.acquire()
        try:
            self._open()
        except BaseException:
            if self._file_lock is not None:
                self._file_lock.release()
            raise
        self.is_open = True

    def close(self) -> None:
        with self.lock:
            if not self.is_open:
                return
            try:
                self._close()
            finally:
                self.is_open = False
                if self._file_lock is not None:
                    self._file_lock.release()
                wire_log.debug("%s: closed", self.resource)

    def reconnect(self) -> None:
        """Close and open again, keeping the lock file (no other process slips in)."""
        with self.lock:
            wire_log.debug("%s: reconnecting", self.resource)
            if self.is_open:
                try:
                    self._close()
                except Exception as exc:  # a broken link may not close cleanly
                    wire_log.debug("%s: close while reconnecting: %s", self.resource, exc)
                self.is_open = False
            self._open_locked()

    def __enter__(self) -> Transport:
        self.open()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ------------------------------------------------------------- timeouts
    @property
    def timeout_s(self) -> float:
        return self._timeout_s

    @timeout_s.setter
    def timeout_s(self, value: float) -> None:
        if not value > 0:
            raise ValueError("timeout_s must be positive")
        self._timeout_s = float(value)
        if self.is_open:
            self._apply_timeout()

    def _apply_timeout(self) -> None:  # noqa: B027 - optional hook, a no-op by default
        """Push the timeout to the open link (if it keeps one of its own)."""

    # ------------------------------------------------------------- bytes
    def write(self, message: bytes) -> None:
        """Send one message; the transport adds its own termination."""
        with self.lock:
            wire_log.debug("%s -> %s", self.resource, describe(message))
            self._write(message)

    def read_line(self) -> bytes:
        """One reply line, without its CR LF."""
        with self.lock:
            line = self._read_line()
            wire_log.debug("%s <- %s", self.resource, describe(line))
            return line

    def read_exact(self, count: int) -> bytes:
        """Exactly ``count`` bytes (InstrumentTimeout if they do not all come)."""
        with self.lock:
            data = self._read_exact(count)
            wire_log.debug("%s <- %s", self.resource, describe(data) if count > 8 else summarize(data))
            return data

    def clear(self) -> None:
        """Device clear: the instrument abandons its output, stale input is discarded."""
        with self.lock:
            wire_log.debug("%s: device clear", self.resource)
            self._clear()

    # ------------------------------------------------------------- to implement
    @abstractmethod
    def _open(self) -> None: ...

    @abstractmethod
    def _close(self) -> None: ...

    @abstractmethod
    def _write(self, message: bytes) -> None: ...

    @abstractmethod
    def _read_line(self) -> bytes: ...

    @abstractmethod
    def _read_exact(self, count: int) -> bytes: ...

    @abstractmethod
    def _clear(self) -> None: ...
