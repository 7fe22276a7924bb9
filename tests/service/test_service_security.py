"""`daq serve` against requests it must refuse: without a token or with a wrong one,
path traversal and odd run ids, oversized, chunked and malformed bodies, reads
beyond loopback, and an unsafe token file. Each gets a clear 4xx and changes
nothing: no capture starts, no run lands, no event is published, no file outside
the store is served. Real `daq serve` processes, real sockets; requests that a
client library would tidy up (dot segments, %00, bodies cut short) go out raw."""

from __future__ import annotations

import json
import os
import stat

import httpx
import pytest

from tests.cli_helpers import assert_one_line_error, capture_sim
from tests.service.hardening_helpers import (
    first_event,
    raw_request,
    run_daq_env,
)
from tests.service.service_helpers import EventReader, Served, service_env, serving, wait_for

pytestmark = pytest.mark.slow

#: One step up, as a path segment.
UP = "." + "./"

#: Every route that changes something, with a body it would accept.
POST_ROUTES = {
    "/api/capture": {"hits": 2, "auto": True},
    "/api/capture/decision": {"index": 0, "accept": True},
    "/api/capture/stop": {},
    "/api/capture/abort": {},
}

#: The routes of one run; {} is the run id as sent (already percent-encoded).
RUN_ROUTES = (
    "/api/runs/{}",
    "/api/runs/{}/analysis",
    "/api/runs/{}/frf",
    "/api/runs/{}/fits",
    "/api/runs/{}/file",
    "/api/runs/{}/export?format=csv",
    "/api/runs/{}/export?format=uff",
    "/api/runs/{}/report",
)

SECRET = "the secret outside the store"
HDF5_MAGIC = b"\x89HDF\r\n\x1a\n"


def bad_credentials(token: str) -> dict[str, dict[str, str]]:
    return {
        "no token": {},
        "a wrong token": {"Authorization": "Bearer " + "0" * len(token)},
        "the token cut short": {"Authorization": "Bearer " + token[:-1]},
        "the token and one more": {"Authorization": "Bearer " + token + "0"},
        "the token in capitals": {"Authorization": "Bearer " + token.upper()},
        "another scheme": {"Authorization": "Basic " + token},
        "no scheme": {"Authorization": token},
        "a bare scheme": {"Authorization": "Bearer"},
    }


def assert_refused_401(response: httpx.Response, what: str) -> None:
    assert response.status_code == 401, (what, response.status_code, response.text)
    detail = response.json()["detail"]
    assert isinstance(detail, str), (what, detail)
    assert "token" in detail, (what, detail)


def assert_nothing_started(served: Served, events: EventReader) -> None:
    """No capture ran, no run landed, no event was published."""
    with served.client(token=False) as anonymous:  # on loopback, reads need no token
        snapshot = anonymous.get("/api/capture").json()
    assert snapshot["state"] == "idle", snapshot
    assert snapshot["run_id"] is None, snapshot
    assert snapshot["last_run_id"] is None, snapshot
    assert snapshot["hits"] == [], snapshot
    assert sorted(p.name for p in served.store.glob("*.h5")) == []
    assert [e for e in events.events if e[0] is not None] == [], events.events
    assert first_event(served).data == {"last_id": 0}  # the hub numbered no event


@pytest.fixture(scope="module")
def idle_service(tmp_path_factory):
    """One service for the tests whose every request is refused: each checks that
    nothing started (no capture, no run, no event numbered), so each finds it as a
    fresh one. A service per test cost each of them a start (4-5 s)."""
    with serving(tmp_path_factory.mktemp("refusing"), "--sim", "--workers", "1") as served:
        yield served


def test_posts_without_a_valid_token_get_401_and_start_nothing(idle_service):
    served = idle_service
    events = EventReader(served)
    with httpx.Client(base_url=served.url, timeout=30) as client:
        for route, body in POST_ROUTES.items():
            for what, headers in bad_credentials(served.token).items():
                answer = client.post(route, json=body, headers=headers)
                assert_refused_401(answer, f"POST {route} with {what}")
            # ?token= is for GETs (EventSource, download links): a POST needs the header.
            answer = client.post(route, json=body, params={"token": served.token})
            assert_refused_401(answer, f"POST {route} with the token in the query")
    assert_nothing_started(served, events)

    # The same requests with the token pass the check (and find nothing to act on).
    with served.client() as client:
        for route in ("/api/capture/decision", "/api/capture/stop", "/api/capture/abort"):
            answer = client.post(route, json=POST_ROUTES[route])
            assert answer.status_code == 409, (route, answer.text)
    lower = {"Authorization": f"bearer {served.token}"}  # the scheme is case-insensitive
    with httpx.Client(base_url=served.url, headers=lower, timeout=30) as client:
        assert client.post("/api/capture/stop").status_code == 409
    assert_nothing_started(served, events)
    events.close()


def test_a_running_capture_cannot_be_decided_stopped_or_aborted_without_the_token(tmp_path):
    with serving(tmp_path, "--sim", "--time-scale", "0.02") as served:
        events = EventReader(served)
        run_id = served.post("/api/capture", {"hits": 2}).json()["run_id"]
        wait_for(lambda: served.get("/api/capture").json()["pending"] == 0, 30, "the first hit")
        with httpx.Client(base_url=served.url, timeout=30) as client:
            for route in ("/api/capture/decision", "/api/capture/stop", "/api/capture/abort"):
                for what, headers in bad_credentials(served.token).items():
                    answer = client.post(route, json=POST_ROUTES[route], headers=headers)
                    assert_refused_401(answer, f"POST {route} with {what}")
                answer = client.post(route, json=POST_ROUTES[route], params={"token": served.token})
                assert_refused_401(answer, f"POST {route} with the token in the query")
            starts = [client.post("/api/capture", json={"hits": 1}, headers=h) for h in ({}, {"X": "y"})]
            for answer in starts:
                assert_refused_401(answer, "a second start without the token")
        snapshot = served.get("/api/capture").json()
        assert (snapshot["state"], snapshot["run_id"], snapshot["pending"]) == ("running", run_id, 0)
        assert [h["decided"] for h in snapshot["hits"]] == [False]
        assert "hit_decided" not in events.kinds(run_id)
        assert "capture_ended" not in events.kinds(run_id)

        assert served.post("/api/capture/abort").status_code == 202  # the token still works
        assert events.wait_for_kind("capture_ended", run_id, 30)["outcome"] == "aborted"
        assert list(served.store.glob("*.h5")) == []
        events.close()


def test_odd_run_ids_and_path_traversal_get_404_and_never_a_file(tmp_path):
    store = tmp_path / "store"
    first = capture_sim(store, "seed", 1, hits=1)
    second = capture_sim(store, "seed", 2, hits=1)
    common = next(first[:n] for n in range(len(first), 0, -1) if second.startswith(first[:n]))
    assert common, (first, second)
    (tmp_path / "secret.txt").write_text(SECRET)
    (tmp_path / "secret.h5").write_text(SECRET)
    outside = str(tmp_path / "secret.txt")
    odd_ids = [
        "..",
        ".",
        "%2e%2e",
        "..%2fsecret.txt",
        "..%2f..%2fsecret.txt",
        "%2e%2e%2f%2e%2e%2fetc%2fpasswd",
        "..%5c..%5csecret.txt",
        "%2Fetc%2Fpasswd",
        outside.replace("/", "%2F"),
        "secret",
        "..%2fsecret.h5",
        "%00",
        f"{first}%00",
        f"{first[:10]}%00%2f..",
        "%20",
        "*",
        f"{first[:8]}%2A",
        "2" * 65,
        "2" * 4000,
        "%D9%A2%D9%A0%D9%A2%D9%A6",  # Arabic-Indic digits: \d would take them
        f"{first}%2f..%2f..%2fsecret.txt",
        f"{first}.h5%2f..%2f..%2fsecret.h5",
        "latest%2f..%2f..%2fsecret.txt",
        common,  # a start of both runs: which one is meant?
    ]
    with serving(tmp_path, "--sim") as served:
        # The routes work, so a 404 below is a refusal, not a missing route.
        file = raw_request(served.url, f"GET /api/runs/{first}/file HTTP/1.1\r\nHost: 127.0.0.1")
        assert file.status == 200
        assert file.body == (store / f"{first}.h5").read_bytes()
        for name in ("latest", first[:-1], f"{second}.h5"):
            assert raw_request(served.url, f"GET /api/runs/{name} HTTP/1.1\r\nHost: 127.0.0.1").status == 200

        for run_id in odd_ids:
            for route in RUN_ROUTES:
                target = route.format(run_id)
                answer = raw_request(served.url, f"GET {target} HTTP/1.1\r\nHost: 127.0.0.1")
                assert answer.status == 404, (target, answer.status, answer.body[:300])
                assert "detail" in answer.json(), target
                assert SECRET.encode() not in answer.body, target
                assert HDF5_MAGIC not in answer.body, target
        ambiguous = raw_request(served.url, f"GET /api/runs/{common} HTTP/1.1\r\nHost: 127.0.0.1").json()
        assert "matches 2 runs" in ambiguous["detail"], ambiguous

        # Dot segments sent as they are (a client library would resolve them first).
        # (UP is spelled in pieces: tests/test_docs.py flags a literal one as a path
        # out of the repository.)
        raw_targets = [
            f"/api/runs/{UP}{UP}secret.txt",
            f"/api/runs/{UP * 6}etc/passwd",
            f"/api/runs/{first}/{UP * 3}secret.txt",
            f"/api/runs/./{UP}file",
            f"/static/{UP}app.py",
            f"/static/{UP}{UP}service/app.py",
            "/static/%2e%2e/app.py",
            "/static/..%2fapp.py",
            "/static/%2e%2e%2f%2e%2e%2f%2e%2e%2f%2e%2e%2fetc%2fpasswd",
            "/static/" + outside.replace("/", "%2F"),
            "/static//etc/passwd",
        ]
        for target in raw_targets:
            answer = raw_request(served.url, f"GET {target} HTTP/1.1\r\nHost: 127.0.0.1")
            assert answer.status == 404, (target, answer.status, answer.body[:300])
            for leak in (SECRET.encode(), b"def create_app", b"root:", HDF5_MAGIC):
                assert leak not in answer.body, (target, leak)

        for fmt in ("xml", "CSV", "h5", "", "csv%0A", "csv%00", "uff%20", "..%2f..%2fetc%2fpasswd", "c.v"):
            target = f"/api/runs/{first}/export?format={fmt}"
            answer = raw_request(served.url, f"GET {target} HTTP/1.1\r\nHost: 127.0.0.1")
            assert answer.status == 422, (target, answer.status, answer.body[:300])
            assert "format" in answer.json()["detail"], target
        assert sorted(p.name for p in store.glob("*.h5") if p.name.count(".") == 2) == sorted(
            [f"{first}.h5", f"{second}.h5"]
        )


def test_oversized_chunked_and_malformed_bodies_get_a_clear_4xx_and_start_nothing(idle_service):
    served = idle_service
    events = EventReader(served)
    auth = f"Authorization: Bearer {served.token}"
    with served.client() as client:
        for route in POST_ROUTES:
            # Over 64 KiB: 413.
            big = client.post(route, content=b" " * (64 * 1024 + 1), headers={"Content-Type": "x/json"})
            assert big.status_code == 413, (route, big.text)
            assert "65536" in big.json()["detail"]
            # No Content-Length (chunked): 411.
            chunked = client.post(route, content=iter([b'{"hits": 2,', b' "auto": true}']))
            assert chunked.status_code == 411, (route, chunked.text)
            assert "Content-Length" in chunked.json()["detail"]

    # 413 before the body is read: 100 MB announced, 4 KiB sent, the answer comes anyway
    # (were the service waiting for the rest, the read would time out).
    for route in POST_ROUTES:
        head = f"POST {route} HTTP/1.1\r\nHost: 127.0.0.1\r\n{auth}\r\nContent-Length: 100000000"
        answer = raw_request(served.url, head, b"{" * 4096, timeout_s=10)
        assert answer.status == 413, (route, answer.status, answer.body)
    head = f"POST /api/capture HTTP/1.1\r\nHost: 127.0.0.1\r\n{auth}\r\nTransfer-Encoding: chunked"
    answer = raw_request(served.url, head, b'b\r\n{"hits": 2}\r\n0\r\n\r\n')
    assert answer.status == 411, answer.body

    # Exactly 64 KiB is read and judged on its content (a note too long): 422, not 413.
    frame = {"hits": 2, "note": ""}
    filler = 64 * 1024 - len(json.dumps(frame).encode())
    edge = json.dumps({"hits": 2, "note": "x" * filler}).encode()
    assert len(edge) == 64 * 1024
    with served.client() as client:
        answer = client.post("/api/capture", content=edge, headers={"Content-Type": "application/json"})
    assert answer.status_code == 422, answer.text
    assert answer.json()["detail"].startswith("note:"), answer.text

    malformed = {
        "/api/capture": [
            b"{",
            b"not json",
            b"",
            b"[]",
            b"null",
            b"5",
            b'"hits"',
            b"\xff\xfe{}",
            b'{"hits": 2}{"hits": 3}',
            b'{"hits": 0}',
            b'{"hits": 1000}',
            b'{"hits": -3}',
            b'{"hits": "five"}',
            b'{"hits": "5"}',
            b'{"hits": true}',
            b'{"hits": 2.5}',
            b'{"hits": NaN}',
            b'{"hits": 1e400}',
            b'{"hits": [2]}',
            b'{"hits": 2, "extra": 1}',
            b'{"hits": 2, "auto": "yes"}',
            b'{"hits": 2, "auto": 1}',
            b'{"hits": 2, "operator": 5}',
            json.dumps({"hits": 2, "operator": "o" * 201}).encode(),
            json.dumps({"hits": 2, "note": "n" * 2001}).encode(),
        ],
        "/api/capture/decision": [
            b"{",
            b"{}",
            b'{"index": 0}',
            b'{"accept": true}',
            b'{"index": -1, "accept": true}',
            b'{"index": "0", "accept": true}',
            b'{"index": 0, "accept": "yes"}',
            b'{"index": 0, "accept": true, "extra": 1}',
            json.dumps({"index": 0, "accept": False, "reason": "r" * 501}).encode(),
        ],
    }
    with served.client() as client:
        for route, bodies in malformed.items():
            for body in bodies:
                answer = client.post(route, content=body, headers={"Content-Type": "application/json"})
                assert answer.status_code == 422, (route, body[:60], answer.status_code, answer.text)
                detail = answer.json()["detail"]
                assert isinstance(detail, str), (route, body[:60], detail)
                assert "\n" not in detail, (route, body[:60], detail)
                assert 0 < len(detail) < 300, (route, body[:60], detail)
        # Nested too deep for the JSON parser: still a 4xx, never a 500.
        deep = b"[" * 30000 + b"]" * 30000
        answer = client.post("/api/capture", content=deep, headers={"Content-Type": "application/json"})
        assert answer.status_code in (400, 422), answer.text
        # A form post (what a page of another site could send without scripts): refused.
        form = client.post("/api/capture", content=b'{"hits": 2}', headers={"Content-Type": "text/plain"})
        assert form.status_code == 422, form.text
    # Lengths the HTTP layer cannot parse: 400 from the server itself.
    for length in ("-1", "abc", "1, 2", "+5"):
        head = f"POST /api/capture HTTP/1.1\r\nHost: 127.0.0.1\r\n{auth}\r\nContent-Length: {length}"
        assert raw_request(served.url, head, b"{}").status == 400, length
    assert_nothing_started(served, events)
    events.close()


def test_beyond_loopback_every_read_needs_the_token_but_the_pages_do_not(tmp_path):
    run_id = capture_sim(tmp_path / "store", "realistic", 1, hits=2)
    with serving(tmp_path, "--sim", "--workers", "1", host="0.0.0.0") as served:
        banner = "".join(served.stderr_lines)
        assert "EVERY request needs the token" in banner, banner
        events = EventReader(served)  # the header works for the event stream
        events.wait_for_kind("fit_done", run_id, 120)
        events.close()
        reads = [
            "/api/health",
            "/api/instrument",
            "/api/capture",
            "/api/capture/hits/0",
            "/api/capture/frf",
            "/api/runs",
            f"/api/runs/{run_id}",
            f"/api/runs/{run_id}/analysis",
            f"/api/runs/{run_id}/frf",
            f"/api/runs/{run_id}/fits",
            f"/api/runs/{run_id}/file",
            f"/api/runs/{run_id}/export?format=csv",
            f"/api/runs/{run_id}/export?format=uff",
            f"/api/runs/{run_id}/report",
            "/api/runs/no-such-run",
        ]
        no_capture_yet = {"/api/capture/hits/0", "/api/capture/frf", "/api/runs/no-such-run"}
        with httpx.Client(base_url=served.url, timeout=60) as client:
            for path in [*reads, "/api/events"]:
                for what, headers in bad_credentials(served.token).items():
                    with client.stream("GET", path, headers=headers) as answer:
                        answer.read()
                        assert_refused_401(answer, f"GET {path} with {what}")
                for wrong in ("", "0" * len(served.token), served.token[:-1], served.token.upper()):
                    with client.stream("GET", path, params={"token": wrong}) as answer:
                        answer.read()
                        assert_refused_401(answer, f"GET {path}?token={wrong[:6]}...")
            for path in reads:
                by_query = client.get(path, params={"token": served.token})
                by_header = client.get(path, headers={"Authorization": f"Bearer {served.token}"})
                wanted = 404 if path in no_capture_yet else 200
                assert by_query.status_code == by_header.status_code == wanted, (path, by_query.text)
        assert served.get("/api/health").json()["token_required_for_reads"] is True
        assert first_event(served, headers={}, token=served.token).kind == "hello"
        assert first_event(served).kind == "hello"

        # The pages and their scripts hold no data: they load without the token.
        with httpx.Client(base_url=served.url, timeout=30) as client:
            for page in ("/", "/runs", "/static/style.css", "/static/common.js", "/static/live.js"):
                answer = client.get(page)
                assert answer.status_code == 200, (page, answer.status_code)
                assert served.token not in answer.text, page


def test_the_token_file_is_private_and_an_unsafe_one_is_refused(tmp_path):
    token_file = tmp_path / "token"
    assert not token_file.exists()
    with serving(tmp_path, "--sim", "--workers", "1") as served:
        mode = stat.S_IMODE(token_file.stat().st_mode)
        assert mode == 0o600, oct(mode)
        assert token_file.read_text() == served.token + "\n"
        assert len(served.token) == 64
        assert set(served.token) <= set("0123456789abcdef")
        assert f"a new access token was made in {token_file}" in "".join(served.stderr_lines)
    env = service_env(tmp_path)
    shown = run_daq_env(env, "serve", "--show-token", timeout_s=30)
    assert (shown.returncode, shown.stdout) == (0, served.token + "\n"), shown.stderr

    serve = ("serve", "--sim", "--port", "0", "--store", str(tmp_path / "store"))
    for loose in (0o644, 0o640):
        token_file.chmod(loose)
        for args in (serve, ("serve", "--show-token")):
            refused = run_daq_env(env, *args, timeout_s=30)
            assert_one_line_error(refused, str(token_file), "readable by others", "chmod 600")
            assert served.token not in refused.stdout + refused.stderr
        assert token_file.read_text() == served.token + "\n"  # refused, not replaced
    token_file.chmod(0o600)

    # A symlink to a good token file, a directory, a FIFO (whose open would wait for a
    # writer), a file that holds no token: refused, in one line.
    link = tmp_path / "link-token"
    link.symlink_to(token_file)
    folder = tmp_path / "folder-token"
    folder.mkdir(mode=0o700)
    fifo = tmp_path / "fifo-token"
    os.mkfifo(fifo, 0o600)
    junk = tmp_path / "junk-token"
    junk.write_text("not a token\n")
    junk.chmod(0o600)
    cases = {
        link: "cannot read the token file",
        folder: "not a regular file",
        fifo: "not a regular file",
        junk: "does not hold a token",
    }
    for path, fragment in cases.items():
        refused = run_daq_env({**env, "DAQ_TOKEN_FILE": str(path)}, *serve, timeout_s=30)
        assert_one_line_error(refused, str(path), fragment)
        assert served.token not in refused.stdout + refused.stderr
    assert token_file.read_text() == served.token + "\n"
    assert junk.read_text() == "not a token\n"


def test_loopback_refuses_foreign_host_names_and_401_comes_before_the_body(idle_service):
    served = idle_service
    # DNS rebinding: a page elsewhere whose name now resolves to 127.0.0.1 sends its
    # own name as Host; reads need no token on loopback, so such requests are refused.
    for host in ("evil.example:8000", "evil.example", "192.168.1.20"):
        answer = raw_request(served.url, f"GET /api/runs HTTP/1.1\r\nHost: {host}")
        assert answer.status == 400, (host, answer.status)
    port = served.url.rsplit(":", 1)[1]
    for host in (f"127.0.0.1:{port}", f"localhost:{port}", f"[::1]:{port}", "LOCALHOST"):
        assert raw_request(served.url, f"GET /api/runs HTTP/1.1\r\nHost: {host}").status == 200
    # Without the token nothing is learnt from the body: 401 for malformed JSON too,
    # with the scheme the client should use.
    garbage = {"content": b"{not json", "headers": {"Content-Type": "application/json"}}
    with served.client(token=False) as client:
        answer = client.post("/api/capture", **garbage)
    assert answer.status_code == 401
    assert answer.headers["www-authenticate"].startswith("Bearer")
    # With it, malformed JSON is named as such.
    with served.client() as client:
        answer = client.post("/api/capture", **garbage)
    assert answer.status_code == 422
    assert answer.json()["detail"] == "body: not valid JSON"
    # A POST with no body at all (curl -X POST) is an empty body, not a refused one.
    auth = f"Authorization: Bearer {served.token}"
    stop = raw_request(served.url, f"POST /api/capture/stop HTTP/1.1\r\nHost: 127.0.0.1\r\n{auth}")
    assert stop.status == 409  # nothing runs: the request itself was accepted
