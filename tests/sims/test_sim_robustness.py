"""Simulator behaviour a review found wanting: zoom phase, odd Prologix input,
oversized faults, connections abandoned during a slow reply."""

import socket
import time

import numpy as np
import pytest
import serial

from sims.faults import parse_fault
from sims.instrument import Analyzer
from sims.prologix import PrologixPty
from sims.sources import PhysicsSource
from sims.tcp_server import TcpServer
from tests.sims.wire import decode_trace


@pytest.mark.parametrize("center", ["6.25", "36"], ids=["baseband", "zoom"])
def test_linear_spectra_average_coherently_in_zoom_too(make_analyzer, connect, center):
    # A vector average of triggered hits keeps the amplitude only if every hit's
    # spectrum has the same phase: the zoom oscillator must count from the trigger.
    conn = connect(make_analyzer("seed", seed=0, noise=False))
    conn.write(
        f"FRS 12.5 HZ;CF {center} HZ;TSRC CH1;TLVL 2 MV;TDLY -20 MS;UNIF;NAVG 5;STBL;"
        "RNG1 20 MV;RNG2 1 V;STRT\n".encode()
    )
    assert conn.query("SMSD") == b"1\r\n"
    conn.write(b"LSP1;DDAN\n")
    _, linear = decode_trace(conn.read(timeout_s=5))
    conn.write(b"PSP1;DDAN\n")
    _, power = decode_trace(conn.read(timeout_s=5))
    np.testing.assert_allclose(np.abs(linear).mean(), np.sqrt(power).mean(), rtol=0.05)


@pytest.mark.timeout(20)
def test_prologix_survives_a_read_up_to_an_impossible_character():
    source = PhysicsSource("seed", seed=0)
    with PrologixPty(Analyzer(source), 11) as pty, serial.Serial(pty.port, timeout=1) as port:
        port.write(b"++auto 0\nID?\n++read 300\n++ver\n")
        assert port.readline() == b"Prologix GPIB-USB Controller version 6.101\r\n"
        port.write(b"++read eoi\n")
        assert port.readline() == b"HP35660A\r\n"


def test_garbage_fault_size_is_bounded():
    with pytest.raises(ValueError, match=r"nbytes must be 0\.\.65536"):
        parse_fault("garbage,nbytes=1e8")
    assert parse_fault("garbage,nbytes=65536").params["nbytes"] == 65536


@pytest.mark.timeout(20)
def test_a_client_that_leaves_during_a_slow_reply_is_let_go_at_once():
    with TcpServer(Analyzer(PhysicsSource("seed", seed=0)), faults=["slow,delay=30"]) as server:
        client = socket.create_connection(("127.0.0.1", server.port))
        client.sendall(b"ID?\n")
        deadline = time.monotonic() + 5
        while server.active_connections == 0 and time.monotonic() < deadline:
            time.sleep(0.01)
        client.close()
        deadline = time.monotonic() + 5
        while server.active_connections and time.monotonic() < deadline:
            time.sleep(0.02)
        assert server.active_connections == 0
