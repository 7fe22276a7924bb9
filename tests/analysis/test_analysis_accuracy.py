"""`daq analyze` on simulated captures: the modes it finds against numbers from outside
the code (the exact beam and eq (18) poles of docs/method.md, the simulator's modal
damping), the JSON it prints, the cache, and FRF-only runs.

Captures run through the real chain (simulator on a socket, driver, store) in-process.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np
import pytest

from daq.store import MeasuredFrf, seal
from tests.cli_helpers import assert_one_line_error, capture_sim, daq_json, invoke_daq
from tests.reference import (
    EQ18_DAMPING_RATIOS,
    EQ18_POLE_MAGNITUDE_HZ,
    EXACT_TABULATED_HZ,
    REALISTIC_DAMPING_RATIOS,
)
from tests.store.store_helpers import make_run


def analyze_json(store: Path, *args: str) -> list[dict]:
    return daq_json("analyze", store, *args)


def match(modes: list[dict], truth_hz: tuple[float, ...]) -> list[dict]:
    """The identified mode nearest each true frequency."""
    return [min(modes, key=lambda m: abs(m["frequency_hz"] - f)) for f in truth_hz]


@pytest.fixture(scope="module")
def realistic(tmp_path_factory) -> tuple[Path, str]:
    store = tmp_path_factory.mktemp("realistic")
    return store, capture_sim(store, "realistic", seed=3)


def test_realistic_run_gives_the_exact_beam_and_the_simulated_damping(realistic):
    store, run_id = realistic
    (info,) = analyze_json(store, run_id)
    assert info["run_id"] == run_id
    freqs = [m["frequency_hz"] for m in info["modes"]]
    assert freqs == sorted(freqs)
    found = match(info["modes"], EXACT_TABULATED_HZ)
    for mode, f_true, zeta_true in zip(found, EXACT_TABULATED_HZ, REALISTIC_DAMPING_RATIOS, strict=True):
        assert mode["frequency_hz"] == pytest.approx(f_true, rel=1e-3)
        assert mode["damping_ratio"] == pytest.approx(zeta_true, rel=0.10)
    # The Table 2 rows name the same modes beside the analytical columns.
    rows = info["table2"]["rows"]
    assert [r["exact_hz"] for r in rows[:3]] == pytest.approx(EXACT_TABULATED_HZ[:3], rel=1e-5)
    assert rows[0]["identified_hz"] == pytest.approx(EXACT_TABULATED_HZ[0], rel=1e-3)


def test_seed_run_gives_the_eq18_poles(tmp_path):
    run_id = capture_sim(tmp_path, "seed", seed=4)
    (info,) = analyze_json(tmp_path, run_id)
    found = match(info["modes"], EQ18_POLE_MAGNITUDE_HZ)
    for mode, f_true, zeta_true in zip(found, EQ18_POLE_MAGNITUDE_HZ, EQ18_DAMPING_RATIOS, strict=True):
        assert mode["frequency_hz"] == pytest.approx(f_true, rel=5e-3)
        assert mode["damping_ratio"] == pytest.approx(zeta_true, rel=0.10)


def test_a_second_analysis_is_a_cache_hit_and_the_run_is_untouched(realistic):
    store, run_id = realistic
    path = store / f"{run_id}.h5"
    before = hashlib.sha256(path.read_bytes()).hexdigest()
    first = analyze_json(store, run_id)[0]
    second = analyze_json(store, run_id)[0]
    assert second["cached"] is True
    assert second["modes"] == first["modes"]
    forced = analyze_json(store, run_id, "--force")[0]
    assert forced["cached"] is False
    other = analyze_json(store, run_id, "--max-order", "30")[0]
    assert other["cached"] is False  # other options, another analysis
    assert hashlib.sha256(path.read_bytes()).hexdigest() == before
    assert (store / f"{run_id}.analysis.h5").is_file()


def synthetic_frf(freqs_hz, zetas, f):
    w = 2 * np.pi * f
    h = np.zeros_like(w, dtype=complex)
    for fn, z in zip(freqs_hz, zetas, strict=True):
        wn = 2 * np.pi * fn
        h += -(w**2) / (wn**2 - w**2 + 2j * z * wn * w)
    return h


def test_a_run_of_imported_frfs_is_identified_without_an_fft(tmp_path):
    f = np.linspace(0.0, 200.0, 801)
    truth = ((12.0, 61.0, 143.0), (0.02, 0.01, 0.015))
    frf = MeasuredFrf(f, synthetic_frf(*truth, f)[np.newaxis, :], None, ["driving point"])
    run = make_run(kind="imported", measured=frf)
    seal(run, tmp_path)
    (info,) = analyze_json(tmp_path, run.run_id)
    assert info["source"] == "measured_frf"
    found = match(info["modes"], truth[0])
    for mode, f_true, z_true in zip(found, *truth, strict=True):
        assert mode["frequency_hz"] == pytest.approx(f_true, rel=1e-3)
        assert mode["damping_ratio"] == pytest.approx(z_true, rel=0.05)


def test_all_runs_in_parallel(tmp_path):
    f = np.linspace(0.0, 200.0, 401)
    ids = []
    for k in range(3):
        frf = MeasuredFrf(f, synthetic_frf((20.0 + 10 * k,), (0.02,), f)[np.newaxis, :], None, ["H"])
        run = make_run(kind="imported", measured=frf)
        seal(run, tmp_path)
        ids.append(run.run_id)
    infos = analyze_json(tmp_path, "--all", "--jobs", "2")
    assert [i["run_id"] for i in infos] == sorted(ids)
    for k, info in enumerate(infos):
        assert match(info["modes"], (20.0 + 10 * k,))[0]["frequency_hz"] == pytest.approx(
            20.0 + 10 * k, rel=1e-3
        )


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        ((), "name the runs"),
        (("--band", "abc", "x"), "LOW:HIGH"),
        (("--band", "50:10", "x"), "LOW < HIGH"),
        (("--frequencies", "5,x", "x"), "separated by commas"),
        (("--estimator", "h9", "x"), "estimator"),
        (("nosuchrun",), "nosuchrun"),
    ],
)
def test_bad_analyze_arguments_are_one_line(tmp_path, args, fragment):
    assert_one_line_error(invoke_daq("analyze", *args, "--store", str(tmp_path)), fragment)
