"""`daq serve`: the lab service (docs/service.md).

One long-running process owns the analyzer, runs captures on request from its web
page or HTTP API, seals each run, and analyses and fits every run as it lands.
"""

from __future__ import annotations

import os
import signal
import sys
from pathlib import Path
from typing import Annotated

import typer

from daq.cli.errors import UserError
from daq.cli.options import (
    DEFAULT_SCENARIO,
    DEFAULT_TIME_SCALE,
    DialectOption,
    OldSimModelOption,
    SetupOption,
    SimHammerOption,
    SimModel,
    SimModelOption,
    SimScenarioOption,
    SimSeedOption,
    SimTimeScaleOption,
    StoreOption,
    check_dialect,
    given_once,
)


def register(app: typer.Typer) -> None:
    app.command(name="serve")(serve)


def serve(
    resource: Annotated[
        str | None,
        typer.Option("--resource", "-r", metavar="<resource>", help="The analyzer's VISA resource."),
    ] = None,
    sim: Annotated[bool, typer.Option("--sim", help="Serve the built-in simulated analyzer.")] = False,
    dialect: DialectOption = None,
    store: StoreOption = None,
    host: Annotated[
        str,
        typer.Option(
            metavar="<address>", help="Address to listen on; beyond loopback every request needs the token."
        ),
    ] = "127.0.0.1",
    port: Annotated[int, typer.Option(metavar="<port>", help="TCP port (0: any free one).")] = 8000,
    jobs: Annotated[
        int | None,
        typer.Option(metavar="<n>", help="Analysis worker processes [default: cores - 1, at least 1]."),
    ] = None,
    workers: Annotated[int | None, typer.Option("--workers", hidden=True, help="Old name of --jobs.")] = None,
    scheduler: Annotated[
        str | None,
        typer.Option(
            metavar="<tcp://host:port>", help="Hand analyses to this Dask scheduler (else $DAQ_SCHEDULER)."
        ),
    ] = None,
    show_token: Annotated[
        bool, typer.Option("--show-token", help="Print the access token (made at first start) and exit.")
    ] = False,
    scenario: SimScenarioOption = None,
    seed: SimSeedOption = None,
    time_scale: SimTimeScaleOption = None,
    hammer: SimHammerOption = None,
    analyzer: SimModelOption = None,
    model: OldSimModelOption = None,
    setup: SetupOption = None,
    undo_window: Annotated[
        float | None,
        typer.Option(
            "--undo-window",
            metavar="<s>",
            help="Seconds a decision made on the page is held before it goes to the analyzer, so "
            "that Undo can take it back; 0: none [default: $DAQ_UNDO_WINDOW_S, else 3].",
        ),
    ] = None,
) -> None:
    """Run the lab service: the analyzer, the store, a live web page and an HTTP API.

    Open the printed address in a browser on the lab PC. Captures started there (or
    through the API) are checked hit by hit, accepted or rejected on the page, sealed
    into the store, then analysed and fitted in worker processes. Ctrl-C stops the
    service; a capture in progress is sealed as an incomplete run.
    """
    # First, before the slow imports: a signal that lands while the service starts
    # stops it, even where SIGINT arrived ignored (see _stop_on_signals). It is only
    # noted until the service exists: raised inside an import, it would come out as
    # that library's error (pydantic wraps it while building its schemas).
    previous = _note_signals()
    try:
        _serve(
            jobs=jobs, workers=workers, analyzer=analyzer, model=model, show_token=show_token, sim=sim,
            resource=resource, port=port, scenario=scenario, seed=seed, time_scale=time_scale,
            hammer=hammer, undo_window=undo_window, dialect=dialect, scheduler=scheduler, store=store,
            setup=setup, host=host,
        )  # fmt: skip
    except _Shutdown:
        # A second signal while the service closed.
        sys.stderr.write("daq serve: stopped\n")
    except Exception:
        if not _NOTED:
            raise
        # ... or that second signal wrapped by a library the closing imported.
        sys.stderr.write("daq serve: stopped\n")
    finally:
        for signum, handler in previous.items():  # as found: serve may run inside another program
            signal.signal(signum, handler)


def _serve(
    *, jobs, workers, analyzer, model, show_token, sim, resource, port, scenario, seed, time_scale,
    hammer, undo_window, dialect, scheduler, store, setup, host,
) -> None:  # fmt: skip
    from daq.service.auth import TokenError, load_or_create_token, token_path
    from daq.store import resolve_store_dir
    from daq.workflows.connect import configured_resource

    n_jobs = given_once("--jobs", jobs, "--workers", workers)
    simulated = given_once("--analyzer", analyzer, "--model", model)
    path = token_path()
    try:
        token, created = load_or_create_token(path)
    except TokenError as exc:
        raise UserError(str(exc)) from None
    if show_token:
        typer.echo(token)
        return
    if sim and resource:
        raise UserError("--sim and --resource exclude each other", exit_code=2)
    if not 0 <= port <= 65535:
        raise UserError("--port must be 0..65535", exit_code=2)
    if n_jobs is not None and n_jobs < 1:  # type: ignore[operator]
        flag = "--jobs" if workers is None else "--workers"  # as the user spelled it
        raise UserError(f"{flag} must be at least 1", exit_code=2)
    real = None if sim else configured_resource(resource)
    if real is None and not sim:
        # Unlike daq capture, never fall back to the simulator: a service left running on
        # it by mistake would collect runs nobody measured.
        raise UserError(
            "no analyzer configured: give --resource <resource> (or set $DAQ_RESOURCE, or resource "
            "in the config file), or --sim for the built-in simulator",
            exit_code=2,
        )
    sim_options = {
        "--scenario": scenario, "--seed": seed, "--time-scale": time_scale, "--analyzer": analyzer,
        "--model": model, "--hammer": hammer,
    }  # fmt: skip
    if real is not None and (given := [k for k, v in sim_options.items() if v is not None]):
        raise UserError(f"{', '.join(given)} only apply to the simulator (use --sim)", exit_code=2)
    if time_scale is not None and not time_scale >= 0:
        raise UserError("--time-scale must be >= 0", exit_code=2)
    if hammer:
        from daq.workflows.connect import simulator_source

        try:
            simulator_source((scenario or DEFAULT_SCENARIO).value, 0, hammer)
        except ValueError as exc:
            raise UserError(f"--hammer: {exc}", exit_code=2) from None
    if undo_window is not None and not 0 <= undo_window <= 60:
        raise UserError("--undo-window must be 0..60 s", exit_code=2)
    forced = check_dialect(dialect)
    address = _scheduler(scheduler)
    store_dir, _ = resolve_store_dir(store)
    if setup is not None:
        setup = service_setup(store_dir, setup)
    run_service(
        store_dir, real, sim, host, port, token, created, path, n_jobs, address,
        scenario=(scenario or DEFAULT_SCENARIO).value, seed=seed,
        time_scale=DEFAULT_TIME_SCALE if time_scale is None else time_scale,
        model=(simulated or SimModel.hp35660a).value, dialect=forced, setup=setup,
        undo_window_s=undo_window, hammer=hammer or "",
    )  # fmt: skip


def service_setup(store_dir, setup: str) -> str:
    """The setup the service is to use, checked now (one error line if it does not
    resolve; its cautions printed): a name as given, a file as its absolute path."""
    from daq.cli.commands.setup import print_cautions
    from daq.workflows.setups import is_setup_path, resolve_setup

    print_cautions(resolve_setup(store_dir, setup).cautions)
    return str(Path(setup).resolve()) if is_setup_path(setup) else setup


def _scheduler(option: str | None) -> str | None:
    if option is None and not os.environ.get("DAQ_SCHEDULER"):
        return None
    from daq.batch.dask_backend import scheduler_address

    return scheduler_address(option)


def run_service(
    store_dir, resource, sim, host, port, token, created, token_file, workers, scheduler,
    scenario: str, seed: int | None, time_scale: float, model: str = "35660A", dialect: str | None = None,
    setup: str | None = None, undo_window_s: float | None = None, hammer: str = "",
) -> None:  # fmt: skip
    import socket

    import uvicorn

    from daq.service.app import create_app
    from daq.service.auth import is_loopback
    from daq.service.limits import ConnectionGuard, connection_cap, raise_fd_limit
    from daq.service.service import Service, ServiceConfig
    from daq.store import StoreError
    from daq.workflows.instrument_link import SimSpec
    from drivers.errors import DriverError

    if _NOTED:
        # A signal came while the libraries above were imported: stop before anything is
        # bound or built, rather than build a service only to close it (a SIGTERM 0.3 s
        # into start-up outlasted the 20 s a test gives, once, on a loaded machine).
        raise _Shutdown
    loopback = is_loopback(host)
    # Idle clients must not take every file descriptor: raise the soft limit, and keep
    # the connections well below it (ConnectionGuard).
    guard = ConnectionGuard(connection_cap(raise_fd_limit()))
    # Bind first, so that the port is known (for --port 0) and taken before anything starts.
    try:
        family = socket.AF_INET6 if ":" in host else socket.AF_INET
        # IPPROTO_TCP said, not left 0: asyncio sets TCP_NODELAY on accepted connections only
        # when the listening socket's proto says TCP; without it every response on a kept-alive
        # connection waits ~40 ms for the client's delayed ACK (Nagle).
        sock = socket.socket(family, socket.SOCK_STREAM, socket.IPPROTO_TCP)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        sock.bind((host, port))
        sock.listen(2048)  # from now on connections queue until uvicorn accepts them
    except OSError as exc:
        raise UserError(f"cannot listen on {host}:{port}: {exc.strerror or exc}") from None
    spec = SimSpec(scenario, seed, time_scale, hammer=hammer, model=model) if resource is None else None
    config = ServiceConfig(
        store_dir=store_dir, resource=resource, sim=spec, host=host, port=sock.getsockname()[1],
        token=token, reads_need_token=not loopback, scheduler=scheduler, dialect=dialect, setup=setup,
    )  # fmt: skip
    if workers is not None:
        config.workers = workers
    if undo_window_s is not None:
        config.undo_window_s = undo_window_s
    service = Service(config)
    _stop_on_signals()
    # Everything after this point ends in close(): a Ctrl-C that lands during start-up,
    # before uvicorn handles signals, must not leave the simulator's or the workers'
    # threads keeping the process alive.
    try:
        if _NOTED:
            raise _Shutdown  # a signal came while the service was being built
        try:
            # A store another service holds is refused in one line, before the start line.
            service.claim_store()
            # Start-up (the analyzer, the workers, the store's index) can take half a minute
            # on a loaded machine: say at once where the service will be, for a log read
            # meanwhile.
            shown = f"[{host}]" if ":" in host else host
            sys.stderr.write(
                f"daq serve: starting on port {config.port} of {shown}; the address to open follows "
                "once it is ready\n"
            )
            sys.stderr.flush()
            service.start()
        except (DriverError, StoreError, ValueError) as exc:
            raise UserError(str(exc)) from None
        server = _make_server_class()(
            uvicorn.Config(
                create_app(service),
                log_level="warning",
                access_log=False,
                lifespan="off",
                timeout_graceful_shutdown=3,
                # uvicorn closes idle keep-alive connections after 5 s by default; a client
                # that sends on one just then gets "disconnected without a response". Pages
                # poll and browsers keep connections far longer: keep them a minute.
                timeout_keep_alive=60,
                # uvicorn's h11 protocol, with a header timeout and a cap on connections.
                http=guard.protocol_class(),
            ),
            service,
        )
        _banner(service, config, store_dir, scheduler, created, token_file, loopback, host, token)
        server.run(sockets=[sock])
    except _Shutdown:
        pass
    except Exception:
        # The shutdown raised inside a library's lazy import or start-up comes out as that
        # library's error ("ImportError: initialization failed" from a C extension): it is
        # still the signal, not a failure of the service.
        if not _NOTED:
            raise
    finally:
        # From here on the process ends, whatever hangs: a read stuck in a damaged run
        # file cannot be interrupted, and the interpreter would wait for it at exit.
        watchdog = _exit_after(STOP_DEADLINE_S)
        service.close()
        sock.close()
        # Stopped in time: a program that ran serve in its own process goes on without it.
        watchdog.cancel()
    sys.stderr.write("daq serve: stopped\n")
    if service.reads.busy():
        sys.stderr.flush()
        sys.stdout.flush()
        os._exit(0)  # reads still running in their threads: do not wait for them


#: Seconds the service may take to stop (seal the capture, end the workers) after a
#: signal, before the process ends anyway.
STOP_DEADLINE_S = 30.0


def _exit_after(seconds: float):
    """A started daemon timer that ends the process after ``seconds`` (cancel it once
    stopped)."""
    import threading

    def watchdog() -> None:
        sys.stderr.write(f"daq serve: not stopped after {seconds:g} s; ending now\n")
        sys.stderr.flush()
        os._exit(1)

    timer = threading.Timer(seconds, watchdog)
    timer.daemon = True
    timer.start()
    return timer


class _Shutdown(BaseException):
    """SIGTERM or SIGINT: stop as Ctrl-C does (the capture in progress is sealed). A
    BaseException, as KeyboardInterrupt is: raised in the main thread wherever it happens
    to be, an `except Exception` of the start-up (a driver's retry, a library's guard) must
    not swallow it, or the service starts and runs on, the signal lost (1 run in 3 of
    tests/service/test_service_sigint_at_start.py's 1 s case on a loaded machine)."""


#: Signals received before the service existed (_note_signals).
_NOTED: list[int] = []


def _note_signals() -> dict:
    """From the command's first line until _stop_on_signals: SIGTERM, SIGINT (even where
    it arrived ignored) and SIGHUP (unless ignored) are noted, and the service stops as
    soon as it exists. Returns the handlers found, to be put back."""
    _NOTED.clear()
    previous = {}
    for signum in (signal.SIGTERM, signal.SIGINT, signal.SIGHUP):
        if signum != signal.SIGHUP or signal.getsignal(signum) is not signal.SIG_IGN:
            previous[signum] = signal.signal(signum, _note)
    return previous


def _note(signum: int, frame: object) -> None:
    _NOTED.append(signum)


def _raise_shutdown(signum: int, frame: object) -> None:
    _NOTED.append(signum)  # so that the shutdown is known when a library wraps it
    raise _Shutdown


def _stop_on_signals() -> None:
    """SIGTERM (systemd, kill, shutdown) and SIGINT stop the service the same way.
    uvicorn handles both while it serves, then restores these handlers and raises the
    signal again: without them SIGTERM would end the process before the capture in
    progress is sealed. SIGINT is handled even where it arrived ignored (a background
    job of a script): uvicorn stops on it once serving, so ignoring it only while the
    service starts made the first `kill -INT` of a starting service do nothing."""
    signal.signal(signal.SIGTERM, _raise_shutdown)
    signal.signal(signal.SIGINT, _raise_shutdown)
    # A closed terminal or a dropped ssh session (SIGHUP) stops the service as SIGTERM
    # does, sealing the capture in progress at once: uvicorn handles SIGTERM, not SIGHUP.
    if signal.getsignal(signal.SIGHUP) is not signal.SIG_IGN:
        signal.signal(signal.SIGHUP, _as_sigterm)


def _as_sigterm(signum: int, frame: object) -> None:
    os.kill(os.getpid(), signal.SIGTERM)


def _make_server_class():
    import uvicorn

    class Server(uvicorn.Server):
        """uvicorn's server, ending the live event streams first when it shuts down:
        an open page would otherwise hold the shutdown until its grace period ends."""

        def __init__(self, config: uvicorn.Config, service) -> None:
            super().__init__(config)
            self.service = service

        async def shutdown(self, sockets=None) -> None:
            self.service.hub.close()
            await super().shutdown(sockets=sockets)

    return Server


def _banner(service, config, store_dir, scheduler, created, token_file, loopback, host, token) -> None:
    status = service.link.status()
    what = "simulated analyzer" if status["simulated"] else "analyzer"
    state = status["identification"] or f"not answering: {status['last_error']}"
    say = sys.stderr.write
    say(f"daq serve: {what} at {status['resource']} ({state})\n")
    if config.sim is not None:
        sim = config.sim
        seed = "a fresh seed per capture" if sim.seed is None else f"seed {sim.seed} for every capture"
        say(
            f"daq serve: simulating the {sim.scenario} beam, time scale {sim.time_scale:g}, {seed} "
            "(recorded in its run)\n"
        )
    plural = "" if config.workers == 1 else "s"
    workers = f"{config.workers} analysis worker{plural}" + (f" on {scheduler}" if scheduler else "")
    say(f"daq serve: store {store_dir}; {workers}\n")
    if created:
        say(f"daq serve: a new access token was made in {token_file}\n")
    if loopback:
        say(f"daq serve: open {config.url}/#token={token}\n")
    else:
        reachable = config.url
        if host in ("0.0.0.0", "::"):  # every address: name the machine, not the wildcard
            import socket

            reachable = f"http://{socket.gethostname()}:{config.port}"
        say(
            f"daq serve: listening on {host}, beyond this machine: EVERY request needs the token "
            f"(daq serve --show-token); open {reachable}/#token=<token>\n"
        )
    say("daq serve: Ctrl-C stops the service\n")
