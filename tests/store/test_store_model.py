"""The in-memory run refuses inconsistent parts with a ValueError saying what is wrong."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from daq.store import Hits, MeasuredFrf, Run, Sample
from tests.store.store_helpers import make_frf, make_hits, make_run


def _hits_args(**changes):
    hits = make_hits(3, 16)
    args = {f.name: getattr(hits, f.name) for f in dataclasses.fields(Hits)}
    args.update(changes)
    return args


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"force_n": np.zeros((3, 15))}, "differ in shape"),
        ({"force_n": np.zeros((3, 16), dtype=np.float32)}, "float64"),
        ({"force_n": np.zeros(16)}, "shape"),
        ({"force_n": np.zeros((0, 16)), "response_m_s2": np.zeros((0, 16))}, "n_hits >= 1"),
        ({"force_n": np.zeros((3, 16), complex)}, "both"),
        ({"sample_rate_hz": 0.0}, "sample_rate_hz"),
        ({"sample_rate_hz": float("nan")}, "sample_rate_hz"),
        ({"center_hz": 100.0}, "center_hz = 0"),
        ({"accepted": np.array([1, 1, 0])}, "accepted"),
        ({"accepted": np.array([True, True])}, "shape"),
        ({"reject_reason": ["", "", ""]}, "reject_reason"),
        ({"reject_reason": ["late", "", "x"]}, r"hit 1 \(index 0\) is accepted"),
        ({"overload": np.zeros((3, 1), bool)}, "overload"),
        ({"peak_force_n": np.zeros(4)}, "peak_force_n"),
        ({"timestamp_utc": ["2026-11-23T10:15:00"] * 3}, "UTC"),
        ({"timestamp_utc": ["yesterday"] * 3}, "ISO 8601"),
        ({"checks": [{}, {}]}, "3 dicts"),
        ({"checks": [{}, {}, {"x": np.int64(1)}]}, "JSON"),
        ({"checks": [{}, {}, {"x": float("nan")}]}, "JSON"),
    ],
)
def test_hits_refuse(changes, message):
    with pytest.raises(ValueError, match=message):
        Hits(**_hits_args(**changes))


def test_frf_refuses():
    good = make_frf(2, 5)
    with pytest.raises(ValueError, match="strictly increasing"):
        MeasuredFrf(good.frequency_hz[::-1], good.frf, None, good.labels)
    with pytest.raises(ValueError, match="shape"):
        MeasuredFrf(good.frequency_hz, good.frf[:, :4], None, good.labels)
    with pytest.raises(ValueError, match="coherence"):
        MeasuredFrf(good.frequency_hz, good.frf, np.ones((2, 4)), good.labels)
    with pytest.raises(ValueError, match="labels"):
        MeasuredFrf(good.frequency_hz, good.frf, None, ["one"])


def test_sample_refuses():
    with pytest.raises(ValueError, match="length_m"):
        Sample(2700, 69e9, 0.025, 0.003, -0.3, 7.5e-5, 5.6e-11)
    with pytest.raises(ValueError, match="outside the beam"):
        Sample(2700, 69e9, 0.025, 0.003, 0.3, 7.5e-5, 5.6e-11, force_position_m=0.31)


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"run_id": "../x"}, "valid run id"),
        ({"kind": "measured"}, "kind"),
        ({"complete": 1}, "bool"),
        ({"start_time": "2026-11-23 10:15"}, "UTC"),
        ({"end_time": "2026-11-23T11:15:00+01:00"}, "UTC"),
        ({"note": "a\x00b"}, "NUL"),
        ({"operator": 7}, "str"),
        ({"provenance": {"seed": object()}}, "JSON"),
        ({"hits": None}, "none"),
        ({"hits": "hits"}, "Hits"),
    ],
)
def test_run_refuses(changes, message):
    args = {f.name: getattr(make_run(), f.name) for f in dataclasses.fields(Run)}
    args.update(changes)
    with pytest.raises(ValueError, match=message):
        Run(**args)
