"""In-process front end: the analyzer's byte stream without a socket, for fast tests.

Each ``write`` is one complete message (as with EOI on GPIB); ``read`` returns
the reply bytes as an instrument would put them on the wire, slow and faulty
ones included.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Sequence

from sims.instrument import Analyzer
from sims.session import Session


class InProcessConnection:
    def __init__(self, analyzer: Analyzer, faults: Sequence[str] = ()) -> None:
        self.session = Session(analyzer, tuple(faults))
        # (bytes, when they may go, what they wait for besides: SCPI's *OPC?)
        self._out: deque[list] = deque()
        self._closed = False
        self._drop_pending = False

    def write(self, data: bytes) -> None:
        if self._closed:
            raise ConnectionResetError("the simulated analyzer closed the connection")
        chunks = self.session.feed(data) + self.session.end_of_message()
        ready = max(time.monotonic(), self._out[-1][1] if self._out else 0.0)
        for chunk in chunks:
            # A slow instrument answers one reply after the other: delays add up.
            ready += chunk.delay_s
            if chunk.data:
                self._out.append([bytearray(chunk.data), ready, chunk.until])
            if chunk.close:
                self._drop_pending = True

    def read(self, size: int = -1, timeout_s: float = 1.0) -> bytes:
        """Up to ``size`` bytes (all that are ready if -1); TimeoutError if none come in time."""
        deadline = time.monotonic() + timeout_s
        while True:
            if self._out and self._ready(self._out[0]):
                break
            if not self._out and self._drop_pending:
                self._closed = True
                raise ConnectionResetError("the simulated analyzer closed the connection")
            if time.monotonic() >= deadline:
                raise TimeoutError(f"no reply within {timeout_s:g} s")
            time.sleep(0.001)
        data = bytearray()
        while self._out and self._ready(self._out[0]) and (size < 0 or len(data) < size):
            chunk = self._out[0][0]
            take = len(chunk) if size < 0 else min(len(chunk), size - len(data))
            data += chunk[:take]
            del chunk[:take]
            if not chunk:
                self._out.popleft()
        return bytes(data)

    @staticmethod
    def _ready(entry: list) -> bool:
        if entry[1] > time.monotonic():
            return False
        if entry[2] is not None:
            if not entry[2]():
                return False
            entry[2] = None  # once ready, it stays ready
        return True

    def clear(self) -> None:
        """Device clear: pending output and partial input are discarded."""
        self._out.clear()
        self.session.clear()

    def close(self) -> None:
        self._closed = True
        self._out.clear()
