"""`daq fit` on simulated captures: the damping the fitted matrix implies against the
simulator's truth (eq (18) for the seed beam, docs/method.md; the realistic beam's
modal damping), the JSON it prints, reproducibility, and bad arguments."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from analysis.damping.fit_limits import de_bounds as _de_bounds
from tests.cli_helpers import assert_one_line_error, capture_sim, daq_json, invoke_daq
from tests.reference import EQ18_DAMPING_RATIOS, REALISTIC_DAMPING_RATIOS


def fit_json(store: Path, *args: str) -> list[dict]:
    return daq_json("fit", store, *args)


@pytest.fixture(scope="module")
def seed_run(tmp_path_factory) -> tuple[Path, str]:
    store = tmp_path_factory.mktemp("seed")
    return store, capture_sim(store, "seed", seed=5)


@pytest.fixture(scope="module")
def realistic_run(tmp_path_factory) -> tuple[Path, str]:
    """One capture of the realistic beam for the tests that fit it with different options
    (each fit stores its own result: a fit with other options is computed again)."""
    store = tmp_path_factory.mktemp("realistic")
    return store, capture_sim(store, "realistic", seed=6)


def test_seed_run_least_squares_gives_the_eq18_damping_at_the_noise_level(seed_run):
    store, run_id = seed_run
    # eq (18) is 3 x 3: the model is the seed's N = 3 whatever the analysis identified.
    (info,) = fit_json(store, run_id, "--functions", "3")
    assert info["run_id"] == run_id
    assert info["method"] == "ls"
    assert len(info["damping_matrix"]) == 3
    zetas = [m["damping_ratio"] for m in info["modes"]]
    assert zetas == pytest.approx(EQ18_DAMPING_RATIOS, rel=0.05)
    floor = info["psi_noise_floor"]
    assert floor is not None
    assert info["psi"] < 2.0 * floor  # the fit leaves little more than the sensor noise


def test_the_seed_ga_is_reproducible_and_reported_as_it_comes_out(seed_run):
    store, run_id = seed_run
    first = fit_json(store, run_id, "--method", "ga", "--seed", "3", "--functions", "3")[0]
    again = fit_json(store, run_id, "--method", "ga", "--seed", "3", "--functions", "3", "--recompute")[0]
    other = fit_json(store, run_id, "--method", "ga", "--seed", "4", "--functions", "3", "--recompute")[0]
    assert first["damping_matrix"] == again["damping_matrix"]
    assert other["damping_matrix"] != first["damping_matrix"]
    assert first["n_evaluations"] >= 1500  # the seed's budget: 50 x 30 (+ the first generation)


def test_realistic_run_defaults_give_a_dissipative_r_at_the_noise_floor(realistic_run):
    """The defaults (one Ritz function per identified mode, R = L L^T, each mode at its
    identified frequency) on the realistic beam: all four modes in the 200 Hz band, Psi
    at the noise floor, R positive semi-definite, and no caution but the one saying
    that one tip measurement leaves terms of a 4 x 4 R undetermined (only the modal
    dampings are fixed: docs/damping.md)."""
    store, run_id = realistic_run
    (info,) = fit_json(store, run_id)
    assert info["model"]["ritz_functions"] == 4
    assert info["model"]["functions_reason"] == "4 Ritz functions: 4 modes identified in 0-200 Hz"
    assert info["options"]["n_functions"] == 4  # stored as resolved
    zetas = [m["damping_ratio"] for m in info["modes"]]
    assert zetas == pytest.approx(REALISTIC_DAMPING_RATIOS, rel=0.15)
    assert info["psi"] < 1.5 * info["psi_noise_floor"]
    assert info["psd"]
    assert min(info["damping_eigenvalues"]) >= -1e-9 * max(info["damping_eigenvalues"])
    assert all(row[i] > 0 for i, row in enumerate(info["damping_matrix"]))
    (caution,) = info["cautions"]
    assert "not determined by these data" in caution
    assert info["stiffness"]["mode_frequencies"]["applied"]
    # Each fitted mode names the analysis' mode it stands for, with that reading's u.
    assert [m["identified"]["mode"] for m in info["modes"]] == [1, 2, 3, 4]
    assert all(m["identified"]["damping_u"] > 0 for m in info["modes"])


def test_realistic_run_old_defaults_stay_reachable_and_say_what_is_wrong(realistic_run):
    """The former defaults, given explicitly (3 functions, unconstrained, one factor on E):
    the first three dampings, Psi far above the floor, and cautions that name the fix."""
    store, run_id = realistic_run
    old = ("--functions", "3", "--unconstrained", "--stiffness", "scale")
    (info,) = fit_json(store, run_id, *old)
    zetas = [m["damping_ratio"] for m in info["modes"]]
    assert zetas == pytest.approx(REALISTIC_DAMPING_RATIOS[:3], rel=0.15)
    assert info["stiffness"]["update"] == "scale on E"
    assert info["psi"] > 3 * info["psi_noise_floor"]
    assert any("noise floor" in c and "--functions 4" in c for c in info["cautions"])
    printed = invoke_daq("fit", run_id, *old, "--store", str(store)).stdout
    assert any(line.startswith("caution: Psi is") for line in printed.splitlines())
    # This beam's R has terms far beyond the seed's GA coding range [-10, 10]: the GA
    # is run as the paper has it and says it cannot reach the optimum; DE's box is
    # sized from the modal estimate, so it holds the least-squares optimum.
    fitted = np.abs(np.array(info["damping_matrix"])).max()
    assert fitted > 10
    assert fitted < _de_bounds(np.array(info["start"]["damping_matrix"]), psd=False)[1]
    result = invoke_daq("fit", run_id, "--method", "ga", *old, "--store", str(store))
    assert result.returncode == 0, result.stderr
    assert "outside the search range [-10, 10] (the seed paper’s GA range)" in result.stdout
    ga = fit_json(store, run_id, "--method", "ga", *old)[0]
    assert ga["psi_noise_floor"] == info["psi_noise_floor"]  # one floor per run, whatever the method


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        ((), "name the runs"),
        (("--method", "magic", "x"), "method"),
        (("--stiffness", "wild", "x"), "stiffness"),
        (("nosuchrun",), "nosuchrun"),
    ],
)
def test_bad_fit_arguments_are_one_line(tmp_path, args, fragment):
    assert_one_line_error(invoke_daq("fit", *args, "--store", str(tmp_path)), fragment)


def test_any_model_size_and_the_per_hit_cross_check(seed_run):
    store, run_id = seed_run
    (info,) = fit_json(store, run_id, "--functions", "4")
    assert len(info["damping_matrix"]) == 4
    assert all(len(row) == 4 for row in info["damping_matrix"])
    assert len(info["uncertainty"]["names"]) == 10  # 4 x 5 / 2 symmetric terms
    # Unconstrained: an interior optimum, where the Fisher figure and the refits
    # measure the same thing (R = L L^T may sit on the boundary, rank-deficient).
    (three,) = fit_json(store, run_id, "--functions", "3", "--unconstrained")
    from_hits = three["uncertainty"]["std_from_hits"]
    assert from_hits is not None
    assert len(from_hits) == 6
    # Refitting each hit alone gives a spread of the same order as the Fisher figure
    # (both measure how noise moves R; they need not agree closely, see docs/damping.md).
    unc = three["uncertainty"]
    for fisher, hits in zip(unc["std_fisher"], from_hits, strict=True):
        assert 0.1 < hits / fisher < 10
    # The printed ± is the larger of the two, term by term, and says which it is.
    figures = zip(unc["std"], unc["std_fisher"], from_hits, unc["std_source"], strict=True)
    for std, fisher, hits, source in figures:
        assert std == max(fisher, hits)
        assert source == ("hits" if hits > fisher else "fisher")


def test_the_frequency_domain_fit_models_the_exponential_window(seed_run):
    store, run_id = seed_run
    (info,) = fit_json(store, run_id, "--domain", "frequency", "--functions", "3")
    assert info["domain"] == "frequency"
    zetas = [m["damping_ratio"] for m in info["modes"]]
    # The analysed FRF carries the exponential window's extra decay (docs/analysis.md);
    # the fit puts it into the model, so the ratios are the beam's, not the window's.
    assert zetas == pytest.approx(EQ18_DAMPING_RATIOS, rel=0.05)


def test_an_imported_frf_run_is_fitted_in_the_frequency_domain(tmp_path):
    import numpy as np
    from store.store_helpers import make_run

    from analysis.beam import TABLE_1
    from analysis.response import frequency_response
    from analysis.ritz import RitzBeam
    from analysis.seed import eq18_damping_matrix
    from daq.store import MeasuredFrf, Sample, seal

    f = np.linspace(0.0, 200.0, 801)
    model = RitzBeam.build(n_functions=3).structure()
    h = frequency_response(model, eq18_damping_matrix(), f, "acceleration")
    run = make_run(kind="imported", measured=MeasuredFrf(f, h[np.newaxis, :], None, ["tip"]))
    run.sample = Sample(
        **TABLE_1.to_dict(), force_position_m=TABLE_1.length_m, sensor_position_m=TABLE_1.length_m
    )
    seal(run, tmp_path)
    (info,) = fit_json(tmp_path, run.run_id, "--stiffness", "none")
    assert info["domain"] == "frequency"
    zetas = [m["damping_ratio"] for m in info["modes"]]
    assert zetas == pytest.approx(EQ18_DAMPING_RATIOS, rel=1e-3)


def test_random_starts_find_no_better_optimum_on_the_seed_run(seed_run):
    store, run_id = seed_run
    (info,) = fit_json(store, run_id, "--starts", "4", "--functions", "3")
    check = info["multi_start"]
    assert check["starts"] == 4
    assert not check["better_psi_found"]
    assert check["reached_same_psi"] >= 1
    assert check["best_psi"] == pytest.approx(info["psi"], rel=1e-3)


def test_an_exported_analyzer_frf_keeps_its_window_through_uff(seed_run, tmp_path):
    """The analyzer's FRF went through the exponential window: exported to UFF and
    imported alone, its damping must come out as the beam's, not the window's."""
    import warnings

    import pyuff

    store, run_id = seed_run
    whole = tmp_path / "whole.uff"
    assert invoke_daq("export", run_id, "-f", "uff", "-o", str(whole), "--store", str(store)).returncode == 0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        frf_sets = [s for s in pyuff.UFF(str(whole)).read_sets() if s["func_type"] in (4, 6)]
        pyuff.UFF(str(tmp_path / "frf.uff")).write_sets(frf_sets, mode="add")
    other = tmp_path / "other"
    assert invoke_daq("import", str(tmp_path / "frf.uff"), "--store", str(other)).returncode == 0
    result = invoke_daq("analyze", "latest", "--json", "--store", str(other))
    assert result.returncode == 0, result.stderr
    (info,) = json.loads(result.stdout)
    assert info["source"] == "measured_frf"
    zetas = [m["damping_ratio"] for m in info["modes"][:3]]
    assert zetas == pytest.approx(EQ18_DAMPING_RATIOS, rel=0.05)


def test_the_printed_fit_says_which_stiffness_it_used(seed_run):
    store, run_id = seed_run
    scale = fit_json(store, run_id)[0]["stiffness"]["scale"]
    assert 0.9 < scale < 1.1
    assert scale != 1.0
    scaled = invoke_daq("fit", run_id, "--store", str(store))
    assert f"stiffness scaled by {scale:.5f} to the run's frequencies first" in scaled.stdout
    plain = invoke_daq("fit", run_id, "--stiffness", "none", "--store", str(store))
    assert "stiffness as built (--stiffness none)" in plain.stdout
    assert "stiffness scaled" not in plain.stdout
