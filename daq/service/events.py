"""Live events of the service, from the threads that cause them to every client.

Each event gets the next number (the SSE ``id``), is encoded to JSON once, kept in
a bounded history (so a client that reconnects with ``Last-Event-ID`` gets what it
missed) and handed to every subscriber's queue on the subscriber's own event loop.
Publishing happens under one lock, numbers and hand-over together, so every
subscriber sees the events in number order, none twice, none skipped.

A subscriber that stops reading does not hold memory forever: past
``MAX_QUEUED`` undelivered events it is dropped (its stream ends; the browser's
EventSource reconnects and catches up from the history).
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import math
import threading
from collections import deque
from dataclasses import dataclass, field
from typing import Any

#: Events kept for reconnecting clients.
HISTORY_EVENTS = 1000
#: Bytes of event data kept at most (hit events carry traces, ~40 kB each).
HISTORY_BYTES = 32 * 2**20
#: Undelivered events a subscriber may have before it is dropped.
MAX_QUEUED = 5000


@dataclass(frozen=True)
class Event:
    """id : 1, 2, ... in publication order. kind : the SSE event name. data : JSON text."""

    id: int
    kind: str
    data: str

    def sse(self) -> bytes:
        return f"id: {self.id}\nevent: {self.kind}\ndata: {self.data}\n\n".encode()


@dataclass(eq=False)
class Subscriber:
    loop: asyncio.AbstractEventLoop
    queue: asyncio.Queue = field(default_factory=asyncio.Queue)
    dropped: bool = False


class EventHub:
    """Thread-safe publish; asyncio subscribe."""

    def __init__(self, history_events: int = HISTORY_EVENTS, history_bytes: int = HISTORY_BYTES) -> None:
        self._lock = threading.Lock()
        self._next_id = 1
        self._history: deque[Event] = deque()
        self._history_bytes = 0
        self._max_events = history_events
        self._max_bytes = history_bytes
        self._subscribers: set[Subscriber] = set()
        self._closed = False

    @property
    def last_id(self) -> int:
        with self._lock:
            return self._next_id - 1

    @property
    def n_subscribers(self) -> int:
        with self._lock:
            return len(self._subscribers)

    def publish(self, kind: str, data: dict[str, Any]) -> Event:
        """Number, record and deliver one event; callable from any thread."""
        text = json.dumps(plain(data), separators=(",", ":"), allow_nan=False)
        with self._lock:
            event = Event(self._next_id, kind, text)
            self._next_id += 1
            self._history.append(event)
            self._history_bytes += len(text)
            while len(self._history) > self._max_events or self._history_bytes > self._max_bytes:
                self._history_bytes -= len(self._history.popleft().data)
            for sub in list(self._subscribers):
                try:
                    sub.loop.call_soon_threadsafe(_deliver, self, sub, event)
                except RuntimeError:  # its loop is closed: the client is gone
                    self._subscribers.discard(sub)
        return event

    def subscribe(self, since: int | None = None) -> tuple[Subscriber, list[Event]]:
        """A subscriber on the running loop, and the kept events after ``since``
        (none if ``since`` is None). Events published later arrive in its queue."""
        sub = Subscriber(asyncio.get_running_loop())
        with self._lock:
            backlog = [e for e in self._history if since is not None and e.id > since]
            if self._closed:
                sub.queue.put_nowait(None)
            else:
                self._subscribers.add(sub)
        return sub, backlog

    def close(self) -> None:
        """End every stream (the service stops): each subscriber gets the end marker,
        so that its connection closes at once instead of holding the shutdown."""
        with self._lock:
            subscribers, self._subscribers = list(self._subscribers), set()
            self._closed = True
        for sub in subscribers:
            sub.dropped = True
            with contextlib.suppress(RuntimeError):  # its loop is already closed
                sub.loop.call_soon_threadsafe(sub.queue.put_nowait, None)

    def unsubscribe(self, sub: Subscriber) -> None:
        with self._lock:
            self._subscribers.discard(sub)

    def _drop(self, sub: Subscriber) -> None:
        with self._lock:
            self._subscribers.discard(sub)
        sub.dropped = True


def _deliver(hub: EventHub, sub: Subscriber, event: Event) -> None:
    if sub.dropped:
        return
    if sub.queue.qsize() >= MAX_QUEUED:
        hub._drop(sub)
        sub.queue.put_nowait(None)  # wakes the stream, which then ends
        return
    sub.queue.put_nowait(event)


def plain(value: Any) -> Any:
    """``value`` with numpy arrays and scalars as lists and numbers, tuples as lists,
    and non-finite floats as None: what JSON can carry."""
    if isinstance(value, dict):
        return {str(k): plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [plain(v) for v in value]
    if hasattr(value, "tolist"):  # numpy array or scalar
        return plain(value.tolist())
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, complex):
        return [plain(value.real), plain(value.imag)]
    return value
