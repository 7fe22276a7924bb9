"""Runs made by hand for the store's tests (also imported by the tests' child processes)."""

from __future__ import annotations

import numpy as np

from daq.store import Hits, Instrument, MeasuredFrf, Run, Sample, new_run_id

NOTE_MARKER = "note-marker-Qx7"


def make_hits(n_hits: int = 4, n_samples: int = 256, zoom: bool = False, seed: int = 0) -> Hits:
    rng = np.random.default_rng(seed)
    if zoom:
        force = rng.normal(size=(n_hits, n_samples)) + 1j * rng.normal(size=(n_hits, n_samples))
        response = rng.normal(size=(n_hits, n_samples)) + 1j * rng.normal(size=(n_hits, n_samples))
    else:
        force = rng.normal(size=(n_hits, n_samples))
        response = rng.normal(size=(n_hits, n_samples)) * 50.0
    accepted = np.ones(n_hits, dtype=bool)
    reasons = [""] * n_hits
    if n_hits > 1:
        accepted[-1] = False
        reasons[-1] = "double hit — second peak 40 % of first"  # non-ASCII on purpose
    overload = np.zeros((n_hits, 2), dtype=bool)
    overload[0, 1] = True
    return Hits(
        force_n=force,
        response_m_s2=response,
        sample_rate_hz=2560.0 if not zoom else 400.0,
        start_s=-0.0125,
        center_hz=0.0 if not zoom else 1234.5,
        accepted=accepted,
        reject_reason=reasons,
        overload=overload,
        peak_force_n=rng.uniform(10, 200, n_hits),
        timestamp_utc=[f"2026-11-23T10:15:{i % 60:02d}.{i:03d}Z" for i in range(n_hits)],
        checks=[
            {"double_hit": bool(not a), "snr_db": 41.5 + i, "notes": ["ok", i]}
            for i, a in enumerate(accepted)
        ],
    )


def make_frf(n_frf: int = 2, n_lines: int = 401, coherence: bool = True, seed: int = 1) -> MeasuredFrf:
    rng = np.random.default_rng(seed)
    return MeasuredFrf(
        frequency_hz=np.linspace(0.0, 1000.0, n_lines),
        frf=rng.normal(size=(n_frf, n_lines)) + 1j * rng.normal(size=(n_frf, n_lines)),
        coherence=rng.uniform(0, 1, (n_frf, n_lines)) if coherence else None,
        labels=[f"H{i + 1}1 point {i}" for i in range(n_frf)],
    )


def make_run(
    kind: str = "simulated",
    hits: Hits | None = None,
    analyzer: MeasuredFrf | None = None,
    measured: MeasuredFrf | None = None,
    note: str = NOTE_MARKER,
    run_id: str | None = None,
    seed: int = 0,
    n_hits: int = 4,
    n_samples: int = 256,
) -> Run:
    if hits is None and analyzer is None and measured is None:
        hits = make_hits(n_hits, n_samples, seed=seed)
    return Run(
        run_id=run_id or new_run_id(),
        kind=kind,
        complete=True,
        start_time="2026-11-23T10:15:03.123Z",
        end_time="2026-11-23T10:17:45.000+00:00",
        operator="Ada Lovelace",
        note=note,
        provenance={
            "scenario": "seed",
            "seed": seed,
            "imported_from": {"file": "x.uff", "sha256": "ab" * 32},
        },
        instrument=Instrument(
            model="HP 35660A",
            identification="HEWLETT-PACKARD,35660A,0,A.01.08",
            resource="GPIB0::11::INSTR",
            transport="prologix",
            dialect="35660A",
            settings={
                "span_hz": 1000.0,
                "lines": 400,
                "record_points": 1024,
                "windows": ["force", "exponential"],
            },
        ),
        sample=Sample(2700.0, 69e9, 0.025, 0.003, 0.3, 7.5e-5, 5.625e-11, force_position_m=0.29),
        hits=hits,
        analyzer=analyzer,
        measured_frfs=measured,
    )


def assert_same_array(a: np.ndarray | None, b: np.ndarray | None) -> None:
    if a is None or b is None:
        assert a is None
        assert b is None
        return
    assert a.dtype == b.dtype
    assert a.shape == b.shape
    assert a.tobytes() == b.tobytes()  # bit-exact, NaN included


def assert_same_run(got: Run, want: Run) -> None:
    for name in (
        "run_id",
        "kind",
        "complete",
        "start_time",
        "end_time",
        "operator",
        "note",
        "software",
        "provenance",
    ):
        assert getattr(got, name) == getattr(want, name), name
    if want.instrument is None:
        assert got.instrument is None
    else:
        assert vars(got.instrument) == vars(want.instrument)
    if want.sample is None:
        assert got.sample is None
    else:
        assert vars(got.sample) == vars(want.sample)
    if want.hits is None:
        assert got.hits is None
    else:
        g, w = got.hits, want.hits
        for name in ("force_n", "response_m_s2", "accepted", "overload", "peak_force_n"):
            assert_same_array(getattr(g, name), getattr(w, name))
        for name in ("sample_rate_hz", "start_s", "center_hz", "checks"):
            assert getattr(g, name) == getattr(w, name), name
        assert list(g.reject_reason) == list(w.reject_reason)
        assert list(g.timestamp_utc) == list(w.timestamp_utc)
    for name in ("analyzer", "measured_frfs"):
        g, w = getattr(got, name), getattr(want, name)
        if w is None:
            assert g is None
            continue
        assert_same_array(g.frequency_hz, w.frequency_hz)
        assert_same_array(g.frf, w.frf)
        assert_same_array(g.coherence, w.coherence)
        assert g.labels == w.labels
        assert g.form == w.form


def add_hard_link_bomb(path, fan_out: int = 30, depth: int = 7):
    """Turn the sealed run at ``path`` into the issue's hostile file: its root then holds
    groups of ``fan_out`` hard links each to the next, ``depth`` levels deep, so a walk
    that follows every name visits fan_out**depth paths through a handful of objects."""
    import h5py

    with h5py.File(path, "r+") as f:
        level = f
        for k in range(depth):
            child = f.create_group(f"level{k}")
            for j in range(fan_out):
                level[f"n{j}"] = child
            del f[f"level{k}"]
            level = child
    return path
