"""One point of a multi-point test: the FRF its run measured, in one form for every point.

A roving-hammer test joins one run per point; the test's analysis needs each run's FRF
on the same lines, with its coherence, each hit's own FRF (for the scatter over hits),
and the decay the response window added (to take it out of the poles). Time records
are turned into H1 with the run's own windows (daq/workflows/analysis.py window_specs);
runs that hold FRFs only (imported files, the analyzer's average) give those.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from analysis.pretrigger import cut_at_impact, impact_starts
from analysis.spectra import convert_form, frf_estimate, linear_spectra, per_hit_frf
from analysis.windows import added_decay_rate
from daq.store import Run
from daq.workflows.analysis import window_specs


@dataclass
class PointFrf:
    """frequency_hz (n_lines,) Hz; frf (n_lines,) complex accelerance, (m/s^2)/N, with the
    exponential window's gain at the pulse undone (its added decay is still in the poles);
    coherence (n_lines,) or None; per_hit (n_hits, n_lines) complex or None (FRF-only
    runs); added_decay_1_s: the exponential window's decay in the poles, 1/s;
    source: "hits", "measured_frf" or "analyzer"; force_autospectrum (n_lines,) the
    averaged force autospectrum, N^2 s^2 (hits only: the band choice reads it);
    impact_starts (n_hits,) the sample each accepted hit's pulse starts at, for hits
    without windows at baseband (analysis.pretrigger; else None), in records of n_samples
    at sample_rate_hz, as measured (before any cut)."""

    frequency_hz: np.ndarray
    frf: np.ndarray
    coherence: np.ndarray | None
    per_hit: np.ndarray | None
    added_decay_1_s: float
    source: str
    force_autospectrum: np.ndarray | None = None
    impact_starts: np.ndarray | None = None
    n_samples: int = 0
    sample_rate_hz: float = 0.0

    @property
    def n_hits(self) -> int:
        return 0 if self.per_hit is None else int(self.per_hit.shape[0])


def point_frf(run: Run, n_keep: int | None = None) -> PointFrf:
    """The H1 FRF over the run's accepted hits, else the first FRF the run holds.
    n_keep: hits without windows are cut at their impacts to this many samples first
    (analysis.pretrigger.cut_at_impact; a multi-point test cuts every point to one length,
    so that they keep one frequency axis). Raises ValueError (one line) when the run has
    neither hits nor an FRF."""
    if run.hits is not None and run.hits.accepted.any():
        force_window, response_window, _ = window_specs(run)
        accepted = run.hits.accepted
        force, response = run.hits.force_n[accepted], run.hits.response_m_s2[accepted]
        unwindowed = force_window.kind == response_window.kind == "uniform"
        starts = None
        if unwindowed and run.hits.center_hz == 0 and np.isrealobj(force):
            starts = impact_starts(force)
            if n_keep is not None:
                force, response = cut_at_impact(force, response, starts, n_keep)
        spectra = linear_spectra(
            force, response, run.hits.sample_rate_hz, force_window, response_window, run.hits.center_hz,
        )  # fmt: skip
        estimate = frf_estimate(spectra)
        decay = added_decay_rate(response_window) - added_decay_rate(force_window)
        # The response's exponential window, counted from the record's start, scales the
        # FRF by its value at the pulse (analysis/damping/windowed_frf.py): undone here so
        # that residues, and shapes scaled to unit modal mass, keep their size.
        gain = float(np.exp(decay * max(0.0, -float(run.hits.start_s))))
        return PointFrf(
            estimate.frequency_hz, gain * estimate.h1, estimate.coherence, gain * per_hit_frf(spectra),
            float(decay), "hits", estimate.g_ff, starts, int(run.hits.force_n.shape[1]),
            float(run.hits.sample_rate_hz),
        )  # fmt: skip
    frfs = run.measured_frfs if run.measured_frfs is not None else run.analyzer
    if frfs is None:
        raise ValueError(f"run {run.run_id} has no accepted hit and no FRF")
    source = "measured_frf" if run.measured_frfs is not None else "analyzer"
    frf = frfs.frf[0]
    form = getattr(frfs, "form", "accelerance")
    if form != "accelerance":
        frf = convert_form(frf, frfs.frequency_hz, "accelerance", form)
    coherence = None if frfs.coherence is None else frfs.coherence[0]
    # The analyzer's windows, or those the importer read from the file (stated, not undone).
    _, response_window, _ = window_specs(run)
    decay = added_decay_rate(response_window)
    return PointFrf(frfs.frequency_hz, frf, coherence, None, float(decay), source)


def stack_points(
    names: list[str], points: list[PointFrf]
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """(frequency_hz (n_lines,), frf (n_points, n_lines), coherence (n_points, n_lines) or
    None) of points measured on the same lines. Raises ValueError naming the first point
    whose lines differ: a test's FRFs are one data set only on one frequency axis."""
    if not points:
        raise ValueError("no measured point to analyse")
    f0 = points[0].frequency_hz
    for name, point in zip(names, points, strict=True):
        f = point.frequency_hz
        if f.shape != f0.shape or not np.allclose(f, f0, rtol=1e-9, atol=1e-12):
            raise ValueError(
                f"point {name} was measured on other lines ({f.size} lines, {f[0]:g}-{f[-1]:g} Hz) than "
                f"point {names[0]} ({f0.size} lines, {f0[0]:g}-{f0[-1]:g} Hz): measure every point with "
                "one setup"
            )
    frf = np.stack([p.frf for p in points])
    if all(p.coherence is not None for p in points):
        coherence = np.stack([p.coherence for p in points])
    else:
        coherence = None
    return np.asarray(f0, dtype=float), frf, coherence
