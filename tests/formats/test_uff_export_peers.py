"""Our UFF export read by another modal tool: pyuff reads the file, sdypy-EMA finds the
modes in it, and finds the damping `daq analyze` finds (issue 24).

Real files, through daq's command line (in this process: tests/cli_helpers.py): `daq
capture --sim` of the `realistic` beam (seed 3, 5 hits), `daq analyze RUN --json`, `daq
export RUN --format uff`; then pyuff and sdypy-EMA (LSCF, polynomial order 30, 1-199 Hz,
its own `select_closest_poles` near daq's frequencies) on the file, as a user of that
tool would.

Tolerance. `daq analyze` states a standard uncertainty (scatter over the 5 hits) of
0.05-0.3 % of each damping ratio here: three of them would test sdypy's method, not our
file. sdypy's own estimate moves more than that with its settings: over seeds 1-8 of
this capture its damping differed from daq's by +0.6 to +3.4 % (mode 2), -1.7 to
+0.1 % (mode 3) and +5.5 to +9.0 % (mode 4, 8 Hz below the band's top, where LSCF's
band edge bites), and by up to 8 % between polynomial orders 20 and 40 on one file.
So the stated tolerance is 5 % for modes 2 and 3 and 12 % for mode 4; what it must
catch is the window: the analyzer's exponential window (decay 3 1/s) adds +227 %,
+123 % and +78 % (sdypy on the stored windowed FRF, checked below too). Mode 1
(5.6 Hz, 11 lines above 0 Hz) has no stable pole in sdypy's stabilisation with either
FRF, so it is not compared. The simulator's own ratios (sims/scenarios.py: 0.6, 0.4,
0.3 %) are met within the issue's 15 % as well.
"""

from __future__ import annotations

import contextlib
import io
import json
import subprocess
import warnings
from pathlib import Path

import numpy as np
import pytest
import pyuff

from daq.formats.uff58_export import write_uff
from daq.store import open_run
from tests.cli_helpers import invoke_daq

EMA = pytest.importorskip("sdypy.EMA")

SIMULATED_DAMPING = {2: 0.006, 3: 0.004, 4: 0.003}  # sims/scenarios.py REALISTIC_DAMPING_RATIOS
TOLERANCE = {2: 0.05, 3: 0.05, 4: 0.12}  # relative, against daq analyze (module docstring)
ISSUE_TOLERANCE = 0.15  # issue 24: modes 2 and 3 within 15 % of the simulator's damping
BAND_HZ = (1.0, 199.0)
ORDER = 30


def daq(*args: str) -> subprocess.CompletedProcess:
    result = invoke_daq(*args)
    assert result.returncode == 0, result.stderr
    return result


def frf_sets(path: Path) -> list[dict]:
    uff = pyuff.UFF(str(path))
    sets = uff.read_sets()
    sets = sets if isinstance(sets, list) else [sets]
    return [s for s in sets if s["type"] == 58 and s["func_type"] == 4]


def sdypy_damping(path: Path, approx_hz: list[float]) -> tuple[np.ndarray, np.ndarray]:
    """(frequency_hz, damping ratio) sdypy-EMA finds in the file near ``approx_hz``."""
    model = EMA.Model(lower=BAND_HZ[0], upper=BAND_HZ[1], pol_order_high=ORDER)
    with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()):
        warnings.simplefilter("ignore")  # its numpy divisions and deprecations, not ours
        model.read_uff(str(path))
        model.get_poles(method="lscf", show_progress=False)
        model.select_closest_poles(approx_hz)
    assert model.frf_form == "accelerance"  # read from the file's first dataset 58
    return np.asarray(model.nat_freq, dtype=float), np.asarray(model.nat_xi, dtype=float)


@pytest.fixture(scope="module")
def driving_point(tmp_path_factory) -> dict:
    """A simulated realistic run (hammer and sensor at the tip), daq's modes, its UFF."""
    folder = tmp_path_factory.mktemp("peer")
    store = folder / "store"
    daq(
        "capture", "--sim", "--scenario", "realistic", "--hits", "5", "--yes", "--time-scale", "0",
        "--seed", "3", "--store", str(store),
    )  # fmt: skip
    (run_file,) = [p for p in store.glob("*.h5") if not p.name.endswith(".analysis.h5")]
    run_id = run_file.stem
    (analysis,) = json.loads(daq("analyze", run_id, "--json", "--store", str(store)).stdout)
    out = folder / "run.uff"
    daq("export", run_id, "--format", "uff", "-o", str(out), "--store", str(store))
    return {"store": store, "run_file": run_file, "analysis": analysis, "uff": out, "folder": folder}


def test_sdypy_finds_daq_analyzes_damping_in_the_export(driving_point):
    modes = driving_point["analysis"]["modes"]
    assert len(modes) >= 4
    compared = {k: modes[k - 1] for k in TOLERANCE}
    freq, damping = sdypy_damping(driving_point["uff"], [m["frequency_hz"] for m in compared.values()])
    for (k, mode), f, zeta in zip(compared.items(), freq, damping, strict=True):
        assert abs(f - mode["frequency_hz"]) <= 0.01 * mode["frequency_hz"], (k, f, mode["frequency_hz"])
        # daq's stated uncertainty is well inside the tolerance: the tolerance is the peer's.
        # (0.3 of it since the u carries the noise bias the hits show: mode 3's 0.44 %.)
        assert 3 * mode["damping_u"] <= 0.3 * TOLERANCE[k] * mode["damping_ratio"], (k, mode["damping_u"])
        assert zeta == pytest.approx(mode["damping_ratio"], rel=TOLERANCE[k]), (
            k,
            zeta,
            mode["damping_ratio"],
        )
        if k in (2, 3):
            assert zeta == pytest.approx(SIMULATED_DAMPING[k], rel=ISSUE_TOLERANCE), (k, zeta)


def test_the_stored_windowed_frf_would_not_pass(driving_point):
    """The same run's stored analyzer FRF (exponential window on the response, stated in
    its ID line 4) gives sdypy the window's damping: what the export no longer writes."""
    modes = driving_point["analysis"]["modes"]
    windowed = driving_point["folder"] / "windowed.uff"
    write_uff(open_run(driving_point["run_file"]), windowed)
    (record,) = frf_sets(windowed)
    assert "response_window=exponential exp_decay_s=" in record["id4"]
    _, damping = sdypy_damping(windowed, [modes[k - 1]["frequency_hz"] for k in TOLERANCE])
    for k, zeta in zip(TOLERANCE, damping, strict=True):
        assert zeta > (1 + 5 * TOLERANCE[k]) * modes[k - 1]["damping_ratio"], (k, zeta)


def test_the_driving_point_is_one_node(driving_point):
    (record,) = frf_sets(driving_point["uff"])
    assert (record["ref_node"], record["ref_dir"]) == (1, 3)  # tip, +z
    assert (record["rsp_node"], record["rsp_dir"]) == (1, 3)
    assert record["id5"].strip() == "ref_name=tip rsp_name=tip"
    assert "response_window=uniform" in record["id4"]
    assert record["ordinate_spec_data_type"] == 12  # accelerance over force (13)


def test_a_transfer_keeps_two_nodes(tmp_path):
    store = tmp_path / "store"
    daq(
        "capture", "--sim", "--scenario", "realistic", "--hits", "1", "--yes", "--time-scale", "0",
        "--seed", "3", "--force-at", "0.35", "--store", str(store),
    )  # fmt: skip
    out = tmp_path / "transfer.uff"
    daq("export", "latest", "--format", "uff", "-o", str(out), "--store", str(store))
    (record,) = frf_sets(out)
    assert (record["ref_node"], record["ref_dir"], record["rsp_node"], record["rsp_dir"]) == (1, 3, 2, 3)
    (run_file,) = [p for p in store.glob("*.h5") if not p.name.endswith(".analysis.h5")]
    points = open_run(run_file).resolved_points()
    assert points.force_point.position_m == pytest.approx(0.35)
    (response,) = points.response_points
    assert record["id5"].strip() == f"ref_name={points.force_point.name} rsp_name={response.name}"
