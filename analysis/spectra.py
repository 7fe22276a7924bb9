"""Linear spectra of impact-test records and the averaged FRF estimators. Pure numpy/scipy.

Records are the analyzer's time records, (n_hits, n_samples): float64 at baseband, or
complex128 in zoom (the complex envelope of the band mixed down by ``center_hz``;
each real sinusoid appears as one complex exponential of half its amplitude).
Force in N, response (acceleration) in m/s^2.

Scaling. :class:`Spectra` holds peak linear spectra like the analyzer's LSP display:
a sinusoid of amplitude X that sits on a line reads |X| there. For a window w that is
2 / sum(w) times the DFT of the windowed record, 1 / sum(w) at baseband DC and Nyquist
(a real record's DFT there carries the whole sinusoid, not half of it).

The FRF estimators do not use that scaling: a hammer test pairs different windows on
the two channels (force window, exponential window), and peak scaling would multiply
A/F by sum(w_force)/sum(w_response), a bias a transient must not get. The analyzer
averages unscaled spectra for this reason (sims/dsp.py). Here the averages are built
from the windowed records' Fourier transforms, X(f) = dt * DFT(x w): the same factor
on both channels (so H1 = G_fa/G_ff is the unscaled ratio, as the analyzer's), and for
a transient that lies inside the record, X(f) is its continuous Fourier transform, so
the auto spectra have units N^2 s^2 and (m/s^2)^2 s^2 (energy spectra). pyFRF's H1
multiplies by the ratio of its windows' amplitude corrections instead: with different
windows on the two channels its FRF differs from ours (and the analyzer's) by that
constant.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.fft

from analysis.windows import WindowSpec, window

#: Sample rate per analysed bandwidth: the anti-alias filter leaves 0..fs/2.56 (baseband)
#: or center +- fs/2.56 (zoom, complex records at 1.28 x span) free of aliases.
ALIAS_FREE_FACTOR = 2.56

#: Exponent of j omega in each FRF form: X = H F with X displacement, velocity, acceleration.
_FORM_POWER = {"receptance": 0, "mobility": 1, "accelerance": 2}


@dataclass
class Spectra:
    """Peak linear spectra of every hit on the analysed lines.

    frequency_hz : (n_lines,) Hz, ascending.
    force : (n_hits, n_lines) complex, N peak (a sinusoid on a line reads its amplitude).
    response : (n_hits, n_lines) complex, m/s^2 peak.
    force_scale, response_scale : (n_lines,) the factor from the DFT of the windowed
        record to ``force`` / ``response`` (2 / sum(w), see the module docstring); None
        when the spectra were built elsewhere and need no correction (taken as 1).
    sample_rate_hz : Hz, for the Fourier-transform scaling dt = 1 / fs of the averages;
        None takes dt = 1.
    """

    frequency_hz: np.ndarray
    force: np.ndarray
    response: np.ndarray
    force_scale: np.ndarray | None = None
    response_scale: np.ndarray | None = None
    sample_rate_hz: float | None = None


@dataclass
class FrfEstimate:
    """Averaged FRF estimators over the selected hits.

    frequency_hz : (n_lines,) Hz.
    h1, h2, hv : (n_lines,) complex accelerance, (m/s^2)/N. NaN on lines where the
        estimator's denominator is 0 (e.g. no force: G_ff == 0).
    coherence : (n_lines,) ordinary coherence |G_fa|^2 / (G_ff G_aa), 0..1; NaN where
        G_ff G_aa == 0.
    g_ff : (n_lines,) averaged force auto spectrum, real, N^2 s^2.
    g_aa : (n_lines,) averaged response auto spectrum, real, (m/s^2)^2 s^2.
    g_fa : (n_lines,) averaged cross spectrum mean(conj(F) A), complex, N (m/s^2) s^2.
    n_averages : hits averaged.
    (G are averages of the windowed records' Fourier transforms dt * DFT(x w), see the
    module docstring; H1 = g_fa / g_ff exactly.)
    """

    frequency_hz: np.ndarray
    h1: np.ndarray
    h2: np.ndarray
    hv: np.ndarray
    coherence: np.ndarray
    g_ff: np.ndarray
    g_aa: np.ndarray
    g_fa: np.ndarray
    n_averages: int


def _records(name: str, values: np.ndarray) -> np.ndarray:
    records = np.asarray(values)
    if records.ndim == 1:
        records = records[np.newaxis, :]  # one hit
    if records.ndim != 2 or records.shape[0] < 1 or records.shape[1] < 2:
        raise ValueError(
            f"{name} must be (n_hits, n_samples) with at least 1 hit of 2 samples, got shape {records.shape}"
        )
    if not any(np.issubdtype(records.dtype, kind) for kind in (np.floating, np.complexfloating, np.integer)):
        raise ValueError(f"{name} must be real or complex numbers, got dtype {records.dtype}")
    if not np.all(np.isfinite(records)):
        raise ValueError(f"{name} contains NaN or inf samples")
    return records


def _peak_scale(win: np.ndarray, offsets: np.ndarray, n_samples: int, zoom: bool) -> np.ndarray:
    """2 / sum(w) per line; 1 / sum(w) on a real record's DC and Nyquist lines. (n_lines,)."""
    scale = np.full(offsets.size, 2.0 / float(win.sum()))
    if not zoom:
        # DC and (even n) Nyquist have no mirrored negative-frequency twin in a real record.
        single = (offsets == 0) | ((n_samples % 2 == 0) & (offsets == n_samples // 2))
        scale[single] /= 2.0
    return scale


def linear_spectra(
    force_n: np.ndarray,
    response_m_s2: np.ndarray,
    sample_rate_hz: float,
    force_window: WindowSpec,
    response_window: WindowSpec,
    center_hz: float = 0.0,
    max_frequency_hz: float | None = None,
) -> Spectra:
    """Windowed, peak-scaled linear spectra of every hit.

    force_n : (n_hits, n_samples) N; response_m_s2 : (n_hits, n_samples) m/s^2. Both real
        (baseband) or both complex (zoom); a 1-D record is taken as one hit.
    sample_rate_hz : Hz (2.56 x span at baseband, 1.28 x span in zoom on the HP analyzer).
    force_window, response_window : each channel's window (analysis.windows).
    center_hz : 0 at baseband; the zoom band's center, Hz (> 0) for complex records.
    max_frequency_hz : baseband: the top line kept, Hz, default sample_rate / 2.56 (the
        alias-free band: 1024 samples -> 401 lines 0..span). Zoom: the top of the band,
        default center + sample_rate / 2.56; lines center +- (max - center) are kept
        (512 samples at 1.28 x span -> 401 lines over center +- span/2).
    Returns :class:`Spectra` with (n_lines,) frequency_hz.
    """
    force = _records("force_n", force_n)
    response = _records("response_m_s2", response_m_s2)
    if force.shape != response.shape:
        raise ValueError(
            f"force and response records must have the same shape, got {force.shape} and {response.shape}"
        )
    zoom = np.iscomplexobj(force)
    if zoom != np.iscomplexobj(response):
        raise ValueError("force and response must both be real (baseband) or both complex (zoom) records")
    if not (math.isfinite(sample_rate_hz) and sample_rate_hz > 0):
        raise ValueError(f"sample_rate_hz must be finite and > 0 Hz, got {sample_rate_hz}")
    if not math.isfinite(center_hz):
        raise ValueError(f"center_hz must be finite, got {center_hz}")
    if zoom and not center_hz > 0:
        raise ValueError("complex (zoom) records need center_hz > 0, the frequency they were mixed down by")
    if not zoom and center_hz != 0:
        raise ValueError(
            f"real records are baseband: center_hz must be 0, got {center_hz} (zoom records are complex)"
        )
    n_samples = force.shape[1]
    df = sample_rate_hz / n_samples
    half_band = sample_rate_hz / ALIAS_FREE_FACTOR
    if max_frequency_hz is not None:
        if not math.isfinite(max_frequency_hz):
            raise ValueError(f"max_frequency_hz must be finite, got {max_frequency_hz}")
        half_band = max_frequency_hz - center_hz
        if not 0 < half_band <= sample_rate_hz / 2:
            where = "center_hz < max_frequency_hz <= center_hz + " if zoom else "0 < max_frequency_hz <= "
            raise ValueError(f"need {where}sample_rate_hz / 2, got max_frequency_hz = {max_frequency_hz} Hz")
    # Lines are whole bins; the small slack keeps fs/2.56 on its line despite rounding.
    k_max = math.floor(half_band / df * (1 + 1e-12) + 1e-9)

    w_force = window(force_window, n_samples, sample_rate_hz)
    w_response = window(response_window, n_samples, sample_rate_hz)
    if zoom:
        if center_hz - k_max * df < -1e-9 * sample_rate_hz:
            raise ValueError(
                f"the zoom band center_hz +- {k_max * df:g} Hz reaches below 0 Hz (center_hz = {center_hz})"
            )
        # Bins -k_max..k_max of the full FFT; an even record has no +n/2 bin, so the
        # top is clipped there (only when the whole Nyquist band is asked for).
        offsets = np.arange(-k_max, min(k_max, (n_samples - 1) // 2) + 1)
        index = np.mod(offsets, n_samples)  # negative bins live at the end of an unshifted FFT

        def lines(records: np.ndarray, win: np.ndarray) -> np.ndarray:
            return scipy.fft.fft(records * win, axis=-1)[:, index]

    else:
        offsets = np.arange(min(k_max, n_samples // 2) + 1)

        def lines(records: np.ndarray, win: np.ndarray) -> np.ndarray:
            return scipy.fft.rfft(records * win, axis=-1)[:, : offsets.size]

    force_scale = _peak_scale(w_force, offsets, n_samples, zoom)
    response_scale = _peak_scale(w_response, offsets, n_samples, zoom)
    return Spectra(
        frequency_hz=center_hz + offsets * df,
        force=lines(force, w_force) * force_scale,
        response=lines(response, w_response) * response_scale,
        force_scale=force_scale,
        response_scale=response_scale,
        sample_rate_hz=float(sample_rate_hz),
    )


def _transforms(spectra: Spectra) -> tuple[np.ndarray, np.ndarray]:
    """Fourier transforms dt * DFT(x w) of the windowed records, (n_hits, n_lines) each."""
    force = np.asarray(spectra.force)
    response = np.asarray(spectra.response)
    n_lines = np.asarray(spectra.frequency_hz).shape
    if force.ndim != 2 or force.shape != response.shape or force.shape[1:] != n_lines:
        raise ValueError(
            "spectra.force and spectra.response must be (n_hits, n_lines) matching frequency_hz "
            f"{n_lines}, got {force.shape} and {response.shape}"
        )
    dt = 1.0 / spectra.sample_rate_hz if spectra.sample_rate_hz else 1.0
    # Undo the peak scaling (window sums) channel by channel; a common dt keeps A/F as the analyzer's.
    if spectra.force_scale is not None:
        force = force * (dt / np.asarray(spectra.force_scale))
    elif dt != 1.0:
        force = force * dt
    if spectra.response_scale is not None:
        response = response * (dt / np.asarray(spectra.response_scale))
    elif dt != 1.0:
        response = response * dt
    return force, response


def _divide(numerator: np.ndarray, denominator: np.ndarray) -> np.ndarray:
    """numerator / denominator, NaN (without a warning) where the denominator is 0."""
    dtype = np.result_type(numerator, denominator, np.float64)
    out = np.full(np.broadcast_shapes(np.shape(numerator), np.shape(denominator)), np.nan, dtype=dtype)
    return np.divide(numerator, denominator, out=out, where=denominator != 0)


def _selected(hits: np.ndarray | None, n_hits: int) -> np.ndarray | slice:
    if hits is None:
        return slice(None)
    chosen = np.asarray(hits)
    if chosen.dtype == bool:
        if chosen.shape != (n_hits,):
            raise ValueError(f"a boolean hit mask must have shape ({n_hits},), got {chosen.shape}")
        chosen = np.flatnonzero(chosen)
    elif chosen.ndim != 1 or (chosen.size and not np.issubdtype(chosen.dtype, np.integer)):
        raise ValueError(f"hits must be a 1-D array of hit indices or a boolean mask, got {chosen!r}")
    if chosen.size == 0:
        raise ValueError("no hits selected: an average needs at least one hit")
    if chosen.min() < 0 or chosen.max() >= n_hits:
        raise ValueError(f"hit indices must be in 0..{n_hits - 1}, got {chosen.tolist()}")
    if np.unique(chosen).size != chosen.size:
        raise ValueError(f"a hit index is repeated in {chosen.tolist()}: each hit counts once")
    return chosen


def frf_estimate(spectra: Spectra, hits: np.ndarray | None = None) -> FrfEstimate:
    """H1, H2, Hv and coherence averaged over the selected hits.

    spectra : from :func:`linear_spectra`.
    hits : indices or a boolean mask over spectra's hits; None averages them all.

    H1 = G_fa / G_ff (noise on the response), H2 = G_aa / G_af with G_af = conj(G_fa)
    (noise on the force), Hv the total-least-squares estimator (noise on both, equal
    weight in N and m/s^2). Hv is the eigenvector of the smallest eigenvalue of the
    Hermitian cross-spectral matrix [[G_ff, G_af], [G_fa, G_aa]] (Allemang, UC-SDRL
    "Experimental Modal Analysis" notes, Hv estimator; Shin & Hammond, "Fundamentals of
    Signal Processing for Sound and Vibration Engineers", Wiley 2008, p. 293, H_W with
    kappa = 1): with lambda_min = (G_ff + G_aa - D) / 2, D = sqrt((G_ff - G_aa)^2 +
    4 |G_fa|^2), the eigenvector gives Hv = G_fa / (G_ff - lambda_min)
    = 2 G_fa / (G_ff - G_aa + D) = (G_aa - G_ff + D) / (2 G_af). The two closed forms
    are equal; each line uses the one without cancellation (the first where
    G_ff >= G_aa, the second elsewhere; D >= |G_ff - G_aa| keeps both denominators >= 0).
    """
    force, response = _transforms(spectra)
    rows = _selected(hits, force.shape[0])
    force, response = force[rows], response[rows]
    n_averages = force.shape[0]
    g_ff = np.mean(force.real**2 + force.imag**2, axis=0)
    g_aa = np.mean(response.real**2 + response.imag**2, axis=0)
    g_fa = np.mean(np.conj(force) * response, axis=0)
    g_af = np.conj(g_fa)
    has_force = g_ff > 0

    h1 = _divide(g_fa, g_ff)
    h2 = _divide(g_aa, g_af)
    root = np.sqrt((g_ff - g_aa) ** 2 + 4.0 * (g_fa.real**2 + g_fa.imag**2))
    force_larger = g_ff >= g_aa
    hv = np.where(
        force_larger,
        _divide(2.0 * g_fa, np.where(force_larger, g_ff - g_aa + root, 0.0)),
        _divide((g_aa - g_ff + root).astype(complex), np.where(force_larger, 0.0, 2.0 * g_af)),
    )
    hv = np.where(has_force, hv, np.nan)
    coherence = _divide(g_fa.real**2 + g_fa.imag**2, g_ff * g_aa)
    return FrfEstimate(
        frequency_hz=np.array(spectra.frequency_hz, dtype=np.float64),
        h1=h1,
        h2=h2,
        hv=hv,
        coherence=coherence,
        g_ff=g_ff,
        g_aa=g_aa,
        g_fa=g_fa,
        n_averages=int(n_averages),
    )


def per_hit_frf(spectra: Spectra) -> np.ndarray:
    """Each hit's own FRF A/F, (n_hits, n_lines) complex (m/s^2)/N; NaN where F == 0.

    Uses the same window-sum-free spectra as :func:`frf_estimate` (one hit's H1 is this).
    """
    force, response = _transforms(spectra)
    return _divide(response, force)


def convert_form(
    frf: np.ndarray, frequency_hz: np.ndarray, to: str, from_form: str = "accelerance"
) -> np.ndarray:
    """Convert an FRF between accelerance, mobility and receptance.

    frf : (..., n_lines) complex FRF in ``from_form`` ((m/s^2)/N, (m/s)/N or m/N).
    frequency_hz : (n_lines,) Hz.
    Returns (..., n_lines) complex in ``to``: each step from accelerance towards
    receptance divides by j omega (omega = 2 pi f), each step back multiplies. Where a
    division meets omega = 0 (the DC line) the result is NaN, not inf: the static term
    cannot be recovered from acceleration or velocity.
    """
    for name, form in (("to", to), ("from_form", from_form)):
        if form not in _FORM_POWER:
            raise ValueError(f"{name} must be one of {', '.join(_FORM_POWER)}, got {form!r}")
    values = np.asarray(frf)
    freq = np.asarray(frequency_hz, dtype=np.float64)
    if freq.ndim != 1 or values.ndim < 1 or values.shape[-1] != freq.size:
        raise ValueError(
            f"frf's last axis must match frequency_hz: got shapes {values.shape} and {freq.shape}"
        )
    power = _FORM_POWER[to] - _FORM_POWER[from_form]
    jw = 2j * np.pi * freq
    if power >= 0:
        return values * jw**power
    return _divide(values.astype(complex), jw ** (-power))
