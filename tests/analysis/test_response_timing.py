"""A file whose response is not timed with its force (analysis/hit_checks.py
response_timing): the response moves before the hammer strikes, or stays quiet long
after. Found in such files, said once for the file at import and as a caution of the
analysis; never in a file timed right, nor in the simulator's captures."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from analysis.hit_checks import (
    RESPONSE_TIMING,
    TIMING_LAG_S,
    TIMING_LEAD_SAMPLES,
    file_checks,
    response_timing,
)
from tests.analysis.impact_synth import DAMPED_CASES as DAMPED
from tests.analysis.impact_synth import IMPACT_CASES as CASES
from tests.analysis.impact_synth import impact_hits
from tests.cli_helpers import invoke_daq


def _delayed(response: np.ndarray, samples: int) -> np.ndarray:
    """The response recorded ``samples`` later (> 0) or earlier (< 0) than the force, as a
    skewed recorder gives it: the samples shifted in are the record's quiet start or its
    decayed end, not the other end wrapped round."""
    if samples > 0:
        return np.concatenate([np.full(samples, response[0]), response[:-samples]])
    return np.concatenate([response[-samples:], np.full(-samples, response[-1])])


@pytest.mark.parametrize("case", CASES + DAMPED)
@pytest.mark.parametrize("noise", [0.0, 0.01, 0.05])
def test_hits_timed_right_pass(case, noise):
    fn, zeta, amp, fs, seconds, pulse = case
    force, response = impact_hits(fn, zeta, amp, fs, seconds, 3, noise, pulse, 11, pretrigger_s=0.02)
    for f, a in zip(force, response, strict=True):
        check = response_timing(f, a, fs)
        assert check.passed, check.detail
        assert response_timing(-f, -a, fs).passed  # gauges wired the other way
        assert abs(check.value) < 2e-3, check.detail  # pinned: the response starts with the hit


@pytest.mark.parametrize("case", CASES + DAMPED)
def test_a_response_later_than_the_lab_allows_fails(case):
    fn, zeta, amp, fs, seconds, pulse = case
    force, response = impact_hits(fn, zeta, amp, fs, seconds, 1, 0.01, pulse, 3, pretrigger_s=0.02)
    lag = round(3 * TIMING_LAG_S * fs)
    check = response_timing(force[0], _delayed(response[0], lag), fs)
    assert not check.passed
    assert check.name == RESPONSE_TIMING
    assert check.value == pytest.approx(lag / fs, abs=3 / fs + pulse)
    assert "after the hammer strikes" in check.detail
    assert RESPONSE_TIMING in {
        c.name for c in file_checks(force[0], _delayed(response[0], lag), fs) if not c.passed
    }


@pytest.mark.parametrize("case", CASES + DAMPED)
def test_a_response_ahead_of_the_hammer_fails(case):
    fn, zeta, amp, fs, seconds, pulse = case
    force, response = impact_hits(fn, zeta, amp, fs, seconds, 1, 0.01, pulse, 3, pretrigger_s=0.02)
    lead = TIMING_LEAD_SAMPLES + 8
    check = response_timing(force[0], _delayed(response[0], -lead), fs)
    assert not check.passed, check.detail
    assert "before the hammer strikes" in check.detail
    # The onset read at a quarter of the peak, the force's start at 5 % of its: within the pulse.
    assert -check.value == pytest.approx(lead / fs, abs=pulse + 2 / fs)


def test_a_lead_within_the_slack_passes():
    fn, zeta, amp, fs, seconds, pulse = CASES[0]
    force, response = impact_hits(fn, zeta, amp, fs, seconds, 1, 0.01, pulse, 3, pretrigger_s=0.02)
    assert response_timing(force[0], _delayed(response[0], -TIMING_LEAD_SAMPLES), fs).passed


def test_a_response_of_noise_only_is_not_called_skewed():
    """A dead accelerometer: its 'onset' is wherever the noise first crosses a share of its
    largest value, which says nothing of timing."""
    fn, zeta, amp, fs, seconds, pulse = CASES[0]
    force, _ = impact_hits(fn, zeta, amp, fs, seconds, 1, 0.01, pulse, 3, pretrigger_s=0.02)
    noise = np.random.default_rng(0).standard_normal(force.shape[1])
    assert response_timing(force[0], noise, fs).passed


def test_short_constant_and_zoomed_records_are_not_judged():
    assert response_timing(np.r_[0.0, 1.0, np.zeros(30)], np.ones(32), 1000.0).value is None
    assert response_timing(np.r_[np.zeros(100), 1.0, np.zeros(99)], np.zeros(200), 1000.0).value is None
    zoomed = np.exp(1j * np.arange(256.0))
    assert response_timing(zoomed, zoomed, 1000.0).value is None


@settings(max_examples=60, deadline=None)
@given(
    fn=st.floats(20.0, 400.0),
    zeta=st.floats(0.001, 0.08),
    noise=st.floats(0.0, 0.05),
    skew_ms=st.sampled_from([-6.0, -3.0, 0.0, 25.0, 60.0]),
    seed=st.integers(0, 2**16),
)
def test_the_skew_is_found_whatever_the_structure(fn, zeta, noise, skew_ms, seed):
    """Timed right: never called skewed. Skewed: found wherever the response is quiet
    before the hit (a response still ringing from before, here the synthesis' own
    wrap-around of a light mode as a previous hit's ring-down would be, may go unjudged)."""
    fs = 2048.0
    force, response = impact_hits([fn], [zeta], [1.0], fs, 1.0, 1, noise, 2e-3, seed, pretrigger_s=0.02)
    samples = round(skew_ms * 1e-3 * fs)
    check = response_timing(force[0], _delayed(response[0], samples) if samples else response[0], fs)
    if samples == 0:
        assert check.passed, check.detail
        return
    before = response[0][: round(0.02 * fs) - abs(min(samples, 0)) - 1]
    quiet = np.sqrt(np.mean((before - np.median(response[0])) ** 2)) < 0.01 * np.max(np.abs(response[0]))
    if quiet:
        assert not check.passed, check.detail


@pytest.mark.parametrize("scenario", ["seed", "realistic"])
@pytest.mark.parametrize("analyzer", ["35660A", "3562A", "35670A"])
def test_the_simulators_captures_are_timed_right(tmp_path, scenario, analyzer):
    from daq.store import Store

    result = invoke_daq(
        "capture", "--sim", "--yes", "--scenario", scenario, "--analyzer", analyzer, "--hits", "3",
        "--time-scale", "0", "--seed", "5", "--store", str(tmp_path),
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    (summary,) = Store(tmp_path).list()
    hits = Store(tmp_path).open(summary.run_id).hits
    for k in range(hits.n_hits):
        check = response_timing(hits.force_n[k], hits.response_m_s2[k], hits.sample_rate_hz)
        assert check.passed, check.detail


def _skewed_file(tmp_path, lag_s: float):
    fn, zeta, amp, fs, seconds, pulse = CASES[0]
    force, response = impact_hits(fn, zeta, amp, fs, seconds, 3, 0.01, pulse, 7, pretrigger_s=0.02)
    rows = ["hit,time,force,response"]
    for k in range(3):
        late = _delayed(response[k], round(lag_s * fs))
        rows += [f"{k},{i / fs:.9g},{force[k, i]:.9g},{late[i]:.9g}" for i in range(force.shape[1])]
    path = tmp_path / "skewed.csv"
    path.write_text("\n".join(rows) + "\n")
    return path


def test_a_skewed_file_is_said_once_at_import_and_in_the_analysis(tmp_path):
    path = _skewed_file(tmp_path, 0.05)
    store = tmp_path / "store"
    imported = invoke_daq("import", str(path), "--store", str(store))
    assert imported.returncode == 0, imported.stderr
    output = imported.stdout + imported.stderr
    said = [line for line in output.splitlines() if "not timed with the force" in line]
    assert len(said) == 1, output
    assert "in every hit" in said[0]
    assert "align the response with the force" in said[0]
    assert "failed the response timing check" not in output  # not once more per hit
    analysed = invoke_daq("analyze", "latest", "--store", str(store), "--json")
    assert analysed.returncode == 0, analysed.stderr
    (result,) = json.loads(analysed.stdout)
    skew = [c for c in result["cautions"] if "not timed with the force" in c]
    assert len(skew) == 1, result["cautions"]
    assert "may not be the structure's" in skew[0]


def test_a_file_timed_right_says_nothing_of_timing(tmp_path):
    path = _skewed_file(tmp_path, 0.0)
    store = tmp_path / "store"
    imported = invoke_daq("import", str(path), "--store", str(store))
    assert imported.returncode == 0, imported.stderr
    assert "not timed with the force" not in imported.stdout + imported.stderr


def test_a_run_imported_before_the_check_is_judged_from_its_records(tmp_path):
    """A run whose hits carry no timing verdict (imported by an earlier version) gets the
    caution from its records when analysed."""
    from daq.store import Store
    from daq.workflows.run_views import skewed_channels

    path = _skewed_file(tmp_path, 0.05)
    store = tmp_path / "store"
    assert invoke_daq("import", str(path), "--store", str(store)).returncode == 0
    (summary,) = Store(store).list()
    run = Store(store).open(summary.run_id)
    for checks in run.hits.checks:
        del checks[RESPONSE_TIMING]
    skewed = skewed_channels(run)
    assert skewed is not None
    assert skewed[0] == [0, 1, 2]
    assert "50" in skewed[1]


def test_a_lone_spike_in_the_response_is_no_onset():
    """One glitched sample 1000 times the response's peak, 250 ms into the record: timed by
    it, the response 'started 250 ms after the hammer' (a new user's trial)."""
    fn, zeta, amp, fs, seconds, pulse = CASES[0]
    force, response = impact_hits(fn, zeta, amp, fs, seconds, 1, 0.01, pulse, 3, pretrigger_s=0.02)
    glitched = response[0].copy()
    glitched[round(0.25 * fs)] = 1000 * np.max(np.abs(glitched))
    check = response_timing(force[0], glitched, fs)
    assert check.passed
    assert "lone spike" in check.detail


def test_a_double_impact_with_the_larger_second_strike_is_no_skew():
    """The response to the first, smaller strike came before the larger second one: timed
    from the largest, it 'moved 14.6 ms before the hammer' (review of the first version).
    The hammer strikes where its first tap starts."""
    fn, zeta, amp, fs, seconds, pulse = CASES[1]
    force, response = impact_hits(fn, zeta, amp, fs, seconds, 1, 0.01, pulse, 3, pretrigger_s=0.1)
    lag = round(0.015 * fs)
    force2 = force[0] + 1.5 * np.r_[np.zeros(lag), force[0][:-lag]]
    response2 = response[0] + 1.5 * np.r_[np.zeros(lag), response[0][:-lag]]
    check = response_timing(force2, response2, fs)
    assert check.passed, check.detail


def test_a_lone_glitch_in_the_pre_trigger_is_no_lead():
    """One response sample at 30 % of the peak, 0.35 s before the hit: a glitch, not a
    response that moves before the hammer (review of the first version)."""
    fn, zeta, amp, fs, seconds, pulse = CASES[1]
    force, response = impact_hits(fn, zeta, amp, fs, seconds, 1, 0.01, pulse, 3, pretrigger_s=0.5)
    glitched = response[0].copy()
    glitched[round(0.15 * fs)] = 0.3 * np.max(np.abs(glitched))
    check = response_timing(force[0], glitched, fs)
    assert check.passed, check.detail


def test_a_response_one_sample_late_at_a_low_rate_is_no_skew():
    """At 64 Hz one sample is 15.6 ms, more than the 10 ms limit: a low-frequency
    structure's response reaching a tenth of its peak one sample after the force is
    timed right (the limit is never under TIMING_LAG_SAMPLES samples)."""
    fs = 64.0
    n = 512
    force = np.zeros(n)
    force[40] = 50.0
    t = (np.arange(n) - 40) / fs
    response = np.where(
        t > 0, np.exp(-0.3 * t) * (np.sin(2 * np.pi * 2 * t) - np.sin(2 * np.pi * 6 * t)), 0.0
    )
    check = response_timing(force, response, fs)
    assert check.passed, check.detail
    late = np.r_[np.zeros(8), response[:-8]]  # 8 samples, 125 ms: a skew
    assert not response_timing(force, late, fs).passed


def _file_of(tmp_path, lags_s: list[float], clip_hit: int | None = None):
    fn, zeta, amp, fs, seconds, pulse = CASES[0]
    force, response = impact_hits(fn, zeta, amp, fs, seconds, len(lags_s), 0.01, pulse, 7, pretrigger_s=0.02)
    rows = ["hit,time,force,response"]
    for k, lag in enumerate(lags_s):
        r = _delayed(response[k], round(lag * fs))
        if k == clip_hit:
            r = np.clip(r, -0.5 * np.max(np.abs(r)), 0.5 * np.max(np.abs(r)))
        rows += [f"{k},{i / fs:.9g},{force[k, i]:.9g},{r[i]:.9g}" for i in range(force.shape[1])]
    path = tmp_path / "hits.csv"
    path.write_text("\n".join(rows) + "\n")
    return path


def test_one_hit_out_of_time_is_a_failed_check_with_the_line_that_leaves_it_out(tmp_path):
    """A recorder's skew is every hit's; one hit of three 30 ms late was cut from another
    trigger: a failed check of that hit, not the file's (review of the first version)."""
    store = tmp_path / "store"
    imported = invoke_daq("import", str(_file_of(tmp_path, [0.0, 0.03, 0.0])), "--store", str(store))
    assert imported.returncode == 0, imported.stderr
    assert "hit 2 failed the response timing check" in imported.stdout
    assert "not timed with the force in every hit" not in imported.stdout
    (result,) = json.loads(invoke_daq("analyze", "latest", "--store", str(store), "--json").stdout)
    (caution,) = [c for c in result["cautions"] if "response timing" in c]
    assert "'# rejected hit 1: response timing'" in caution


def test_a_skewed_file_with_a_clipped_hit_says_both(tmp_path):
    store = tmp_path / "store"
    path = _file_of(tmp_path, [0.05, 0.05, 0.05], clip_hit=2)
    assert invoke_daq("import", str(path), "--store", str(store)).returncode == 0
    (result,) = json.loads(invoke_daq("analyze", "latest", "--store", str(store), "--json").stdout)
    (caution,) = [c for c in result["cautions"] if "not timed with the force" in c]
    assert "hit 3: clipped" in caution
    assert "'# rejected hit 2: clipped'" in caution
    assert "response timing (" not in caution  # the skew is said once, for the file
