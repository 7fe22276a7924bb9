"""Hits a file holds that are no new measurement (hypothesis), for every reader alike
(daq/formats/imported.py make_hits): a hit that repeats an earlier one sample for sample
(a block pasted twice) and a hit whose response is zero throughout (a dead or unplugged
sensor) are kept as rejected with why; a file where no hit with a force has a response is
refused in one line. Any other hits are kept as they are."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from daq.formats.errors import FormatError
from daq.formats.imported import make_hits
from tests.analysis.impact_synth import impact_hits

SETTINGS = settings(max_examples=60, deadline=None)


def _hits(n_hits: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    return impact_hits([45.0, 120.0], [0.01, 0.02], [1.0, -0.5], 1024.0, 0.25, n_hits, 0.02, 0.003, seed)


def _made(force: np.ndarray, response: np.ndarray):
    return make_hits(Path("hits.csv"), force, response, 1024.0, 0.0, 0.0, "2026-12-08T00:00:00Z")


@SETTINGS
@given(n_hits=st.integers(2, 6), seed=st.integers(0, 2**16), data=st.data())
def test_copies_are_kept_as_rejected_and_named_by_the_hit_they_repeat(n_hits, seed, data):
    force, response = _hits(n_hits, seed)
    original = data.draw(st.integers(0, n_hits - 2))
    copy = data.draw(st.integers(original + 1, n_hits - 1))
    force[copy], response[copy] = force[original], response[original]
    hits = _made(force, response)
    rejected = [k for k in range(n_hits) if not hits.accepted[k]]
    # The copy and any later hit that happens to repeat the same original.
    assert copy in rejected
    assert original not in rejected
    assert hits.reject_reason[copy] == f"the same samples as hit {original + 1} (counted from 1): a copy"
    assert hits.accepted.sum() == n_hits - len(rejected)


@SETTINGS
@given(n_hits=st.integers(2, 6), seed=st.integers(0, 2**16), data=st.data())
def test_a_dead_response_is_kept_as_rejected_unless_every_hit_has_one(n_hits, seed, data):
    force, response = _hits(n_hits, seed)
    dead = data.draw(st.sets(st.integers(0, n_hits - 1), min_size=1, max_size=n_hits))
    for k in dead:
        response[k] = 0.0
    if len(dead) == n_hits:
        with pytest.raises(
            FormatError, match="the response is zero in every sample of every hit with a force"
        ):
            _made(force, response)
        return
    hits = _made(force, response)
    for k in range(n_hits):
        assert bool(hits.accepted[k]) == (k not in dead)
        if k in dead:
            assert hits.reject_reason[k] == "the response is zero in every sample"


@SETTINGS
@given(n_hits=st.integers(1, 6), seed=st.integers(0, 2**16), nudge=st.floats(1e-12, 1e-3))
def test_hits_that_differ_anywhere_are_all_kept(n_hits, seed, nudge):
    force, response = _hits(n_hits, seed)
    if n_hits > 1:
        force[1], response[1] = force[0], response[0] * (1 + nudge)  # one value apart at least
    hits = _made(force, response)
    assert hits.accepted.all()
