"""A sample rate the imported file knows only roughly (LabVIEW's Delta_X printed to 3
digits, with no whole or common rate it allows) scales every frequency alike: its share
is in each frequency's ± and a caution says so; a rate it pins down adds nothing."""

from __future__ import annotations

import json
import math

import pytest

from tests.cli_helpers import invoke_daq
from tests.formats.test_lvm import hammer_hit, lvm_text, write

TRUE_RATE_HZ = 1500.0
MODE_HZ = 120.0


def analysed(tmp_path, delta_x: str) -> dict:
    segments = []
    for seed in range(4):
        force, a1, _ = hammer_hit(3000, TRUE_RATE_HZ, MODE_HZ, seed)
        segments.append([("F", "N", force), ("a1", "m/s^2", a1)])
    path = write(tmp_path / "taps.lvm", lvm_text(segments, delta_x=delta_x))
    store = tmp_path / "runs"
    imported = invoke_daq("import", str(path), "--store", str(store))
    assert imported.returncode == 0, imported.stderr
    result = invoke_daq("analyze", "latest", "--store", str(store), "--json")
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout)[0]


def test_a_rate_known_to_0_05_percent_is_in_every_frequency_u_and_cautioned(tmp_path):
    # 0.000667 s allows 1498.1 to 1500.4 Hz: two whole rates, no common one; 1/0.000667 is
    # taken, 0.05 % below the truth, +-0.075 % (uniform: u = 0.043 %).
    info = analysed(tmp_path, "0.000667")
    u_rel = 0.0000005 / 0.000667 / math.sqrt(3)
    (mode,) = [m for m in info["modes"] if abs(m["frequency_hz"] - MODE_HZ) < 2]
    assert mode["frequency_hz"] == pytest.approx(MODE_HZ * 1 / 0.000667 / TRUE_RATE_HZ, rel=2e-4)
    assert mode["frequency_u_hz"] >= mode["frequency_hz"] * u_rel
    assert abs(mode["frequency_hz"] - MODE_HZ) <= 2 * mode["frequency_u_hz"]
    said = [c for c in info["cautions"] if c.startswith("the sample rate")]
    assert len(said) == 1, info["cautions"]
    assert "±0.075 %" in said[0]
    assert "--sample-rate" in said[0]


def test_a_rate_the_step_pins_down_adds_no_caution(tmp_path):
    info = analysed(tmp_path, "0.000666667")  # 7 digits: 1500 Hz to 0.0001 %
    assert not [c for c in info["cautions"] if c.startswith("the sample rate")], info["cautions"]


def test_a_coarsely_printed_csv_time_column_is_a_doubt_too(tmp_path):
    # Times printed to 3 decimals at 512 Hz (half a unit is 26 % of the step) over 1024
    # samples: the fitted rate is known to about +-0.5 Hz.
    force, a1, _ = hammer_hit(1024, 512.0, 40.0)
    rows = [f"{k / 512:.3f},{f!r},{a!r}" for k, (f, a) in enumerate(zip(force, a1, strict=True))]
    path = tmp_path / "coarse.csv"
    path.write_text("time,force,response\n" + "\n".join(rows) + "\n")
    store = tmp_path / "runs"
    imported = invoke_daq("import", str(path), "--store", str(store))
    assert imported.returncode == 0, imported.stderr
    assert "printed coarsely" in imported.stdout
    result = invoke_daq("analyze", "latest", "--store", str(store), "--json")
    info = json.loads(result.stdout)[0]
    assert [c for c in info["cautions"] if c.startswith("the sample rate")], info["cautions"]
