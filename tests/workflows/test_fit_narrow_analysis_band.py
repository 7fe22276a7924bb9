"""A default `daq fit` after `daq analyze --band` narrower than the fitted band: the
model takes a function for each of the beam's modes the analysis did not look for,
rather than pairing too few modes and blaming the test article."""

from __future__ import annotations

from tests.cli_helpers import capture_sim, daq_json, invoke_daq


def test_a_narrow_analysis_band_adds_the_model_modes_it_left_out(tmp_path):
    store = tmp_path / "store"
    run_id = capture_sim(store, "realistic", seed=1)
    assert invoke_daq("analyze", run_id, "--band", "20:120", "--store", str(store)).returncode == 0
    result = invoke_daq("fit", run_id, "--store", str(store))
    assert "do not look like this beam's" not in result.stderr
    assert "looked for in 20-120 Hz only" in result.stdout
    (info,) = daq_json("fit", store, run_id)
    model = info["model"]
    assert model["modes_identified_in_band"] == 2
    # The realistic beam's modes at 5.6 and 192 Hz lie in 0-200 Hz, outside 20-120 Hz.
    assert model["ritz_functions"] == 4
    assert "2 of the beam model's modes" in model["functions_reason"]
    assert any("daq analyze --band 0:200, then daq fit" in c for c in info["cautions"])


def test_the_default_counts_the_left_out_model_modes_and_an_explicit_number_wins():
    from daq.workflows.fit import resolve_functions

    assert resolve_functions(2, 0.0, 200.0, None, (20.0, 120.0), [5.6, 191.8])[0] == 4
    assert resolve_functions(2, 0.0, 200.0, None, (20.0, 120.0), [])[0] == 2
    assert resolve_functions(2, 0.0, 200.0, 3, (20.0, 120.0), [5.6, 191.8])[0] == 3
