"""An even UFF 58 frequency axis whose step is printed to 6 significant digits (ASCII
58's E13.5) is known no better: its doubt scales every frequency, and daq analyze adds it
to each ± (a new user's 1/3 Hz lines, 3.33333E-01, put a 4000 Hz mode 0.0033 Hz low with a
± of 0.0010 Hz)."""

from __future__ import annotations

import gc
import json
import math
import warnings
from pathlib import Path

import numpy as np
import pytest
import pyuff

from daq.formats.uff58 import read_uff
from tests.cli_helpers import daq_import, invoke_daq


def _write(path: Path, step: float, binary: int, n: int = 600, start: float = 300.0) -> Path:
    f = start + step * np.arange(n)
    w, wn = 2 * np.pi * f, 2 * np.pi * 400.0
    h = -(w**2) / (wn**2 - w**2 + 2j * 0.01 * wn * w)
    dset = pyuff.prepare_58(
        binary=binary, id1="H", func_type=4, rsp_node=1, rsp_dir=3, ref_node=1, ref_dir=3,
        abscissa_spacing=1, abscissa_spec_data_type=18, ordinate_spec_data_type=12,
        orddenom_spec_data_type=13, z_axis_spec_data_type=0, data=h, x=f,
    )  # fmt: skip
    dset.update(abscissa_axis_units_lab="Hz", ordinate_axis_units_lab="m/s^2", orddenom_axis_units_lab="N")
    path.unlink(missing_ok=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ResourceWarning)
        pyuff.UFF(str(path)).write_sets([dset], mode="add")
        gc.collect()
    return path


@pytest.mark.parametrize("binary", [0, 1])  # binary 58's header is text as well
def test_a_step_printed_short_of_its_digits_carries_its_doubt(tmp_path, binary):
    data = read_uff(_write(tmp_path / "third.uff", 1 / 3, binary=binary))
    # Half a unit of the 6th digit of 3.33333E-01, as a standard uncertainty, over the step.
    want = 0.5e-6 / 3.33333e-1 / math.sqrt(3)
    assert data.details["frequency_axis_u_rel"] == pytest.approx(want, rel=1e-9)
    assert any("printed to 6 significant digits" in note for note in data.details["notes"])


@pytest.mark.parametrize(("step", "binary"), [(1.0, 0), (0.25, 0), (0.5, 1)])
def test_a_short_step_is_exact(tmp_path, step, binary):
    data = read_uff(_write(tmp_path / "exact.uff", step, binary=binary))
    assert "frequency_axis_u_rel" not in data.details


def test_daq_analyze_adds_the_share_to_every_frequency_u(tmp_path):
    store = tmp_path / "runs"
    assert daq_import(store, _write(tmp_path / "third.uff", 1 / 3, binary=0)).returncode == 0
    result = invoke_daq("analyze", "latest", "--json", "--store", str(store))
    assert result.returncode == 0, result.stderr
    (analysis,) = json.loads(result.stdout)
    (mode,) = analysis["modes"]
    share = mode["frequency_hz"] * 0.5e-6 / 3.33333e-1 / math.sqrt(3)
    assert mode["frequency_u_hz"] >= share
    assert abs(mode["frequency_hz"] - 400.0) <= 3 * mode["frequency_u_hz"]
