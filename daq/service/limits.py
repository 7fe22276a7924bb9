"""What a request must be before the application sees it.

Request bodies are small (a capture's hits, operator and note; a decision): anything
bigger is refused before it is read, so that no client can make the service buffer
megabytes. A body must announce its length (a chunked one is refused); one that sends
more than it announced is cut off by the server (uvicorn's h11 enforces
Content-Length). Requests that need the token are refused before anything else."""

from __future__ import annotations

import json
from typing import Any

#: Largest request body accepted, bytes.
MAX_BODY_BYTES = 64 * 1024

_METHODS_WITH_BODY = {"POST", "PUT", "PATCH"}


class BodyLimit:
    """ASGI middleware: 411 without Content-Length, 413 above MAX_BODY_BYTES."""

    def __init__(self, app: Any, max_bytes: int = MAX_BODY_BYTES) -> None:
        self.app = app
        self.max_bytes = max_bytes

    async def __call__(self, scope: dict, receive: Any, send: Any) -> None:
        if scope["type"] == "http" and scope["method"] in _METHODS_WITH_BODY:
            headers = dict(scope.get("headers") or [])
            length = headers.get(b"content-length")
            if length is None and b"transfer-encoding" in headers:
                return await _refuse(send, 411, "a body needs a Content-Length header")
            if length is not None and (not length.isdigit() or int(length) > self.max_bytes):
                return await _refuse(send, 413, f"the body must be at most {self.max_bytes} bytes")
        await self.app(scope, receive, send)


class TokenGate:
    """ASGI middleware: requests that need the token are refused (401) before their
    body is read or parsed, so that no one without it learns anything from the
    validation of a body. ``needs_token(method, path)`` says which; ``check(request
    headers and query)`` compares in constant time."""

    def __init__(self, app: Any, needs_token: Any, given_ok: Any) -> None:
        self.app = app
        self.needs_token = needs_token
        self.given_ok = given_ok

    async def __call__(self, scope: dict, receive: Any, send: Any) -> None:
        if scope["type"] == "http" and self.needs_token(scope["method"], scope["path"]):
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
    body = json.dumps({"detail": detail}).encode()
    headers = [(b"content-type", b"application/json"), (b"content-length", str(len(body)).encode())]
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
