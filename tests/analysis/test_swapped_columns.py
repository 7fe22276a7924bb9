"""A file read with its force and response the wrong way round (analysis/hit_checks.py
channels_swapped): the response column then holds a pulse and the force column a
response ringing on. Found in such files; never in a file the right way round, nor in
the simulator's captures."""

from __future__ import annotations

import numpy as np
import pytest

from analysis.hit_checks import SWAPPED, channels_swapped, file_checks
from tests.analysis.impact_synth import DAMPED_CASES as DAMPED
from tests.analysis.impact_synth import IMPACT_CASES as CASES
from tests.analysis.impact_synth import impact_hits
from tests.cli_helpers import invoke_daq


@pytest.mark.parametrize("case", CASES)
@pytest.mark.parametrize("noise", [0.0, 0.01, 0.05])
def test_hits_the_right_way_round_pass(case, noise):
    fn, zeta, amp, fs, seconds, pulse = case
    force, response = impact_hits(fn, zeta, amp, fs, seconds, 3, noise, pulse, 11)
    for f, a in zip(force, response, strict=True):
        check = channels_swapped(f, a, fs)
        assert check.passed, check.detail
        assert channels_swapped(-f, a, fs).passed  # a gauge wired the other way


def test_the_lightly_damped_hits_swapped_fail():
    fn, zeta, amp, fs, seconds, pulse = CASES[0]
    force, response = impact_hits(fn, zeta, amp, fs, seconds, 3, 0.01, pulse, 11)
    for f, a in zip(force, response, strict=True):
        check = channels_swapped(a, f, fs)
        assert not check.passed
        assert check.detail.endswith("as a decaying response's")
        assert check.name in {c.name for c in file_checks(a, f, fs) if not c.passed}


def test_short_or_silent_records_are_not_judged():
    assert channels_swapped(np.r_[0.0, 1.0, np.zeros(30)], np.ones(32), 1000.0).passed
    assert channels_swapped(np.zeros(1024), np.r_[1.0, np.zeros(1023)], 1000.0).passed


@pytest.mark.parametrize("scenario", ["seed", "realistic"])
@pytest.mark.parametrize("analyzer", ["35660A", "3562A", "35670A"])
def test_the_simulators_captures_pass(tmp_path, scenario, analyzer):
    from daq.store import Store

    result = invoke_daq(
        "capture", "--sim", "--yes", "--scenario", scenario, "--analyzer", analyzer, "--hits", "3",
        "--time-scale", "0", "--seed", "5", "--hammer", "double_hit_probability=0.3",
        "--store", str(tmp_path),
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    (summary,) = Store(tmp_path).list()
    hits = Store(tmp_path).open(summary.run_id).hits
    for k in range(hits.n_hits):
        check = channels_swapped(hits.force_n[k], hits.response_m_s2[k], hits.sample_rate_hz)
        assert check.passed, (k, check.detail)
        assert check.name == SWAPPED


@pytest.mark.parametrize("case", DAMPED)
def test_hits_of_a_more_damped_structure_swapped_fail_by_their_swing(case):
    """Their response holds as much of its energy near its peak as a pulse does (0.66 and
    more): the energy alone passed these swapped files (the new user's was reported as a
    double impact on every hit). The force column then swings both ways, and the response
    column, the hammer pulse, one way. The right way round they pass."""
    fn, zeta, amp, fs, seconds, pulse = case
    force, response = impact_hits(fn, zeta, amp, fs, seconds, 3, 0.01, pulse, 11)
    for f, a in zip(force, response, strict=True):
        check = channels_swapped(a, f, fs)
        assert not check.passed, check.detail
        assert "swings both ways" in check.detail
        assert check.name in {c.name for c in file_checks(a, f, fs) if not c.passed}
        assert channels_swapped(f, a, fs).passed
