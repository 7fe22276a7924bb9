"""The defaults of `daq fit` (docs/damping.md, "The defaults"): one Ritz function per
identified mode, R = L L^T, each mode at its identified frequency; the options that
give the former behaviour; the cautions stored with the fit; Pilkey-Inman on runs
with more identified modes than functions."""

from __future__ import annotations

import numpy as np
import pytest

from analysis.damping import pilkey_inman, undamped_modes, update_mode_frequencies, update_stiffness
from analysis.modal import damped_modes
from analysis.ritz import RitzBeam
from analysis.seed import eq18_damping_matrix
from daq.workflows.fit import FitOptions, _searched_band, fit_cautions, resolve_functions
from tests.cli_helpers import assert_one_line_error, capture_sim, daq_json, invoke_daq


def test_the_default_options_and_their_result_names():
    default = FitOptions()
    assert (default.psd, default.n_functions, default.stiffness) == (True, None, "modes")
    assert default.result_name == "fit-ls"  # what the service and the report look for
    assert FitOptions(psd=False).result_name == "fit-ls-unconstrained"
    assert FitOptions(n_functions=3, psd=False).result_name == "fit-ls-unconstrained-n3"
    assert FitOptions(method="ga", n_functions=4).result_name == "fit-ga-n4"
    with pytest.raises(ValueError, match="n_functions"):
        FitOptions(n_functions=11)


def test_the_number_of_functions_and_why():
    assert resolve_functions(4, 0.0, 400.0, None) == (4, "4 Ritz functions: 4 modes identified in 0-400 Hz")
    assert resolve_functions(0, 1.0, 400.0, None)[0] == 1
    n, why = resolve_functions(12, 0.0, 2000.0, None)
    assert n == 10
    assert "at most 10" in why
    assert resolve_functions(4, 0.0, 200.0, 3) == (
        3,
        "3 Ritz functions (--functions); 4 modes identified in 0-200 Hz",
    )


def test_each_mode_at_its_identified_frequency_under_light_damping_only():
    model = RitzBeam.build(n_functions=3).structure()
    target = np.array([5.5, 34.9, 97.7])
    scaled, _, _ = update_stiffness(model, target)
    updated, info = update_mode_frequencies(scaled, target, np.array([0.01, 0.006, 0.004]))
    assert info["applied"]
    assert undamped_modes(updated)[0] / (2 * np.pi) == pytest.approx(target, rel=1e-12)
    np.testing.assert_allclose(updated.mass, scaled.mass)
    kept, info = update_mode_frequencies(scaled, target, np.array([0.036, 0.2, 0.16]))
    assert not info["applied"]
    assert "20 % damping" in info["reason"]
    assert kept is scaled


def test_pilkey_inman_keeps_r_dissipative_and_still_matches_the_poles():
    model = RitzBeam.build(n_functions=3).structure()
    poles = damped_modes(model, eq18_damping_matrix()).poles
    r, info = pilkey_inman(model, poles, psd=True)
    assert info["residual"] < 1e-8
    assert np.linalg.eigvalsh(r).min() >= -1e-9 * np.abs(r).max()
    with pytest.raises(ValueError, match="Newton"):
        pilkey_inman(model, poles, psd=True, update="lancaster")


def test_an_analysis_band_narrower_than_the_fit_is_named_with_the_remedy():
    """A fourth user's run: the time records span 0-1562 Hz, the analysis looked in 1-401 Hz;
    the count of identified modes then says nothing of 401-1562 Hz, and the output must say so."""
    assert _searched_band({"band": {"low_hz": 1.0, "high_hz": 401.0, "reason": ""}}, 0.0, 1562.5) == (
        1.0,
        401.0,
    )
    # The few lines at 0 Hz an analysis band leaves out, or none recorded: nothing to say.
    assert _searched_band({"band": {"low_hz": 0.5, "high_hz": 200.0, "reason": ""}}, 0.0, 200.0) is None
    assert _searched_band({"band": None}, 0.0, 200.0) is None
    assert _searched_band({}, 0.0, 200.0) is None
    n, why = resolve_functions(3, 0.0, 1562.5, None, (1.0, 401.0))
    assert n == 3
    assert why == (
        "3 Ritz functions: 3 modes identified in 0-1562 Hz, looked for in 1-401 Hz only (the analysis's "
        "band; daq analyze --band 0:1562 looks over the whole fitted band)"
    )
    model = {"ritz_functions": 3, "modes_identified_in_band": 3, "band_hz": [0.0, 1562.5],
             "analysis_band_hz": [1.0, 401.0]}  # fmt: skip
    (far,) = fit_cautions(_summary(psi=0.5, model=model))
    assert (
        "try daq analyze --band 0:1562, then daq fit (the analysis looked for modes in 1-401 Hz only)" in far
    )


def test_a_fit_that_is_no_result_says_so_where_it_is_shown_and_a_capped_model_is_not_told_to_grow():
    """A fifth user's trial: the report and the page showed Psi and R of a fit the terminal
    called 'no damping matrix' (exit 1); and a default stepped down to 6 functions, because 7
    put a model mode outside the band, was told to try --functions 7."""
    (verdict, *_) = fit_cautions(_summary(psi_noise_floor=None, relative_residual=42.14))
    assert verdict.startswith("no damping matrix: the model leaves 4.21e+03 % of the data unexplained")
    model = {
        "ritz_functions": 6,
        "modes_identified_in_band": 7,
        "band_hz": [0.0, 400.0],
        "largest_in_band": 6,
    }
    (far,) = fit_cautions(_summary(psi=0.5, model=model))
    assert "--functions" not in far
    (fine,) = fit_cautions(_summary(model={**model, "largest_in_band": None}))
    assert "try --functions 7" in fine


def _summary(**changes):
    summary = {
        "method": "ls", "psd": True, "psi": 0.03, "psi_noise_floor": 0.024, "relative_residual": 0.01,
        "success": True, "message": "", "search_box": None, "start": {"coded_scale": 1.0},
        "damping_matrix": [[2.0, 0.5], [0.5, 3.0]], "modes": [{"damping_ratio": 0.01}] * 2,
        "model": {"ritz_functions": 2, "modes_identified_in_band": 2, "band_hz": [0.0, 200.0]},
        "options": {"stiffness": "modes"}, "stiffness": {"update": "scale on E"}, "pole_fit": None,
    }  # fmt: skip
    summary.update(changes)
    return summary


def test_cautions_say_what_is_wrong_and_what_to_try():
    assert fit_cautions(_summary()) == []
    (far,) = fit_cautions(
        _summary(psi=0.5, model={"ritz_functions": 2, "modes_identified_in_band": 4, "band_hz": [0, 200]})
    )
    assert far.startswith("Psi is 20.8x the noise floor")
    assert "--functions 4" in far
    (fewer,) = fit_cautions(_summary(model={"ritz_functions": 2, "modes_identified_in_band": 3,
                                            "band_hz": [0, 200]}))  # fmt: skip
    assert "try --functions 3" in fewer
    raw = fit_cautions(_summary(psd=False, damping_matrix=[[-1.0, 2.0], [2.0, 3.0]]))
    assert any("negative diagonal term (R11 = -1)" in c and "drop --unconstrained" in c for c in raw)
    assert any("not positive semi-definite" in c for c in raw)
    (poor,) = fit_cautions(_summary(psi_noise_floor=None, relative_residual=0.4))
    assert poor.startswith("a poor fit: the model leaves 40 % of the data unexplained")
    names = ["R11", "R12", "R22"]
    (some,) = fit_cautions(_summary(uncertainty={"names": names, "determined": [True, False, True]}))
    assert some.startswith("R12 is not determined by these data")
    (none,) = fit_cautions(_summary(uncertainty={"names": names, "determined": [False] * 3}))
    assert none.startswith("no single term of R is determined by these data")


@pytest.fixture(scope="module")
def realistic(tmp_path_factory):
    store = tmp_path_factory.mktemp("realistic")
    return store, capture_sim(store, "realistic", seed=6)


@pytest.mark.parametrize("method", ["modal", "ls", "ga", "pilkey-inman"])
def test_every_method_keeps_r_dissipative_by_default(realistic, method):
    store, run_id = realistic
    (info,) = daq_json("fit", store, run_id, "--method", method)
    eig = np.linalg.eigvalsh(np.array(info["damping_matrix"]))
    assert eig.min() >= -1e-9 * eig.max(), method
    assert isinstance(info["cautions"], list)
    assert info["model"]["ritz_functions"] == info["model"]["modes_identified_in_band"] == 4


def test_pilkey_inman_fits_a_run_with_more_modes_than_functions(realistic):
    """4 identified modes, a 3-function model: it used to stop on 'poles must be a
    1-D array of 1..3 complex values'; now it takes the three it can pair."""
    store, run_id = realistic
    (info,) = daq_json("fit", store, run_id, "--method", "pilkey-inman", "--functions", "3")
    assert info["pole_fit"]["poles_used"] == 3
    assert info["pole_fit"]["poles_left_out"] == 1
    assert "left out" in info["message"]


def test_psd_is_a_no_op_and_contradicts_unconstrained(realistic):
    store, run_id = realistic
    (default,) = daq_json("fit", store, run_id)
    (alias,) = daq_json("fit", store, run_id, "--psd")
    assert alias["damping_matrix"] == default["damping_matrix"]
    assert alias["cached"]  # the same result file and cache key
    result = invoke_daq("fit", run_id, "--psd", "--unconstrained", "--store", str(store))
    assert_one_line_error(result, "--unconstrained")
    printed = invoke_daq("fit", run_id, "--store", str(store)).stdout
    assert "4 Ritz functions: 4 modes identified in 0-200 Hz" in printed
    assert "(R = L L^T)" in printed
