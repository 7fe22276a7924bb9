"""Each set of fit options has its own result file: a fit in the frequency domain or with
another stiffness no longer replaces the default fit (and the default fit it)."""

from __future__ import annotations

import pytest

from daq.report.build import stored_fits
from daq.store import Store
from daq.workflows.fit import FitOptions
from tests.cli_helpers import assert_one_line_error, capture_sim, daq_json, invoke_daq


def test_non_default_domain_and_stiffness_are_in_the_name():
    assert FitOptions().result_name == "fit-ls"
    assert FitOptions(domain="frequency").result_name == "fit-ls-frequency"
    assert FitOptions(stiffness="scale").result_name == "fit-ls-stiffness-scale"
    assert FitOptions(stiffness="none", domain="frequency", psd=False, n_functions=3).result_name == (
        "fit-ls-unconstrained-n3-frequency-stiffness-none"
    )
    names = {
        FitOptions(domain=d, stiffness=s).result_name
        for d in ("time", "frequency")
        for s in ("modes", "scale", "none")
    }
    assert len(names) == 6


def test_unconstrained_modal_is_refused_in_one_line(tmp_path):
    with pytest.raises(ValueError, match="means nothing for --method modal"):
        FitOptions(method="modal", psd=False)
    result = invoke_daq("fit", "latest", "--method", "modal", "--unconstrained", "--store", str(tmp_path))
    assert result.returncode == 2
    assert_one_line_error(result, "--unconstrained means nothing for --method modal")


def test_a_frequency_fit_is_stored_beside_the_default_and_both_are_listed(tmp_path):
    store = tmp_path / "store"
    run_id = capture_sim(store, "seed", seed=3, hits=3)
    (default,) = daq_json("fit", store, run_id)
    (frequency,) = daq_json("fit", store, run_id, "--domain", "frequency")
    (again,) = daq_json("fit", store, run_id)
    assert again["cached"]  # the default fit is still there, not replaced
    assert again["domain"] == default["domain"] == "time"
    assert frequency["domain"] == "frequency"
    fits = stored_fits(Store(store), run_id)
    assert set(fits) == {"fit-ls", "fit-ls-frequency"}
    assert fits["fit-ls-frequency"]["summary"]["domain"] == "frequency"


def test_a_global_search_with_another_seed_keeps_its_own_file():
    """--method ga --seed 1 and --seed 2 shared fit-ga.h5: the second replaced the first
    and the report's "Fit fit-ga" did not say which seed it was."""
    from daq.workflows.fit import FitOptions

    assert FitOptions(method="ga").result_name == "fit-ga"
    assert FitOptions(method="ga", seed=1).result_name == "fit-ga-seed1"
    assert FitOptions(method="de", seed=2, domain="frequency").result_name == "fit-de-seed2-frequency"
    assert FitOptions(method="ls", seed=3).result_name == "fit-ls"  # ls takes no seed


def test_the_modal_estimate_is_not_compared_with_a_least_squares_time_reading():
    """--method modal --domain frequency was cautioned that "the FRF and the time records of
    the same hits give different R": the proportional estimate against the least-squares
    fit of the time records, not one domain against the other."""
    from daq.workflows.fit import _readings_apart

    for method in ("modal", "pilkey-inman"):
        assert _readings_apart({"domain": "frequency", "method": method, "uncertainty": {}}) is None
    assert "lower bound" in _readings_apart({"domain": "frequency", "method": "ls", "uncertainty": {}})
