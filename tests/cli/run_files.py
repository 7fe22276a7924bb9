"""A small run file as `daq runs` lists and shows it (one rejected hit, one overload),
for the command-line and service tests."""

from __future__ import annotations

import numpy as np

from daq.store import Hits, Instrument, MeasuredFrf, Run, Sample

NOTE = "bolt re-torqued — second try"  # non-ASCII on purpose


def make_run(run_id: str, n_hits: int = 3, kind: str = "simulated", complete: bool = True) -> Run:
    rng = np.random.default_rng(0)
    accepted = np.ones(n_hits, dtype=bool)
    reasons = [""] * n_hits
    accepted[-1] = False
    reasons[-1] = "double hit"
    overload = np.zeros((n_hits, 2), dtype=bool)
    overload[0, 1] = True
    hits = Hits(
        force_n=rng.normal(size=(n_hits, 64)),
        response_m_s2=rng.normal(size=(n_hits, 64)),
        sample_rate_hz=2560.0,
        start_s=-0.0125,
        center_hz=0.0,
        accepted=accepted,
        reject_reason=reasons,
        overload=overload,
        peak_force_n=np.linspace(50.0, 60.0, n_hits),
        timestamp_utc=[f"2026-11-23T10:15:{i:02d}.000Z" for i in range(n_hits)],
        checks=[{"double_hit": not bool(a)} for a in accepted],
    )
    analyzer = MeasuredFrf(
        frequency_hz=np.linspace(0.0, 800.0, 33),
        frf=rng.normal(size=(1, 33)) + 1j * rng.normal(size=(1, 33)),
        coherence=rng.uniform(0, 1, (1, 33)),
        labels=["H21"],
    )
    return Run(
        run_id=run_id,
        kind=kind,
        complete=complete,
        start_time="2026-11-23T10:15:03.123Z",
        end_time="2026-11-23T10:17:45.000Z",
        operator="Ada Lovelace",
        note=NOTE,
        provenance={"scenario": "seed", "seed": 7},
        instrument=Instrument("HP 35660A", "HEWLETT-PACKARD,35660A,0,A.01.08", "sim", "tcp", "35660A", {}),
        sample=Sample(2700.0, 69e9, 0.025, 0.003, 0.3, 7.5e-5, 5.625e-11),
        hits=hits,
        analyzer=analyzer,
    )
