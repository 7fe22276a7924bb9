"""`daq demo`: an impact test on the simulated analyzer over TCP, its FRF peaks beside
the exact beam (docs/method.md, "Reproduced numbers"; tests/reference.py)."""

from __future__ import annotations

import re

import pytest

from tests.cli_helpers import invoke_daq
from tests.reference import EXACT_TABULATED_HZ

LINE_SPACING_HZ = 0.5  # 200 Hz span / 400 lines


@pytest.mark.timeout(60)
def test_demo_finds_every_mode_of_the_exact_beam_within_a_line(tmp_path):
    result = invoke_daq("demo", "--time-scale", "0", "--seed", "4", env={"DAQ_LOCK_DIR": str(tmp_path)})
    assert result.returncode == 0, result.stderr
    assert result.stdout.count("hit accepted") == 5
    rows = re.findall(r"│\s+(\d)\s+│\s+([\d.]+)\s+│", result.stdout)
    peaks = {int(mode): float(peak) for mode, peak in rows}
    assert sorted(peaks) == [1, 2, 3, 4]
    for mode, exact_hz in enumerate(EXACT_TABULATED_HZ, start=1):
        assert abs(peaks[mode] - exact_hz) <= LINE_SPACING_HZ, (mode, peaks[mode], exact_hz)
