"""Every ± is the standard uncertainty of the value it follows: on simulated impact tests
with known truth, the truth lies within ±1 u about 68 % of the time and within ±2 u about
95 % (over hits), and no less often than that (bootstrap over lines, one FRF)."""

from __future__ import annotations

import numpy as np
import pytest

from analysis.measurement_text import with_uncertainty
from analysis.run_analysis import analyze_frfs, analyze_hits
from analysis.windows import WindowSpec
from tests.analysis.impact_synth import impact_hits

FN = np.array([23.0, 61.0, 118.0, 197.0])
ZETA = np.array([0.02, 0.012, 0.008, 0.01])
AMP = np.array([1.0, -0.8, 0.6, 0.5])
TRIALS = 20


def z_scores(results) -> tuple[np.ndarray, np.ndarray]:
    zf, zz = [], []
    for result in results:
        for m in result.modes:
            k = int(np.argmin(np.abs(FN - m.frequency_hz)))
            assert abs(FN[k] - m.frequency_hz) < 0.02 * FN[k]
            assert np.isfinite(m.frequency_u_hz)
            assert np.isfinite(m.damping_u)
            zf.append((m.frequency_hz - FN[k]) / m.frequency_u_hz)
            zz.append((m.damping_ratio - ZETA[k]) / m.damping_u)
    return np.array(zf), np.array(zz)


@pytest.mark.slow
def test_uncertainty_over_hits_covers_the_truth():
    uniform = WindowSpec("uniform")
    results = []
    for seed in range(TRIALS):
        force, response = impact_hits(FN, ZETA, AMP, 1024.0, 4.0, 5, 0.02, 2e-3, seed)
        results.append(analyze_hits(force, response, 1024.0, np.ones(5, bool), uniform, uniform))
    assert all(m.uncertainty_from == "5 hits" for r in results for m in r.modes)
    for z in z_scores(results):
        assert z.size >= 0.9 * TRIALS * FN.size
        # 80 draws: the binomial spread of 68 % is 5 %; 95 % is 2.4 %.
        assert 0.55 <= np.mean(np.abs(z) <= 1) <= 0.85
        assert np.mean(np.abs(z) <= 2) >= 0.88


@pytest.mark.slow
def test_bootstrap_over_lines_never_understates():
    f = np.arange(1, 1601) * 0.25
    w = 2 * np.pi * f
    h = sum(a * -(w**2) / ((2 * np.pi * r) ** 2 - w**2 + 2j * z * 2 * np.pi * r * w)
            for a, r, z in zip(AMP, FN, ZETA, strict=True))  # fmt: skip
    level = np.sqrt(np.mean(np.abs(h) ** 2))
    results = []
    for seed in range(TRIALS // 2):
        rng = np.random.default_rng(seed)
        noisy = h + 0.02 * level * (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size)) / np.sqrt(
            2
        )
        results.append(analyze_frfs(f, noisy[np.newaxis, :], None, "measured_frf"))
    assert all(m.uncertainty_from == "bootstrap over lines" for r in results for m in r.modes)
    for z in z_scores(results):
        assert np.mean(np.abs(z) <= 1) >= 0.6
        assert np.mean(np.abs(z) <= 2) >= 0.9


@pytest.mark.parametrize(("hits", "share"), [(2, 80), (3, 85), (5, None)])
def test_a_spread_over_two_or_three_hits_says_how_little_its_u_covers(hits, share):
    """With 2 or 3 hits the spread is itself uncertain: ±2 u held the truth in 78-82 % and
    85-86 % of 120 simulated modes (FEW_HITS_COVERAGE), and the result says so."""
    uniform = WindowSpec("uniform")
    force, response = impact_hits(FN, ZETA, AMP, 1024.0, 4.0, hits, 0.02, 2e-3, 100)
    result = analyze_hits(force, response, 1024.0, np.ones(hits, bool), uniform, uniform)
    said = [c for c in result.cautions if "the ± come from the spread over" in c]
    if share is None:
        assert said == []
    else:
        assert said == [
            f"the ± come from the spread over {hits} hits: so few that the spread is itself uncertain, and "
            f"the truth may lie within ±2 u only about {share} % of the time, not 95 %; take 5 or more hits"
        ]


def test_modes_found_in_only_3_of_5_hits_are_named_not_the_hits_taken():
    """A new user's 5-hit plate test: the top 3 modes were matched in 3 hits only, and the
    caution said "take 5 or more hits" of a run of 5, naming no mode."""
    from analysis.run_analysis import _cautions

    uniform = WindowSpec("uniform")
    force, response = impact_hits(FN, ZETA, AMP, 1024.0, 4.0, 5, 0.02, 2e-3, 100)
    result = analyze_hits(force, response, 1024.0, np.ones(5, bool), uniform, uniform)
    assert not [c for c in result.cautions if "spread over" in c]
    top = result.modes[-1]
    top.n_hits_matched, top.uncertainty_from = 3, "3 of 5 hits"
    (said,) = [c for c in _cautions(result) if "spread over" in c]
    assert said.startswith(
        f"the ± of the mode at {with_uncertainty(top.frequency_hz, top.frequency_u_hz, '.6g')[0]} Hz"
    )
    assert "only 3 of the 5 hits" in said
    assert "take 5 or more hits" not in said


def test_two_frequencies_asked_for_that_find_one_mode_are_said():
    """--frequencies 23,24 on a run with one mode near both: one mode, and a caution
    saying that 24 Hz found the mode 23 Hz found."""
    from analysis.run_analysis import AnalysisOptions

    uniform = WindowSpec("uniform")
    force, response = impact_hits(FN, ZETA, AMP, 1024.0, 4.0, 5, 0.02, 2e-3, 100)
    options = AnalysisOptions(frequencies_hz=(23.0, 24.0))
    result = analyze_hits(force, response, 1024.0, np.ones(5, bool), uniform, uniform, options=options)
    assert len(result.modes) == 1
    (said,) = [c for c in result.cautions if "found the same mode" in c]
    assert said.startswith(f"24 Hz and 23 Hz found the same mode, {result.modes[0].frequency_hz:.6g} Hz: ")


def test_a_damping_whose_u_exceeds_it_is_said():
    from analysis.run_analysis import _cautions

    uniform = WindowSpec("uniform")
    force, response = impact_hits(FN, ZETA, AMP, 1024.0, 4.0, 5, 0.02, 2e-3, 100)
    result = analyze_hits(force, response, 1024.0, np.ones(5, bool), uniform, uniform)
    assert not any("is not fixed by the data" in c for c in result.cautions)
    mode = result.modes[0]
    mode.damping_u = 2 * mode.damping_ratio
    (said,) = [c for c in _cautions(result) if "is not fixed by the data" in c]
    at = with_uncertainty(mode.frequency_hz, mode.frequency_u_hz)[0]
    assert said.startswith(f"the damping of the mode at {at} Hz is not fixed by the data")


def test_several_dampings_not_fixed_by_the_data_are_said_in_one_line():
    """A noisy run has many such modes, and a line each buried the other cautions."""
    from analysis.run_analysis import _cautions

    uniform = WindowSpec("uniform")
    force, response = impact_hits(FN, ZETA, AMP, 1024.0, 4.0, 5, 0.02, 2e-3, 100)
    result = analyze_hits(force, response, 1024.0, np.ones(5, bool), uniform, uniform)
    for mode in result.modes[:2]:
        mode.damping_u = 2 * mode.damping_ratio
    (said,) = [c for c in _cautions(result) if "is not fixed by the data" in c]
    at = [with_uncertainty(m.frequency_hz, m.frequency_u_hz)[0] for m in result.modes[:2]]
    assert said.startswith(f"the damping of the modes at {at[0]}, {at[1]} Hz is not fixed by the data: ")


def test_that_caution_writes_the_damping_as_the_mode_line_does():
    """Value to the decimal place of its u (two significant digits), as the mode line
    writes it: 0.47 % with u 1.4 % is "0.5 %", not "0.47 %" beside a mode line's 0.5 %."""
    from analysis.run_analysis import _cautions

    uniform = WindowSpec("uniform")
    force, response = impact_hits(FN, ZETA, AMP, 1024.0, 4.0, 5, 0.02, 2e-3, 100)
    result = analyze_hits(force, response, 1024.0, np.ones(5, bool), uniform, uniform)
    mode = result.modes[0]
    mode.damping_ratio, mode.damping_u = 0.0047, 0.014
    (said,) = [c for c in _cautions(result) if "is not fixed by the data" in c]
    assert "its ± (1.4 %) is larger than the value (0.5 %)" in said


def test_overlapping_modes_too_damped_to_refine_carry_a_caution_on_their_u():
    """Two modes at 1200 and 1250 Hz, 2 and 2.5 %: LSCF's bias stays (over 2 % nothing is
    refined) and the truth lay within 2 u only 40-80 % of the time in 10 draws
    (bench/new_user_cases_coverage.py): the caution says the ± is a lower bound there.
    Modes apart from each other, or refined, get none."""
    uniform = WindowSpec("uniform")
    fn, zeta, amp = [250.0, 1200.0, 1250.0, 3300.0], [0.01, 0.02, 0.025, 0.03], [1.0, 2.0, 1.5, 3.0]
    force, response = impact_hits(fn, zeta, amp, 25600.0, 0.5, 5, 0.02, 3e-4, 0, pretrigger_s=0.005)
    result = analyze_hits(force, response, 25600.0, np.ones(5, bool), uniform, uniform)
    (said,) = [c for c in result.cautions if "too damped" in c]
    listed = [float(x) for x in said.split(" Hz overlap")[0].removeprefix("the modes at ").split(", ")]
    assert [round(f / 50) * 50 for f in listed] == [1200, 1250]
    assert said.endswith("take the ± as a lower bound")
    force, response = impact_hits(FN, ZETA, AMP, 1024.0, 4.0, 5, 0.02, 2e-3, 100)
    apart = analyze_hits(force, response, 1024.0, np.ones(5, bool), uniform, uniform)
    assert not any("too damped" in c for c in apart.cautions)
