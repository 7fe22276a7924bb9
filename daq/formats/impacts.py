"""A continuous record of several hammer taps, cut into one hit per tap.

Loggers (LabVIEW, a DAQ card's own program, a scope) often write one long record while
the technician taps several times. Read as one hit, its FRF mixes the taps and the double
impact check fails it. Where the record holds two or more clear taps and the structure
rang down between each and the next, each tap is a whole hit of its own: the record is
cut at the taps, every hit the same length and starting the same pre-trigger before its
tap. A second tap while the response still rings (a bounce, a hurried second strike) is
left alone: cutting would truncate the first response, and the double impact check says
so instead.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

#: A tap: the force rises above this fraction of the record's largest pulse.
TAP_FRACTION = 0.5
#: Samples above the threshold closer than this (s) are one tap (the pulse and its bounce).
TAP_MERGE_S = 0.02
#: The response has rung down before the next tap: the RMS of the response over the
#: stretch just before it is below this fraction of the RMS just after the tap.
RUNG_DOWN_FRACTION = 0.1
#: ... or below this many times the RMS of the quiet before the first tap (the noise).
NOISE_MARGIN = 1.5
#: ... or, with no quiet before the first tap to measure the noise by, below this fraction
#: of the RMS after the tap and no lower than the RMS halfway between the taps over this
#: ratio: stationary, so noise. A ringing response cannot do both: decayed by 1/0.3 over
#: the spacing, it is sqrt(1/0.3) = 1.8 times higher halfway. (A new user's taps 0.02 s
#: into the record, 2 % noise: the response between taps at 0.17 of its RMS after each tap,
#: flat; the record was left one hit and read three spurious modes.)
STATIONARY_FRACTION = 0.3
STATIONARY_RATIO = 1.25
#: The stretch, as a fraction of the spacing of the taps, over which those RMS are taken.
STRETCH_FRACTION = 0.1
#: A tap closer to the one before than this fraction of the taps' median spacing is no
#: hit of its own.
CLOSE_FRACTION = 0.25
#: The shortest hit worth cutting, samples (128 frequency lines).
MIN_HIT_SAMPLES = 256
#: The pre-trigger of each cut hit, as a fraction of its length.
PRETRIGGER_FRACTION = 1 / 64


@dataclass(frozen=True)
class Cut:
    """Where a record is cut: the first sample of each hit, the common length and the
    pre-trigger (samples before each tap)."""

    starts: np.ndarray  # (n_hits,) int sample indices into the record
    length: int
    pretrigger: int
    taps: np.ndarray  # (n_hits,) int sample index of each tap
    left_in: tuple[int, ...] = ()  # taps too close to the one before to cut at: inside its hit
    left_out: tuple[int, ...] = ()  # a last tap with too little record after it


def find_cut(force: np.ndarray, response: np.ndarray, sample_rate_hz: float) -> Cut | None:
    """The cut of one record (force, response: (n,) real) into hits, or None where it is
    one hit (one tap, taps too close, or a response still ringing at the next tap)."""
    force = np.asarray(force, dtype=np.float64)
    response = np.asarray(response, dtype=np.float64)
    n = force.size
    if n < 2 * MIN_HIT_SAMPLES or not (np.all(np.isfinite(force)) and np.all(np.isfinite(response))):
        return None
    level = force - np.median(force)  # loggers' offsets: the lvm corpus file's sits at 0.05
    if -level.min() > level.max():  # a gauge wired the other way: taps negative
        level = -level
    peak = float(level.max())
    if not peak > 0:
        return None
    above = np.flatnonzero(level > TAP_FRACTION * peak)
    merge = max(round(TAP_MERGE_S * sample_rate_hz), 1)
    taps = above[np.concatenate(([True], np.diff(above) > merge))]
    if taps.size < 2:
        return None
    left_in: tuple[int, ...] = ()
    if taps.size > 2:
        # A tap far closer to the one before than the taps are to each other is a second
        # strike, not a hit of its own: cutting there would shorten every hit to that gap
        # (a trial's 0.35 s among 3 s gaps threw 88 % of each hit away). It stays in the
        # hit before, where the double impact check names it.
        gaps = np.diff(taps)
        close = np.concatenate(([False], gaps < CLOSE_FRACTION * np.median(gaps)))
        left_in = tuple(int(t) for t in taps[close])
        taps = taps[~close]
        if taps.size < 2:
            return None
    spacing = np.diff(taps)
    gap = int(spacing.min())
    pretrigger = min(int(taps[0]), int(gap * PRETRIGGER_FRACTION))
    left_out: tuple[int, ...] = ()
    if n - taps[-1] + pretrigger < gap // 2 and taps.size > 2:
        left_out = (int(taps[-1]),)  # too little record after it: it would shorten every hit
        taps = taps[:-1]
    length = min(gap, n - int(taps[-1]) + pretrigger)
    if length < MIN_HIT_SAMPLES or gap < 4 * merge:
        return None
    stretch = max(int(STRETCH_FRACTION * gap), 8)
    mean = float(np.median(response))
    # The sensor's noise, where the record has quiet before its first tap: a response
    # rung down to it counts as rung down however weakly the tap excited the structure.
    quiet = response[: max(int(taps[0]) - pretrigger, 0)] - mean
    floor = NOISE_MARGIN * float(np.sqrt(np.mean(quiet**2))) if quiet.size >= 64 else 0.0
    for tap, following in itertools.pairwise(taps):
        after = _rms(response[tap : tap + stretch] - mean)
        before = response[max(following - pretrigger - stretch, tap) : following - pretrigger] - mean
        ringing = _rms(before) if before.size else math.inf
        if ringing <= max(RUNG_DOWN_FRACTION * after, floor):
            continue
        middle = (tap + following) // 2
        halfway = _rms(response[middle - stretch // 2 : middle + stretch // 2] - mean)
        if not (ringing <= STATIONARY_FRACTION * after and halfway <= STATIONARY_RATIO * ringing):
            return None
    starts = taps - pretrigger
    if starts[-1] + length > n:
        return None
    return Cut(
        starts=starts.astype(np.int64),
        length=length,
        pretrigger=pretrigger,
        taps=taps.astype(np.int64),
        left_in=left_in,
        left_out=left_out,
    )


def _rms(values: np.ndarray) -> float:
    return float(np.sqrt(np.mean(values**2))) if values.size else 0.0


def cut_note(cut: Cut, sample_rate_hz: float) -> str:
    """The import's note on a record cut into hits."""
    times = ", ".join(f"{t / sample_rate_hz:.4g}" for t in cut.taps[:8]) + (
        ", ..." if cut.taps.size > 8 else ""
    )
    said = (
        f"one record holding {cut.taps.size} taps (at {times} s), the response rung down before each next "
        f"one: cut into {cut.taps.size} hits of {cut.length} samples, each from "
        f"{1000 * cut.pretrigger / sample_rate_hz:.4g} ms before its tap"
    )
    if cut.left_in:
        shown = ", ".join(f"{t / sample_rate_hz:.4g}" for t in cut.left_in)
        said += (
            f"; the tap{'s' * (len(cut.left_in) > 1)} at {shown} s, too close to the one before to be "
            "a hit of its own, left in that hit"
        )
    if cut.left_out:
        said += (
            f"; the tap at {cut.left_out[0] / sample_rate_hz:.4g} s left out: the record ends less than "
            "half a spacing after it"
        )
    return said
