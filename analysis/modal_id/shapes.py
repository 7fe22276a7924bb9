"""Complex mode shapes of a multi-point test from shared poles and per-point residues,
scaled to unit modal mass through the driving point, with their complexity (MPC, MPD)
and standard uncertainty.

The test. Every FRF H_k (k = 0..n_points-1) has one fixed end and one roving end:
roving hammer (sensor fixed at point s, force at point k: H_k = H_sk) or roving sensor
(force fixed at point s, sensor at k: H_k = H_ks). By reciprocity (H_ks = H_sk for a
linear, passive structure) both give the same algebra below. The driving point is the
FRF whose two ends coincide (k = s), if the test has one.

Residues. analysis.modal_id.lsfd fits, for the given poles lambda_r (rad/s, Im > 0),

    H_k(jw) = sum_r A_kr / (jw - lambda_r) + conj(A_kr) / (jw - conj(lambda_r)) + residuals,

A in the FRF's units times rad/s. For viscously damped modes with a symmetric system
the receptance (displacement/force) is

    alpha_ij(s) = sum_r psi_ir psi_jr / (a_r (s - lambda_r)) + c.c.,

psi_r the (complex) mode shape and a_r its modal scaling constant. For real normal
modes (proportional damping) with unit modal mass, phi^T M phi = 1,

    phi_i phi_j / (w_r^2 + 2 zeta w_r s + s^2) = phi_i phi_j / ((s - lambda)(s - conj lambda))
      = [phi_i phi_j / (2 j w_d)] / (s - lambda) + c.c.,   w_d = Im lambda,

so the receptance residue is R_ij = phi_i phi_j / (2 j w_d), i.e. phi_i phi_j = 2 j w_d R_ij.
We keep that definition for complex modes too: the shapes psi are scaled so that
psi_i psi_j = 2 j w_d R_ij (modal A constant a_r = 2 j w_d, the complex-mode analogue of
unit modal mass; for real modes psi = phi exactly).

From mobility or accelerance. Mobility is s alpha(s), accelerance s^2 alpha(s), s = jw.
Near the pole,  s^p R / (s - lambda) = lambda^p R / (s - lambda) + (a polynomial in s),
since s^p - lambda^p is divisible by s - lambda. So the residue fitted to the mobility
is lambda R and to the accelerance lambda^2 R (not -w^2 R at some line: the factor
is the pole's own (j lambda / j)^2 = lambda^2, complex), and

    R = A / lambda^p,   p = 0 receptance, 1 mobility, 2 accelerance.

The polynomial left over is, for accelerance, (s + lambda) R + c.c. = 2 Re(R) s +
2 Re(lambda R): a constant (taken by LSFD's lower residual, "1" for accelerance) and a
term in s, which is zero for real modes (R imaginary) and small for lightly complex
ones; LSFD has no such column, so strongly complex modes in accelerance carry a small
model error there.

Scaling through the driving point s: psi_s^2 = 2 j w_d R_s, psi_s = sqrt(...) (the root
with non-negative real part: positive at the driving point for a real mode), then
psi_k = 2 j w_d R_k / psi_s. Units: SI FRFs (m/N, (m/s)/N, (m/s^2)/N) give psi in
1/sqrt(kg), the unit of analysis.beam_shapes. Without a driving point the modal scale
is not measurable: each shape is divided by its largest residue, so that component is
1 (dimensionless, phase 0) and the others are relative to it ("unit largest component").

Complexity (invariant to the shape's scale and phase):

    MPC = |sum_k psi_k^2|^2 / (sum_k |psi_k|^2)^2   (modal phase collinearity, 1: a real mode),
    MPD = sum_k |psi_k| dev_k / sum_k |psi_k|       (mean phase deviation, degrees),

dev_k the angle (0..90 deg) between psi_k and the best straight line through 0 in the
complex plane, whose direction is arg(sum psi^2) / 2 (the principal axis of the points).

Uncertainty: a bootstrap, as for a run's modes (analysis.run_analysis). With the FRFs of
every hit of every point (per_hit_frf, each point at least 2 hits): each replicate
draws each point's hits with replacement and averages them (the deviation of that mean
widened by sqrt(n/(n-1)), n the point's hits, as the plain bootstrap's variance of a
mean is (n-1)/n of the unbiased one). Otherwise: each line is
counted a Poisson(1) number of times (a bootstrap over lines, weighted least squares).
Poles: by default the given poles (LSCF's, which are biased by a few tenths of a
percent in damping on noisy data) are first refitted to all FRFs together: Gauss-Newton
on the LSFD misfit with the residues eliminated (variable projection), i.e. the least-
squares estimate of the pole-residue model above; a refit that moves a pole by more
than POLE_SHIFT_LIMIT half-power half-widths is refused. Each bootstrap replicate
takes one Gauss-Newton step from those poles on its own data (to first order its own
optimum), so the spread includes the poles' uncertainty, then its residues and shapes,
scaled the same way and on the same root branch as the nominal result. shape_std is the
standard deviation over the replicates of the real part of each shape value,
shape_std_imag of the imaginary part. With refit_poles=False the given poles are used
throughout and the residues are identify_modes' modal constants exactly. Seeded by
default: the same data give the same figures.

Assumptions: linear, time-invariant, reciprocal structure; viscous (possibly
non-proportional) damping; the given poles are those seen in the FRFs (windowed: an
exponential window's added damping is still in them); every FRF shares the same force
normalisation and units.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg

from analysis.modal_id.lsfd import FORMS, lsfd, residual_bases

#: Bootstrap replicates of the shape uncertainty.
BOOTSTRAP_REPLICATES = 40
#: The default seed (the same as a run's bootstrap: reproducible figures).
DEFAULT_SEED = 20261124
#: Gauss-Newton iterations of the pole refit in each replicate.
POLE_ITERATIONS = 4
#: The nominal refit may move a pole by this many half-power half-widths |Re lambda|.
POLE_SHIFT_LIMIT = 2.0
#: A driving-point residue under this fraction of the mode's largest is near a node.
NODE_FRACTION = 0.05
#: A driving-point product 2 j w_d R further than this from the positive real axis (deg)
#: is not a physical mode's (it is psi_s^2, about |phi_s|^2 for a nearly real mode).
DRIVING_PHASE_LIMIT_DEG = 45.0

_POWER = {"receptance": 0, "mobility": 1, "accelerance": 2}


@dataclass
class ModeShapes:
    """Mode shapes of a test at its points.

    poles (n_modes,) complex rad/s the shapes were computed at: the given poles refitted
        (refit_poles) or as given; given_poles (n_modes,) as given. frequency_hz,
        damping_ratio (n_modes,) from ``poles``: |lambda| / 2 pi Hz and -Re lambda / |lambda|.
    residues (n_modes, n_points) complex: the LSFD residues A of each FRF in its own
        form (FRF units times rad/s).
    shapes (n_modes, n_points) complex, scaled as ``scaling`` says.
    shape_std, shape_std_imag (n_modes, n_points): standard uncertainty of the real and
        imaginary part of each shape value, same unit (NaN: too few replicates).
    mpc (n_modes,) in [0, 1]; mpd_deg (n_modes,) in [0, 90].
    frequency_std_hz, damping_std (n_modes,): the spread of the refitted poles over the
        same replicates (NaN without refit).
    scaling: how the shapes are scaled, in words with the unit.
    uncertainty_from: which bootstrap, with its replicate count.
    driving_index: the FRF of the driving point, or None.
    cautions: what in the result may mislead, one sentence each.
    """

    poles: np.ndarray
    given_poles: np.ndarray
    frequency_hz: np.ndarray
    damping_ratio: np.ndarray
    residues: np.ndarray
    shapes: np.ndarray
    shape_std: np.ndarray
    shape_std_imag: np.ndarray
    mpc: np.ndarray
    mpd_deg: np.ndarray
    frequency_std_hz: np.ndarray
    damping_std: np.ndarray
    scaling: str
    uncertainty_from: str
    driving_index: int | None
    cautions: list[str] = field(default_factory=list)


def modal_phase_collinearity(shapes: np.ndarray) -> np.ndarray:
    """MPC of each shape, (n_modes,) for shapes (n_modes, n_points) (or a scalar for
    one shape (n_points,)): |sum psi^2|^2 / (sum |psi|^2)^2, 1 for a real mode (all
    components on one line through 0), lower the more the phases scatter. NaN for a zero shape."""
    s = np.asarray(shapes, dtype=complex)
    num = np.abs(np.sum(s**2, axis=-1)) ** 2
    den = np.sum(np.abs(s) ** 2, axis=-1) ** 2
    with np.errstate(invalid="ignore", divide="ignore"):
        # Round-off can put a real mode a few ulps above 1.
        return np.where(den > 0, np.minimum(num / np.where(den > 0, den, 1.0), 1.0), np.nan)


def mean_phase_deviation_deg(shapes: np.ndarray) -> np.ndarray:
    """MPD of each shape, degrees (0 for a real mode, at most 90): the magnitude-weighted
    mean angle between each component and the best line through 0 (direction
    arg(sum psi^2)/2). shapes (n_modes, n_points) -> (n_modes,); NaN for a zero shape."""
    s = np.asarray(shapes, dtype=complex)
    axis = 0.5 * np.angle(np.sum(s**2, axis=-1))
    rotated = s * np.exp(-1j * axis)[..., None]
    mag = np.abs(s)
    with np.errstate(invalid="ignore", divide="ignore"):
        cos_dev = np.where(mag > 0, np.abs(rotated.real) / np.where(mag > 0, mag, 1.0), 1.0)
        dev = np.degrees(np.arccos(np.clip(cos_dev, 0.0, 1.0)))
        total = mag.sum(axis=-1)
        return np.where(total > 0, np.sum(mag * dev, axis=-1) / np.where(total > 0, total, 1.0), np.nan)


def receptance_residues(residues: np.ndarray, poles: np.ndarray, form: str) -> np.ndarray:
    """R = A / lambda^p (p = 0, 1, 2 for receptance, mobility, accelerance): the residue
    the receptance would have, from the residues A (n_modes, n_points) of the FRFs in
    ``form``, poles (n_modes,) rad/s. Units: the FRF's times rad/s over (rad/s)^p."""
    if form not in FORMS:
        raise ValueError(f"form must be one of {', '.join(FORMS)}, got {form!r}")
    lam = np.asarray(poles, dtype=complex).reshape(-1, 1)
    return np.asarray(residues, dtype=complex) / lam ** _POWER[form]


def _check(frequency_hz, frf, poles, form, driving_index, band):
    f = np.asarray(frequency_hz, dtype=float)
    h = np.asarray(frf)
    if f.ndim != 1 or f.size < 4 or not np.all(np.isfinite(f)) or np.any(np.diff(f) <= 0):
        raise ValueError("frequency_hz must be a 1-D increasing array of at least 4 finite lines")
    if h.ndim not in (1, 2) or h.shape[-1] != f.size:
        raise ValueError(f"frf must have shape (n_points, {f.size}), got {h.shape}")
    h = np.atleast_2d(h.astype(complex))
    if not np.all(np.isfinite(h)):
        raise ValueError("frf holds non-finite values")
    if form not in FORMS:
        raise ValueError(f"form must be one of {', '.join(FORMS)}, got {form!r}")
    lam = np.atleast_1d(np.asarray(poles, dtype=complex))
    if lam.ndim != 1 or lam.size == 0 or not np.all(np.isfinite(lam)):
        raise ValueError("poles must be a non-empty 1-D array of finite complex rad/s")
    if np.any(lam.imag <= 0) or np.any(lam.real >= 0):
        raise ValueError("poles must have Im > 0 and Re < 0 (one of each stable conjugate pair)")
    if driving_index is not None and not (
        isinstance(driving_index, int | np.integer) and 0 <= driving_index < h.shape[0]
    ):
        raise ValueError(
            f"driving_index must be an FRF index 0..{h.shape[0] - 1} or None, got {driving_index!r}"
        )
    use = np.ones(f.size, dtype=bool)
    if band is not None:
        use = (f >= band[0]) & (f <= band[1])
    low, up = residual_bases(2 * np.pi * f, form)
    use &= np.isfinite(low) & np.isfinite(up)  # 0 Hz in receptance and mobility
    if use.sum() < 2 * lam.size + 4:
        raise ValueError(f"{int(use.sum())} usable lines for {lam.size} modes: widen the band")
    return f, h, lam, use


def _design(omega: np.ndarray, lam: np.ndarray, form: str):
    """Complex basis (n_lines, 2R + 4) of lsfd's model, and the pole fractions."""
    jw = 1j * omega[:, None]
    pp = 1.0 / (jw - lam[None, :])
    pm = 1.0 / (jw - np.conj(lam)[None, :])
    low, up = residual_bases(omega, form)
    basis = np.concatenate(
        [pp + pm, 1j * (pp - pm), low[:, None], 1j * low[:, None], up[:, None], 1j * up[:, None]], axis=1
    )
    return basis, pp, pm


def _orthonormal(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """a = q r, q (m, n) orthonormal columns, r (n, n) upper triangular: Cholesky QR done
    twice (as accurate as Householder for a column-scaled design of condition well
    under 1e8, and tens of times faster on a tall matrix); Householder if it fails."""
    try:
        q, r = a, np.eye(a.shape[1])
        for _ in range(2):
            c = scipy.linalg.cholesky(q.T @ q, lower=False)
            q = q @ scipy.linalg.solve_triangular(c, np.eye(c.shape[0]))
            r = c @ r
        return q, r
    except (np.linalg.LinAlgError, ValueError):
        return np.linalg.qr(a)


def _prepare(omega, lam, form, sw):
    """The weighted design of the poles ``lam`` (it does not depend on the data): the
    real design (2F, 2R + 4), its column norms, an orthonormal basis q of it with the
    triangular factor r, and the pole fractions (F, R)."""
    basis, pp, pm = _design(omega, lam, form)
    sw2 = np.concatenate([sw, sw])
    design = np.concatenate([basis.real, basis.imag], axis=0) * sw2[:, None]
    # Column scaling: the residual bases differ from the pole terms by orders of magnitude.
    norm = np.linalg.norm(design, axis=0)
    norm[norm == 0] = 1.0
    q, r = _orthonormal(design / norm)
    return design, norm, q, r, pp, pm


def _weighted_fit(omega, h, lam, form, sw, prepared=None):
    """Weighted LSFD: coefficients (2R + 4, n_frf), weighted real residual (2F, n_frf),
    an orthonormal basis q of the weighted design, and the pole fractions. ``prepared``:
    _prepare's result for the same poles and weights (reused across replicates)."""
    design, norm, q, r, pp, pm = prepared or _prepare(omega, lam, form, sw)
    sw2 = np.concatenate([sw, sw])
    target = np.concatenate([h.real, h.imag], axis=1).T * sw2[:, None]
    coef = scipy.linalg.solve_triangular(r, q.T @ target) / norm[:, None]
    resid = target - design @ coef
    return coef, resid, q, pp, pm


def _refit_poles(omega, h, lam, form, sw, iterations=POLE_ITERATIONS, prepared=None):
    """Poles minimising the weighted LSFD misfit of all FRFs together, by Gauss-Newton
    from ``lam`` with the residues eliminated (variable projection, Kaufman's Jacobian)
    and step halving. Returns the poles (n_modes,) and the LSFD coefficients there
    (2 n_modes + 4, n_frf)."""
    n = lam.size
    sw2 = np.concatenate([sw, sw])
    coef, resid, q, pp, pm = _weighted_fit(omega, h, lam, form, sw, prepared)
    cost = float(np.sum(resid**2))
    for _ in range(iterations):
        alpha, beta = coef[:n].T, coef[n : 2 * n].T  # (n_frf, R): A = alpha + j beta
        s2, d2 = pp**2 + pm**2, pp**2 - pm**2  # (F, R)
        # d/d(Re lambda) and d/d(Im lambda) of each FRF's model, (n_frf, F, R) complex.
        da = alpha[:, None, :] * s2[None] + 1j * beta[:, None, :] * d2[None]
        db = 1j * alpha[:, None, :] * d2[None] - beta[:, None, :] * s2[None]
        g = np.concatenate([da, db], axis=2)
        g = np.concatenate([g.real, g.imag], axis=1) * sw2[None, :, None]  # (n_frf, 2F, 2R)
        g = g - q[None] @ (q.T[None] @ g)
        jac = g.reshape(-1, 2 * n)
        # Normal equations of the 2R pole parameters (a few, well scaled: all rad/s).
        step = np.linalg.lstsq(jac.T @ jac, jac.T @ resid.T.reshape(-1), rcond=None)[0]
        delta = step[:n] + 1j * step[n:]
        accepted = False
        for _half in range(6):
            trial = lam + delta
            if np.all(trial.real < 0) and np.all(trial.imag > 0):
                c2, r2, q2, pp2, pm2 = _weighted_fit(omega, h, trial, form, sw)
                cost2 = float(np.sum(r2**2))
                if cost2 <= cost:
                    lam, coef, resid, q, pp, pm, cost = trial, c2, r2, q2, pp2, pm2, cost2
                    accepted = True
                    break
            delta = 0.5 * delta
        if not accepted or np.max(np.abs(delta) / np.abs(lam)) < 1e-10:
            break
    return lam, coef


def _scale(rec: np.ndarray, lam: np.ndarray, driving_index, largest, ref_driving=None) -> np.ndarray:
    """Shapes (R, P) from receptance residues rec (R, P): through the driving point
    (root branch nearest ref_driving when given), else divided by the residue at
    ``largest`` (R,) indices."""
    rows = np.arange(rec.shape[0])
    if driving_index is None:
        return rec / rec[rows, largest][:, None]
    prod = 2j * lam.imag[:, None] * rec  # psi_i psi_s
    root = np.sqrt(prod[:, driving_index])
    if ref_driving is not None:
        root = np.where(np.abs(root - ref_driving) <= np.abs(root + ref_driving), root, -root)
    with np.errstate(invalid="ignore", divide="ignore"):
        return prod / root[:, None]


def _resampled_mean(hits: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """The mean of n hits drawn with replacement, its deviation from the mean of all
    hits widened by sqrt(n / (n - 1)): the plain bootstrap's variance of a mean is
    (n - 1)/n of the sample estimate's, 20 % short with 5 hits."""
    n = hits.shape[0]
    mean = hits.mean(axis=0)
    return mean + np.sqrt(n / (n - 1)) * (hits[rng.integers(0, n, n)].mean(axis=0) - mean)


def _hit_sets(per_hit_frf, n_frf: int, n_lines: int) -> list[np.ndarray]:
    if len(per_hit_frf) != n_frf:
        raise ValueError(f"per_hit_frf must hold one set of hits per FRF ({n_frf}), got {len(per_hit_frf)}")
    out = []
    for k, hits in enumerate(per_hit_frf):
        a = np.atleast_2d(np.asarray(hits, dtype=complex))
        if a.ndim != 2 or a.shape[1] != n_lines or not np.all(np.isfinite(a)):
            raise ValueError(f"per_hit_frf[{k}] must be finite, (n_hits, {n_lines}), got {a.shape}")
        out.append(a)
    return out


def mode_shapes(
    frequency_hz: np.ndarray,
    frf: np.ndarray,
    poles: np.ndarray,
    form: str = "accelerance",
    driving_index: int | None = None,
    per_hit_frf: Sequence[np.ndarray] | np.ndarray | None = None,
    rng: np.random.Generator | int | None = None,
    *,
    band: tuple[float, float] | None = None,
    n_bootstrap: int = BOOTSTRAP_REPLICATES,
    refit_poles: bool = True,
) -> ModeShapes:
    """Complex mode shapes at a test's points (see the module docstring for the model,
    the scaling and the bootstrap).

    frequency_hz (n_lines,) Hz, increasing. frf (n_points, n_lines) complex, one FRF per
    point (roving hammer or roving sensor, the other end fixed), in the units of
    ``form``. poles (n_modes,) complex rad/s, Im > 0, Re < 0, as seen in the FRFs (e.g.
    identify_modes' Mode.pole). driving_index: the FRF whose force and response share a
    point (unit modal mass scaling), None when the test has none (unit largest
    component). per_hit_frf: per point, its hits' FRFs (n_hits_k, n_lines) (a sequence
    of n_points arrays, or one array (n_points, n_hits, n_lines)): bootstrap over hits;
    None (or a point with fewer than 2 hits): bootstrap over lines. rng: a Generator or
    seed (default: a fixed seed). band (f1, f2) Hz: the lines to fit (default all; give
    the band the poles were found in). n_bootstrap: replicates (0: no uncertainty).
    refit_poles: refit the poles to all FRFs together before the residues (and again
    in each replicate, so that their spread enters the shapes'); False: the given poles
    throughout, and the residues are exactly identify_modes' modal constants.

    Returns ModeShapes; raises ValueError on bad inputs.
    """
    f, h, lam, use = _check(frequency_hz, frf, poles, form, driving_index, band)
    omega = 2 * np.pi * f[use]
    hu = h[:, use]
    n_modes, n_points = lam.size, h.shape[0]
    cautions = []
    given = lam
    if refit_poles:
        lam, coef = _refit_poles(omega, hu, lam, form, np.ones(omega.size))
        # A refit that walks a pole further than POLE_SHIFT_LIMIT half-power half-widths
        # has left the given mode (to a neighbour or to noise): keep the given poles.
        if np.any(np.abs(lam - given) > POLE_SHIFT_LIMIT * np.abs(given.real)):
            lam = given
            cautions.append(
                "the pole refit moved a pole away from the given mode; the shapes use the given poles"
            )
    est = lsfd(f[use], hu, lam, form)
    residues = np.asarray(est.modal_constants, dtype=complex)  # (R, P)
    rec = receptance_residues(residues, lam, form)
    largest = np.argmax(np.abs(rec), axis=1)
    shapes = _scale(rec, lam, driving_index, largest)
    if driving_index is None:
        scaling = (
            "unit largest component (no driving point: the modal mass is not measured); "
            "dimensionless, the largest component of each mode is 1 with phase 0"
        )
    else:
        scaling = (
            f"unit modal mass through the driving point (FRF {driving_index}): psi_i psi_s = 2 j w_d R_is, "
            "R the receptance residue; 1/sqrt(kg) for SI FRFs"
        )
        # Named by the given poles, the modes as the caller lists them (a refit moves them).
        fn_hz = np.abs(given) / (2 * np.pi)
        ratio = np.abs(rec[:, driving_index]) / np.abs(rec[np.arange(n_modes), largest])
        prod_phase = np.degrees(np.angle(2j * lam.imag * rec[:, driving_index]))
        for r in range(n_modes):
            if ratio[r] < NODE_FRACTION:
                cautions.append(
                    f"the driving point lies near a node of the mode at {fn_hz[r]:.6g} Hz (its residue is "
                    f"{100 * ratio[r]:.1f} % of the largest): that mode's unit-modal-mass scale is unreliable"
                )
            elif abs(prod_phase[r]) > DRIVING_PHASE_LIMIT_DEG:
                cautions.append(
                    f"the driving-point residue of the mode at {fn_hz[r]:.6g} Hz is {prod_phase[r]:.0f} deg "
                    "from a physical mode's (psi_s^2 should be near the positive real axis): the mode is "
                    "poorly identified, or the FRF is not a driving point"
                )
    rng = (
        rng
        if isinstance(rng, np.random.Generator)
        else np.random.default_rng(DEFAULT_SEED if rng is None else rng)
    )
    hits = None if per_hit_frf is None else _hit_sets(per_hit_frf, n_points, f.size)
    by_hits = hits is not None and all(a.shape[0] >= 2 for a in hits)
    if hits is not None and not by_hits:
        cautions.append("a point has fewer than 2 hits: the uncertainty comes from a bootstrap over lines")
    ref_driving = None if driving_index is None else shapes[:, driving_index]
    rep_shapes, rep_poles = [], []
    ones = np.ones(omega.size)
    # Every replicate over hits starts from the same poles with unit weights: one design.
    nominal_design = _prepare(omega, lam, form, ones) if by_hits and n_bootstrap > 0 else None
    for _ in range(max(0, int(n_bootstrap))):
        if by_hits:
            h_rep = np.array([_resampled_mean(a, rng)[use] for a in hits])
            sw, prepared = ones, nominal_design
        else:
            h_rep = hu
            sw, prepared = np.sqrt(rng.poisson(1.0, omega.size).astype(float)), None
        try:
            # One Gauss-Newton step from the nominal optimum: a replicate differs little
            # from the data, so one step takes its poles to first order (and is cheap).
            if refit_poles:
                lam_rep, coef = _refit_poles(omega, h_rep, lam, form, sw, 1, prepared)
            else:
                lam_rep, coef = lam, _weighted_fit(omega, h_rep, lam, form, sw, prepared)[0]
        except np.linalg.LinAlgError:
            continue  # a degenerate resample adds nothing
        res_rep = (coef[:n_modes] + 1j * coef[n_modes : 2 * n_modes]).astype(complex)
        rec_rep = receptance_residues(res_rep, lam_rep, form)
        rep_shapes.append(_scale(rec_rep, lam_rep, driving_index, largest, ref_driving))
        rep_poles.append(lam_rep)
    nan = np.full((n_modes, n_points), np.nan)
    std_re, std_im = nan, nan.copy()
    f_std, z_std = np.full(n_modes, np.nan), np.full(n_modes, np.nan)
    if len(rep_shapes) >= 3:
        s = np.array(rep_shapes)
        std_re, std_im = np.std(s.real, axis=0, ddof=1), np.std(s.imag, axis=0, ddof=1)
        if refit_poles:
            p = np.array(rep_poles)
            f_std = np.std(np.abs(p) / (2 * np.pi), axis=0, ddof=1)
            z_std = np.std(-p.real / np.abs(p), axis=0, ddof=1)
    how = "hits" if by_hits else "lines"
    return ModeShapes(
        poles=lam,
        given_poles=given,
        frequency_hz=np.abs(lam) / (2 * np.pi),
        damping_ratio=-lam.real / np.abs(lam),
        residues=residues.copy(),
        shapes=shapes,
        shape_std=std_re,
        shape_std_imag=std_im,
        mpc=modal_phase_collinearity(shapes),
        mpd_deg=mean_phase_deviation_deg(shapes),
        frequency_std_hz=f_std,
        damping_std=z_std,
        scaling=scaling,
        uncertainty_from=f"bootstrap over {how} ({len(rep_shapes)} replicates"
        + (", poles refitted in each)" if refit_poles else ", poles fixed)"),
        driving_index=None if driving_index is None else int(driving_index),
        cautions=cautions,
    )
