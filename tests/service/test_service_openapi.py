"""The OpenAPI description lists every error answer of the API with its body, and the
real answers have that body (issue 24: 401, 404, 409, 411, 413, 422, 503)."""

from __future__ import annotations

import socket
from urllib.parse import urlparse

from tests.service.service_helpers import serving


def _error_codes(spec: dict, path: str, method: str) -> set[str]:
    answers = spec["paths"][path][method]["responses"]
    codes = {code for code in answers if code[0] in "45"}
    for code in codes:
        schema = answers[code]["content"]["application/json"]["schema"]
        assert schema == {"$ref": "#/components/schemas/Error"}, (path, method, code)
        assert answers[code]["description"], (path, method, code)
    return codes


def test_every_error_answer_is_described_and_answered_with_its_body(tmp_path):
    with serving(tmp_path, "--sim", "--seed", "1", "--time-scale", "0") as served:
        spec = served.get("/openapi.json").json()
        assert spec["components"]["schemas"]["Error"]["required"] == ["detail"]
        # On loopback reads need no token; writes always do.
        assert _error_codes(spec, "/api/capture", "post") == {"401", "409", "411", "413", "422", "503"}
        assert _error_codes(spec, "/api/capture/decision", "post") == {"401", "409", "411", "413", "422"}
        assert {"404", "422", "503"} <= _error_codes(spec, "/api/runs/{run_id}", "get")
        assert "401" not in _error_codes(spec, "/api/runs/{run_id}", "get")
        every = set().union(
            *(
                _error_codes(spec, p, m)
                for p, ops in spec["paths"].items()
                if p.startswith("/api/")
                for m in ops
            )
        )
        assert every == {"401", "404", "409", "411", "413", "422", "503"}

        # The real answers carry the described body.
        answers = {
            "401": served.client(token=False).post("/api/capture/stop"),
            "404": served.get("/api/runs/20260101T000000.000Z-00000000"),
            "409": served.post("/api/capture/decision", {"index": 0, "accept": True}),
            "422": served.post("/api/capture", {"hits": "many"}),
        }
        for code, answer in answers.items():
            assert str(answer.status_code) == code, (code, answer.text)
            assert isinstance(answer.json()["detail"], str)
            assert set(answer.json()) == {"detail"}
        # 411: a chunked body, sent by hand (clients add a Content-Length on their own).
        where = urlparse(served.url)
        head = (
            b"POST /api/capture HTTP/1.1\r\nHost: 127.0.0.1\r\nAuthorization: Bearer " + served.token.encode()
        )
        chunked = (
            b"\r\nContent-Type: application/json\r\nTransfer-Encoding: chunked\r\n\r\n2\r\n{}\r\n0\r\n\r\n"
        )
        with socket.create_connection((where.hostname, where.port), timeout=10) as sock:
            sock.sendall(head + chunked)
            reply = b""
            while chunk := sock.recv(4096):  # the service closes the connection after it
                reply += chunk
        assert reply.startswith(b"HTTP/1.1 411"), reply[:80]
        assert b'{"detail":' in reply
