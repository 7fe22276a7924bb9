"""`daq capture` against the simulator over real TCP, into a real store."""

from __future__ import annotations

import re
import tomllib

import numpy as np
import pytest

from daq.cli.commands import capture as capture_command
from daq.store import Store
from daq.workflows.capture import Capture, CaptureError, HitArrived
from drivers.hp_mnemonic import HPMnemonicAnalyzer as HP35660A
from drivers.settings import ImpactSettings
from sims.instrument import Analyzer
from sims.sources import PhysicsSource
from sims.tcp_server import TcpServer
from tests.cli_helpers import assert_one_line_error, invoke_daq, run_daq
from tests.reference import EXACT_TABULATED_HZ

NO_CONFIG = {"DAQ_RESOURCE": None, "DAQ_STORE": None}


@pytest.fixture
def env(tmp_path):
    return {**NO_CONFIG, "DAQ_CONFIG": str(tmp_path / "absent.toml")}


def test_simulated_capture_seals_a_complete_run(tmp_path, env):
    store = tmp_path / "runs"
    result = invoke_daq(
        "capture", "--sim", "--yes", "--hits", "3", "--time-scale", "0", "--store", str(store), env=env
    )
    assert result.returncode == 0, result.stderr
    banner = result.stdout.splitlines()[0]
    assert re.match(
        r"Simulated 35660A \(realistic beam, seed \d+, time scale 0\) at TCPIP::127\.0\.0\.1::", banner
    )
    (summary,) = Store(store).list()
    run = Store(store).open(summary.run_id)
    assert summary.run_id in result.stdout
    assert run.kind == "simulated"
    assert run.complete
    assert run.provenance["simulator"]["scenario"] == "realistic"
    assert f"seed {run.provenance['simulator']['seed']}," in banner  # the fresh seed, printed and recorded
    assert run.hits.n_hits == 3
    assert run.hits.accepted.all()
    assert run.hits.force_n.shape == (3, 1024)
    assert run.hits.response_m_s2.shape == (3, 1024)
    assert run.hits.sample_rate_hz == 512.0  # 2.56 x 200 Hz
    assert set(run.hits.checks[0]) == {"overload", "double impact", "force roll-off", "too weak"}
    assert run.instrument.dialect == "35660A"
    assert run.instrument.settings["span_hz"] == 200.0
    assert run.sample.force_position_m == run.sample.sensor_position_m == 0.7
    frf = run.analyzer
    assert frf.n_lines == 401
    spacing = frf.frequency_hz[1] - frf.frequency_hz[0]
    magnitude = np.abs(frf.frf[0])
    for f_exact in EXACT_TABULATED_HZ:
        near = np.abs(frf.frequency_hz - f_exact) < 0.08 * f_exact + 2 * spacing
        f_peak = frf.frequency_hz[near][np.argmax(magnitude[near])]
        assert abs(f_peak - f_exact) <= spacing, (f_peak, f_exact)


def test_double_hits_are_rejected_as_double_impact():
    analyzer = Analyzer(PhysicsSource("realistic", seed=2), time_scale=0.0)
    with TcpServer(analyzer) as server, HP35660A.open(server.resource) as dsa:
        dsa.send("SIM:HAMMER double_hit_probability=1")
        job = Capture(dsa, ImpactSettings(span_hz=200.0), 2, resource=server.resource, max_hits=4)
        offered: list[str] = []

        def take_hits() -> None:
            offered.extend(e.suggested_reason for e in job if isinstance(e, HitArrived))

        with pytest.raises(CaptureError, match="4 hits taken, only 0 of 2 accepted"):
            take_hits()
        run = job.partial_run()
    assert offered == ["double impact"] * 4
    assert run is not None
    assert not run.complete
    assert run.kind == "captured"
    assert list(run.hits.reject_reason) == ["double impact"] * 4
    assert not run.hits.accepted.any()


def test_print_setup_round_trips_through_setup(tmp_path, env):
    printed = invoke_daq("capture", "--print-setup", env=env)
    assert printed.returncode == 0, printed.stderr
    data = tomllib.loads(printed.stdout)
    assert data["span_hz"] == 200.0
    assert data["hammer"]["window"] == "FORC"
    path = tmp_path / "setup.toml"
    path.write_text(printed.stdout)
    assert capture_command.read_setup(path) == ImpactSettings()
    changed = printed.stdout.replace("span_hz = 200.0", "span_hz = 400.0")
    path.write_text(changed)
    settings = capture_command.read_setup(path)
    assert settings.span_hz == 400.0
    assert settings.pre_trigger_s == pytest.approx(1.0 / 32)


@pytest.mark.parametrize(
    ("text", "fragment"),
    [
        ("span = 200\n", "span: unknown key"),
        ('span_hz = "wide"\n', "span_hz: must be a number"),
        ("span_hz = -5.0\n", "span_hz: must be a positive number"),
        ('[hammer]\nrange_v = "big"\n', 'hammer.range_v: must be a number or "auto"'),
        ('[hammer]\nwindow = "BOX"\n', "hammer.window: 'BOX' is not a window; one of UNIF, HANN"),
        ("span_hz = \n", "not valid TOML"),
    ],
)
def test_bad_setup_file_gives_one_line(tmp_path, env, text, fragment):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    result = invoke_daq("capture", "--sim", "--setup", str(path), "--store", str(tmp_path), env=env)
    assert_one_line_error(result, fragment)
    assert result.returncode in (1, 2)


@pytest.mark.timeout(60)
def test_the_technician_accepts_and_rejects_at_the_keyboard(tmp_path, monkeypatch):
    """Without --yes each hit waits for an answer: a, r, a accept two hits of three."""
    store = tmp_path / "runs"
    monkeypatch.setenv("DAQ_CONFIG", str(tmp_path / "none"))
    monkeypatch.delenv("DAQ_RESOURCE", raising=False)
    result = run_daq(
        "capture", "--sim", "--hits", "2", "--time-scale", "0", "--store", str(store),
        input="a\nr\na\n",
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert result.stdout.count("[a]ccept / [r]eject") == 3
    run = Store(store).open(Store(store).list()[0].run_id)
    assert run.complete
    assert run.hits.accepted.tolist() == [True, False, True]
    assert run.hits.reject_reason.tolist()[1] == "rejected by operator"


@pytest.mark.timeout(60)
def test_no_answer_on_stdin_keeps_the_hit_as_an_incomplete_run(tmp_path, monkeypatch):
    store = tmp_path / "runs"
    monkeypatch.setenv("DAQ_CONFIG", str(tmp_path / "none"))
    monkeypatch.delenv("DAQ_RESOURCE", raising=False)
    result = run_daq(
        "capture", "--sim", "--hits", "2", "--time-scale", "0", "--store", str(store),
        input="",
    )  # fmt: skip
    assert_one_line_error(result, "no answer on stdin", "incomplete run")
    (summary,) = Store(store).list()
    run = Store(store).open(summary.run_id)
    assert not run.complete
    assert run.hits.n_hits == 1
    assert not run.hits.accepted[0]
