"""One simulator default for every command, and a fresh seed per capture (issue 24).

`daq sim serve`, `daq capture --sim`, `daq demo` and `daq serve --sim` play the scenario
and time scale declared once in daq/cli/options.py (DEFAULT_SCENARIO,
DEFAULT_TIME_SCALE): their help says so, and so do the banner and the run's provenance.
A capture given no --seed plays a fresh random one, printed in its banner and recorded
in the run (provenance.simulator.seed); `daq capture --sim --seed <recorded>` takes the
same hits again, bit for bit.
"""

from __future__ import annotations

import os
import re
import select
import signal
import subprocess
import time

import numpy as np
import pytest

from daq.cli.options import DEFAULT_SCENARIO, DEFAULT_TIME_SCALE
from daq.store import Store
from tests.cli_helpers import DAQ, ENV, invoke_daq

NO_CONFIG = {"DAQ_RESOURCE": None, "DAQ_STORE": None}


@pytest.fixture
def env(tmp_path):
    return {**NO_CONFIG, "DAQ_CONFIG": str(tmp_path / "absent.toml"), "DAQ_LOCK_DIR": str(tmp_path)}


def _help(*command: str) -> str:
    result = invoke_daq(*command, "--help")
    assert result.returncode == 0, result.stderr
    return " ".join(result.stdout.split())  # the help's line breaks fall anywhere


def _option_help(text: str, option: str) -> str:
    """The help of ``option`` alone: from its name to the next option's."""
    start = text.index(f" {option} ")
    following = re.search(r" --[a-z]", text[start + len(option) + 2 :])
    return text[start : start + len(option) + 2 + (following.start() if following else len(text))]


@pytest.mark.parametrize("command", [("sim", "serve"), ("capture",), ("demo",), ("serve",)])
def test_every_command_states_the_declared_scenario_and_time_scale(command):
    text = _help(*command)
    assert f"[default: {DEFAULT_SCENARIO.value}" in _option_help(text, "--scenario")
    assert f"[default: {DEFAULT_TIME_SCALE:g}]" in _option_help(text, "--time-scale")
    assert "[default: a fresh random one" in _option_help(text, "--seed")


def test_the_declared_defaults_are_the_lab_beam_at_twenty_times_real_time():
    # docs/simulator.md, "Defaults", says why; a change there is a change here.
    assert (DEFAULT_SCENARIO.value, DEFAULT_TIME_SCALE) == ("realistic", 0.05)


def _capture(store, env, *args: str):
    result = invoke_daq("capture", "--sim", "--yes", "--hits", "2", "--store", str(store), *args, env=env)
    assert result.returncode == 0, result.stderr
    banner = result.stdout.splitlines()[0]
    run_id = re.search(r"Run (\S+) sealed", result.stdout).group(1)
    return banner, Store(store).open(run_id)


@pytest.mark.timeout(120)
def test_captures_without_seed_differ_and_the_recorded_seed_replays_them(tmp_path, env):
    store = tmp_path / "runs"
    banner_a, a = _capture(store, env)
    _, b = _capture(store, env)
    simulator = a.provenance["simulator"]
    # The defaults, as declared, recorded in the run and said in the banner.
    assert simulator["scenario"] == DEFAULT_SCENARIO.value
    assert simulator["time_scale"] == DEFAULT_TIME_SCALE
    seed_a, seed_b = simulator["seed"], b.provenance["simulator"]["seed"]
    assert f"{DEFAULT_SCENARIO.value} beam, seed {seed_a}, time scale {DEFAULT_TIME_SCALE:g})" in banner_a
    # A fresh seed per capture: other seeds, other hits.
    assert seed_a != seed_b
    assert not np.array_equal(a.hits.force_n, b.hits.force_n)
    # `daq capture --sim --seed <recorded>` takes the same hits again.
    banner_c, c = _capture(store, env, "--seed", str(seed_a))
    assert f"seed {seed_a}," in banner_c
    assert c.provenance["simulator"]["seed"] == seed_a
    np.testing.assert_array_equal(c.hits.force_n, a.hits.force_n)
    np.testing.assert_array_equal(c.hits.response_m_s2, a.hits.response_m_s2)
    np.testing.assert_array_equal(c.analyzer.frf, a.analyzer.frf)


@pytest.mark.timeout(120)
def test_the_same_seed_gives_the_same_hits_at_any_time_scale(tmp_path, env):
    store = tmp_path / "runs"
    _, one = _capture(store, env, "--seed", "7", "--time-scale", "0")
    _, two = _capture(store, env, "--seed", "7")
    assert one.provenance["simulator"]["seed"] == two.provenance["simulator"]["seed"] == 7
    np.testing.assert_array_equal(one.hits.force_n, two.hits.force_n)
    np.testing.assert_array_equal(one.hits.response_m_s2, two.hits.response_m_s2)


@pytest.mark.timeout(60)
def test_demo_plays_the_defaults_and_prints_its_fresh_seed(env):
    runs = [invoke_daq("demo", "--hits", "1", env=env) for _ in range(2)]
    seeds = []
    for result in runs:
        assert result.returncode == 0, result.stderr
        found = re.search(
            rf"\({DEFAULT_SCENARIO.value} beam, seed (\d+), time scale {DEFAULT_TIME_SCALE:g}\)",
            result.stdout,
        )
        assert found, result.stdout.splitlines()[0]
        seeds.append(found.group(1))
    assert seeds[0] != seeds[1]


def _sim_serve_banner(*args: str) -> str:
    """Start `daq sim serve --tcp 0 ARGS`, stop it once it serves; its stderr."""
    proc = subprocess.Popen(
        [str(DAQ), "sim", "serve", "--tcp", "0", *args],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        env={**os.environ, **ENV},
    )
    try:
        deadline = time.monotonic() + 30
        while not select.select([proc.stdout], [], [], 0.5)[0]:
            assert proc.poll() is None, "daq sim serve ended early"
            assert time.monotonic() < deadline, "no resource line"
        assert proc.stdout.readline().startswith(b"TCPIP::127.0.0.1::")
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=15)
        return err.decode()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate(timeout=5)


@pytest.mark.timeout(90)
def test_sim_serve_plays_the_defaults_with_a_fresh_seed_at_each_start():
    banners = [_sim_serve_banner() for _ in range(2)]
    pattern = rf"\(scenario {DEFAULT_SCENARIO.value}, seed (\d+), time scale {DEFAULT_TIME_SCALE:g}\)"
    seeds = [re.search(pattern, banner) for banner in banners]
    assert all(seeds), banners
    assert seeds[0].group(1) != seeds[1].group(1)
    assert "seed 12, time scale 1)" in _sim_serve_banner("--seed", "12", "--time-scale", "1")


@pytest.mark.slow
@pytest.mark.timeout(240)
def test_service_captures_get_fresh_seeds_that_daq_capture_replays(tmp_path, env):
    from tests.service.service_helpers import serving, wait_for

    with serving(tmp_path, "--sim", "--workers", "1") as served:
        assert any("a fresh seed per capture" in line for line in served.stderr_lines)
        runs = []
        for _ in range(2):
            run_id = served.post("/api/capture", {"hits": 2, "auto": True}).json()["run_id"]
            wait_for(lambda: served.get("/api/capture").json()["state"] == "idle", 60, "the capture")
            ended = served.get("/api/capture").json()
            # A capture that ended early keeps its hits so far: say why, not a shape mismatch.
            assert ended["last_outcome"] == "sealed", (ended["last_outcome"], ended["last_message"])
            runs.append(Store(served.store).open(run_id))
    first, second = (run.provenance["simulator"] for run in runs)
    assert (first["scenario"], first["time_scale"]) == (DEFAULT_SCENARIO.value, DEFAULT_TIME_SCALE)
    assert first["seed"] != second["seed"]
    # The second capture's seed, not the service's first, replays its hits.
    _, again = _capture(tmp_path / "again", env, "--seed", str(second["seed"]))
    np.testing.assert_array_equal(again.hits.force_n, runs[1].hits.force_n)
    np.testing.assert_array_equal(again.hits.response_m_s2, runs[1].hits.response_m_s2)
