"""A point's FRF turned to its axes' positive sense before the shapes (daq/workflows/test_analysis.py)."""

from __future__ import annotations

import numpy as np

from daq.store import Point, RunPoints
from daq.workflows.point_frf import PointFrf
from daq.workflows.test_analysis import _along_axes

FREE = {"kind": "free", "nodes": [{"name": "n4", "x_m": 0.5, "y_m": 0.0, "z_m": 0.0, "direction": "+x"}]}


def _point_frf() -> PointFrf:
    f = np.linspace(1.0, 10.0, 5)
    return PointFrf(f, (1 + 2j) * f, np.full(5, 0.9), np.ones((3, 5), complex), 3.0, "hits", f**2)


def test_an_accelerometer_facing_the_hammer_turns_the_sign_and_keeps_the_rest():
    """Force +x, response -x at one node (ModeLAB's driving point): H is negated (so is
    each hit's), the coherence, decay and force spectrum are kept."""
    measured = _point_frf()
    points = RunPoints(FREE, Point("n4", node="n4", direction="+x"), (Point("s", node="n4", direction="-x"),))
    turned = _along_axes(measured, points)
    np.testing.assert_array_equal(turned.frf, -measured.frf)
    np.testing.assert_array_equal(turned.per_hit, -measured.per_hit)
    np.testing.assert_array_equal(turned.force_autospectrum, measured.force_autospectrum)
    assert (turned.added_decay_1_s, turned.source) == (3.0, "hits")


def test_both_along_the_same_sense_change_nothing():
    measured = _point_frf()
    for direction in ("+x", "-x"):
        points = RunPoints(
            FREE, Point("n4", node="n4", direction=direction), (Point("s", node="n4", direction=direction),)
        )
        assert _along_axes(measured, points) is measured
