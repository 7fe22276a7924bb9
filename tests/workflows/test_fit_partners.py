"""A fitted mode is numbered and compared by the run's identified mode it stands for
(daq/workflows/fit.py _partner, _disagreeing): an overdamped mode of the fitted R,
padded last, must not shift the others' numbers, and a damping R does not reproduce
is a caution."""

from __future__ import annotations

from daq.workflows.fit import _disagreeing, _partner

IDENTIFIED = [
    {"frequency_hz": 5.57, "damping_ratio": 0.0100, "frequency_u_hz": 0.001, "damping_u": 0.0002},
    {"frequency_hz": 34.90, "damping_ratio": 0.0061, "frequency_u_hz": 0.001, "damping_u": 0.00002},
    {"frequency_hz": 97.72, "damping_ratio": 0.0040, "frequency_u_hz": 0.001, "damping_u": 0.000002},
]


def test_partners_follow_frequency_not_position():
    # As --method ga gave it: the first model mode overdamped (NaN, padded last).
    fitted = [(34.89, 0.0061), (97.52, 0.0037), (float("nan"), float("nan"))]
    partners = [_partner(f, IDENTIFIED) for f, _ in fitted]
    assert [p["mode"] if p else None for p in partners] == [2, 3, None]


def test_a_mode_far_from_every_identified_one_has_no_partner():
    assert _partner(60.0, IDENTIFIED) is None


def test_a_damping_r_does_not_reproduce_is_named_with_the_analysis_reading():
    summary = {
        "modes": [
            {"frequency_hz": f, "damping_ratio": z, "identified": _partner(f, IDENTIFIED)}
            for f, z in [(5.57, 0.0101), (34.89, 0.0061), (97.52, 0.0035)]
        ]
    }
    (said,) = _disagreeing(summary)
    assert said == "mode 3: 0.35 % against 0.40000 ± 0.00020 %"
