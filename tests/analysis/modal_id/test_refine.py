"""Close modes' poles refined on the FRF (analysis/modal_id/refine.py): LSCF's noise bias
gone, with honest uncertainties, on simulated impact tests with known truth."""

from __future__ import annotations

import numpy as np
import pytest

import analysis.modal_id.refine as refine
from analysis.modal_id.refine import refine_poles, to_refine
from analysis.run_analysis import analyze_hits
from analysis.windows import WindowSpec
from tests.analysis.impact_synth import impact_hits

UNIFORM = WindowSpec("uniform")
#: Two modes 2 Hz apart (half-power half-widths 0.75 and 1.2 Hz) and one alone.
FN, ZETA, AMP = np.array([150.0, 152.0, 400.0]), np.array([0.005, 0.008, 0.01]), np.array([1.0, 0.8, 1.0])
RATE_HZ = 2048.0


def _pair(result):
    return [min(result.modes, key=lambda m: abs(m.frequency_hz - f)) for f in FN[:2]]


def _analyse(seed: int):
    force, response = impact_hits(FN, ZETA, AMP, RATE_HZ, 1.0, 5, 0.02, 1.5e-3, seed)
    return analyze_hits(force, response, RATE_HZ, np.ones(5, bool), UNIFORM, UNIFORM)


def _pole(f_hz: float, zeta: float) -> complex:
    w = 2 * np.pi * f_hz
    return complex(-zeta * w, w * np.sqrt(1 - zeta**2))


def test_only_close_light_modes_are_refined():
    poles = np.array(
        [
            _pole(f, z)
            for f, z in zip([150, 152, 400, 1000, 1010], [0.005, 0.008, 0.01, 0.03, 0.03], strict=True)
        ]
    )
    assert list(to_refine(poles)) == [True, True, False, False, False]


def test_poles_are_found_exactly_on_an_frf_without_noise():
    f = np.arange(100.0, 200.0, 0.25)
    jw = 2j * np.pi * f
    true = np.array([_pole(150.0, 0.005), _pole(152.0, 0.008)])
    residues = np.array([1.0 + 0.2j, -0.6 + 0.1j]) * 1e3
    h = sum(a / (jw - p) + np.conj(a) / (jw - np.conj(p)) for a, p in zip(residues, true, strict=True))
    start = true * np.array([1.0004 + 0.0j, 0.9996 + 0.0j]) + np.array([-0.15, 0.2])
    found, done = refine_poles(f, h, start, 0.25)
    assert done.all()
    np.testing.assert_allclose(found, true, rtol=1e-7)


def test_a_pole_that_would_wander_off_is_left_where_lscf_put_it():
    """A pole with nothing under it (noise only) may not move beyond its half-width."""
    rng = np.random.default_rng(1)
    f = np.arange(100.0, 200.0, 0.25)
    h = rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size)
    start = np.array([_pole(150.0, 0.005), _pole(152.0, 0.008)])
    found, done = refine_poles(f, h, start, 0.25)
    for p, q, d in zip(found, start, done, strict=True):
        assert (p == q) or d
        assert abs(abs(p) - abs(q)) / (2 * np.pi) <= max(abs(q.real) / (2 * np.pi), 0.25) + 1e-9


@pytest.mark.slow
def test_close_modes_read_their_damping_without_lscfs_noise_bias_and_within_their_u():
    """12 draws of 5 hits, response noise 2 % of its RMS: LSCF alone reads the pair's
    damping 48 % high on average (0 of 24 within 1 u); refined, within 12 % and the truth
    within 2 u of each value at least 90 % of the time."""
    rel, z_f, z_zeta = [], [], []
    for seed in range(12):
        for mode, f, zeta in zip(_pair(_analyse(seed)), FN, ZETA, strict=False):
            assert mode.quality["refined"]
            rel.append(mode.damping_ratio / zeta - 1)
            z_f.append((mode.frequency_hz - f) / mode.frequency_u_hz)
            z_zeta.append((mode.damping_ratio - zeta) / mode.damping_u)
    assert abs(np.mean(rel)) < 0.03
    assert np.max(np.abs(rel)) < 0.15
    assert np.mean(np.abs(z_f) <= 2) >= 0.9
    assert np.mean(np.abs(z_zeta) <= 2) >= 0.9


def test_lscf_alone_was_biased(monkeypatch):
    """The test above can fail: with refinement off the same draws read the 150 Hz mode's
    damping over 20 % high."""
    monkeypatch.setattr(refine, "MAX_DAMPING", 0.0)
    rel = []
    for seed in range(3):
        mode = _pair(_analyse(seed))[0]
        assert not mode.quality["refined"]
        rel.append(mode.damping_ratio / ZETA[0] - 1)
    assert min(rel) > 0.2, rel


def test_when_every_pole_is_dropped_the_synthesis_is_the_residual_terms_alone():
    """Pure noise: whatever poles LSCF offers, the spurious test drops them all, and the
    synthesis (and its error) is then that of the residual terms alone, not of the
    dropped poles (the service's page printed 97.9 % where the data say 99 %)."""
    from analysis.modal_id import identify_modes, lsfd

    rng = np.random.default_rng(5)
    f = np.arange(1.0, 801.0)
    h = rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size)
    result = identify_modes(f, h)
    assert result.modes == []
    alone = lsfd(f, h[np.newaxis, :], np.empty(0, dtype=complex))
    assert result.synthesis_error == pytest.approx(alone.relative_error, rel=1e-12)
    np.testing.assert_allclose(result.synthesized, alone.synthesized)


def _three_frfs(seed: int, noise: float = 0.02):
    """FRFs only (no hits): the pair and the lone mode at three points, real mode shapes,
    complex noise of ``noise`` times each FRF's RMS; 0.5 Hz lines, 1-1000 Hz."""
    rng = np.random.default_rng(seed)
    f = np.arange(1.0, 1000.0, 0.5)
    w = 2 * np.pi * f
    shapes = np.array([[1.0, 0.8, 1.0], [0.6, -1.0, 0.9], [-0.4, 0.5, 0.3]]) * AMP
    frfs = []
    for shape in shapes:
        h = sum(
            a * -(w**2) / (wr**2 - w**2 + 2j * z * wr * w)
            for a, wr, z in zip(shape, 2 * np.pi * FN, ZETA, strict=True)
        )
        rms = np.sqrt(np.mean(np.abs(h) ** 2))
        frfs.append(
            h + noise * rms / np.sqrt(2) * (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size))
        )
    return f, np.array(frfs)


def test_a_third_pole_between_a_close_pair_is_dropped_as_redundant():
    """LSCF holds the pair of three FRFs with a third pole between its two biased ones
    (150.19, 150.77 and 151.88 Hz in 4 of these 5 draws), which the spurious test keeps;
    refined, the pair alone fits as well, so the third goes: three modes, at the truth."""
    from analysis.modal_id import identify_modes

    for seed in range(5):
        f, h = _three_frfs(seed)
        lscf = identify_modes(f, h, refine=False)
        result = identify_modes(f, h)
        assert len(result.modes) == 3, (seed, [m.frequency_hz for m in result.modes])
        for mode, fn, zeta in zip(result.modes, FN, ZETA, strict=True):
            assert mode.frequency_hz == pytest.approx(fn, abs=0.02)
            assert mode.damping_ratio == pytest.approx(zeta, rel=0.02)
        if seed != 3:  # the test can fail: LSCF alone keeps the third pole
            assert any(abs(m.frequency_hz - 150.77) < 0.05 for m in lscf.modes), seed


def test_a_real_close_triple_keeps_all_three_poles():
    """Three real modes 2 and 2.5 Hz apart: none does the others' work."""
    f = np.arange(100.0, 200.0, 0.25)
    jw = 2j * np.pi * f
    true = np.array([_pole(150.0, 0.005), _pole(152.0, 0.008), _pole(154.5, 0.006)])
    residues = np.array([1.0, 0.8, 0.7]) * 1e3
    h = sum(a / (jw - p) + np.conj(a) / (jw - np.conj(p)) for a, p in zip(residues, true, strict=True))
    h = h + 0.01 * np.sqrt(np.mean(np.abs(h) ** 2)) * np.random.default_rng(2).standard_normal(f.size)
    assert not refine.redundant(f, h, true * 1.0005, 0.25).any()
    # ... and a fourth pole between them is.
    extra = np.append(true * 1.0005, _pole(151.1, 0.004))
    assert list(refine.redundant(f, h, extra, 0.25)) == [False, False, False, True]


def test_a_close_mode_lscf_missed_is_added_by_refitting_its_neighbours():
    """150, 152 and 154.5 Hz, 5 hits, 2 % noise: LSCF never holds the middle mode (at any
    order up to 100) and pushes the other two apart, 149.8 and 154.9 Hz at 0.67 and
    0.93 %, 4-9 u off. The group refitted with one pole more finds it, and the three
    read their truth: frequency within 2 u, damping within 2 u (or 10 %)."""
    fn, zeta, amp = [150.0, 152.0, 154.5, 400.0], [0.005, 0.008, 0.006, 0.01], [1.0, 0.8, 0.7, 1.0]
    for seed in (0, 1, 4):
        force, response = impact_hits(fn, zeta, amp, RATE_HZ, 1.0, 5, 0.02, 1.5e-3, seed)
        result = analyze_hits(force, response, RATE_HZ, np.ones(5, bool), UNIFORM, UNIFORM)
        assert len(result.modes) == 4, (seed, [m.frequency_hz for m in result.modes])
        assert [bool(m.quality["added"]) for m in result.modes] == [False, True, False, False]
        for mode, f, z in zip(result.modes[:3], fn[:3], zeta[:3], strict=True):
            assert abs(mode.frequency_hz - f) <= 2 * mode.frequency_u_hz, (seed, mode.frequency_hz)
            assert abs(mode.damping_ratio - z) <= max(2 * mode.damping_u, 0.1 * z), (seed, mode.damping_ratio)


def test_without_the_added_mode_the_triple_read_its_outer_modes_wrong(monkeypatch):
    """The test above can fail: with no pole added the outer two are beyond 4 u."""
    monkeypatch.setattr(refine, "ADD_F", np.inf)
    fn, zeta, amp = [150.0, 152.0, 154.5, 400.0], [0.005, 0.008, 0.006, 0.01], [1.0, 0.8, 0.7, 1.0]
    force, response = impact_hits(fn, zeta, amp, RATE_HZ, 1.0, 5, 0.02, 1.5e-3, 0)
    result = analyze_hits(force, response, RATE_HZ, np.ones(5, bool), UNIFORM, UNIFORM)
    assert len(result.modes) == 3
    assert abs(result.modes[1].frequency_hz - 154.5) > 4 * result.modes[1].frequency_u_hz


def test_no_pole_is_added_to_a_real_pair_with_noise():
    """The pair of the draws above, FRFs only and from hits: a pole more only fits noise."""
    from analysis.modal_id import identify_modes

    for seed in range(3):
        f, h = _three_frfs(seed)
        assert refine.missing(f, h, np.array([_pole(150.0, 0.005), _pole(152.0, 0.008)]), 0.5).size == 0
    assert len(identify_modes(f, h).modes) == 3
    assert not any(m.quality["added"] for m in _analyse(0).modes)


#: A new user's file: 0.5 % at 120 Hz 6 Hz from 0.8 % at 126 Hz, among three others;
#: 10.24 kHz for 1 s, 5 hits, response noise 2 % of its RMS.
A_FN = np.array([45.0, 120.0, 126.0, 410.0, 900.0])
A_ZETA = np.array([0.012, 0.005, 0.008, 0.03, 0.045])
A_AMP = np.array([1.0, 0.6, 0.5, 1.5, 2.0])


def _mode_near_120(seed: int):
    force, response = impact_hits(A_FN, A_ZETA, A_AMP, 10240.0, 1.0, 5, 0.02, 8e-4, seed, pretrigger_s=0.01)
    result = analyze_hits(force, response, 10240.0, np.ones(5, bool), UNIFORM, UNIFORM)
    return min(result.modes, key=lambda m: abs(m.frequency_hz - 120.0))


@pytest.mark.parametrize("seed", [0, 1])
def test_a_light_mode_beside_another_is_read_right_though_lscf_read_it_far_off(seed):
    """LSCF reads the 120 Hz mode at 120.8-121 Hz and 1.25-1.27 %, 2.5 times too damped;
    refined, it is 120.00-120.02 Hz and 0.49 %, within its u."""
    mode = _mode_near_120(seed)
    assert mode.quality["refined"]
    assert abs(mode.frequency_hz - 120.0) < 0.05
    assert abs(mode.damping_ratio / 0.005 - 1) < 0.05
    assert abs(mode.damping_ratio - 0.005) <= mode.damping_u


def test_with_the_old_factor_2_the_refined_value_was_refused(monkeypatch):
    """The test above can fail: refinement may change the damping by a factor of 2 at most,
    LSCF's 1.27 % stands and reads 0.77 Hz off."""
    monkeypatch.setattr(refine, "MAX_DAMPING_FACTOR", 2.0)
    mode = _mode_near_120(0)
    assert not mode.quality["refined"]
    assert mode.damping_ratio > 2 * 0.005
    assert mode.frequency_hz > 120.5
