"""The damping matrix from several measurement points: eq (17) over every point's records.

A multi-point test measures the same structure (one M, one K: the Ritz model of the
article) with the force and the sensor at several positions. Each record (a
``TimeData`` of hits or a ``FrequencyData`` FRF, analysis.damping.objective) carries
its own ``StructuralModel`` whose ``force_shape`` and ``sensor_shape`` are the Ritz
functions at that record's force and sensor positions. The fit compares every record
with the model of the same R:

    residuals = [w_1 r_1(R), w_2 r_2(R), ...]  (stacked over records),
    Psi(R) = ||residuals|| / n_total,          n_total = sum of the records' lengths,

which is eq (17) with its sum running over every sample (or FRF line) of every
point, as it already runs over every hit of one point. Least squares and the GA
minimise this same Psi; ``psi_per_record`` gives each record's own eq (17) value.
w_k (default 1) weights a record, e.g. 1 / its noise level.

Uncertainty (``uncertainty``): the Fisher (Cramer-Rao) figure sigma^2 (J^T J)^-1 at
the fit, J the stacked residual Jacobian in R's upper-triangle terms, sigma from the
residual; and the delete-one jackknife over the test's units (every hit of a time
record, every FRF record), each refitted from the fit. The stated std is the larger
of the two, term by term. ``cramer_rao_frf`` is the a-priori bound for a set of FRFs
with the noise given per line (analytic derivative of H with respect to R).

Units: R in N s/m (generalised coordinates); time residuals in m/s^2, FRF residuals
in (m/s^2)/N times sqrt(weight).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from analysis.damping import bandlimited as _bandlimited
from analysis.damping import ga as _ga
from analysis.damping import local as _local
from analysis.damping.bandlimited import BandLimitedData
from analysis.damping.identifiability import identifiability, parameter_names, parameter_scale
from analysis.damping.objective import (
    FrequencyData,
    TimeData,
    batched_residuals,
    batched_residuals_frf,
    psi,
    psi_frf,
)
from analysis.damping.result import FitResult
from analysis.structure import StructuralModel

Record = TimeData | BandLimitedData | FrequencyData

#: A term (or a combination) whose relative standard deviation exceeds this is not determined.
DETERMINED_THRESHOLD = 0.3


@dataclass(frozen=True)
class MultiPointData:
    """The records of one test, each with its own force and sensor shapes.

    records : sequence of ``TimeData`` or ``BandLimitedData`` (hits at one force/sensor
        pair; the band-limited form for records taken through an analyzer's filters,
        analysis.damping.bandlimited) or ``FrequencyData`` (one FRF), in any mix; all
        models share M (N, N, kg) and
        K (N, N, N/m), checked to 1e-9 relative.
    weights : (n_records,) >= 0 multipliers of each record's residuals, or None (all 1).
    labels : (n_records,) names (e.g. the point), or None ("0", "1", ...).
    """

    records: tuple[Record, ...]
    weights: np.ndarray | None = None
    labels: tuple[str, ...] | None = None
    _sizes: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        recs = tuple(self.records)
        if not recs:
            raise ValueError("a multi-point fit needs at least one record")
        for r in recs:
            if not isinstance(r, (TimeData, BandLimitedData, FrequencyData)):
                raise TypeError(
                    f"records must be TimeData, BandLimitedData or FrequencyData, got {type(r).__name__}"
                )
        m0, k0 = recs[0].model.mass, recs[0].model.stiffness
        for i, r in enumerate(recs[1:], start=1):
            m, k = r.model.mass, r.model.stiffness
            if m.shape != m0.shape or not (
                np.allclose(m, m0, rtol=1e-9, atol=0.0)
                and np.allclose(k, k0, rtol=1e-9, atol=1e-12 * np.abs(k0).max())
            ):
                raise ValueError(
                    f"record {i} has a different mass or stiffness matrix: one structure per test"
                )
        w = np.ones(len(recs)) if self.weights is None else np.asarray(self.weights, dtype=float)
        if w.shape != (len(recs),) or not np.all(np.isfinite(w)) or np.any(w < 0):
            raise ValueError(f"weights must be ({len(recs)},), finite and >= 0")
        labels = tuple(str(i) for i in range(len(recs))) if self.labels is None else tuple(self.labels)
        if len(labels) != len(recs):
            raise ValueError("one label per record")
        object.__setattr__(self, "records", recs)
        object.__setattr__(self, "weights", w)
        object.__setattr__(self, "labels", labels)
        object.__setattr__(self, "_sizes", np.array([_n_residuals(r) for r in recs]))

    @property
    def n_dof(self) -> int:
        return self.records[0].model.n_dof

    @property
    def n_residuals(self) -> int:
        return int(self._sizes.sum())


def _n_residuals(record: Record) -> int:
    if isinstance(record, TimeData):
        return record.n_hits * record.n_samples
    if isinstance(record, BandLimitedData):
        return record.n_compared
    return 2 * record.frequency_hz.size


def record_residuals(record: Record, damping: np.ndarray) -> np.ndarray:
    """One record's residuals for each damping matrix (B, N, N): (B, n_res)."""
    if isinstance(record, TimeData):
        return batched_residuals(record, damping)
    if isinstance(record, BandLimitedData):
        return _bandlimited.batched_residuals(record, damping)
    return batched_residuals_frf(record, damping)


def _frf_group_residuals(records: list[FrequencyData], damping: np.ndarray) -> list[np.ndarray]:
    """Residuals (B, 2 F) of FRF records sharing one frequency grid, from one batched solve.

    The records share M, K and R, so G(s) = (K + s R + s^2 M)^-1 is common: one solve per
    member and line with every record's force shape as a right-hand side, then
    H_k = s^2 sensor_k^T G force_k (the accelerance, as ``frequency_response``).
    """
    model = records[0].model
    s = 2j * np.pi * records[0].frequency_hz
    z = model.stiffness + s[None, :, None, None] * damping[:, None] + (s**2)[None, :, None, None] * model.mass
    forces = np.stack([rec.model.force_shape for rec in records], axis=-1).astype(complex)  # (N, K)
    with np.errstate(all="ignore"):
        try:
            g = np.linalg.solve(z, np.broadcast_to(forces, (*z.shape[:-2], *forces.shape)))  # (B, F, N, K)
        except np.linalg.LinAlgError:  # a singular member: fall back, member by member
            return [batched_residuals_frf(rec, damping) for rec in records]
        sensors = np.stack([rec.model.sensor_shape for rec in records])  # (K, N)
        h = (s**2)[None, :, None] * np.einsum("bfnk,kn->bfk", g, sensors)
        out = []
        for k, rec in enumerate(records):
            diff = np.sqrt(rec.weights) * (rec.frf - h[..., k])
            out.append(np.concatenate([diff.real, diff.imag], axis=-1))
    return out


def multi_batched_residuals(data: MultiPointData, damping: np.ndarray) -> np.ndarray:
    """Weighted residuals of every record, stacked in record order: (B, n_total).

    damping : (B, N, N), N s/m. Non-finite where a member is unstable or invalid. FRF
    records on one frequency grid are computed together (``_frf_group_residuals``).
    """
    r = np.asarray(damping, dtype=float)
    n = data.n_dof
    if r.ndim != 3 or r.shape[1:] != (n, n):
        raise ValueError(f"damping matrices must have shape (B, {n}, {n}), got {r.shape}")
    valid = np.all(np.isfinite(r) & (np.abs(r) < 1e100), axis=(-2, -1))
    safe = np.where(valid[:, None, None], r, 0.0)
    parts: list[np.ndarray | None] = [None] * len(data.records)
    groups: list[list[int]] = []
    for i, rec in enumerate(data.records):
        if isinstance(rec, (TimeData, BandLimitedData)):
            parts[i] = record_residuals(rec, safe)
            continue
        for group in groups:
            if np.array_equal(data.records[group[0]].frequency_hz, rec.frequency_hz):
                group.append(i)
                break
        else:
            groups.append([i])
    for group in groups:
        for i, res in zip(group, _frf_group_residuals([data.records[i] for i in group], safe), strict=True):
            parts[i] = res
    out = np.concatenate([w * p for p, w in zip(parts, data.weights, strict=True)], axis=-1)
    out[~valid] = np.nan
    return out


def multi_residuals(data: MultiPointData, damping: np.ndarray) -> np.ndarray:
    """Stacked weighted residuals of one damping matrix (N, N): (n_total,)."""
    r = np.asarray(damping, dtype=float)
    if r.ndim != 2:
        raise ValueError(f"expected one (N, N) damping matrix, got shape {r.shape}")
    return multi_batched_residuals(data, r[None])[0]


def _record_psi(record: Record, damping: np.ndarray) -> np.ndarray:
    if isinstance(record, TimeData):
        return psi(record, damping)
    if isinstance(record, BandLimitedData):
        return _bandlimited.psi(record, damping)
    return psi_frf(record, damping)


def psi_per_record(data: MultiPointData, damping: np.ndarray) -> np.ndarray:
    """Each record's own eq (17) (unweighted) for damping (..., N, N): (..., n_records)."""
    vals = [_record_psi(rec, damping) for rec in data.records]
    return np.stack([np.asarray(v, dtype=float) for v in vals], axis=-1)


def multi_psi(data: MultiPointData, damping: np.ndarray) -> np.ndarray:
    """Eq (17) over all records, ||stacked weighted residuals|| / n_total: shape (...); inf if unstable.

    Built from the records' own Psi (the fast correlation route for time data):
    sum of squares of record k = (psi_k n_k)^2.
    """
    per = psi_per_record(data, damping)
    with np.errstate(all="ignore"):
        sse = np.sum((data.weights * per * data._sizes) ** 2, axis=-1)
        value = np.sqrt(sse) / data.n_residuals
    return np.where(np.isfinite(value), value, np.inf)


def fit_least_squares(
    data: MultiPointData,
    start: np.ndarray,
    psd: bool = True,
    max_nfev: int | None = None,
) -> FitResult:
    """Least squares on the stacked residuals (analysis.damping.local.fit_least_squares).

    start : (N, N) symmetric start, N s/m (positive semi-definite when psd).
    psd : R = L L^T (dissipative, the default as for one point); False fits R's terms.
    Returns a FitResult with method "multi_point_least_squares_trf", psi the stacked
    eq (17), jacobian and residual stacked (theta in the fit's coding).
    """
    res = _local.fit_least_squares(
        lambda r: multi_residuals(data, r),
        start,
        psd=psd,
        batched_residuals=lambda r: multi_batched_residuals(data, r),
        max_nfev=max_nfev,
    )
    res.method = "multi_point_" + res.method
    return res


def fit_ga(data: MultiPointData, psd: bool = True, seed: int = 0, **ga_options) -> FitResult:
    """The seed's GA (analysis.damping.ga.fit_ga, its defaults) on the stacked eq (17).

    ga_options : bounds, population, generations, ... as ``fit_ga`` takes them.
    Method name "multi_point_ga".
    """
    res = _ga.fit_ga(lambda r: multi_psi(data, r), data.n_dof, seed=seed, psd=psd, **ga_options)
    res.method = "multi_point_ga"
    return res


def fit_de(data: MultiPointData, psd: bool = True, seed: int = 0, **de_options) -> FitResult:
    """Differential evolution (analysis.damping.local.fit_de) on the stacked eq (17); "multi_point_de"."""
    res = _local.fit_de(lambda r: multi_psi(data, r), data.n_dof, seed=seed, psd=psd, **de_options)
    res.method = "multi_point_de"
    return res


# ---------------------------------------------------------------------------------
# Uncertainty


@dataclass
class MultiPointUncertainty:
    """Uncertainty of R's upper-triangle terms from a multi-point fit or bound.

    names : ["R11", "R12", ...], P = N (N + 1) / 2 terms, row-major upper triangle.
    value : (P,) N s/m.
    scale : (P,) sqrt(|R_ii R_jj|), N s/m: what relative figures are relative to.
    std : (P,) N s/m, the stated standard uncertainty: the larger of std_fisher and
        std_jackknife term by term (std_fisher alone without a jackknife).
    relative_std : (P,) std / scale.
    std_fisher : (P,) sigma^2 (J^T J)^-1 (Cramer-Rao when sigma is the noise level).
    std_jackknife : (P,) or None, the delete-one jackknife over units.
    std_source : (P,) "fisher" or "jackknife", which figure gave std.
    determined : (P,) bool, relative_std < threshold.
    undetermined_combinations : eigen-directions of the scaled Fisher matrix whose
        relative std exceeds the threshold, worst first: {"relative_std": s,
        "combination": {name: component}} (unit vector in scaled terms, largest
        component positive): moving R by s along it changes the fit by one sigma.
    fisher_relative_std_by_direction : (P,) relative std of every eigen-direction, ascending.
    n_units : jackknife units (0 without one).
    """

    names: list[str]
    value: np.ndarray
    scale: np.ndarray
    std: np.ndarray
    relative_std: np.ndarray
    std_fisher: np.ndarray
    std_jackknife: np.ndarray | None
    std_source: list[str]
    determined: np.ndarray
    undetermined_combinations: list[dict]
    fisher_relative_std_by_direction: np.ndarray
    n_units: int = 0


def _upper(r: np.ndarray) -> np.ndarray:
    rows, cols = np.triu_indices(r.shape[-1])
    return r[..., rows, cols]


def _from_upper(theta: np.ndarray, n: int) -> np.ndarray:
    rows, cols = np.triu_indices(n)
    m = np.zeros((*theta.shape[:-1], n, n))
    m[..., rows, cols] = theta
    m[..., cols, rows] = theta
    return m


def _directions(
    white_scaled_jac: np.ndarray, names: list[str], threshold: float
) -> tuple[list[dict], np.ndarray]:
    """Eigen-directions of F = J^T J (scaled, whitened J) and their relative stds."""
    fisher = white_scaled_jac.T @ white_scaled_jac
    eig, vec = np.linalg.eigh(fisher)
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = np.where(eig > 0, 1.0 / np.sqrt(np.where(eig > 0, eig, 1.0)), np.inf)
    order = np.argsort(rel)
    combos = []
    for k in order[::-1]:
        if rel[k] <= threshold:
            continue
        v = vec[:, k] * np.sign(vec[np.argmax(np.abs(vec[:, k])), k])
        combos.append(
            {
                "relative_std": float(rel[k]),
                "combination": {n: float(c) for n, c in zip(names, v, strict=True)},
            }
        )
    return combos, rel[order]


def _assemble(
    theta: np.ndarray,
    n: int,
    white_jac: np.ndarray,
    jackknife: np.ndarray | None,
    n_units: int,
    threshold: float,
) -> MultiPointUncertainty:
    names = parameter_names(n)
    scale = parameter_scale(theta, n)
    ident = identifiability(
        white_jac, np.zeros(white_jac.shape[0]), theta, n, threshold=threshold, noise_std=1.0
    )
    std_f = ident.std
    if jackknife is None:
        std, source = std_f.copy(), ["fisher"] * theta.size
    else:
        std = np.maximum(std_f, jackknife)
        source = ["jackknife" if j > f else "fisher" for f, j in zip(std_f, jackknife, strict=True)]
    combos, by_direction = _directions(white_jac * scale, names, threshold)
    rel = std / scale
    return MultiPointUncertainty(
        names=names,
        value=theta.copy(),
        scale=scale,
        std=std,
        relative_std=rel,
        std_fisher=std_f,
        std_jackknife=jackknife,
        std_source=source,
        determined=rel < threshold,
        undetermined_combinations=combos,
        fisher_relative_std_by_direction=by_direction,
        n_units=n_units,
    )


def frf_jacobian(
    model: StructuralModel, damping: np.ndarray, frequencies_hz: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Accelerance H (F,) and its analytic derivative dH/dtheta (F, P) w.r.t. R's upper triangle.

    H(s) = s^2 b_s^T G b_f with G = (K + s R + s^2 M)^-1, s = j 2 pi f, so
    dH/dR_ab = -s^3 (G b_s)_a (G b_f)_b and a symmetric off-diagonal term adds (a, b)
    and (b, a). Units: (m/s^2)/N and (m/s^2)/N per N s/m.
    """
    r = model.check_damping(damping)
    n = model.n_dof
    s = 2j * np.pi * np.asarray(frequencies_hz, dtype=float)
    z = model.stiffness + s[:, None, None] * r + (s**2)[:, None, None] * model.mass
    rhs = np.stack([model.sensor_shape, model.force_shape], axis=-1).astype(complex)
    g = np.linalg.solve(z, np.broadcast_to(rhs, (s.size, n, 2)))
    gs, gf = g[..., 0], g[..., 1]
    h = s**2 * np.einsum("fi,i->f", gf, model.sensor_shape)
    rows, cols = np.triu_indices(n)
    d = gs[:, rows] * gf[:, cols]
    off = rows != cols
    d[:, off] += gs[:, cols[off]] * gf[:, rows[off]]
    return h, -(s**3)[:, None] * d


def cramer_rao_frf(
    models: Sequence[StructuralModel],
    damping: np.ndarray,
    frequencies_hz: Sequence[np.ndarray] | np.ndarray,
    noise_std: Sequence[np.ndarray] | None = None,
    noise_rel: float | None = None,
    threshold: float = DETERMINED_THRESHOLD,
) -> MultiPointUncertainty:
    """Cramer-Rao bound of R's terms from a set of accelerance FRFs (one per model).

    models : one StructuralModel per FRF (its force and sensor shapes at that FRF's points).
    damping : (N, N) N s/m, the R at which the bound is taken (the truth, or a fit).
    frequencies_hz : (F,) shared by all FRFs, or a sequence of (F_k,) arrays, Hz.
    noise_std : per FRF a (F_k,) array (or scalar) of complex noise std per line,
        (m/s^2)/N, E|e|^2 = noise_std^2, real and imaginary parts independent with
        noise_std / sqrt(2) each; or
    noise_rel : noise_std = noise_rel |H| on every line (0.01 for 1 % per line).
    Lines where noise_std is 0 (or H is, with noise_rel) are dropped.
    Returns a MultiPointUncertainty with the Fisher figure only (std = std_fisher).
    """
    if (noise_std is None) == (noise_rel is None):
        raise ValueError("give exactly one of noise_std and noise_rel")
    models = list(models)
    if not models:
        raise ValueError("at least one model")
    r = np.asarray(damping, dtype=float)
    r = 0.5 * (r + r.T)
    n = r.shape[0]
    freqs = (
        [np.asarray(frequencies_hz, dtype=float)] * len(models)
        if np.ndim(frequencies_hz[0]) == 0
        else [np.asarray(f, dtype=float) for f in frequencies_hz]
    )
    if len(freqs) != len(models):
        raise ValueError("one frequency array per model")
    blocks = []
    for k, (model, f) in enumerate(zip(models, freqs, strict=True)):
        h, jac = frf_jacobian(model, r, f)
        if noise_rel is not None:
            sigma = float(noise_rel) * np.abs(h)
        else:
            sigma = np.broadcast_to(np.asarray(noise_std[k], dtype=float), h.shape)
        keep = sigma > 1e-12 * np.max(sigma)
        sd = sigma[keep, None] / np.sqrt(2.0)
        blocks += [jac[keep].real / sd, jac[keep].imag / sd]
    return _assemble(_upper(r), n, np.concatenate(blocks), None, 0, threshold)


def residual_jacobian(data: MultiPointData, damping: np.ndarray, rel_step: float = 1e-6) -> np.ndarray:
    """d(stacked residuals)/d(R's upper-triangle terms) by central differences: (n_total, P).

    Steps rel_step times each term's scale sqrt(|R_ii R_jj|); one batched call of 2P matrices.
    """
    r = np.asarray(damping, dtype=float)
    n = r.shape[0]
    theta = _upper(r)
    h = rel_step * parameter_scale(theta, n)
    eye = np.diag(h)
    res = multi_batched_residuals(data, _from_upper(np.concatenate([theta + eye, theta - eye]), n))
    p = theta.size
    return ((res[:p] - res[p:]) / (2.0 * h[:, None])).T


def _units(data: MultiPointData) -> list[tuple[int, int | None]]:
    """Jackknife units: (record, hit) for time records with >= 2 hits, (record, None) otherwise."""
    units: list[tuple[int, int | None]] = []
    for i, rec in enumerate(data.records):
        if isinstance(rec, (TimeData, BandLimitedData)) and rec.force_n.shape[0] >= 2:
            units += [(i, h) for h in range(rec.force_n.shape[0])]
        else:
            units.append((i, None))
    return units


def _drop(data: MultiPointData, unit: tuple[int, int | None]) -> MultiPointData:
    i, hit = unit
    recs, weights, labels = list(data.records), list(data.weights), list(data.labels)
    if hit is None:
        del recs[i], weights[i], labels[i]
    else:
        rec = recs[i]
        keep = np.arange(rec.force_n.shape[0]) != hit
        # The left-out hit's samples go with it (a compared-sample mask is dropped).
        recs[i] = type(rec)(rec.model, rec.force_n[keep], rec.response_m_s2[keep], rec.sample_rate_hz)
    return MultiPointData(tuple(recs), np.array(weights), tuple(labels))


def jackknife_std(data: MultiPointData, damping: np.ndarray, max_nfev: int = 50) -> tuple[np.ndarray, int]:
    """Delete-one jackknife std of R's upper-triangle terms (P,), N s/m, and the number of units.

    Each unit (a hit of a time record with >= 2 hits, else a whole record: a point's
    FRF) is left out in turn and R refitted by least squares from ``damping`` in R's
    own terms (unconstrained: refits of a Cholesky factor could not move along its
    zero columns); var = (n - 1) / n sum (theta_i - mean)^2. Needs >= 2 units.
    """
    units = _units(data)
    if len(units) < 2:
        raise ValueError("the jackknife needs at least two units (hits or records)")
    r0 = np.asarray(damping, dtype=float)
    thetas = []
    for unit in units:  # one local refit per left-out unit, few iterations each
        sub = _drop(data, unit)
        fit = _local.fit_least_squares(
            lambda r, d=sub: multi_residuals(d, r),
            r0,
            psd=False,
            batched_residuals=lambda r, d=sub: multi_batched_residuals(d, r),
            max_nfev=max_nfev,
        )
        thetas.append(_upper(fit.damping_matrix))
    t = np.array(thetas)
    m = len(units)
    return np.sqrt((m - 1) / m * np.sum((t - t.mean(axis=0)) ** 2, axis=0)), m


def uncertainty(
    data: MultiPointData,
    damping: np.ndarray,
    jackknife: bool = True,
    noise_std: float | None = None,
    threshold: float = DETERMINED_THRESHOLD,
) -> MultiPointUncertainty:
    """The stated uncertainty of a multi-point fit at its optimum ``damping`` (N, N), N s/m.

    Fisher: sigma^2 (J^T J)^-1 with J = ``residual_jacobian`` and sigma the residual's
    rms, sqrt(r^T r / (n_total - P)), unless noise_std (residual units, after the
    weights) is given. The residual is taken as white: weight the records (and the
    FRF lines, FrequencyData.weights = 1 / noise variance) so that it is.
    jackknife : also the delete-one jackknife over hits and points (``jackknife_std``);
        std is then the larger figure term by term. Skipped with fewer than 2 units.
    """
    r = np.asarray(damping, dtype=float)
    r = 0.5 * (r + r.T)
    n = r.shape[0]
    jac = residual_jacobian(data, r)
    if noise_std is None:
        res = multi_residuals(data, r)
        dof = res.size - jac.shape[1]
        sigma = float(np.sqrt(res @ res / dof)) if dof > 0 else float("nan")
    else:
        sigma = float(noise_std)
    jk, n_units = (None, 0)
    if jackknife and len(_units(data)) >= 2:
        jk, n_units = jackknife_std(data, r)
    return _assemble(_upper(r), n, jac / sigma, jk, n_units, threshold)
