"""Request bodies are small (a capture's hits, operator and note; a decision): anything
bigger is refused before it is read, so that no client can make the service buffer
megabytes. A body must announce its length; one that sends more than it announced
is cut off by the server (uvicorn's h11 enforces Content-Length)."""

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
            if length is None:
                return await _refuse(send, 411, "a body needs a Content-Length header")
            if not length.isdigit() or int(length) > self.max_bytes:
                return await _refuse(send, 413, f"the body must be at most {self.max_bytes} bytes")
        await self.app(scope, receive, send)


async def _refuse(send: Any, status: int, detail: str) -> None:
    body = json.dumps({"detail": detail}).encode()
    await send(
        {
            "type": "http.response.start",
            "status": status,
            "headers": [(b"content-type", b"application/json"), (b"content-length", str(len(body)).encode())],
        }
    )
    await send({"type": "http.response.body", "body": body})
