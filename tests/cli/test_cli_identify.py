"""`daq identify` on every model of the family: which dialect, and why
(docs/dialects.md), over a real TCP socket to the simulator of each model; an
instrument the family does not hold is named by what it replied."""

from __future__ import annotations

import socket
import threading

import pytest

from sims.instrument import Analyzer
from sims.sources import PhysicsSource
from sims.tcp_server import TcpServer
from tests.cli_helpers import assert_one_line_error, invoke_daq

#: model -> (identification, dialect line, geometry line), from docs/dialects.md's table.
EXPECTED = {
    "35660A": (
        "HP35660A",
        "dialect 35660A: no reply to *IDN? within 0.5 s; ID? replied 'HP35660A'",
        "400 lines, 1024-sample records",
    ),
    "3562A": (
        "HP3562A",
        "dialect 3562A: no reply to *IDN? within 0.5 s; ID? replied 'HP3562A'",
        "800 lines, 2048-sample records",
    ),
    "35670A": (
        "HEWLETT-PACKARD,35670A,0000A00000,A.00.00",
        "dialect SCPI: *IDN? replied 'HEWLETT-PACKARD,35670A,0000A00000,A.00.00': a 35670A speaks SCPI",
        "400 lines, 1024-sample records",
    ),
}


@pytest.fixture
def lock_dir(tmp_path, monkeypatch):
    monkeypatch.setenv("DAQ_LOCK_DIR", str(tmp_path / "locks"))
    return tmp_path


def _served(model: str) -> TcpServer:
    return TcpServer(Analyzer(PhysicsSource("seed", seed=0), time_scale=0.0, model=model), "127.0.0.1", 0)


@pytest.mark.timeout(30)
@pytest.mark.parametrize("model", list(EXPECTED))
def test_identify_says_which_dialect_and_why(lock_dir, model):
    with _served(model) as server:
        result = invoke_daq("identify", "-r", server.resource)
    assert result.returncode == 0, result.stderr
    identification, dialect, geometry = EXPECTED[model]
    assert result.stdout.splitlines() == [f"{identification} at {server.resource}", dialect, geometry]


@pytest.mark.timeout(30)
def test_a_forced_dialect_asks_nothing_else(lock_dir):
    with _served("3562A") as server:
        result = invoke_daq("identify", "-r", server.resource, "--dialect", "3562a")
        # Nothing but ID? reached the instrument: no *IDN?, so no error in its queue.
        errors = invoke_daq("query", "-r", server.resource, "--dialect", "3562A", "ERR?")
    assert result.returncode == 0, result.stderr
    forced = "dialect 3562A: the 3562A dialect was forced (--dialect or $DAQ_DIALECT); no detection"
    assert result.stdout.splitlines()[1] == forced
    assert errors.stdout.strip().startswith("0,"), errors.stdout


@pytest.mark.timeout(30)
def test_detection_clears_the_error_its_probe_left(lock_dir):
    with _served("35660A") as server:
        assert invoke_daq("identify", "-r", server.resource).returncode == 0
        errors = invoke_daq("query", "-r", server.resource, "ERR?")
    assert errors.returncode == 0, errors.stderr
    assert errors.stdout.strip().startswith("0,"), errors.stdout


@pytest.mark.timeout(30)
@pytest.mark.parametrize("value", ["35661A", "", "scpi;rm"])
def test_an_unknown_dialect_is_one_line(lock_dir, value):
    result = invoke_daq("identify", "-r", "sim", "--dialect", value)
    assert_one_line_error(result, "--dialect")
    assert result.returncode == 2


class _Stranger:
    """A TCP instrument of another maker: answers one query with one line, ignores the rest."""

    def __init__(self, query: bytes, reply: bytes) -> None:
        self.query, self.reply = query, reply
        self.listener = socket.create_server(("127.0.0.1", 0))
        self.port = self.listener.getsockname()[1]
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._serve, daemon=True)

    def __enter__(self) -> _Stranger:
        self.thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop.set()
        self.listener.close()
        self.thread.join(5)

    def _serve(self) -> None:
        self.listener.settimeout(0.1)
        while not self.stop.is_set():
            try:
                conn, _ = self.listener.accept()
            except OSError:
                continue
            with conn:
                conn.settimeout(0.1)
                pending = b""
                while not self.stop.is_set():
                    try:
                        data = conn.recv(4096)
                    except TimeoutError:
                        continue
                    except OSError:
                        break
                    if not data:
                        break
                    pending += data
                    while b"\n" in pending:
                        message, _, pending = pending.partition(b"\n")
                        if message.strip() == self.query:
                            conn.sendall(self.reply + b"\n")


@pytest.mark.timeout(30)
@pytest.mark.parametrize(
    ("query", "reply", "named"),
    [
        (b"*IDN?", b"ACME,XYZ123,0,1.0", "*IDN? replied 'ACME,XYZ123,0,1.0'"),
        (b"ID?", b"HP8903B", "ID? replied 'HP8903B'"),
    ],
)
def test_an_instrument_the_family_does_not_hold_is_named(lock_dir, query, reply, named):
    with _Stranger(query, reply) as stranger:
        result = invoke_daq("identify", "-r", f"TCPIP::127.0.0.1::{stranger.port}::SOCKET", "--timeout", "2")
    assert_one_line_error(result, named)
    assert result.returncode == 1
    assert "--dialect" in result.stderr


@pytest.mark.timeout(30)
def test_a_silent_instrument_is_one_line(lock_dir):
    with _Stranger(b"NOTHING", b"") as stranger:
        result = invoke_daq("identify", "-r", f"TCPIP::127.0.0.1::{stranger.port}::SOCKET", "--timeout", "2")
    assert_one_line_error(result, "no reply to *IDN? nor to ID?")
    assert result.returncode == 1


@pytest.mark.timeout(60)
@pytest.mark.parametrize(
    ("model", "forced", "named"),
    [
        ("35660A", "3562A", "ID? replied 'HP35660A', an analyzer of the 35660A dialect, not the 3562A"),
        ("3562A", "35660A", "ID? replied 'HP3562A', an analyzer of the 3562A dialect, not the 35660A"),
    ],
)
def test_a_forced_dialect_the_analyzer_does_not_speak_is_one_line_before_any_hit(
    lock_dir, model, forced, named
):
    with _served(model) as server:
        identified = invoke_daq("identify", "-r", server.resource, "--dialect", forced)
        captured = invoke_daq(
            "capture", "-r", server.resource, "--dialect", forced, "--hits", "2", "--yes",
            "--store", str(lock_dir / "store"),
        )  # fmt: skip
    for result in (identified, captured):
        assert_one_line_error(result, named, "was forced (--dialect or $DAQ_DIALECT)")
    assert "Hammer away" not in captured.stdout


@pytest.mark.timeout(60)
def test_a_forced_dialect_on_something_else_entirely_is_refused(lock_dir):
    with _Stranger(b"ID?", b"<!DOCTYPE HTML>") as stranger:
        result = invoke_daq(
            "identify", "-r", f"TCPIP::127.0.0.1::{stranger.port}::SOCKET", "--dialect", "35660A"
        )
    assert_one_line_error(result, "ID? replied '<!DOCTYPE HTML>', not an analyzer of the family")


@pytest.mark.timeout(60)
def test_a_forced_scpi_dialect_on_a_mnemonic_analyzer_says_the_dialect_may_be_wrong(lock_dir):
    with _served("35660A") as server:
        result = invoke_daq("identify", "-r", server.resource, "--timeout", "1", env={"DAQ_DIALECT": "SCPI"})
    assert_one_line_error(
        result, "the SCPI dialect was forced (--dialect or $DAQ_DIALECT): is it this analyzer's?"
    )


@pytest.mark.timeout(30)
def test_the_3563a_is_a_name_of_the_3562a_dialect(lock_dir):
    with _served("3562A") as server:
        result = invoke_daq("identify", "-r", server.resource, "--dialect", "3563A")
    assert result.returncode == 0, result.stderr
    assert result.stdout.splitlines()[1].startswith("dialect 3562A: ")
