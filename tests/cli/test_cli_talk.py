"""daq instruments / identify / send / query, as a technician runs them, in-process
(daq.cli.app.main); tests/test_cli_sim.py runs `daq sim serve` as a real process and
reaches it the same way these tests reach the simulator here."""

import json

import pytest

from sims.instrument import Analyzer
from sims.sources import PhysicsSource
from sims.tcp_server import TcpServer
from tests.cli_helpers import assert_one_line_error, invoke_daq


@pytest.fixture
def lock_dir(tmp_path, monkeypatch):
    monkeypatch.setenv("DAQ_LOCK_DIR", str(tmp_path / "locks"))
    return tmp_path


@pytest.fixture
def sim_tcp(lock_dir):
    """What `daq sim serve --tcp 0 --time-scale 0` serves, on a thread of this
    process (no second of start-up); yields its resource string."""
    with TcpServer(Analyzer(PhysicsSource("seed", seed=0), time_scale=0.0), "127.0.0.1", 0) as server:
        yield server.resource


@pytest.mark.timeout(30)
def test_identify_the_built_in_simulator(lock_dir):
    result = invoke_daq("identify", "--resource", "sim")
    assert result.returncode == 0, result.stderr
    assert result.stdout.splitlines() == [
        "HP35660A at sim",
        "dialect 35660A: no reply to *IDN? within 0.5 s; ID? replied 'HP35660A'",
        "400 lines, 1024-sample records",
    ]


@pytest.mark.timeout(30)
def test_identify_send_query_over_tcp(sim_tcp):
    assert invoke_daq("identify", "-r", sim_tcp).stdout.splitlines()[0] == f"HP35660A at {sim_tcp}"
    assert invoke_daq("send", "-r", sim_tcp, "FRS 200 HZ").returncode == 0
    # Settings persist in the instrument between connections.
    assert invoke_daq("query", "-r", sim_tcp, "FRS?").stdout == "+2.000000000E+02\n"


@pytest.mark.timeout(30)
def test_resource_from_the_environment(sim_tcp):
    result = invoke_daq("identify", env={"DAQ_RESOURCE": sim_tcp})
    assert result.stdout.splitlines()[0] == f"HP35660A at {sim_tcp}"


@pytest.mark.timeout(30)
def test_query_ddan_decodes_the_trace(sim_tcp):
    setup = "FRS 200 HZ;TSRC CH1;TLVL 2 MV;TDLY -10 MS;RNG1 20 MV;RNG2 1 V;STRT;TIM1"
    assert invoke_daq("send", "-r", sim_tcp, setup).returncode == 0
    result = invoke_daq("query", "-r", sim_tcp, "DDAN")
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert lines[0].startswith("# TIM1: 1024 real points")
    assert len(lines) == 1 + 1024
    t0, _ = lines[1].split("\t")
    assert float(t0) == pytest.approx(-10 / 1000, abs=1 / 512)
    data = json.loads(invoke_daq("query", "-r", sim_tcp, "DDAN", "--json").stdout)
    assert data["header"]["display_function"] == "TIM1"
    assert len(data["data"]) == 1024


@pytest.mark.timeout(30)
def test_instrument_errors_are_one_line(sim_tcp):
    assert_one_line_error(
        invoke_daq("send", "-r", sim_tcp, "FOO"), "instrument error 1: Undefined command: FOO"
    )
    assert_one_line_error(
        invoke_daq("query", "-r", sim_tcp, "DDAN", "--timeout", "1"), "instrument error 5: No data available"
    )


@pytest.mark.timeout(60)
@pytest.mark.parametrize(
    ("resource", "fragment"),
    [
        ("TCPIP::127.0.0.1::1::SOCKET", "Connection refused"),
        ("PROLOGIX::/dev/nonexistent-port::11", "cannot open serial port /dev/nonexistent-port"),
        ("PROLOGIX::/dev/null::99", "GPIB address must be 0..30"),
        ("not-a-resource", "cannot open not-a-resource"),
        ("GPIB0::11::INSTR", "cannot open GPIB0::11::INSTR"),
    ],
)
def test_unreachable_or_wrong_resources_are_one_line(lock_dir, resource, fragment):
    result = invoke_daq("identify", "--resource", resource, "--timeout", "1")
    assert_one_line_error(result, fragment)


@pytest.mark.timeout(30)
def test_missing_resource_and_bad_commands(lock_dir):
    result = invoke_daq("identify", env={"DAQ_RESOURCE": None})
    assert_one_line_error(result, "--resource", "DAQ_RESOURCE")
    assert result.returncode == 2
    assert_one_line_error(invoke_daq("send", "-r", "sim", ""), "not empty")
    assert_one_line_error(invoke_daq("query", "-r", "sim", "ID?", "--timeout", "0"), "--timeout")


@pytest.mark.timeout(30)
def test_instruments_lists_local_resources_without_noise(lock_dir):
    result = invoke_daq("instruments")
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""
    assert "VISA resources" in result.stdout
    assert "Serial ports" in result.stdout
    assert "sim" in result.stdout
    assert "not searched for" in result.stdout


@pytest.mark.timeout(30)
def test_send_refuses_a_query_and_query_decodes_a_selected_dump(lock_dir):
    assert_one_line_error(invoke_daq("send", "-r", "sim", "ID?"), "use query")
    result = invoke_daq("query", "-r", "sim", "TRCB;COHR;DDAN", "--timeout", "1")
    # No data yet: the instrument's own reason, promptly and in one line.
    assert_one_line_error(result, "instrument error 5: No data available: COHR")


def test_the_config_file_names_the_analyzer_when_nothing_else_does(tmp_path, monkeypatch):
    config = tmp_path / "config.toml"
    config.write_text('resource = "sim"\n')
    monkeypatch.setenv("DAQ_LOCK_DIR", str(tmp_path / "locks"))
    found = invoke_daq("identify", env={"DAQ_CONFIG": str(config), "DAQ_RESOURCE": None})
    assert found.returncode == 0, found.stderr
    assert "HP35660A" in found.stdout
    missing = invoke_daq("identify", env={"DAQ_CONFIG": str(tmp_path / "none.toml"), "DAQ_RESOURCE": None})
    assert_one_line_error(missing, "no analyzer given", "config file")
