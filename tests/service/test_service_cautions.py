"""A result that may mislead is never silent: the service passes an analysis's and a
fit's cautions, its band and synthesis error, and the modes' standard uncertainties
to the pages (GET /api/runs for the runs page, the run's analysis and fits for the
live page)."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from daq.service.app import _run_row
from daq.store import Store
from tests.service.service_helpers import import_noise_frf, serving, wait_for


def _service(analysis: dict | None, fit: dict | None) -> SimpleNamespace:
    return SimpleNamespace(
        jobs=SimpleNamespace(state=lambda rid: {"analysis": "done", "fit": "done"}),
        analysis=lambda rid: None if analysis is None else {"summary": analysis},
        default_fit=lambda rid: None if fit is None else {"summary": fit},
    )


def test_a_listed_run_carries_its_cautions_band_and_uncertainties(tmp_path):
    store = tmp_path / "store"
    run_id = import_noise_frf(tmp_path, store)
    (summary,) = Store(store).list()
    analysis = {
        "band": {"low_hz": 5.0, "high_hz": 7035.0, "reason": "the force spectrum falls 20 dB"},
        "synthesis_error": 0.38,
        "modes": [
            {"frequency_hz": 12.5, "damping_ratio": 0.01, "frequency_u_hz": 0.02, "damping_u": 0.001},
            {"frequency_hz": 40.0, "damping_ratio": 0.02, "frequency_u_hz": None, "damping_u": None},
        ],
        "cautions": ["the modes reproduce the FRF poorly (synthesis error 38 % > 20 %)"],
        "windows": {"from": "unknown: the damping includes any window the source applied"},
    }
    fit = {"psi": 3.5, "cautions": ["Psi is 12x the noise floor: try --functions 3"]}
    row = _run_row(_service(analysis, fit), summary)
    assert row["run_id"] == run_id
    assert row["frequencies_hz"] == [12.5, 40.0]  # as before
    assert row["frequencies_u_hz"] == [0.02, None]
    assert row["damping_u"] == [0.001, None]
    assert row["band"] == analysis["band"]
    assert row["synthesis_error"] == 0.38
    assert row["cautions"] == [
        "windows unknown: the damping includes any window the source applied",
        "the modes reproduce the FRF poorly (synthesis error 38 % > 20 %)",
    ]
    assert row["fit_psi"] == 3.5
    assert row["fit_cautions"] == ["Psi is 12x the noise floor: try --functions 3"]

    # Results stored before cautions existed: the same keys, empty.
    old = _run_row(_service({"modes": [{"frequency_hz": 1.0, "damping_ratio": 0.1}]}, {"psi": 1.0}), summary)
    assert old["cautions"] == old["fit_cautions"] == []
    assert old["band"] is None
    assert old["synthesis_error"] is None
    assert old["frequencies_u_hz"] == [None]


@pytest.mark.slow
def test_an_frf_of_pure_noise_is_served_with_its_cautions(tmp_path):
    store = tmp_path / "store"
    run_id = import_noise_frf(tmp_path, store)
    with serving(tmp_path, "--sim", "--workers", "1", store=store) as served:
        wait_for(
            lambda: served.get(f"/api/runs/{run_id}").json()["fit_state"] in ("done", "failed"),
            120,
            "the analysis and fit of the imported run",
        )
        detail = served.get(f"/api/runs/{run_id}").json()
        assert detail["analysis_state"] == "done"
        analysis = served.get(f"/api/runs/{run_id}/analysis").json()
        assert analysis == detail["analysis"]
        assert analysis["modes"] == []
        cautions = analysis["cautions"]
        assert any(c.startswith("no mode found in 1-800 Hz") for c in cautions), cautions
        assert any("synthesis error" in c for c in cautions), cautions
        assert analysis["band"]["low_hz"] == 1.0
        assert analysis["band"]["high_hz"] == 800.0
        assert analysis["band"]["reason"]
        assert analysis["synthesis_error"] > 0.2
        assert analysis["table2"]["rows"] == []
        assert analysis["table2"]["beam"] == "no beam model for this run: it records no test article"

        # What the runs page reads: the listing row says the same.
        (row,) = [r for r in served.get("/api/runs").json() if r["run_id"] == run_id]
        assert row["analysis"] == "done"
        assert row["band"] == analysis["band"]
        assert row["synthesis_error"] == analysis["synthesis_error"]
        assert set(cautions) <= set(row["cautions"])
        assert any(c.startswith("windows unknown") for c in row["cautions"])  # an imported FRF
        assert row["frequencies_hz"] == row["frequencies_u_hz"] == []
