"""Which dialect answers, found over real links (drivers/family.py): the simulator of
each model over a TCP socket (pyvisa-py) and over the Prologix pty (pyserial) gets
the right driver and the reason why; instruments outside the family (tiny TCP
servers of this file's own) are named in an UnknownInstrument; a silent one ends in
an InstrumentTimeout; a forced dialect asks nothing.
"""

from __future__ import annotations

import contextlib
import logging
import selectors
import socket
import threading
from collections.abc import Iterator

import pytest

from drivers.dialects import HP3562A, HP35660A, SCPI
from drivers.errors import InstrumentTimeout, UnknownInstrument
from drivers.family import open_analyzer
from drivers.hp_mnemonic import HPMnemonicAnalyzer
from drivers.scpi_analyzer import ScpiAnalyzer
from sims.instrument import Analyzer
from sims.prologix import PrologixPty
from sims.sources import PhysicsSource
from sims.tcp_server import TcpServer

TIMEOUT_S = 2.0
MODELS = {
    # model: (driver class, dialect, identification, what the reason says)
    "35660A": (HPMnemonicAnalyzer, HP35660A, "HP35660A", "ID? replied 'HP35660A'"),
    "3562A": (HPMnemonicAnalyzer, HP3562A, "HP3562A", "ID? replied 'HP3562A'"),
    "35670A": (
        ScpiAnalyzer,
        SCPI,
        "HEWLETT-PACKARD,35670A,0000A00000,A.00.00",
        "*IDN? replied 'HEWLETT-PACKARD,35670A,0000A00000,A.00.00': a 35670A speaks SCPI",
    ),
    "35665A": (
        ScpiAnalyzer,
        SCPI,
        "HEWLETT-PACKARD,35665A,0000A00000,A.00.00",
        "*IDN? replied 'HEWLETT-PACKARD,35665A,0000A00000,A.00.00': a 35665A speaks SCPI",
    ),
}


@pytest.fixture(autouse=True)
def _lock_dir(monkeypatch: pytest.MonkeyPatch, tmp_path) -> None:
    monkeypatch.setenv("DAQ_LOCK_DIR", str(tmp_path))


@contextlib.contextmanager
def simulated(model: str, wire: str) -> Iterator[tuple[Analyzer, str]]:
    """The simulated ``model`` behind ``wire`` (tcp or prologix): (analyzer, resource)."""
    analyzer = Analyzer(PhysicsSource("seed", seed=3), time_scale=0.0, model=model)
    if wire == "tcp":
        with TcpServer(analyzer, port=0) as server:
            yield analyzer, server.resource
    else:
        with PrologixPty(analyzer, 11) as pty:
            yield analyzer, f"PROLOGIX::{pty.port}::11"


class ScriptedServer:
    """A tiny instrument outside the family on 127.0.0.1: each line it receives is
    kept in ``received``; a line found in ``answers`` is answered, anything else is
    not. Serves any number of connections (the driver reconnects to clear a socket)."""

    def __init__(self, answers: dict[bytes, bytes]) -> None:
        self.answers = answers
        self.received: list[bytes] = []
        self._listener = socket.create_server(("127.0.0.1", 0))
        self._listener.setblocking(False)
        self.port = self._listener.getsockname()[1]
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    @property
    def resource(self) -> str:
        return f"TCPIP::127.0.0.1::{self.port}::SOCKET"

    def __enter__(self) -> ScriptedServer:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join(timeout=5)
        self._listener.close()

    def _run(self) -> None:
        clients: dict[socket.socket, bytes] = {}
        with selectors.DefaultSelector() as selector:
            selector.register(self._listener, selectors.EVENT_READ)
            try:
                while not self._stop.is_set():
                    for key, _ in selector.select(timeout=0.05):
                        sock = key.fileobj
                        if sock is self._listener:
                            conn, _ = self._listener.accept()
                            conn.setblocking(True)
                            clients[conn] = b""
                            selector.register(conn, selectors.EVENT_READ)
                            continue
                        assert isinstance(sock, socket.socket)
                        data = sock.recv(4096)
                        if not data:
                            selector.unregister(sock)
                            sock.close()
                            del clients[sock]
                            continue
                        clients[sock] += data
                        while b"\n" in clients[sock]:
                            line, _, clients[sock] = clients[sock].partition(b"\n")
                            line = line.strip()
                            self.received.append(line)
                            if line in self.answers:
                                sock.sendall(self.answers[line])
            finally:
                for conn in clients:
                    conn.close()


# ================================================================== the family
@pytest.mark.timeout(20)
@pytest.mark.parametrize("wire", ["tcp", "prologix"])
@pytest.mark.parametrize("model", list(MODELS))
def test_each_model_gets_its_dialect_and_the_reason(model: str, wire: str) -> None:
    driver_class, dialect, identification, reason = MODELS[model]
    with (
        simulated(model, wire) as (analyzer, resource),
        open_analyzer(resource, timeout_s=TIMEOUT_S) as drv,
    ):
        assert type(drv) is driver_class
        assert drv.dialect is dialect
        assert reason in drv.detection
        if dialect.family == "hp":
            # The *IDN? the mnemonic box did not know was asked first, and went unanswered.
            assert drv.detection.startswith("no reply to *IDN? within 0.5 s")
        assert drv.identify() == identification
        # Detection leaves nothing in the error queue for the first real command to be
        # blamed for: the mnemonic boxes' error for *IDN? was cleared.
        assert drv.errors() == []
        assert not analyzer.errors


@pytest.mark.timeout(20)
@pytest.mark.parametrize("model", ["35660A", "3562A", "35670A"])
def test_a_forced_dialect_asks_nothing(model: str, caplog: pytest.LogCaptureFixture) -> None:
    driver_class, dialect, identification, _ = MODELS[model]
    caplog.set_level(logging.DEBUG, logger="drivers.wire")
    with (
        simulated(model, "tcp") as (_analyzer, resource),
        open_analyzer(resource, timeout_s=TIMEOUT_S, dialect=dialect.name) as drv,
    ):
        assert type(drv) is driver_class
        assert "forced" in drv.detection
        assert "no detection" in drv.detection
        written = [r.getMessage() for r in caplog.records if " -> " in r.getMessage()]
        assert written == []  # not a byte sent before we ask
        assert drv.identify() == identification
    written = [r.getMessage().split(" -> ", 1)[1] for r in caplog.records if " -> " in r.getMessage()]
    assert written == [f"b'{dialect.identity_query}'"]


@pytest.mark.timeout(20)
def test_forcing_3562a_sends_no_idn_on_the_wire() -> None:
    """On a box of our own that records every line: with ``dialect="3562A"`` the
    first line on the wire is the driver's own ID?, never a *IDN?."""
    with (
        ScriptedServer({b"ID?": b"HP3562A\r\n"}) as server,
        open_analyzer(server.resource, timeout_s=TIMEOUT_S, dialect="3562A") as drv,
    ):
        assert isinstance(drv, HPMnemonicAnalyzer)
        assert drv.dialect is HP3562A
        assert drv.identify() == "HP3562A"
    assert server.received == [b"ID?"]


# ================================================================== outside the family
@pytest.mark.timeout(20)
def test_an_unknown_scpi_instrument_is_named_in_the_error() -> None:
    with ScriptedServer({b"*IDN?": b"ACME,XYZ123,0,1.0\n"}) as server:
        with pytest.raises(UnknownInstrument) as caught:
            open_analyzer(server.resource, timeout_s=TIMEOUT_S)
        message = str(caught.value)
        assert "*IDN? replied 'ACME,XYZ123,0,1.0'" in message
        assert "not an analyzer this driver knows" in message
        assert "--dialect" in message
        assert server.received == [b"*IDN?"]  # a SCPI reply: ID? is never asked


@pytest.mark.timeout(20)
def test_an_unknown_mnemonic_instrument_is_named_in_the_error() -> None:
    with ScriptedServer({b"ID?": b"HP8903B\r\n"}) as server:
        with pytest.raises(UnknownInstrument) as caught:
            open_analyzer(server.resource, timeout_s=TIMEOUT_S)
        message = str(caught.value)
        assert "ID? replied 'HP8903B' (and *IDN? nothing)" in message
        assert "HP35660A, HP3562A" in message
        assert server.received == [b"*IDN?", b"ID?"]


@pytest.mark.timeout(20)
def test_a_silent_instrument_ends_in_a_timeout() -> None:
    with ScriptedServer({}) as server:
        with pytest.raises(InstrumentTimeout, match=r"no reply to \*IDN\? nor to ID\? within 0\.5 s each"):
            open_analyzer(server.resource, timeout_s=TIMEOUT_S)
        assert server.received == [b"*IDN?", b"ID?"]
