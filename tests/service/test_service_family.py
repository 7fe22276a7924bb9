"""`daq serve` with another analyzer of the family (docs/dialects.md): the service
finds the dialect once, says it in /api/instrument, and a capture through it lands
with the model's geometry and gets its analysis, as with the 35660A."""

from __future__ import annotations

import pytest

from daq.store import Store
from tests.service.service_helpers import EventReader, serving

pytestmark = pytest.mark.slow


@pytest.mark.timeout(240)
@pytest.mark.parametrize(
    ("model", "dialect", "samples", "identification"),
    [
        ("3562A", "3562A", 2048, "HP3562A"),
        ("35670A", "SCPI", 1024, "HEWLETT-PACKARD,35670A,0000A00000,A.00.00"),
    ],
)
def test_a_service_on_another_model_captures_with_its_geometry(
    tmp_path, model, dialect, samples, identification
):
    with serving(tmp_path, "--sim", "--model", model, "--time-scale", "0") as served:
        instrument = served.get("/api/instrument").json()
        assert instrument["connected"] is True
        assert instrument["identification"] == identification
        assert instrument["dialect"] == dialect
        assert "*IDN?" in instrument["detection"]
        events = EventReader(served)
        run_id = served.post("/api/capture", {"hits": 2, "auto": True}).json()["run_id"]
        hit = events.wait_for_kind("hit", run_id, 60)
        assert len(hit["force_n"]) == samples
        events.wait_for_kind("analysis_done", run_id, 180)
        run = Store(served.store).open(run_id)
        assert run.instrument.dialect == dialect
        assert run.instrument.settings["lines"] == samples * 100 // 256
        assert run.hits.n_samples == samples
        analysis = served.get(f"/api/runs/{run_id}/analysis").json()
        found = sorted(m["frequency_hz"] for m in analysis["modes"])
        # The exact cantilever's first mode (docs/method.md), within one line of either model.
        assert min(abs(f - 5.569) for f in found) < 0.5, found
