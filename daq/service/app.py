"""The HTTP API and pages of ``daq serve`` (FastAPI; docs/service.md lists every route).

Request handlers that touch the disk or the analyzer are plain ``def``: FastAPI runs
them in its thread pool, so the event loop only ever streams events.
"""

from __future__ import annotations

import asyncio
import os
import re
import stat
import tempfile
from importlib import resources
from pathlib import Path
from typing import Annotated, Any
from urllib.parse import parse_qs

import numpy as np
from fastapi import Depends, FastAPI, Header, HTTPException, Query, Request
from fastapi.concurrency import run_in_threadpool
from fastapi.encoders import jsonable_encoder
from fastapi.exceptions import RequestValidationError
from fastapi.responses import FileResponse, HTMLResponse, JSONResponse, Response, StreamingResponse
from fastapi.staticfiles import StaticFiles
from pydantic import BaseModel, ConfigDict, Field, field_validator
from starlette.background import BackgroundTask
from starlette.routing import Match

from daq import __version__
from daq.service.auth import token_matches
from daq.service.capture_control import MAX_HITS_WANTED, Conflict
from daq.service.events import plain
from daq.service.jobs import analysis_result_name
from daq.service.limits import BodyLimit, LoopbackHost, TokenGate
from daq.service.service import ReadRefused, Service, is_regular
from daq.store import StoreError
from daq.store.ids import RUN_ID_PATTERN
from drivers.errors import DriverError

#: Seconds between keep-alive comments on an idle event stream (proxies and browsers
#: drop silent connections).
KEEPALIVE_S = 15.0


#: Control characters other than tab and line breaks: refused in text a run stores (a NUL
#: cannot be stored at all, an escape sequence would drive a terminal that lists runs).
_CONTROL = re.compile(r"[\x00-\x08\x0b\x0c\x0e-\x1f\x7f]")


def _plain_text(value: str, one_line: bool) -> str:
    if _CONTROL.search(value) or (one_line and re.search(r"[\r\n\t]", value)):
        raise ValueError("control characters are not allowed" + (" (one line of text)" if one_line else ""))
    return value


class CaptureRequest(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True)  # true or "5" is no int, "yes" no bool: 422
    hits: int = Field(5, ge=1, le=MAX_HITS_WANTED, description="Accepted hits to average.")
    operator: str = Field("", max_length=200)
    note: str = Field("", max_length=2000)
    auto: bool = Field(False, description="Decide each hit by the checks instead of waiting for a decision.")
    setup: str | None = Field(
        None, max_length=200, description="A named setup (GET /api/setups); default: the service's."
    )
    test: str | None = Field(None, max_length=200, description="The multi-point test the run measures.")
    point: str | None = Field(
        None, max_length=200, description='The test\'s point to measure, or "next" (the first not measured).'
    )

    setup_version: int | None = Field(
        None, ge=0, description="The setup's version the client shows; 409 if it was saved since."
    )

    @field_validator("setup", "test", "point")
    @classmethod
    def _names(cls, value: str | None) -> str | None:
        return None if value is None else _plain_text(value, one_line=True)

    @field_validator("operator")
    @classmethod
    def _operator(cls, value: str) -> str:
        return _plain_text(value, one_line=True)

    @field_validator("note")
    @classmethod
    def _note(cls, value: str) -> str:
        return _plain_text(value, one_line=False)


class SetupPut(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True)
    setup: dict[str, Any] = Field(
        description="The setup file's tables (setup_codec keys, channels' transducer)."
    )
    version: int = Field(ge=0, description="The version this save starts from; 0 for a new setup.")


class PracticeRequest(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True)
    setup: str | None = Field(None, max_length=200, description="The setup to range; default: the service's.")
    hits: int = Field(3, ge=1, le=100, description="Practice hits to take (none is kept).")


class Decision(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True)  # true or "5" is no int, "yes" no bool: 422
    index: int = Field(ge=0, description="0-based index of the pending hit.")
    accept: bool
    reason: str = Field("", max_length=500)

    @field_validator("reason")
    @classmethod
    def _reason(cls, value: str) -> str:
        return _plain_text(value, one_line=True)


def create_app(service: Service) -> FastAPI:
    app = FastAPI(
        title="daq serve",
        version=__version__,
        description="The lab service: captures on the HP analyzer, the run store, analyses and fits.",
        docs_url=None,  # Swagger UI loads scripts from a CDN; the lab PC may have no network
        redoc_url=None,
    )
    app.state.service = service
    token = service.config.token

    def needs_token(method: str, path: str) -> bool:
        if method not in ("GET", "HEAD"):
            return True
        return service.config.reads_need_token and path.startswith("/api/")

    def route_exists(scope: dict[str, Any]) -> bool:
        """True if a route answers ``scope``'s method at its path: a method or path
        that none does gets its 405 or 404 whatever the token (it learns nothing)."""
        return any(route.matches(scope)[0] == Match.FULL for route in app.router.routes)

    def given_ok(method: str, authorization: str, query: str) -> bool:
        given = None
        if authorization.lower().startswith("bearer "):
            given = authorization[7:].strip()
        elif method in ("GET", "HEAD"):
            given = parse_qs(query).get("token", [None])[0]
        return token_matches(given, token)

    # Added last runs first: the host check, then the token, then the body's size.
    app.add_middleware(BodyLimit)
    app.add_middleware(TokenGate, needs_token=needs_token, given_ok=given_ok, route_exists=route_exists)
    if not service.config.reads_need_token:
        # On loopback the reads need no token, so a page elsewhere whose name was made
        # to resolve to 127.0.0.1 (DNS rebinding) must not be served: only loopback names.
        app.add_middleware(LoopbackHost)

    # The token is checked by TokenGate; these only mark the routes in the OpenAPI description.
    reads: list[Any] = [Depends(_documented_token)] if service.config.reads_need_token else []
    writes: list[Any] = [Depends(_documented_token)]

    @app.exception_handler(RequestValidationError)
    async def _invalid(request: Request, exc: RequestValidationError) -> JSONResponse:
        first = exc.errors()[0] if exc.errors() else {}
        where = ".".join(str(p) for p in first.get("loc", ()) if p != "body") or "body"
        message = first.get("msg", "invalid request")
        if first.get("type") == "json_invalid":
            where, message = "body", "not valid JSON"
        elif where == "body" and first.get("type") in ("model_attributes_type", "dict_type"):
            # A form-encoded body (curl -d 'a=b'), a JSON list, text or number.
            message = "must be a JSON object (Content-Type: application/json)"
        return JSONResponse({"detail": f"{where}: {message}"}, status_code=422)

    # ------------------------------------------------------------ pages
    static = resources.files("daq.service") / "static"

    reads_need_token = "true" if service.config.reads_need_token else "false"

    @app.get("/", include_in_schema=False)
    def live_page() -> Response:
        return _page(static, "index.html", reads_need_token)

    @app.get("/runs", include_in_schema=False)
    def runs_page() -> Response:
        return _page(static, "runs.html", reads_need_token)

    @app.get("/favicon.ico", include_in_schema=False)
    def favicon() -> Response:
        return Response(status_code=204)  # none: but no 404 in the browser's console

    app.mount("/static", StaticFiles(directory=str(static), check_dir=False), name="static")

    # ------------------------------------------------------------ status
    @app.get(
        "/api/health", dependencies=reads, summary="The service, the instrument, the capture, the workers"
    )
    def health() -> dict[str, Any]:
        return {
            "status": "ok",
            "version": __version__,
            "instrument": service.link.status(),
            "capture": {"state": service.capture.state},
            "jobs": service.jobs.counts(),
            "token_required_for_reads": service.config.reads_need_token,
            "clients": service.hub.n_subscribers,
        }

    @app.get("/api/instrument", dependencies=reads, summary="What is known of the analyzer")
    def instrument() -> dict[str, Any]:
        return service.link.status()

    # ------------------------------------------------------------ capture
    @app.get("/api/capture", dependencies=reads, summary="The current or last capture")
    def capture_state() -> dict[str, Any]:
        snapshot = service.capture.snapshot()
        if snapshot.get("setup") is not None:  # the last capture's; a file by its name only
            snapshot["setup"] = {
                **snapshot["setup"],
                "name": _setup_file_named(snapshot["setup"]["name"], snapshot["setup"]["name"]),
            }
        snapshot["next_setup"] = _next_setup(service)  # what a capture naming none uses
        return plain(snapshot)

    @app.post("/api/capture", dependencies=writes, status_code=202, summary="Start a capture")
    def capture_start(body: CaptureRequest) -> dict[str, Any]:
        where = _test_point(service, body.test, body.point)
        setup = _capture_setup(service, body.setup, body.setup_version)
        try:
            run_id = service.capture.start(
                body.hits, body.operator, body.note, body.auto, where=where, setup=setup
            )
        except ValueError as exc:
            raise HTTPException(422, str(exc)) from None
        except Conflict as exc:
            raise HTTPException(409, str(exc)) from None
        except DriverError as exc:
            raise HTTPException(503, f"the analyzer cannot be reached: {exc}") from None
        return {"run_id": run_id}

    @app.post("/api/capture/decision", dependencies=writes, summary="Accept or reject the pending hit")
    def capture_decision(body: Decision) -> dict[str, Any]:
        try:
            service.capture.decide(body.index, body.accept, body.reason)
        except Conflict as exc:
            raise HTTPException(409, str(exc)) from None
        return {"index": body.index, "accepted": body.accept}

    @app.post(
        "/api/capture/practice",
        dependencies=writes,
        status_code=202,
        summary="Practice hits (none kept): the ranges and trigger level for a setup",
    )
    def capture_practice(body: PracticeRequest) -> dict[str, Any]:
        setup = _capture_setup(service, body.setup, None)
        try:
            service.capture.start_practice(setup, body.hits)
        except ValueError as exc:
            raise HTTPException(422, str(exc)) from None
        except Conflict as exc:
            raise HTTPException(409, str(exc)) from None
        except DriverError as exc:
            raise HTTPException(503, f"the analyzer cannot be reached: {exc}") from None
        return {"state": service.capture.state, "hits": body.hits}

    @app.post(
        "/api/capture/undo",
        dependencies=writes,
        summary="Take back the last decision while it is held (the hit is pending again)",
    )
    def capture_undo() -> dict[str, Any]:
        try:
            undone = service.capture.undo()
        except Conflict as exc:
            raise HTTPException(409, str(exc)) from None
        return undone

    @app.post("/api/capture/stop", dependencies=writes, status_code=202, summary="Stop; seal the hits so far")
    def capture_stop() -> dict[str, Any]:
        return _stop(service, "stop")

    @app.post("/api/capture/abort", dependencies=writes, status_code=202, summary="Abort; discard the hits")
    def capture_abort() -> dict[str, Any]:
        return _stop(service, "abort")

    @app.get(
        "/api/capture/hits/{index}",
        dependencies=reads,
        summary="One hit's time records and quality: windows, force spectrum, its FRF, the running average",
    )
    def capture_hit(index: int) -> dict[str, Any]:
        if index < 0:
            raise HTTPException(422, "index: must be 0 or more (hits count from 0 in the API)")
        traces = service.capture.hit_quality(index)
        if traces is None:
            raise HTTPException(404, f"the current capture has no hit of index {index} (hit {index + 1})")
        return plain(traces)

    @app.get("/api/capture/frf", dependencies=reads, summary="The FRF averaged over the accepted hits so far")
    def capture_frf() -> dict[str, Any]:
        frf = service.capture.frf()
        if frf is None:
            raise HTTPException(404, "no hit accepted yet")
        return plain(frf)

    # ------------------------------------------------------------ setups, transducers
    @app.get("/api/setups", dependencies=reads, summary='The named setups ("default" always)')
    def setups() -> dict[str, Any]:
        from daq.workflows.station_setups import setups_listing

        return plain(_station_call(service, setups_listing, service.store.path))

    @app.get("/api/setups/{name}", dependencies=reads, summary="One setup: its tables, settings, cautions")
    def setup_get(
        name: str,
        version: Annotated[
            int | None,
            Query(ge=0, description="That version, from the setup's history; default: the current."),
        ] = None,
    ) -> dict[str, Any]:
        from daq.workflows.station_setups import setup_view

        return plain(_station_call(service, setup_view, service.store.path, name, version))

    @app.put(
        "/api/setups/{name}",
        dependencies=writes,
        summary="Save a setup (a new version), checked against the connected analyzer",
    )
    def setup_put(name: str, body: SetupPut) -> dict[str, Any]:
        from daq.workflows.station_setups import connected_model, save_setup

        status = service.link.status()
        model = connected_model(status.get("dialect"), status.get("identification"))
        return plain(
            _station_call(service, save_setup, service.store.path, name, body.setup, body.version, model)
        )

    @app.get("/api/transducers", dependencies=reads, summary="The transducers (built-ins included)")
    def transducers() -> dict[str, Any]:
        from daq.workflows.station_setups import transducers_listing

        return plain(_station_call(service, transducers_listing, service.store.path))

    @app.get("/api/transducers/{ident}", dependencies=reads, summary="One transducer")
    def transducer_get(ident: str) -> dict[str, Any]:
        from daq.workflows.station_setups import transducer_view

        return plain(_station_call(service, transducer_view, service.store.path, ident))

    @app.put("/api/transducers/{ident}", dependencies=writes, summary="Save a transducer")
    def transducer_put(ident: str, body: dict[str, Any]) -> dict[str, Any]:
        from daq.workflows.station_setups import save_transducer

        return plain(_station_call(service, save_transducer, service.store.path, ident, body))

    # ------------------------------------------------------------ tests
    @app.get(
        "/api/tests", dependencies=reads, summary="The store's multi-point tests, their points and the next"
    )
    def tests() -> dict[str, Any]:
        from daq.workflows.errors import WorkflowError
        from daq.workflows.test_views import tests_listing

        try:
            return plain(tests_listing(service.store.path))
        except WorkflowError as exc:
            raise HTTPException(404, service.public(str(exc))) from None

    @app.get("/api/tests/{name}", dependencies=reads, summary="One test: its points, runs and coherence")
    def test_detail(name: str) -> dict[str, Any]:
        from daq.workflows.errors import WorkflowError
        from daq.workflows.test_views import test_detail

        try:
            return plain(test_detail(service.store.path, name))
        except WorkflowError as exc:
            raise HTTPException(404, service.public(str(exc))) from None

    # ------------------------------------------------------------ runs
    # Every read of a run file goes through service.reads (bounded, with a timeout): a
    # run that is slow or impossible to read must not take the server's threads.
    async def read(what: str, rid: str, fn: Any, *args: Any) -> Any:
        try:
            return await service.reads.run((what, rid), fn, *args)
        except ReadRefused as exc:
            raise HTTPException(503, str(exc), headers={"Retry-After": "5"}) from None

    async def resolve(run_id: str) -> str:
        return await run_in_threadpool(_resolve, service, run_id)

    @app.get("/api/runs", dependencies=reads, summary="Every run of the store, with its results")
    async def runs() -> Response:
        row = lambda s: _run_row(service, s)  # noqa: E731
        return _json_bytes(await read("list", "*", _store_call, service, service.runs_json, row))

    def run_info(rid: str) -> bytes:
        from daq.workflows.run_views import run_dict

        info = run_dict(_store_call(service, service.store.open, rid), service.store.path / f"{rid}.h5")
        info["file"] = f"{rid}.h5"  # not the server's path
        state = service.jobs.state(rid)
        analysis = service.analysis(rid)
        return _encode(
            {
                "run": info,
                "analysis": None if analysis is None else analysis["summary"],
                "fits": {name: p["summary"] for name, p in service.fits(rid).items()},
                "analysis_state": state["analysis"],
                "fit_state": state["fit"],
            }
        )

    @app.get("/api/runs/{run_id}", dependencies=reads, summary="One run, its analysis and fits")
    async def run(run_id: str) -> Response:
        rid = await resolve(run_id)
        return _json_bytes(await read("run", rid, run_info, rid))

    def analysis_json(rid: str) -> bytes:
        data = service.summary_json(rid, analysis_result_name())
        if data is None:
            raise HTTPException(404, f"run {rid} has no analysis yet ({service.jobs.state(rid)['analysis']})")
        return data

    @app.get("/api/runs/{run_id}/analysis", dependencies=reads, summary="The run's analysis: modes, Table 2")
    async def run_analysis(run_id: str) -> Response:
        rid = await resolve(run_id)
        return _json_bytes(await read("analysis", rid, analysis_json, rid))

    def frf_json(rid: str) -> bytes:
        payload = _analysis(service, rid)
        frf = np.atleast_2d(payload["frf"])[0]
        coherence = payload.get("coherence")
        return _encode(
            {
                "frequency_hz": payload["frequency_hz"],
                "frf_abs": np.abs(frf),
                "frf_phase_deg": np.degrees(np.angle(frf)),
                "coherence": None if coherence is None else np.atleast_2d(coherence)[0],
            }
        )

    @app.get("/api/runs/{run_id}/frf", dependencies=reads, summary="The run's analysed FRF and coherence")
    async def run_frf(run_id: str) -> Response:
        rid = await resolve(run_id)
        return _json_bytes(await read("analysis", rid, frf_json, rid))

    def fits_json(rid: str) -> bytes:
        return _encode({name: p["summary"] for name, p in service.fits(rid).items()})

    @app.get("/api/runs/{run_id}/fits", dependencies=reads, summary="The run's damping fits")
    async def run_fits(run_id: str) -> Response:
        rid = await resolve(run_id)
        return _json_bytes(await read("fits", rid, fits_json, rid))

    @app.get("/api/runs/{run_id}/file", dependencies=reads, summary="The run's HDF5 file")
    async def run_file(run_id: str) -> Response:
        rid = await resolve(run_id)
        handle, size = await run_in_threadpool(_open_run_file, service, rid)
        return StreamingResponse(
            _chunks(handle),
            media_type="application/x-hdf5",
            headers={
                "Content-Length": str(size),
                "Content-Disposition": f'attachment; filename="{rid}.h5"',
            },
        )

    def export_file(rid: str, format: str) -> Path:
        the_run = _store_call(service, service.store.open, rid)
        folder = Path(tempfile.mkdtemp(prefix="daq-export-"))
        target = folder / f"{rid}.{format}"
        from daq.workflows.errors import WorkflowError
        from daq.workflows.export import write_run

        try:
            write_run(the_run, target, format)
        except (WorkflowError, ValueError, OSError) as exc:
            _remove(folder)
            message = service.public(f"cannot export run {rid} as {format}: {exc}")
            raise HTTPException(422, message) from None
        return target

    @app.get("/api/runs/{run_id}/export", dependencies=reads, summary="The run as CSV or UFF 58")
    async def run_export(
        run_id: str, format: Annotated[str, Query(pattern="^(csv|uff)$")] = "csv"
    ) -> Response:
        rid = await resolve(run_id)
        # Not shared between requests: each gets its own file, removed once sent.
        target = await read(f"export-{format}-{id(object())}", rid, export_file, rid, format)
        media = "text/csv" if format == "csv" else "application/octet-stream"
        return FileResponse(
            target, media_type=media, filename=target.name, background=BackgroundTask(_remove, target.parent)
        )

    def report(rid: str) -> str:
        try:
            return service.report_html(rid)
        except (StoreError, ValueError) as exc:
            raise HTTPException(422, service.public(f"no report for run {rid}: {exc}")) from None

    @app.get(
        "/api/runs/{run_id}/report",
        dependencies=reads,
        response_class=HTMLResponse,
        summary="The run's report",
    )
    async def run_report(run_id: str) -> HTMLResponse:
        rid = await resolve(run_id)
        return HTMLResponse(await read("report", rid, report, rid))

    # ------------------------------------------------------------ events
    @app.get("/api/events", dependencies=reads, summary="Live events (server-sent events)")
    async def events(
        request: Request,
        since: Annotated[int | None, Query(ge=0)] = None,
        last_event_id: Annotated[str | None, Header()] = None,
    ) -> StreamingResponse:
        text = (last_event_id or "").strip()
        # isascii: "\xb2" (superscript 2) is a digit to isdigit() but not to int(); and an
        # id is far below 19 digits (int() refuses over 4300): anything else is no id.
        if since is None and text.isascii() and text.isdigit() and len(text) < 19:
            since = int(text)
        return StreamingResponse(
            _stream(service, request, since),
            media_type="text/event-stream",
            headers={"Cache-Control": "no-cache", "X-Accel-Buffering": "no"},
        )

    _document_error_answers(app, service.config.reads_need_token)
    return app


#: What each error answer of the API means; every one has the body ``{"detail": "..."}``.
ERROR_ANSWERS = {
    "401": "no token, or the wrong one (writes always; reads when the service is not on loopback)",
    "404": "no such run, hit, result, test, setup or transducer",
    "409": "the capture is not in a state that allows this (one already running, no pending hit, a "
    "decision already with the analyzer, ...), or a setup saved since the version given",
    "411": "a body without a Content-Length header (chunked bodies are refused)",
    "413": "a body larger than the service accepts",
    "422": "a parameter or the body is not valid; detail names the field",
    "503": "the analyzer or a run file cannot be reached now; try again (Retry-After)",
}
_CAPTURE_CONTROL = (
    "/api/capture", "/api/capture/decision", "/api/capture/undo", "/api/capture/stop", "/api/capture/abort",
    "/api/capture/practice",
)  # fmt: skip


def _document_error_answers(app: FastAPI, reads_need_token: bool) -> None:
    """List every error answer each /api route can give, with its body, in the OpenAPI
    description (FastAPI lists only 422, and with its own body, not this service's)."""
    from fastapi.openapi.utils import get_openapi

    def openapi() -> dict[str, Any]:
        if app.openapi_schema:
            return app.openapi_schema
        schema = get_openapi(
            title=app.title, version=app.version, description=app.description, routes=app.routes
        )
        schemas = schema.setdefault("components", {}).setdefault("schemas", {})
        schemas["Error"] = {
            "title": "Error",
            "type": "object",
            "properties": {"detail": {"type": "string", "title": "Detail"}},
            "required": ["detail"],
        }
        body = {"application/json": {"schema": {"$ref": "#/components/schemas/Error"}}}
        for path, operations in schema.get("paths", {}).items():
            if not path.startswith("/api/"):
                continue
            for method, operation in operations.items():
                codes = set()
                if method != "get" or reads_need_token:
                    codes.add("401")
                if method in ("post", "put"):
                    codes |= {"411", "413"}
                if operation.get("parameters") or operation.get("requestBody"):
                    codes.add("422")
                if ("{" in path and method != "put") or path == "/api/capture/frf":
                    codes.add("404")
                if method == "post" and path in _CAPTURE_CONTROL:
                    codes.add("409")
                if method == "put" and path.startswith("/api/setups/"):
                    codes.add("409")
                if method == "put":
                    codes.add("422")
                if (
                    method == "post" and path in ("/api/capture", "/api/capture/practice")
                ) or path.startswith("/api/runs"):
                    codes.add("503")
                answers = operation.setdefault("responses", {})
                for code in sorted(codes):
                    answers[code] = {"description": ERROR_ANSWERS[code], "content": body}
        app.openapi_schema = schema
        return schema

    app.openapi = openapi  # type: ignore[method-assign]


async def _stream(service: Service, request: Request, since: int | None):
    sub, backlog = service.hub.subscribe(since)
    try:
        yield f'event: hello\ndata: {{"last_id": {service.hub.last_id}}}\n\n'.encode()
        for event in backlog:
            yield event.sse()
        while True:
            try:
                event = await asyncio.wait_for(sub.queue.get(), KEEPALIVE_S)
            except TimeoutError:
                if await request.is_disconnected():
                    return
                yield b": keep-alive\n\n"
                continue
            if event is None:  # the client fell too far behind: it reconnects and catches up
                return
            yield event.sse()
    finally:
        service.hub.unsubscribe(sub)


async def _documented_token(authorization: Annotated[str | None, Header()] = None) -> None:
    """Declares the Authorization header in the OpenAPI description (TokenGate checks it)."""


def _json_bytes(data: bytes) -> Response:
    """Already-encoded JSON (FastAPI's encoder would walk every value again)."""
    return Response(data, media_type="application/json")


def _page(static: Any, name: str, reads_need_token: str) -> Response:
    page = static / name
    if not page.is_file():
        raise HTTPException(404, f"{name} is not installed")
    return HTMLResponse(page.read_text(encoding="utf-8").replace("{{READS_NEED_TOKEN}}", reads_need_token))


def _stop(service: Service, how: str) -> dict[str, Any]:
    try:
        service.capture.stop(how)
    except Conflict as exc:
        raise HTTPException(409, str(exc)) from None
    return {"state": service.capture.state}


def _station_call(service: Service, fn: Any, *args: Any) -> Any:
    """``fn(*args)`` of daq/workflows/station_setups.py with its errors as HTTP answers:
    an unknown name 404, a version conflict 409, a setup or transducer that does not
    check 422 (the field first), a store that cannot be read 422."""
    from daq.store.setups import VersionConflict
    from daq.workflows.errors import WorkflowError
    from daq.workflows.station_setups import UnknownName

    try:
        return fn(*args)
    except UnknownName as exc:
        raise HTTPException(404, service.public(str(exc))) from None
    except VersionConflict as exc:
        raise HTTPException(409, service.public(str(exc))) from None
    except (WorkflowError, StoreError, ValueError) as exc:
        raise HTTPException(422, service.public(str(exc))) from None


def _capture_setup(service: Service, name: str | None, version: int | None) -> Any:
    """The setup a capture (or practice) uses: ``name``, else the service's (``daq serve
    --setup``), else None (the service's settings). 422 naming the field, 409 when
    ``version`` is given and the setup was saved since."""
    from daq.store.setups import check_setup_name
    from daq.workflows.station_setups import setup_for_capture

    if name is not None:
        # Over HTTP only the store's named setups: a path would read a server file, and
        # its answer would tell whether that file exists.
        try:
            check_setup_name(name)
        except StoreError:
            raise HTTPException(422, "setup: give the name of a stored setup (GET /api/setups)") from None
    name = name or service.config.setup  # the service's own: given on its command line
    if name is None:
        if version is not None:
            raise HTTPException(422, "setup_version: needs a setup")
        return None
    try:
        return _station_call(service, setup_for_capture, service.store.path, name, version)
    except HTTPException as exc:
        detail = _setup_file_named(str(exc.detail), name)
        if exc.status_code == 404:  # a field of the request, not an address
            raise HTTPException(422, detail) from None
        if exc.status_code == 422 and not detail.startswith("setup"):
            raise HTTPException(422, f"setup {_setup_file_named(name, name)}: {detail}") from None
        raise HTTPException(exc.status_code, detail) from None


def _setup_file_named(text: str, name: str) -> str:
    """``text`` with the service's setup file (``daq serve --setup FILE``, an absolute
    path) named by its file name only: no answer names the server's folders."""
    from daq.workflows.setups import is_setup_path

    return text.replace(name, Path(name).name) if is_setup_path(name) else text


def _next_setup(service: Service) -> dict[str, Any] | None:
    """The setup a capture that names none uses (``daq serve --setup``): ``{"name",
    "version"}`` (a file's name only, version 0; version None if it cannot be read
    now); None: the service's own settings, no setup."""
    from daq.store.setups import SetupStore
    from daq.workflows.setups import is_setup_path

    name = service.config.setup
    if name is None:
        return None
    if is_setup_path(name):
        return {"name": Path(name).name, "version": 0}
    try:
        return {"name": name, "version": SetupStore(service.store.path).get(name).version}
    except StoreError:
        return {"name": name, "version": None}


def _test_point(service: Service, test: str | None, point: str | None) -> Any:
    """The test's point a capture measures (``point`` a name or "next"), None without a
    test; 422 naming the field otherwise."""
    from daq.workflows.errors import WorkflowError
    from daq.workflows.test import point_to_measure

    if test is None and point is None:
        return None
    if test is None:
        raise HTTPException(422, "test: a point needs the test it belongs to")
    if point is None:
        raise HTTPException(422, 'point: give the test\'s point to measure, or "next"')
    try:
        return point_to_measure(service.store.path, test, None if point == "next" else point, point == "next")
    except WorkflowError as exc:
        text = service.public(str(exc))
        field = "point" if "has no point" in text or "every point" in text else "test"
        raise HTTPException(422, f"{field}: {text}") from None


def _store_call(service: Service, fn: Any, *args: Any) -> Any:
    """``fn(*args)``; a StoreError is a 404 whose message does not name the server's folders."""
    try:
        return fn(*args)
    except StoreError as exc:
        raise HTTPException(404, service.public(str(exc))) from None


def _resolve(service: Service, run_id: str) -> str:
    """The id of the run named by ``run_id`` (an id, a unique prefix, or latest); 404
    otherwise. Names are checked against the id grammar before any path is formed, and
    a run file that is not a regular file (a link, a FIFO, a device) is no run."""
    if not run_id or len(run_id) > 64:
        raise HTTPException(404, "no such run")
    if RUN_ID_PATTERN.fullmatch(run_id) and is_regular(service.store.path / f"{run_id}.h5"):
        return run_id  # a whole, well-formed id: no need to scan the store for prefixes
    rid = _store_call(service, service.store.resolve, run_id).stem
    if not is_regular(service.store.path / f"{rid}.h5"):
        raise HTTPException(404, f"run {rid} is not a regular file; refused")
    return rid


#: The first bytes of an HDF5 file (its superblock's signature, at offset 0 in a run).
HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"


def _open_run_file(service: Service, rid: str) -> tuple[Any, int]:
    """The run's file, opened without following a link, and its size: only a regular
    file that starts as HDF5 does (not a hard link to the token file, say)."""
    path = service.store.path / f"{rid}.h5"
    try:
        # O_NONBLOCK: a FIFO put in its place must not hang the open (no effect on files).
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC)
    except OSError:
        raise HTTPException(404, f"run {rid} cannot be opened") from None
    handle = os.fdopen(fd, "rb")
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode) or handle.read(len(HDF5_SIGNATURE)) != HDF5_SIGNATURE:
            raise HTTPException(404, f"run {rid} is not a regular HDF5 file; refused")
        handle.seek(0)
    except BaseException:
        handle.close()
        raise
    return handle, info.st_size


def _chunks(handle: Any, size: int = 256 * 1024):
    with handle:
        while chunk := handle.read(size):
            yield chunk


def _encode(value: Any) -> bytes:
    """``value`` as JSON bytes, as FastAPI would send it."""
    return JSONResponse(jsonable_encoder(plain(value))).body


def _analysis(service: Service, rid: str) -> dict[str, Any]:
    payload = service.analysis(rid)
    if payload is None:
        raise HTTPException(404, f"run {rid} has no analysis yet ({service.jobs.state(rid)['analysis']})")
    return payload


def _run_row(service: Service, s: Any) -> dict[str, Any]:
    from daq.service import texts
    from daq.workflows.run_views import summary_dict

    row = summary_dict(s)
    row.pop("file", None)
    if isinstance(row.get("error"), str):
        row["error"] = service.public(row["error"])
    row.update(analysis="none", fit="none", frequencies_hz=None, damping_ratios=None, fit_psi=None)
    # Added later (older clients ignore them): what the page must show beside the numbers,
    # so that a result that may mislead is never silent in the listing.
    row.update(
        frequencies_u_hz=None, damping_u=None, band=None, synthesis_error=None, cautions=[], fit_cautions=[]
    )
    # The same numbers as texts, written as `daq analyze` and the report write them (the
    # page shows these, so that it cannot round differently), why a stage failed, and the
    # formats the run can be exported as (CSV needs time records).
    row.update(
        frequencies_text=None, damping_text=None, band_text=None, synthesis_text=None, fit_psi_text=None,
        analysis_error=None, fit_error=None, exports=["csv", "uff"] if s.n_hits else ["uff"],
    )  # fmt: skip
    if s.error is not None:
        row["exports"] = []
        return plain(row)
    state = service.jobs.state(s.run_id)
    row.update(analysis=state["analysis"], fit=state["fit"])
    errors = getattr(service.jobs, "error", None)  # a stand-in for the jobs (a test's) may lack it
    if errors is not None:
        row.update(analysis_error=errors(s.run_id, "analysis"), fit_error=errors(s.run_id, "fit"))
    # A stored result that is up to date is shown whatever waits in the queue (a run
    # analysed or fitted from the command line before the service started).
    analysis = service.analysis(s.run_id) if _shown(service, s.run_id, state, "analysis") else None
    if analysis is not None:
        summary = analysis["summary"]
        modes = summary.get("modes", [])
        row["frequencies_hz"] = [m["frequency_hz"] for m in modes]
        row["damping_ratios"] = [m["damping_ratio"] for m in modes]
        row["frequencies_u_hz"] = [m.get("frequency_u_hz") for m in modes]
        row["damping_u"] = [m.get("damping_u") for m in modes]
        row["band"] = summary.get("band")
        row["synthesis_error"] = summary.get("synthesis_error")
        row["cautions"] = analysis_cautions(summary)
        row["frequencies_text"] = [texts.frequency_text(m) for m in modes]
        row["damping_text"] = [texts.damping_text(m) for m in modes]
        row["band_text"] = texts.band_text(summary.get("band"))
        row["synthesis_text"] = texts.synthesis_text(summary.get("synthesis_error"))
    fit = service.default_fit(s.run_id) if _shown(service, s.run_id, state, "fit") else None
    if fit is not None:
        row["fit_psi"] = fit["summary"].get("psi")
        row["fit_psi_text"] = texts.psi_text(fit["summary"])
        row["fit_cautions"] = _texts(fit["summary"].get("cautions"))
    return plain(row)


def _shown(service: Service, run_id: str, state: dict[str, str], stage: str) -> bool:
    """Whether the listing shows the stored result of ``stage``: a done one, or one that
    is up to date while its stage waits or runs again."""
    if state[stage] == "done":
        return True
    return state[stage] in ("queued", "running") and service.jobs.current(run_id, stage)


def analysis_cautions(summary: dict[str, Any]) -> list[str]:
    """The analysis's cautions as ``daq analyze`` prints them: its ``cautions``, and
    the windows' when the source does not say which it applied."""
    out = _texts(summary.get("cautions"))
    windows = summary.get("windows")
    source = windows.get("from") if isinstance(windows, dict) else None
    if isinstance(source, str) and source.startswith("unknown") and f"windows {source}" not in out:
        out.insert(0, f"windows {source}")  # an analysis stored before it was a caution
    return out


def _texts(value: Any) -> list[str]:
    """A stored list of sentences as a list of strings (anything else: none)."""
    return [str(v) for v in value] if isinstance(value, list | tuple) else []


def _remove(folder: Path) -> None:
    import shutil

    shutil.rmtree(folder, ignore_errors=True)
