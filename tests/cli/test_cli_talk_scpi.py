"""`daq send` / `daq query` on a SCPI analyzer (the simulated 35670A over a real TCP
socket, docs/instrument-scpi.md): block queries print their values, a refused query
costs one timeout and says the instrument's reason."""

from __future__ import annotations

import json

import numpy as np
import pytest

from sims.instrument import Analyzer
from sims.sources import PhysicsSource
from sims.tcp_server import TcpServer
from tests.cli_helpers import assert_one_line_error, invoke_daq


@pytest.fixture
def scpi(tmp_path, monkeypatch):
    monkeypatch.setenv("DAQ_LOCK_DIR", str(tmp_path / "locks"))
    analyzer = Analyzer(PhysicsSource("seed", seed=0), time_scale=0.0, model="35670A")
    with TcpServer(analyzer, "127.0.0.1", 0) as server:
        yield analyzer, server.resource


@pytest.mark.timeout(60)
def test_a_block_query_prints_every_value(scpi):
    analyzer, resource = scpi
    for command in ("SENS:FREQ:SPAN 200 HZ", "CALC1:FORM REAL", "ABOR;INIT:IMM"):
        assert invoke_daq("send", "-r", resource, command).returncode == 0
    assert invoke_daq("query", "-r", resource, "STAT:OPER:COND?").stdout.strip() == "256"  # done (spec)
    text = invoke_daq("query", "-r", resource, "CALC1:DATA?")
    assert text.returncode == 0, text.stderr
    as_json = invoke_daq("query", "-r", resource, "CALC1:DATA?", "--json")
    values = json.loads(as_json.stdout)
    assert len(values) == 401  # lines + 1 points at the preset 400 lines (docs/instrument-scpi.md)
    assert np.array_equal(np.array([float(v) for v in text.stdout.split()]), np.array(values))
    # What the analyzer holds: the real part of its averaged FRF (CALC1:FORM REAL).
    assert np.array_equal(values, np.real(analyzer.average.trace("FRSP")))


@pytest.mark.timeout(60)
def test_a_refused_query_costs_one_timeout_and_says_why(scpi):
    _, resource = scpi
    result = invoke_daq("query", "-r", resource, "ID?", "--timeout", "1")
    assert_one_line_error(result, "instrument error -113: Undefined header; ID?")
    assert "more" not in result.stderr  # sent once: one error, not one per retry
