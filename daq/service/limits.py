"""What a request must be before the application sees it.

Request bodies are small (a capture's hits, operator and note; a decision): anything
bigger is refused before it is read, so that no client can make the service buffer
megabytes. A body must announce its length: a request with any Transfer-Encoding
(chunked) is refused, whatever Content-Length it also carries; one that sends more
than it announced is cut off by the server (uvicorn's h11 enforces Content-Length).
Requests that need the token are refused before anything else. Every refusal closes
the connection, so that the body it did not read is not read afterwards either.

``GuardedH11Protocol`` bounds the connections themselves (docs/service.md, Security)."""

from __future__ import annotations

import json
from typing import Any

#: Largest request body accepted, bytes.
MAX_BODY_BYTES = 64 * 1024

_METHODS_WITH_BODY = {"POST", "PUT", "PATCH"}


class BodyLimit:
    """ASGI middleware: 411 for any Transfer-Encoding, 413 above MAX_BODY_BYTES."""

    def __init__(self, app: Any, max_bytes: int = MAX_BODY_BYTES) -> None:
        self.app = app
        self.max_bytes = max_bytes

    async def __call__(self, scope: dict, receive: Any, send: Any) -> None:
        if scope["type"] == "http":
            names = [name for name, _ in scope.get("headers") or []]
            # Any Transfer-Encoding, on any method and whatever Content-Length says beside it:
            # the server reads a chunked body until its last chunk, whatever its size, and
            # h11 lets Transfer-Encoding override Content-Length (RFC 9112 6.3).
            if b"transfer-encoding" in names:
                return await _refuse(send, 411, "a body needs a Content-Length header (chunked is refused)")
            if scope["method"] in _METHODS_WITH_BODY:
                lengths = [value for name, value in scope.get("headers") or [] if name == b"content-length"]
                if any(not v.isdigit() or int(v) > self.max_bytes for v in lengths):
                    return await _refuse(send, 413, f"the body must be at most {self.max_bytes} bytes")
        await self.app(scope, receive, send)


class TokenGate:
    """ASGI middleware: requests that need the token are refused (401) before their
    body is read or parsed, so that no one without it learns anything from the
    validation of a body. ``needs_token(method, path)`` says which; ``check(request
    headers and query)`` compares in constant time."""

    def __init__(self, app: Any, needs_token: Any, given_ok: Any, route_exists: Any = None) -> None:
        self.app = app
        self.needs_token = needs_token
        self.given_ok = given_ok
        #: route_exists(scope): whether any route answers the method at the path. A
        #: request none answers gets its 404 or 405 whatever the token: a 401 would tell
        #: the client to find a token for a route that does not exist.
        self.route_exists = route_exists or (lambda scope: True)

    async def __call__(self, scope: dict, receive: Any, send: Any) -> None:
        if (
            scope["type"] == "http"
            and self.needs_token(scope["method"], scope["path"])
            and self.route_exists(scope)
        ):
            headers = dict(scope.get("headers") or [])
            authorization = headers.get(b"authorization", b"").decode("latin-1")
            query = scope.get("query_string", b"").decode("latin-1")
            if not self.given_ok(scope["method"], authorization, query):
                return await _refuse(
                    send,
                    401,
                    "a valid token is needed (Authorization: Bearer <token>; daq serve --show-token)",
                    [(b"www-authenticate", b'Bearer realm="daq serve"')],
                )
        await self.app(scope, receive, send)


async def _refuse(send: Any, status: int, detail: str, extra: list | None = None) -> None:
    """Answer ``status`` and close the connection: the request's body, if any, is never
    read (closing is the only way not to read it: on a kept-alive connection the server
    would go on parsing it, to its last byte, to find the next request)."""
    body = json.dumps({"detail": detail}).encode()
    headers = [
        (b"content-type", b"application/json"),
        (b"content-length", str(len(body)).encode()),
        (b"connection", b"close"),
    ]
    await send({"type": "http.response.start", "status": status, "headers": headers + (extra or [])})
    await send({"type": "http.response.body", "body": body})


#: Names a browser on this machine uses for the service when it listens on loopback.
LOOPBACK_NAMES = frozenset({"127.0.0.1", "localhost", "[::1]"})


def host_name(header: str) -> str:
    """The name part of a Host header: ``[::1]:8000`` -> ``[::1]``, ``a:80`` -> ``a``."""
    header = header.strip().lower()
    if header.startswith("["):
        return header[: header.find("]") + 1] if "]" in header else header
    return header.rsplit(":", 1)[0] if ":" in header else header


class LoopbackHost:
    """ASGI middleware for a service on loopback, whose reads need no token: a request
    must name it as 127.0.0.1, localhost or [::1] (400 otherwise), so that a web page
    elsewhere whose name was made to resolve to 127.0.0.1 (DNS rebinding) gets nothing."""

    def __init__(self, app: Any) -> None:
        self.app = app

    async def __call__(self, scope: dict, receive: Any, send: Any) -> None:
        if scope["type"] == "http":
            headers = dict(scope.get("headers") or [])
            name = host_name(headers.get(b"host", b"").decode("latin-1"))
            if name not in LOOPBACK_NAMES:
                return await _refuse(send, 400, "this service answers only to 127.0.0.1, localhost or [::1]")
        await self.app(scope, receive, send)


# ---------------------------------------------------------------- connections
#: Seconds a connection may take from its first byte (or from its opening, if it sends
#: nothing) to the end of a request's headers. A browser sends them at once.
HEADER_TIMEOUT_S = 10.0

#: Open connections at most, whatever the file-descriptor limit allows.
MAX_CONNECTIONS = 4096

#: File descriptors kept for everything but connections (run files, worker pipes, the
#: analyzer, the store's index): at least this many, and at least a quarter of the limit.
FD_RESERVE = 64


def raise_fd_limit(wanted: int = 65536) -> int:
    """Raise the soft limit on open files towards the hard one (at most ``wanted``); the
    soft limit now. Many systems start processes at 1,024, which idle clients fill."""
    import resource

    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    target = wanted if hard == resource.RLIM_INFINITY else min(hard, wanted)
    if soft != resource.RLIM_INFINITY and soft < target:
        try:
            resource.setrlimit(resource.RLIMIT_NOFILE, (target, hard))
            soft = target
        except (ValueError, OSError):
            pass
    return soft


def connection_cap(fd_limit: int) -> int:
    """Connections the service keeps open at most, under ``fd_limit`` open files."""
    reserve = max(FD_RESERVE, fd_limit // 4)
    return max(8, min(MAX_CONNECTIONS, fd_limit - reserve))


class ConnectionGuard:
    """What the connections of one server share: their number and age, the cap, the
    header timeout. At the cap a new connection takes the place of the one idle the
    longest (no request in progress: one that has sent nothing, or only part of its
    headers, or waits between requests); if every connection has a request in
    progress (event streams), the new one is closed."""

    def __init__(self, cap: int, header_timeout_s: float = HEADER_TIMEOUT_S) -> None:
        self.cap = cap
        self.header_timeout_s = header_timeout_s
        #: Open connections, the one idle longest first (moved to the end when active).
        self.open: dict[Any, None] = {}
        self.evicted = 0
        self.timed_out = 0
        self.refused = 0

    def protocol_class(self) -> type:
        from uvicorn.protocols.http.h11_impl import H11Protocol

        guard = self

        class GuardedH11Protocol(H11Protocol):
            """uvicorn's h11 protocol, with a header timeout and a connection cap
            (uvicorn has neither: an idle connection is kept until the client closes it)."""

            _header_timer: Any = None

            def connection_made(self, transport: Any) -> None:
                super().connection_made(transport)
                if len(guard.open) >= guard.cap and not guard.make_room():
                    guard.refused += 1
                    transport.abort()
                    return
                guard.open[self] = None
                self._arm_header_timer()

            def connection_lost(self, exc: Exception | None) -> None:
                guard.open.pop(self, None)
                self._disarm_header_timer()
                super().connection_lost(exc)

            def data_received(self, data: bytes) -> None:
                if self._header_timer is None and self.idle:
                    self._arm_header_timer()  # the first byte of the next request: its clock starts
                super().data_received(data)
                if not self.idle:
                    self._disarm_header_timer()
                    guard.touch(self)

            def on_response_complete(self) -> None:
                super().on_response_complete()
                guard.touch(self)  # idle again, from now (uvicorn's keep-alive timeout runs)

            @property
            def idle(self) -> bool:
                """No request in progress: nothing, part of a request's headers, or
                nothing since the last response."""
                return self.cycle is None or self.cycle.response_complete

            def _arm_header_timer(self) -> None:
                self._disarm_header_timer()
                self._header_timer = self.loop.call_later(guard.header_timeout_s, self._header_timed_out)

            def _disarm_header_timer(self) -> None:
                if self._header_timer is not None:
                    self._header_timer.cancel()
                    self._header_timer = None

            def _header_timed_out(self) -> None:
                self._header_timer = None
                if self.idle and not self.transport.is_closing():
                    guard.timed_out += 1
                    self.transport.abort()

        return GuardedH11Protocol

    def touch(self, protocol: Any) -> None:
        if protocol in self.open:
            del self.open[protocol]
            self.open[protocol] = None

    def make_room(self) -> bool:
        """Close the connection idle longest; False if none is idle."""
        for protocol in self.open:
            if protocol.idle:
                del self.open[protocol]
                protocol._disarm_header_timer()
                self.evicted += 1
                protocol.transport.abort()
                return True
        return False
