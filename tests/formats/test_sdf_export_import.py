"""`daq export --format sdf` and `daq import` of SDF files (docs/sdf.md): a run exported as SDF and
imported back is analysed with the same windows (the channel headers carry them); a
damaged HP .DAT file gets the SDF reader's reason; units kept as they were are said
on stderr, not only in the provenance."""

from __future__ import annotations

import json

import pytest

from daq.store import Store
from tests.cli_helpers import assert_one_line_error, invoke_daq


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    root = tmp_path_factory.mktemp("trial")
    store = root / "store"
    captured = invoke_daq(
        "capture", "--sim", "--yes", "--hits", "3", "--seed", "2", "--scenario", "realistic",
        "--time-scale", "0", "--store", str(store),
    )  # fmt: skip
    assert captured.returncode == 0, captured.stderr
    (run,) = Store(store).list()
    out = root / "run.sdf"
    result = invoke_daq("export", run.run_id, "--format", "sdf", "-o", str(out), "--store", str(store))
    assert result.returncode == 0, result.stderr
    return root, store, run.run_id, out


def _modes(run_id: str, store) -> tuple[list[tuple[float, float]], dict]:
    result = invoke_daq("analyze", run_id, "--json", "--store", str(store))
    assert result.returncode == 0, result.stderr
    info = json.loads(result.stdout)[0]
    return [(m["frequency_hz"], m["damping_ratio"]) for m in info["modes"]], info["windows"]


@pytest.mark.timeout(120)
def test_an_sdf_round_trip_is_analysed_with_the_windows_it_was_measured_with(exported):
    root, store, run_id, out = exported
    target = root / "imported"
    result = invoke_daq("import", str(out), "--store", str(target))
    assert result.returncode == 0, result.stderr
    (imported,) = Store(target).list()
    original, _ = _modes(run_id, store)
    again, windows = _modes(imported.run_id, target)
    assert windows["from"] == "the imported file's channel headers"
    assert windows["force"]["kind"] == "force"
    assert windows["response"]["kind"] == "exponential"
    assert len(again) == len(original)
    for (f0, z0), (f1, z1) in zip(original, again, strict=True):
        assert f1 == pytest.approx(f0, rel=1e-9)
        assert z1 == pytest.approx(z0, rel=1e-9)


@pytest.mark.timeout(60)
@pytest.mark.parametrize("cut", [2, 7, 40])
def test_a_damaged_dat_file_gets_the_sdf_reason_not_a_csv_one(exported, tmp_path, cut):
    _, _, _, out = exported
    damaged = tmp_path / "IMPACT.DAT"
    damaged.write_bytes(out.read_bytes()[:cut])
    result = invoke_daq("import", str(damaged), "--store", str(tmp_path / "store"))
    assert_one_line_error(result, "IMPACT.DAT")
    assert "not a number" not in result.stderr
    assert "UTF-8" not in result.stderr
    assert "rows" not in result.stderr
    assert not (tmp_path / "store").exists() or Store(tmp_path / "store").list() == []
