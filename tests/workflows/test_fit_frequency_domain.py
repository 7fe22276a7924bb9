"""`daq fit --domain frequency` on a run with hits: the FRF of the hits, per-hit refits
and the time records' reading behind its ±, and a caution where the readings differ."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from daq.workflows.fit import fit_cautions
from tests.cli_helpers import capture_sim, daq_json


@pytest.fixture(scope="module")
def frequency_fit(tmp_path_factory) -> dict:
    store: Path = tmp_path_factory.mktemp("seed-frequency")
    run_id = capture_sim(store, "seed", seed=11)
    (info,) = daq_json("fit", store, run_id, "--domain", "frequency")
    return info


def test_the_frequency_domain_plus_minus_is_never_below_refits_or_the_time_reading(frequency_fit):
    info = frequency_fit
    assert info["domain"] == "frequency"
    unc = info["uncertainty"]
    std = np.array(unc["std"], dtype=float)
    # Per-hit refits in the frequency domain, as in the time domain.
    assert unc["std_from_hits"] is not None
    assert np.all(std >= np.array(unc["std_from_hits"], dtype=float))
    assert np.all(std >= np.array(unc["std_fisher"], dtype=float))
    # The same hits' time records read R too; the ± covers the difference.
    reading = np.array(unc["time_reading"], dtype=float)
    r = np.array(info["damping_matrix"], dtype=float)
    rows, cols = np.triu_indices(3)
    assert np.all(std >= np.abs(r - reading)[rows, cols] * (1 - 1e-9))
    assert set(unc["std_source"]) <= {"fisher", "hits", "readings"}


def _summary(r: list[list[float]], reading: list[list[float]] | None, own: list[float]) -> dict:
    n = len(r)
    return {
        "domain": "frequency", "method": "ls", "psd": True, "success": True, "damping_matrix": r,
        "psi": 1.0, "psi_noise_floor": None, "relative_residual": 0.01, "modes": [],
        "model": {"ritz_functions": n, "modes_identified_in_band": n, "band_hz": [0.0, 200.0]},
        "options": {"stiffness": "modes"}, "stiffness": {"update": "scale on E"},
        "uncertainty": {"names": ["R11", "R12", "R22"], "determined": [True] * 3, "std_own": own,
                        "time_reading": reading},
    }  # fmt: skip


def test_a_frequency_fit_the_time_records_contradict_is_cautioned():
    apart = _summary([[5.0, 1.0], [1.0, 20.0]], [[5.0, 1.0], [1.0, 4.0]], [0.1, 0.1, 2.0])
    (caution,) = [c for c in fit_cautions(apart) if "time records" in c]
    assert "R22 20 against 4" in caution
    assert "prefer the time domain" in caution
    close = _summary([[5.0, 1.0], [1.0, 5.0]], [[5.0, 1.0], [1.0, 4.0]], [0.1, 0.1, 2.0])
    assert not [c for c in fit_cautions(close) if "time records" in c]


def test_an_frf_without_hits_says_its_plus_minus_is_the_fisher_figure_alone():
    alone = _summary([[5.0, 1.0], [1.0, 5.0]], None, [0.1, 0.1, 2.0])
    assert any("Fisher figure alone" in c and "lower bound" in c for c in fit_cautions(alone))
    time = {**alone, "domain": "time"}
    assert not any("Fisher figure alone" in c for c in fit_cautions(time))
