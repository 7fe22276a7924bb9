"""Capture -> analyse -> fit on each simulated model of the family (docs/dialects.md):
the same beam measured by a 35660A (400 lines), a 3562A (800 lines, 2,048-sample
records) and a 35670A (SCPI) gives the same identified modes within the line
spacing, and each run records the model, dialect and lines it was measured with.

The exact beam's frequencies come from outside the code (tests/reference.py)."""

from __future__ import annotations

import json

import pytest

from tests.cli_helpers import assert_one_line_error, invoke_daq
from tests.reference import EXACT_TABULATED_HZ, REALISTIC_DAMPING_RATIOS

#: model -> (dialect recorded, model recorded, lines, samples per record, span Hz for 200 Hz asked)
MODELS = {
    "35660A": ("35660A", "HP 35660A", 400, 1024, 200.0),
    "3562A": ("3562A", "HP 3562A", 800, 2048, 100_000 / 2**8),
    "35670A": ("SCPI", "HP 35670A", 400, 1024, 200.0),
}


def _capture_and_analyse(tmp_path, model: str) -> tuple[dict, dict, dict, str]:
    store = str(tmp_path / model)
    env = {"DAQ_LOCK_DIR": str(tmp_path)}
    captured = invoke_daq(
        "capture", "--sim", "--model", model, "--hits", "3", "--yes", "--scenario", "realistic",
        "--seed", "2", "--time-scale", "0", "--store", store, env=env,
    )  # fmt: skip
    assert captured.returncode == 0, captured.stderr
    shown = invoke_daq("runs", "show", "latest", "--json", "--store", store, env=env)
    assert shown.returncode == 0, shown.stderr
    analysed = invoke_daq("analyze", "latest", "--json", "--store", store, env=env)
    assert analysed.returncode == 0, analysed.stderr
    fitted = invoke_daq("fit", "latest", "--json", "--method", "modal", "--store", store, env=env)
    assert fitted.returncode == 0, fitted.stderr
    return json.loads(shown.stdout), json.loads(analysed.stdout)[0], json.loads(fitted.stdout)[0], store


@pytest.fixture(scope="module")
def chains(tmp_path_factory):
    root = tmp_path_factory.mktemp("family")
    return {model: _capture_and_analyse(root, model) for model in MODELS}


@pytest.mark.timeout(300)
@pytest.mark.parametrize("model", list(MODELS))
def test_each_model_records_what_measured_it(chains, model):
    dialect, name, lines, samples, span = MODELS[model]
    run, _, _, _ = chains[model]
    assert run["instrument"]["dialect"] == dialect
    assert run["instrument"]["model"] == name
    assert run["instrument"]["settings"]["lines"] == lines
    assert run["instrument"]["settings"]["span_hz"] == pytest.approx(span, rel=1e-12)
    assert run["hits"]["n_samples"] == samples


@pytest.mark.timeout(300)
@pytest.mark.parametrize("model", list(MODELS))
def test_each_model_finds_the_exact_beam_within_its_line_spacing(chains, model):
    _, _, lines, _, span = MODELS[model]
    _, analysis, _, _ = chains[model]
    found = sorted(m["frequency_hz"] for m in analysis["modes"])
    spacing = span / lines
    for exact in EXACT_TABULATED_HZ[:3]:
        nearest = min(found, key=lambda f: abs(f - exact))
        assert abs(nearest - exact) <= spacing, (model, exact, found)


@pytest.mark.timeout(300)
def test_every_model_identifies_the_same_modes_within_the_coarsest_line_spacing(chains):
    spacing = max(span / lines for _, _, lines, _, span in MODELS.values())
    per_model = {model: sorted(m["frequency_hz"] for m in chains[model][1]["modes"])[:3] for model in MODELS}
    first = per_model["35660A"]
    for model, modes in per_model.items():
        assert len(modes) == 3, (model, modes)
        for a, b in zip(first, modes, strict=True):
            assert abs(a - b) <= spacing, (model, first, modes)


@pytest.mark.timeout(300)
@pytest.mark.parametrize("model", list(MODELS))
def test_each_model_run_gets_a_damping_fit(chains, model):
    _, _, fit, _ = chains[model]
    ratios = [mode["damping_ratio"] for mode in fit["modes"]]
    # One Ritz function per mode identified in the band (daq fit's default): at least the
    # beam's first three, the first four carrying the realistic beam's truth
    # (tests/reference.py) within 10 % whatever the analyzer measured it with.
    assert len(ratios) >= 3
    n = min(len(ratios), len(REALISTIC_DAMPING_RATIOS))
    for zeta, truth in zip(ratios[:n], REALISTIC_DAMPING_RATIOS[:n], strict=True):
        assert zeta == pytest.approx(truth, rel=0.1), (model, ratios)


@pytest.mark.timeout(300)
@pytest.mark.parametrize(
    ("model", "replayed_by"),
    # A 35670A run at 400 lines and 200 Hz records as a 35660A does: the first model that fits.
    [("3562A", "3562A"), ("35670A", "35660A")],
)
def test_a_run_of_another_model_replays_bit_for_bit_through_a_model_that_records_like_it(
    chains, model, replayed_by, tmp_path
):
    run, _, _, store = chains[model]
    result = invoke_daq("replay", run["run_id"], "--store", store, env={"DAQ_LOCK_DIR": str(tmp_path)})
    assert result.returncode == 0, result.stderr
    assert f"through the simulated {replayed_by} at" in result.stdout
    assert "bit for bit" in result.stdout


@pytest.mark.timeout(300)
def test_lines_from_the_setup_file_reach_a_35670a_and_its_run_replays_through_it(tmp_path):
    env = {"DAQ_LOCK_DIR": str(tmp_path)}
    setup = tmp_path / "setup.toml"
    setup.write_text("span_hz = 200.0\nlines = 1600\n", encoding="utf-8")
    store = str(tmp_path / "store")
    captured = invoke_daq(
        "capture", "--sim", "--model", "35670A", "--setup", str(setup), "--hits", "2", "--yes",
        "--time-scale", "0", "--store", store, env=env,
    )  # fmt: skip
    assert captured.returncode == 0, captured.stderr
    assert "1600 lines, 8 s records" in captured.stdout
    run = json.loads(invoke_daq("runs", "show", "latest", "--json", "--store", store, env=env).stdout)
    assert run["hits"]["n_samples"] == 4096  # 2.56 x 1,600 (docs/dialects.md)
    replayed = invoke_daq("replay", run["run_id"], "--store", store, env=env)
    assert replayed.returncode == 0, replayed.stderr
    assert "through the simulated 35670A at" in replayed.stdout


@pytest.mark.timeout(60)
def test_lines_a_model_does_not_offer_are_one_line_before_any_hit(tmp_path):
    env = {"DAQ_LOCK_DIR": str(tmp_path)}
    setup = tmp_path / "setup.toml"
    setup.write_text("lines = 800\n", encoding="utf-8")
    result = invoke_daq(
        "capture", "--sim", "--setup", str(setup), "--hits", "2", "--yes", "--time-scale", "0",
        "--store", str(tmp_path / "store"), env=env,
    )  # fmt: skip
    assert_one_line_error(result, "lines: the 35660A offers 400 lines only, not 800")


@pytest.mark.timeout(60)
def test_a_35665a_refuses_1600_lines_in_one_line_before_any_hit(tmp_path):
    env = {"DAQ_LOCK_DIR": str(tmp_path)}
    setup = tmp_path / "setup.toml"
    setup.write_text("lines = 1600\n", encoding="utf-8")
    result = invoke_daq(
        "capture", "--sim", "--model", "35665A", "--setup", str(setup), "--hits", "2", "--yes",
        "--time-scale", "0", "--store", str(tmp_path / "store"), env=env,
    )  # fmt: skip
    assert_one_line_error(result, "the 35665A offers 100, 200, 400, 800 lines, not 1600")
