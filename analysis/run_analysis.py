"""One run's analysis from its arrays: FRFs averaged over the accepted hits, modes
found from the stability diagram, the damping the exponential window adds taken out,
the scatter of each mode over the hits, and the seed's Table 2 beside the result.

Pure: arrays and small dataclasses in, results out. daq/analysis_store.py reads runs,
calls this and stores what it returns beside the run.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np

from analysis.modal_id import ModalResult, identify_modes
from analysis.modal_id.lscf import lscf_poles
from analysis.spectra import frf_estimate, linear_spectra, per_hit_frf
from analysis.windows import WindowSpec, added_decay_rate, correct_pole

ESTIMATORS = ("h1", "h2", "hv")
#: A mode of one hit is the run's mode when its frequency is this close (relative).
HIT_MATCH_TOLERANCE = 0.03
#: A mode found for a frequency of interest must lie this close to it (relative).
FREQUENCY_OF_INTEREST_TOLERANCE = 0.05
#: Consecutive LSCF orders each hit is fitted at for the scatter (their median is kept).
SCATTER_ORDERS = 11


@dataclass(frozen=True)
class AnalysisOptions:
    """What the user may choose.

    band_hz : (low, high) Hz to identify in; None = every line but DC.
    max_order : highest LSCF model order of the stability diagram.
    frequencies_hz : frequencies of interest; None = let the stability diagram decide.
    estimator : "h1", "h2" or "hv" (hits only; FRFs read from a file are used as they are).
    per_hit : also identify every accepted hit alone, for the scatter of each mode.
    """

    band_hz: tuple[float, float] | None = None
    max_order: int = 40
    frequencies_hz: tuple[float, ...] | None = None
    estimator: str = "h1"
    per_hit: bool = True

    def __post_init__(self) -> None:
        if self.estimator not in ESTIMATORS:
            raise ValueError(f"estimator must be one of {', '.join(ESTIMATORS)}, got {self.estimator!r}")
        if not 2 <= int(self.max_order) <= 200:
            raise ValueError(f"max_order must be 2..200, got {self.max_order}")
        if self.band_hz is not None:
            low, high = (float(v) for v in self.band_hz)
            if not (np.isfinite(low) and np.isfinite(high) and 0 <= low < high):
                raise ValueError(f"band must be two frequencies 0 <= low < high, got {self.band_hz}")


@dataclass
class ModeEstimate:
    """One identified mode as reported.

    frequency_hz, damping_ratio : undamped natural frequency (Hz) and damping ratio,
        with the exponential window's added decay removed.
    damping_ratio_windowed : the ratio as seen through the windows (before correction).
    modal_constant : (n_frf,) complex residue of the run's FRF, (m/s^2)/N x rad/s.
    frequency_std_hz, damping_std : sample standard deviation over the accepted hits
        identified one by one (NaN with fewer than 2 hits matched).
    n_hits_matched : hits in which this mode was found again.
    quality : from the stability diagram (orders stable, scatter, synthesis share).
    """

    frequency_hz: float
    damping_ratio: float
    damping_ratio_windowed: float
    modal_constant: np.ndarray
    frequency_std_hz: float = float("nan")
    damping_std: float = float("nan")
    n_hits_matched: int = 0
    quality: dict = field(default_factory=dict)


@dataclass
class RunAnalysis:
    """frequency_hz : (n_lines,). frf : (n_frf, n_lines) complex accelerance, (m/s^2)/N.
    coherence : (n_frf, n_lines) or None. source : "hits", "measured_frf" or "analyzer".
    added_decay_1_s : the exponential window's decay rate removed from every pole, 1/s.
    """

    frequency_hz: np.ndarray
    frf: np.ndarray
    coherence: np.ndarray | None
    source: str
    estimator: str
    n_averages: int
    added_decay_1_s: float
    modal: ModalResult
    modes: list[ModeEstimate]


def analyze_hits(
    force_n: np.ndarray,
    response_m_s2: np.ndarray,
    sample_rate_hz: float,
    accepted: np.ndarray,
    force_window: WindowSpec,
    response_window: WindowSpec,
    center_hz: float = 0.0,
    options: AnalysisOptions | None = None,
) -> RunAnalysis:
    """Analyse time records (n_hits, n_samples), N and m/s^2, over the accepted hits."""
    options = options or AnalysisOptions()
    accepted = np.asarray(accepted, dtype=bool)
    if not accepted.any():
        raise ValueError("no accepted hit to analyse")
    spectra = linear_spectra(
        force_n[accepted], response_m_s2[accepted], sample_rate_hz, force_window, response_window, center_hz
    )
    estimate = frf_estimate(spectra)
    frf = getattr(estimate, options.estimator)[np.newaxis, :]
    # The force window multiplies a pulse it does not touch; only the response's
    # exponential window adds decay to the poles.
    decay = added_decay_rate(response_window) - added_decay_rate(force_window)
    result = _identify(estimate.frequency_hz, frf, estimate.coherence[np.newaxis, :], "hits", options, decay)
    result.n_averages = estimate.n_averages
    if options.per_hit and estimate.n_averages >= 2 and result.modes:
        _scatter(result, per_hit_frf(spectra), options, decay)
    return result


def analyze_frfs(
    frequency_hz: np.ndarray,
    frf: np.ndarray,
    coherence: np.ndarray | None,
    source: str,
    options: AnalysisOptions | None = None,
    added_decay_1_s: float = 0.0,
) -> RunAnalysis:
    """Analyse FRFs (n_frf, n_lines) read from a file or the analyzer (no FFT step)."""
    options = options or AnalysisOptions()
    frf = np.atleast_2d(np.asarray(frf, dtype=complex))
    coherence = None if coherence is None else np.atleast_2d(np.asarray(coherence, dtype=float))
    return _identify(np.asarray(frequency_hz, float), frf, coherence, source, options, added_decay_1_s)


def _lines(frequency_hz: np.ndarray, options: AnalysisOptions) -> np.ndarray:
    keep = np.isfinite(frequency_hz) & (frequency_hz > 0)
    if options.band_hz is not None:
        keep &= (frequency_hz >= options.band_hz[0]) & (frequency_hz <= options.band_hz[1])
    if keep.sum() < 8:
        raise ValueError(f"only {int(keep.sum())} spectral lines in the band: widen it")
    return keep


def _identify(frequency_hz, frf, coherence, source, options, decay) -> RunAnalysis:
    keep = _lines(frequency_hz, options) & np.all(np.isfinite(frf), axis=0)
    if options.frequencies_hz is not None:
        low, high = float(frequency_hz[keep].min()), float(frequency_hz[keep].max())
        outside = [f for f in options.frequencies_hz if not low <= f <= high]
        if outside:
            raise ValueError(
                f"frequencies {', '.join(f'{f:g}' for f in outside)} Hz lie outside the analysed "
                f"lines ({low:g}-{high:g} Hz)"
            )
    modal = identify_modes(
        frequency_hz[keep],
        frf[:, keep],
        max_order=options.max_order,
        frequencies_hz=options.frequencies_hz,
    )
    modes = []
    for mode in modal.modes:
        if options.frequencies_hz is not None and not any(
            abs(mode.frequency_hz - f) <= FREQUENCY_OF_INTEREST_TOLERANCE * f for f in options.frequencies_hz
        ):
            continue  # the nearest cluster to a frequency of interest, but not near it
        f_true, zeta_true = correct_pole(np.array([mode.frequency_hz]), np.array([mode.damping_ratio]), decay)
        modes.append(
            ModeEstimate(
                frequency_hz=float(f_true[0]),
                damping_ratio=float(zeta_true[0]),
                damping_ratio_windowed=float(mode.damping_ratio),
                modal_constant=np.asarray(mode.modal_constant, dtype=complex),
                quality={
                    "n_stable_orders": int(mode.quality.n_stable_orders),
                    "frequency_scatter_rel": float(mode.quality.frequency_scatter_rel),
                    "damping_scatter_rel": float(mode.quality.damping_scatter_rel),
                    "synthesis_share": float(mode.quality.synthesis_share),
                },
            )
        )
    return RunAnalysis(
        frequency_hz=frequency_hz, frf=frf, coherence=coherence, source=source, estimator=options.estimator,
        n_averages=1, added_decay_1_s=float(decay), modal=modal, modes=modes,
    )  # fmt: skip


def _scatter(result: RunAnalysis, hit_frfs: np.ndarray, options: AnalysisOptions, decay: float) -> None:
    """The spread of each mode over the accepted hits, each hit's FRF fitted alone.

    Each hit is fitted by LSCF at SCATTER_ORDERS consecutive orders from the lowest one
    at which every selected mode of the run was stable; each mode takes, at each
    order, the hit's pole nearest to it, and the median over the orders. One order
    alone makes the spread depend on which order was picked (a low order fits a weak
    mode poorly, a high one adds spurious poles); the median over a window does not.
    """
    keep = _lines(result.frequency_hz, options)
    wanted = np.array([m.frequency_hz for m in result.modes])
    first = _common_stable_order(result)
    top = min(first + SCATTER_ORDERS - 1, options.max_order)
    orders = tuple(range(max(1, top - SCATTER_ORDERS + 1), top + 1))
    found = np.full((hit_frfs.shape[0], wanted.size, 2), np.nan)
    for i, h in enumerate(hit_frfs):
        ok = keep & np.isfinite(h)
        try:
            fitted = lscf_poles(result.frequency_hz[ok], h[ok][np.newaxis, :], top, orders=orders)
        except (ValueError, np.linalg.LinAlgError):
            continue  # a hit too poor to fit alone adds nothing to the scatter
        per_order = np.full((len(orders), wanted.size, 2), np.nan)
        for o, order in enumerate(orders):
            poles = fitted.poles[order - 1]
            if poles.size == 0:
                continue
            w_n = np.abs(poles)
            f, z = correct_pole(w_n / (2 * np.pi), -poles.real / w_n, decay)
            for k, target in enumerate(wanted):
                j = int(np.argmin(np.abs(f - target)))
                if abs(f[j] - target) <= HIT_MATCH_TOLERANCE * target:
                    per_order[o, k] = f[j], z[j]
        with np.errstate(all="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN: that mode not found
            found[i] = np.nanmedian(per_order, axis=0)
    for k, mode in enumerate(result.modes):
        ok = np.isfinite(found[:, k, 0]) & np.isfinite(found[:, k, 1])
        mode.n_hits_matched = int(ok.sum())
        if ok.sum() >= 2:
            mode.frequency_std_hz = float(np.std(found[ok, k, 0], ddof=1))
            mode.damping_std = float(np.std(found[ok, k, 1], ddof=1))


def _common_stable_order(result: RunAnalysis) -> int:
    """The lowest model order of the stability diagram holding a pole of every selected
    mode (the highest order if there is none)."""
    stab = result.modal.stability
    everyone = set(range(len(result.modes)))
    for order, cluster in zip(stab.orders, stab.selected_cluster, strict=True):
        if everyone <= {int(c) for c in np.asarray(cluster)}:
            return int(order)
    return int(stab.orders[-1])
