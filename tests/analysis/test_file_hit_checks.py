"""The checks a hit read from a file gets (analysis/hit_checks.py file_checks): a double
impact and a clipped channel are found, whichever way the force gauge was wired, and
clean records, quantised as converters write them, pass."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from analysis.hit_checks import (
    CLIP_SAMPLES,
    CLIPPED,
    DOUBLE_IMPACT,
    FORCE_GLITCH,
    NO_IMPACT,
    RESPONSE_TIMING,
    SWAPPED,
    clipped,
    double_impact,
    file_checks,
    force_glitch,
)
from tests.analysis.impact_synth import impact_hits

FS = 2048.0


def _hit(seed: int) -> tuple[np.ndarray, np.ndarray]:
    force, response = impact_hits([45.0, 132.0, 310.0], [0.015, 0.008, 0.02], [1.0, -0.6, 0.4], FS, 2.0, 1,
                                  0.01, 2e-3, seed)  # fmt: skip
    return force[0], response[0]


def _quantised(x: np.ndarray, bits: int) -> np.ndarray:
    lsb = 2 * np.abs(x).max() * 1.25 / 2**bits  # the range a fifth above the peak
    return np.round(x / lsb) * lsb


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 10_000), bits=st.sampled_from([12, 16, 24]), sign=st.sampled_from([1.0, -1.0]))
def test_clean_hits_pass_however_quantised_and_wired(seed, bits, sign):
    force, response = _hit(seed)
    checks = {c.name: c for c in file_checks(sign * _quantised(force, bits), _quantised(response, bits), FS)}
    assert checks[DOUBLE_IMPACT].passed, checks[DOUBLE_IMPACT].detail
    assert checks[CLIPPED].passed, checks[CLIPPED].detail


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 10_000), level=st.floats(0.2, 0.6), sign=st.sampled_from([1.0, -1.0]))
def test_a_clipped_response_is_found(seed, level, sign):
    """Cut at 60 % of its peak or lower; a cut that touches 2 or 3 samples is not told
    from a peak the converter's steps flatten."""
    force, response = _hit(seed)
    top = level * np.abs(response).max()
    check = clipped(sign * force, np.clip(response, -top, top))
    assert not check.passed
    assert check.value >= CLIP_SAMPLES
    assert check.detail.startswith("the response reaches its largest value in ")


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 10_000), delay_ms=st.floats(20.0, 200.0), share=st.floats(0.3, 0.9),
       sign=st.sampled_from([1.0, -1.0]))  # fmt: skip
def test_a_second_tap_is_found_whichever_way_the_gauge_was_wired(seed, delay_ms, share, sign):
    force, _ = _hit(seed)
    shift = round(delay_ms * 1e-3 * FS)
    second = force + share * np.concatenate([np.zeros(shift), force[:-shift]])
    check = double_impact(sign * second, FS)
    assert not check.passed
    assert abs(check.value - share) < 0.1
    assert double_impact(sign * force, FS).passed


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.sampled_from([64, 1024, 65536]))
def test_a_random_force_is_no_impact_not_a_double_impact(seed, n):
    """Random excitation (a shaker's noise, or a file with no hit in it) is no hammer hit:
    said, not checked for a second tap."""
    rng = np.random.default_rng(seed)
    (impact, *_) = file_checks(rng.normal(size=n), rng.normal(size=n), FS)
    assert impact.name == NO_IMPACT
    assert not impact.passed
    assert impact.detail.startswith("the force is no hammer pulse")


def test_huge_or_non_finite_records_neither_overflow_nor_warn():
    """A file's values near 1e200 (the UFF splice test found them) are checked without an
    overflow; a record with NaN or inf gets no checks (the store refuses it anyway)."""
    force, response = _hit(1)
    checks = file_checks(force * 1e200, response * 1e200, FS)
    assert [c.name for c in checks] == [DOUBLE_IMPACT, CLIPPED, SWAPPED, RESPONSE_TIMING, FORCE_GLITCH]
    assert all(c.passed for c in checks)
    assert file_checks(np.where(np.arange(force.size) == 5, np.nan, force), response, FS) == []
    assert file_checks(force, np.where(np.arange(response.size) == 5, np.inf, response), FS) == []


def test_a_force_zero_in_every_sample_is_said_so_not_given_a_crest_factor():
    (impact, *_) = file_checks(np.zeros(512), np.ones(512), 1024.0)
    assert impact.name == NO_IMPACT
    assert not impact.passed
    assert impact.detail == "the force is zero in every sample"


@settings(max_examples=20, deadline=None)
@given(offset=st.floats(-20.0, 20.0), drift=st.floats(-1.0, 1.0))
def test_a_clean_tap_on_an_offset_or_drifting_gauge_is_an_impact(offset, drift):
    # A trial's logger: 100 N taps on an 8 N offset drifting 0.6 N/s failed "no impact".
    rate, n = 2048.0, 8192
    t = np.arange(n) / rate
    force = offset + drift * t
    force[200:204] += 100 * np.sin(np.pi * np.arange(1, 5) / 5)
    response = np.exp(-3 * t) * np.sin(2 * np.pi * 40 * t)
    (impact, *_) = file_checks(force, response, rate)
    assert impact.name != NO_IMPACT, impact


def test_a_lone_force_sample_the_response_does_not_answer_is_a_glitch():
    """A new user's file: one force sample of 1e6 N at 0.75 s, long after the real tap. It
    stood for the hit in every check and in the band; the import said nothing."""
    force, response = _hit(3)
    glitched = force.copy()
    glitched[int(0.75 * FS)] = 1e6
    check = force_glitch(glitched, response, FS)
    assert not check.passed
    assert check.detail.startswith("the force's largest value, 1e+06 N at 0.75 s, is a lone sample")
    assert FORCE_GLITCH in {c.name for c in file_checks(glitched, response, FS) if not c.passed}


def test_a_one_sample_hammer_pulse_is_no_glitch():
    """A hard tip at a low rate: the pulse is one sample, and the response answers it."""
    fs = 1024.0
    n = 2048
    force = np.zeros(n)
    force[100] = 80.0
    t = (np.arange(n) - 100) / fs
    response = np.where(t >= 0, np.exp(-2.0 * t) * np.sin(2 * np.pi * 60.0 * t + 0.3), 0.0)
    assert force_glitch(force, response, fs).passed
    assert force_glitch(-force, response, fs).passed
    for seed in range(3):
        f, a = _hit(seed)
        assert force_glitch(f, a, FS).passed


def test_a_glitch_is_said_as_a_glitch_not_also_as_a_skew():
    """With a pre-trigger, the response to the real tap comes long before the glitch that
    stands for the hammer: said once, as the glitch, not also as a response that moves
    before the hammer strikes."""
    from analysis.hit_checks import RESPONSE_TIMING

    force, response = impact_hits([45.0, 132.0, 310.0], [0.03, 0.03, 0.03], [1.0, -0.6, 0.4], FS, 2.0, 1,
                                  0.01, 2e-3, 8, pretrigger_s=0.1)  # fmt: skip
    glitched = force[0].copy()
    glitched[int(1.5 * FS)] = 1e6
    failed = {c.name for c in file_checks(glitched, response[0], FS) if not c.passed}
    assert FORCE_GLITCH in failed
    assert RESPONSE_TIMING not in failed
