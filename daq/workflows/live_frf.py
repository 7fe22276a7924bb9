"""The running average a technician watches during a capture: H1 and coherence over the
hits accepted so far, with the windows the analysis will use."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import numpy as np


def live_frf(
    settings: dict[str, Any],
    records: list[tuple[np.ndarray, np.ndarray]],
    sample_rate_hz: float,
    center_hz: float,
) -> dict[str, Any]:
    """H1 and coherence over the accepted hits so far, with the windows the analysis
    will use (the analyzer's settings). records: [(force_n, response_m_s2)] each (n,)."""
    from analysis.spectra import frf_estimate, linear_spectra
    from daq.workflows.analysis import window_specs

    force_window, response_window, _ = window_specs(
        SimpleNamespace(instrument=SimpleNamespace(settings=settings))
    )
    force = np.stack([f for f, _ in records])
    response = np.stack([r for _, r in records])
    spectra = linear_spectra(
        force, response, sample_rate_hz, force_window, response_window, center_hz=center_hz
    )
    est = frf_estimate(spectra)
    return {
        "n_averaged": len(records),
        "frequency_hz": est.frequency_hz,
        "frf_abs": np.abs(est.h1),
        "frf_phase_deg": np.degrees(np.angle(est.h1)),
        "coherence": est.coherence,
    }
