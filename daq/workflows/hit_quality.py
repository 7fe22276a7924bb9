"""What the page shows of one hit's quality: the windows the analysis applies, the force
spectrum against the tip check's roll-off limit, the hit's own FRF, and the running
average as it stood after the hit. A pure view over the records (numpy); the numbers
come from analysis/ (windows, spectra, the check's constants), never computed twice.

Shapes and units (n = samples of a record, m = lines up to the span):

- ``force_window``, ``response_window`` : (n,) 0..1 on the record's time axis
  (sample i at ``start_s + i / sample_rate_hz``), the windows of the analyzer's
  settings as the analysis applies them (daq/workflows/analysis.py ``window_specs``).
- ``force_spectrum`` : the force auto-spectrum exactly as the tip check sees it
  (analysis/hit_checks.py ``force_rolloff``: the unwindowed record's |DFT|^2),
  ``frequency_hz`` (m,) Hz and ``level_db`` (m,) dB relative to its mean over the
  lowest BAND_FRACTION of the span (DC excluded; so that band averages 0 dB in power).
  The check fails when the mean power over the top band, from ``rolloff_hz`` to the top
  of the span, is more than ``-rolloff_limit_db`` dB below: ``rolloff_limit_db`` is
  -MAX_DROP_DB (-10 dB). ``drop_db`` is the check's value. In zoom (complex records)
  the band is centre +- span/2 and ``rolloff_hz`` is the top band's lower edge there too.
- ``frf`` : this hit alone, H1 = A/F with the windows, ``frequency_hz`` (m,) Hz,
  ``magnitude`` (m,) (m/s^2)/N, ``phase_deg`` (m,) degrees.
- ``average`` : H1 and coherence (0..1) over the accepted hits up to and including this
  one (``n_averaged`` of them); None when none was accepted by then.
"""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import numpy as np

from analysis.hit_checks import BAND_FRACTION, MAX_DROP_DB
from analysis.spectra import frf_estimate, linear_spectra
from analysis.windows import WindowSpec, window


def _window_specs(settings: dict[str, Any]) -> tuple[WindowSpec, WindowSpec]:
    from daq.workflows.analysis import window_specs

    force, response, _ = window_specs(SimpleNamespace(instrument=SimpleNamespace(settings=settings)))
    return force, response


def force_spectrum(
    force_n: np.ndarray, sample_rate_hz: float, span_hz: float, max_drop_db: float = MAX_DROP_DB
) -> dict[str, Any]:
    """The force auto-spectrum as the tip check computes it, in dB relative to its low
    band (see the module docstring). force_n : (n,) N, real or complex (zoom)."""
    force = np.asarray(force_n)
    if force.ndim != 1 or force.size < 2:
        raise ValueError(f"a force record must be a 1-D array of 2 or more samples, got {force.shape}")
    if not (sample_rate_hz > 0 and 0 < span_hz <= sample_rate_hz):
        raise ValueError("force spectrum needs 0 < span_hz <= sample_rate_hz")
    if np.iscomplexobj(force):
        offsets = np.fft.fftshift(np.fft.fftfreq(force.size, 1.0 / sample_rate_hz))
        power = np.fft.fftshift(np.abs(np.fft.fft(force)) ** 2)
        keep = np.abs(offsets) <= span_hz / 2
        freq, power = offsets[keep], power[keep]
        low = freq <= -span_hz / 2 + BAND_FRACTION * span_hz
        top = freq >= span_hz / 2 - BAND_FRACTION * span_hz
        rolloff_hz = span_hz / 2 - BAND_FRACTION * span_hz
    else:
        freq = np.fft.rfftfreq(force.size, 1.0 / sample_rate_hz)
        power = np.abs(np.fft.rfft(force)) ** 2
        keep = freq <= span_hz
        freq, power = freq[keep], power[keep]
        low = (freq > 0) & (freq <= BAND_FRACTION * span_hz)
        top = freq >= (1 - BAND_FRACTION) * span_hz
        rolloff_hz = (1 - BAND_FRACTION) * span_hz
    if not (low.any() and top.any()):
        raise ValueError("the record is too short to resolve the span's ends: no spectral lines there")
    reference = float(power[low].mean())
    top_mean = float(power[top].mean())
    with np.errstate(divide="ignore", invalid="ignore"):
        level_db = 10 * np.log10(power / reference) if reference > 0 else np.full(power.shape, np.nan)
        drop_db = 10 * np.log10(reference / top_mean) if reference > 0 and top_mean > 0 else None
    return {
        "frequency_hz": freq,
        "level_db": level_db,
        "rolloff_limit_db": -float(max_drop_db),
        "rolloff_hz": float(rolloff_hz),
        "low_band_hz": [float(freq[low][0]), float(freq[low][-1])],
        "drop_db": drop_db,
    }


def hit_quality(
    settings: dict[str, Any],
    records: list[tuple[np.ndarray, np.ndarray]],
    accepted: list[bool | None],
    index: int,
    sample_rate_hz: float,
    center_hz: float = 0.0,
) -> dict[str, Any]:
    """The quality view of hit ``index`` (see the module docstring).

    settings : the analyzer's settings as a run stores them (setup_codec.settings_to_dict).
    records : every hit's (force_n, response_m_s2), each (n,), N and m/s^2.
    accepted : each hit's verdict (None while undecided), len(records).
    """
    if not 0 <= index < len(records):
        raise IndexError(f"no hit {index}")
    force, response = records[index]
    n = np.asarray(force).size
    force_spec, response_spec = _window_specs(settings)
    span_hz = float(settings.get("span_hz") or sample_rate_hz / 2.56)
    spectra = linear_spectra(force, response, sample_rate_hz, force_spec, response_spec, center_hz=center_hz)
    single = frf_estimate(spectra)
    out: dict[str, Any] = {
        "force_window": window(force_spec, n, sample_rate_hz),
        "response_window": window(response_spec, n, sample_rate_hz),
        "force_spectrum": force_spectrum(force, sample_rate_hz, span_hz),
        "frf": {
            "frequency_hz": single.frequency_hz,
            "magnitude": np.abs(single.h1),
            "phase_deg": np.degrees(np.angle(single.h1)),
        },
        "average": None,
    }
    chosen = [i for i in range(index + 1) if accepted[i]]
    if chosen:
        f = np.stack([records[i][0] for i in chosen])
        r = np.stack([records[i][1] for i in chosen])
        est = frf_estimate(
            linear_spectra(f, r, sample_rate_hz, force_spec, response_spec, center_hz=center_hz)
        )
        out["average"] = {
            "frequency_hz": est.frequency_hz,
            "magnitude": np.abs(est.h1),
            "phase_deg": np.degrees(np.angle(est.h1)),
            "coherence": est.coherence,
            "n_averaged": len(chosen),
        }
    return out
