"""The damping matrix R of the beam's Ritz model fitted to every point of a test at once
(docs/modal-tests.md, docs/damping.md "From several points").

Each measured point gives one FRF record whose model has the force entering at that
point's position through the Ritz functions (analysis.ritz.RitzBeam.structure); the
seed's objective in its FRF form is summed over the points (analysis.damping.multi_point).
The lines are weighted by 1 / their noise variance (from the coherence and the number
of hits) so that the residual is white and the Fisher figure means what it says.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import scipy.linalg

from analysis.damping import complex_modes, multi_point
from analysis.damping.bandlimited import BandLimitedData
from analysis.damping.fit_limits import noise_floor
from analysis.damping.objective import FrequencyData
from analysis.damping.stiffness import update_mode_frequencies
from analysis.ritz import RitzBeam
from daq.store import Store
from daq.workflows.article import article_beam
from daq.workflows.errors import WorkflowError
from daq.workflows.fit import PSI_CAUTION
from daq.workflows.test_analysis import TestAnalysis, aligned_shapes

METHODS = ("ls", "ga", "complex-modes")
#: Above this damping ratio the first-order complex-mode method is not trusted.
LIGHT_DAMPING = 0.05
#: Relative noise floor of a line: coherence 1 (one hit) does not mean no noise.
MIN_RELATIVE_NOISE = 1e-3


@dataclass
class TestFit:
    """R (N, N) N s/m with its standard uncertainty, how it was found and how well it fits."""

    method: str
    n_functions: int
    damping_matrix: np.ndarray
    damping_std: np.ndarray | None
    determined: list[str]
    undetermined: list[dict[str, Any]]
    std_from: str
    psi: float
    psi_noise_floor: float | None
    band_hz: tuple[float, float]
    n_points: int
    eigenvalues: np.ndarray
    cautions: list[str]


def fit_test(
    analysis: TestAnalysis, store_dir: Path, method: str = "ls", psd: bool = True, seed: int = 0
) -> TestFit:
    """Fit R to the test ``analysis`` was made of. method: "ls" (least squares from the
    proportional estimate of the identified modes), "ga" (the seed's GA, then least
    squares from its best), "complex-modes" (Adhikari and Woodhouse's first-order method,
    symmetric, from the measured complex shapes). WorkflowError (one line)."""
    if method not in METHODS:
        raise WorkflowError(f"--method must be one of {', '.join(METHODS)}, got {method!r}", exit_code=2)
    data, result = analysis.data, analysis.result
    beam = article_beam(data.test.article)
    if beam is None or not np.all(np.isfinite(data.positions_m)):
        raise WorkflowError(f"test {data.test.name}: the damping fit needs a beam article with positions")
    ritz = RitzBeam.build(beam, n_functions=3)
    n = ritz.n_functions
    fixed = data.test.fixed_point.position_m
    modes_hz = np.array([m.frequency_hz for m in result.modes])
    zetas = np.array([m.damping_ratio for m in result.modes])
    # The model's frequencies moved to the identified ones (shapes kept), as for one run.
    tip = ritz.structure()
    updated, _ = update_mode_frequencies(tip, modes_hz, zetas)
    stiffness = updated.stiffness
    band = _fit_band(result.band.low_hz, result.band.high_hz, modes_hz, ritz)
    use = (data.frequency_hz >= band[0]) & (data.frequency_hz <= band[1])
    if use.sum() < 8:
        raise WorkflowError(f"test {data.test.name}: fewer than 8 lines in {band[0]:g}-{band[1]:g} Hz to fit")
    records, cautions, kinds = [], [], set()
    store = Store(store_dir)
    for k, x in enumerate(data.positions_m):
        force_at, sensor_at = (x, fixed) if data.test.roving == "hammer" else (fixed, x)
        model = ritz.structure(force_at, sensor_at)
        model = type(model)(model.mass, stiffness, model.force_shape, model.sensor_shape)
        hits = _hits(store, data.run_ids[k])
        if hits is not None:
            # The seed's eq (17) on the raw records (no window enters the fit), the force
            # taken as the band-limited signal its samples define, as for one run.
            records.append(BandLimitedData(model, hits[0], hits[1], hits[2]))
            kinds.add("time records")
            continue
        h = data.frf[k, use]
        sigma = _noise(
            h, None if data.coherence is None else data.coherence[k, use], data.point_frfs[k].n_hits
        )
        records.append(FrequencyData(model, data.frequency_hz[use], h, 1.0 / sigma**2))
        kinds.add("FRFs")
        if data.point_frfs[k].added_decay_1_s > 0:
            cautions.append(
                f"point {data.points[k].name}: its FRF went through an exponential window; the fitted R "
                "includes the window's damping"
            )
    if kinds == {"time records", "FRFs"}:
        cautions.append("some points are time records and some FRFs: their residuals are weighted alike")
    fit_data = multi_point.MultiPointData(tuple(records), labels=tuple(p.name for p in data.points))
    start = _proportional(ritz.mass, stiffness, modes_hz, zetas)
    if method == "complex-modes":
        r, name = _from_complex_modes(analysis, ritz)
        heavy = max(m.damping_ratio for m in result.modes[:n])
        if heavy > LIGHT_DAMPING:
            cautions.append(
                f"complex-modes is a first-order method for light damping; a mode here has "
                f"{100 * heavy:.3g} % damping: its R may be far off (use --method ls)"
            )
    elif method == "ga":
        best = multi_point.fit_ga(fit_data, psd=psd, seed=seed)
        r = multi_point.fit_least_squares(fit_data, best.damping_matrix, psd=psd).damping_matrix
        name = "the seed's GA, then least squares"
    else:
        r = multi_point.fit_least_squares(fit_data, start, psd=psd).damping_matrix
        name = "least squares from the modal estimate"
    r = 0.5 * (r + r.T)
    psi = float(multi_point.multi_psi(fit_data, r))
    floor = _noise_floor(fit_data, r)
    std, determined, undetermined, std_from = None, [], [], "not estimated"
    try:
        if method == "complex-modes":
            # The Fisher figure is the least-squares fit's; the shapes' scatter is not
            # propagated through the complex-mode methods yet.
            raise ValueError(f"not propagated from the shapes for {method}")
        u = multi_point.uncertainty(fit_data, r, jackknife=True)
        std = _symmetric(u.std, n)
        determined = [nm for nm, ok in zip(u.names, u.determined, strict=True) if ok]
        undetermined = list(u.undetermined_combinations)
        std_from = "the larger of the Fisher figure and the jackknife over hits and points"
    except (ValueError, np.linalg.LinAlgError) as exc:
        cautions.append(f"no uncertainty for R: {exc}")
    eig = np.linalg.eigvalsh(r)
    if floor is not None and psi > PSI_CAUTION * floor:
        cautions.append(
            f"the model misses the data by more than its noise (Psi {psi / floor:.3g}x the noise floor): "
            "a 3-function Ritz model of this beam, or a poor measurement; R absorbs the model error"
        )
    if eig.min() < -1e-9 * max(abs(eig).max(), 1e-30):
        cautions.append("R is not positive semi-definite: not a dissipative damping matrix")
    if undetermined:
        cautions.append(
            f"{len(undetermined)} combination(s) of R's terms are not determined by these points "
            "(relative standard uncertainty above 30 %); measure more points"
        )
    return TestFit(
        name, n, r, std, determined, undetermined, std_from, psi, floor, band, len(data.points), eig, cautions
    )


def _noise_floor(data: multi_point.MultiPointData, damping: np.ndarray) -> float | None:
    """Psi (eq 17 over every record) the sensor noise alone would leave at ``damping``:
    each band-limited record's floor (analysis.damping.fit_limits.noise_floor) combined
    as multi_psi combines residuals; None when a record has none (FRFs, one hit)."""
    total = 0.0
    for rec, weight, size in zip(data.records, data.weights, data._sizes, strict=True):
        if not isinstance(rec, BandLimitedData):
            return None
        floor = noise_floor(rec.force_n, rec.response_m_s2, rec.sample_rate_hz, rec.model, damping)
        if floor is None:
            return None
        total += (weight * floor * size) ** 2
    return float(np.sqrt(total) / data.n_residuals)


def _from_complex_modes(analysis: TestAnalysis, ritz: RitzBeam) -> tuple[np.ndarray, str]:
    """R (N, N) from the test's complex shapes mapped to Ritz coordinates by Adhikari and
    Woodhouse's first-order method, symmetric variant; and the method's name.

    Lancaster's formula (analysis.damping.complex_modes.lancaster) is exact on exact modes
    but needs the residues' small real parts right; on the simulated seed beam the
    measured ones are a few degrees off and its R came out far from the truth (Psi 6x
    the noise floor), so the command line does not offer it."""
    data, result = analysis.data, analysis.result
    n = ritz.n_functions
    if len(result.modes) < n or len(data.points) < n:
        raise WorkflowError(
            f"test {data.test.name}: complex-modes needs {n} modes at {n} points or more, found "
            f"{len(result.modes)} modes at {len(data.points)} points"
        )
    poles = np.array([_pole(m.frequency_hz, m.damping_ratio) for m in result.modes[:n]])
    basis = ritz.shapes(data.positions_m).T
    try:
        found = complex_modes.identify(
            poles, aligned_shapes(analysis)[:n].T, basis, ritz.mass, "adhikari_woodhouse_symmetric"
        )
    except ValueError as exc:
        raise WorkflowError(f"test {data.test.name}: complex modes: {exc}") from None
    return found.damping_matrix, "adhikari-woodhouse (symmetric), from the complex modes"


def _hits(store: Store, run_id: str) -> tuple[np.ndarray, np.ndarray, float] | None:
    """(force (n_hits, n_samples) N, response m/s^2, sample rate Hz) of the run's accepted
    baseband hits; None for a run of FRFs or zoom records."""
    run = store.open(run_id)
    if run.hits is None or not run.hits.accepted.any() or run.hits.center_hz:
        return None
    ok = run.hits.accepted
    return run.hits.force_n[ok], run.hits.response_m_s2[ok], float(run.hits.sample_rate_hz)


def _fit_band(low: float, high: float, modes_hz: np.ndarray, ritz: RitzBeam) -> tuple[float, float]:
    """The analysed band cut above the model's modes: halfway from its last mode to the
    next identified one (a 3-function model cannot follow a 4th mode)."""
    n = ritz.n_functions
    if modes_hz.size > n:
        high = min(high, 0.5 * (modes_hz[n - 1] + modes_hz[n]))
    return float(low), float(high)


def _noise(h: np.ndarray, coherence: np.ndarray | None, n_hits: int) -> np.ndarray:
    """Standard deviation of each line's real (and imaginary) part, (m/s^2)/N: H1's
    random error |H| sqrt(1 - g^2) / (|g| sqrt(2 n)) (Bendat and Piersol, Random Data,
    eq 9.90), floored at MIN_RELATIVE_NOISE |H|."""
    mag = np.abs(h)
    floor = MIN_RELATIVE_NOISE * np.maximum(mag, np.median(mag))
    if coherence is None or n_hits < 2:
        return floor
    g2 = np.clip(np.nan_to_num(coherence, nan=0.0), 1e-6, 1.0)
    sigma = mag * np.sqrt((1.0 - g2) / (2.0 * n_hits * g2))
    return np.maximum(sigma, floor)


def _proportional(
    mass: np.ndarray, stiffness: np.ndarray, modes_hz: np.ndarray, zetas: np.ndarray
) -> np.ndarray:
    """R = M Phi diag(2 zeta_r w_r) Phi^T M from the identified damping of the model's
    modes (nearest identified mode each), N s/m: the start of the least squares."""
    omega_sq, phi = scipy.linalg.eigh(stiffness, mass)
    omega = np.sqrt(np.maximum(omega_sq, 0.0))
    zeta = np.empty_like(omega)
    for r, w in enumerate(omega):
        zeta[r] = zetas[int(np.argmin(np.abs(modes_hz - w / (2 * np.pi))))] if zetas.size else 0.01
    return mass @ phi @ np.diag(2.0 * zeta * omega) @ phi.T @ mass


def _pole(frequency_hz: float, damping_ratio: float) -> complex:
    w = 2 * np.pi * frequency_hz
    return complex(-damping_ratio * w, w * np.sqrt(max(1.0 - damping_ratio**2, 0.0)))


def _symmetric(upper: np.ndarray, n: int) -> np.ndarray:
    out = np.zeros((n, n))
    out[np.triu_indices(n)] = upper
    return out + np.triu(out, 1).T


def test_fit_json(fit: TestFit) -> dict[str, Any]:
    """The JSON of `daq test fit --json`."""
    std = None if fit.damping_std is None else fit.damping_std.tolist()
    return {
        "method": fit.method,
        "ritz_functions": fit.n_functions,
        "damping_matrix": fit.damping_matrix.tolist(),
        "damping_matrix_u": std,
        "uncertainty_from": fit.std_from,
        "determined_terms": fit.determined,
        "undetermined_combinations": fit.undetermined,
        "psi": fit.psi,
        "psi_noise_floor": fit.psi_noise_floor,
        "band_hz": list(fit.band_hz),
        "n_points": fit.n_points,
        "eigenvalues": fit.eigenvalues.tolist(),
        "cautions": fit.cautions,
    }
