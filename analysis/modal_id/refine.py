"""The poles LSCF selected, refined by nonlinear least squares on the FRF itself.

Why: LSCF fits the linearised equation A(w) H(w) - B(w) = 0, where the measured H
multiplies the unknowns; its noise then biases the poles (an errors-in-variables bias,
growing with the noise's variance over |H|^2). Two modes 2 Hz apart (150 Hz at 0.5 %,
152 Hz at 0.8 %; 5 hits, response noise 2 % of its RMS) read 0.59-0.60 % and 0.83-0.87 %
in every seed, 6-9 times their spread over hits (which has the same bias in every hit);
at 5 % noise 0.76 % (a new user's hit generator; with tests/analysis/impact_synth.py at
5 % LSCF no longer splits the pair at all, and nothing is refined). Fitting the modal
model itself to H, the residues solved linearly for each trial set of poles (variable
projection), has no such bias: the same hits read 0.50 % and 0.80 %.

A close mode LSCF missed (150/152/154.5 Hz, the middle one never found) leaves the
window holding more than its poles, and refining pushes the two it has apart: missing()
finds it first, by a fit with one pole more. A pole LSCF put beside a close pair to
make up for their bias goes by redundant(), a fit with one pole fewer.

Lines are weighted alike within each FRF (each FRF by its RMS over the window): weights
read from a few hits' scatter correlate with the very noise they weigh and biased the
fit (197 Hz at 1 % read 3.5 u high in damping that way).

How (refine_poles): the poles are taken in groups whose local windows overlap (a close
pair is refined together); each group is fitted on the lines within WINDOW_SPAN
half-widths of its poles (3 half-power half-widths, at least 3 lines, as
identify.spurious_check uses), with the other poles inside that window kept fixed (their
residues free) and a complex constant and slope per FRF for the modes outside it. Each
pole moves in (log sigma, omega_d), so its decay rate stays positive. A refined pole is
kept only where it lowered the misfit and stayed near the LSCF pole: within
MAX_SHIFT_HALF_WIDTHS of its half-power half-width (or a line) in frequency and a factor
MAX_DAMPING_FACTOR in damping; else the LSCF pole stands (a pole the data hold poorly may
wander off to noise).

Pure numpy and scipy.optimize.least_squares. Poles in rad/s, Im > 0.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import least_squares

from analysis.modal_id.stability import frequency_damping, overlapped

#: A group's window spans this many of its poles' half-power half-widths (zeta f) either
#: side, and at least MIN_WINDOW_LINES lines: the peak and its flanks, where a constant
#: and a slope stand for the modes outside (wider windows let them bend the fit).
WINDOW_SPAN = 5.0
MIN_WINDOW_LINES = 10
#: A refined pole may move this many half-power half-widths (zeta f, at least a line).
MAX_SHIFT_HALF_WIDTHS = 1.0
#: ... and its damping may change by this factor at most, either way. LSCF alone read a
#: 0.5 % mode 6 Hz from a 0.8 % one (120 and 126 Hz, 5 hits, a new user's file) at
#: 1.22 %, 2.4 times too high and 3 u off, in 10 of 10 draws: with a factor of 2 the
#: refined 0.49 % was refused and the biased pole stood.
MAX_DAMPING_FACTOR = 3.0
#: Lines a window must hold per real unknown of its fit, or the group is left as it is.
LINES_PER_UNKNOWN = 2
#: A pole of a group is redundant (redundant()) when leaving it out worsens the group's
#: refitted misfit by less than this many times the noise's share of the unknowns left
#: out (an F statistic).
REDUNDANT_F = 4.0
#: A pole is added to a group (missing()) when it lowers the group's refitted misfit by
#: more than this many times the noise's share of the unknowns added (an F statistic) ...
ADD_F = 50.0
#: ... started at this many frequencies across the window but for this share at each end ...
ADD_STARTS = 9
ADD_MARGIN = 0.15
#: ... and its half-power half-width spans at least this many lines (narrower, a pole
#: fits a single line's noise; the under-resolved-peak caution's threshold).
ADD_MIN_HALF_WIDTH_LINES = 0.4
#: A fit whose misfit is this small, relative to the FRF it fits, is exact to rounding (a
#: 24-bit converter resolves 6e-8 of its range).
ROUNDOFF = 1e-9
#: Only poles at most this damped are refined: a window of +-5 half-widths then spans at
#: most +-10 % of the frequency; wider, the modes outside bend the fit more than a
#: constant and a slope follow (1070 Hz at 3.3 % among heavily damped neighbours read
#: 0.6-0.9 Hz low, 3-4 u, where LSCF's poles held).
MAX_DAMPING = 0.02
#: A heavily damped pole's window for missing_beside_heavy spans this many of its
#: half-widths either side: a heavy neighbour reaches further than a light one (150 and
#: 170 Hz at 5 and 8 %, read as one pole at 148 Hz, 4 %: its +-5 half-widths ended at
#: 178 Hz, where the missed 170 Hz mode, half-width 13.6 Hz, sat at the edge, F 33; at
#: +-8, F 113).
HEAVY_WINDOW_SPAN = 8.0
#: ... and the pole it adds may be damped up to this.
HEAVY_ADD_MAX_DAMPING = 0.15


def to_refine(poles: np.ndarray) -> np.ndarray:
    """(n_poles,) bool: the poles LSCF's noise bias reaches and the local fit can mend:
    at most MAX_DAMPING, with another such pole within stability.OVERLAP summed half-power
    half-widths. An isolated mode's LSCF pole holds in noise (400 Hz at 1 %, 5 % noise:
    1.0002-1.0029 %), and a narrow window would read it with fewer lines than LSCF does,
    more scattered (197 Hz at 1 %: 0.028 Hz over seeds for LSCF's 0.016 Hz)."""
    f, zeta = frequency_damping(poles)
    light = zeta <= MAX_DAMPING
    out = np.zeros(f.size, dtype=bool)
    # Close to another light pole only: a heavily damped neighbour overlaps by its own
    # width, yet lies beyond the light pole's window, where a constant and a slope stand
    # in for its curve and bend the fit (a new user's 400 Hz at 1 % beside 370 Hz at 5 %,
    # noise-free: 0.9165 % +- 0.0070 % refined, 1.00000 % from LSCF).
    out[light] = overlapped(f[light], zeta[light])
    return out


def refine_poles(
    frequency_hz: np.ndarray,
    frf: np.ndarray,
    poles: np.ndarray,
    line_hz: float,
    noise_std: np.ndarray | None = None,
    refine: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """(poles (n_poles,) complex rad/s, refined (n_poles,) bool): ``poles`` with each one
    in ``refine`` (bool, default all) replaced by its refined value where it was kept
    (module docstring).

    frequency_hz (n_lines,) Hz; frf (n_frf, n_lines) or (n_lines,) complex; line_hz: the
    line spacing, Hz; noise_std (n_frf, n_lines) or (n_lines,): the noise's standard
    deviation at each line, in the FRF's units (non-finite: the median of the finite
    ones, infinite: the line left out); default: each FRF weighted by its RMS over the
    window, all lines alike. Weights read from the same noisy data (the scatter of a few
    hits) bias the fit: give noise_std only where it does not depend on this FRF's noise.
    """
    f = np.asarray(frequency_hz, dtype=float)
    h = np.atleast_2d(np.asarray(frf, dtype=complex))
    lam = np.asarray(poles, dtype=complex).ravel().copy()
    done = np.zeros(lam.size, dtype=bool)
    if lam.size == 0:
        return lam, done
    todo = np.ones(lam.size, dtype=bool) if refine is None else np.asarray(refine, dtype=bool)
    noise = None if noise_std is None else np.broadcast_to(np.asarray(noise_std, dtype=float), h.shape)
    # A heavily damped pole is refined only beside a pole added to it
    # (missing_beside_heavy), on the window that pole was found in.
    span = np.where(-lam.real / np.abs(lam) > MAX_DAMPING, HEAVY_WINDOW_SPAN, WINDOW_SPAN)
    half, lo, hi = _reach(lam, line_hz, span)
    for group in _groups(lo, hi, todo):
        window, fixed = _window(f, lam, lo, hi, group)
        if not _enough_lines(window, len(group), fixed.size, h.shape[0]):
            continue
        weights = _weights(h[:, window], None if noise is None else noise[:, window])
        new = _fit_group(f[window], h[:, window] * weights, weights, lam[group], fixed)
        if new is None:
            continue
        for k, p in zip(group, new, strict=True):
            if _near(p, lam[k], half[k], line_hz):
                lam[k], done[k] = p, True
    return lam, done


def redundant(
    frequency_hz: np.ndarray,
    frf: np.ndarray,
    poles: np.ndarray,
    line_hz: float,
    refine: np.ndarray | None = None,
) -> np.ndarray:
    """(n_poles,) bool: the poles of a group refine_poles would refine together that the
    group's other poles, refined without them, fit as well (arguments as refine_poles').

    Why: LSCF can hold a close pair with a third pole between its biased poles (150 and
    152 Hz at 0.5 and 0.8 %, three FRFs, 2 % noise: 150.19, 150.77 and 151.88 Hz in 9
    of 10 draws). Against the biased pair the third one improves the fit and passes
    spurious_check; refined, any two of the three become 150.00 and 152.00 Hz and the
    third adds nothing the noise would not.

    How: backward elimination by an F test of nested models. In each group of two or
    more, every pole is left out in turn and the others refitted; where the best of
    those fits is worse than the whole group's by less than REDUNDANT_F times what the
    noise (the whole fit's residual variance) explains with the unknowns left out, that
    pole is redundant, and the group is tested again without it.
    """
    f = np.asarray(frequency_hz, dtype=float)
    h = np.atleast_2d(np.asarray(frf, dtype=complex))
    lam = np.asarray(poles, dtype=complex).ravel()
    drop = np.zeros(lam.size, dtype=bool)
    if lam.size < 2:
        return drop
    todo = np.ones(lam.size, dtype=bool) if refine is None else np.asarray(refine, dtype=bool)
    half_width, lo, hi = _reach(lam, line_hz)
    n_frf = h.shape[0]
    for group in _groups(lo, hi, todo):
        window, fixed = _window(f, lam, lo, hi, group)
        if len(group) < 2 or not _enough_lines(window, len(group), fixed.size, n_frf):
            continue
        weights = _weights(h[:, window], None)
        hw = h[:, window] * weights
        n_residuals = 2 * int(window.sum()) * n_frf
        left = list(group)
        while len(left) >= 2:
            whole = _solve_group(f[window], hw, weights, lam[left], fixed)
            if whole is None:
                break
            n_unknowns = 2 * len(left) + 2 * (len(left) + fixed.size + 2) * n_frf
            variance = whole[2] / max(n_residuals - n_unknowns, 1)
            without = [_solve_group(f[window], hw, weights, lam[[k for k in left if k != out]], fixed)
                       for out in left]  # fmt: skip
            # Leaving a pole out leaves out its 2 pole parameters and 2 residue parts per FRF.
            gain = np.array([np.inf if w is None else w[2] - whole[2] for w in without])
            spare = np.flatnonzero(gain / (2 + 2 * n_frf) < REDUNDANT_F * variance)
            if spare.size == 0:
                break
            # Of the poles the others do as well without, the one whose removal moves the
            # others least: the others keep their identities (a chain's pole stays its own).
            moved = []
            for k in spare:
                rest = [j for j in left if j != left[k]]
                moved.append(_moved(without[k][0], lam[rest], half_width[rest]))
            drop[left.pop(int(spare[int(np.argmin(moved))]))] = True
    return drop


def missing(
    frequency_hz: np.ndarray,
    frf: np.ndarray,
    poles: np.ndarray,
    line_hz: float,
    refine: np.ndarray | None = None,
) -> np.ndarray:
    """(n_added,) complex rad/s: a pole for each group refine_poles would refine together
    whose window holds a mode LSCF missed (arguments as refine_poles').

    Why: three modes 2 and 2.5 Hz apart (150, 152, 154.5 Hz; 5 hits, 2 % noise): LSCF
    never holds the middle one, at any order up to 100, and the two it keeps are pushed
    apart (149.8 and 154.9 Hz, their u 0.02-0.05 Hz). The group fitted again with one
    pole more finds it: 151.9 Hz at 0.73-0.88 % beside 150.0 and 154.5 Hz.

    How, the mirror of redundant(): the group is fitted with one pole more, started at
    ADD_STARTS frequencies across the middle of its window at the group's median damping,
    and the best fit is taken. The pole is added where that fit's misfit is lower than
    the group's alone by more than ADD_F times what the noise (its residual variance)
    explains with the unknowns added, and where it is a mode the lines can show: damped
    between a half-power half-width of ADD_MIN_HALF_WIDTH_LINES lines and MAX_DAMPING,
    inside the window's middle, at least a half-width from every pole of the group, and
    the group's own poles moved no more than refine_poles lets them (else the fit has
    rearranged the group, not found a mode in it). A pole fitted to noise read F 2-19
    (a real pair of 5 hits, three FRFs, close modes at 1 %), the missed middle mode
    250-490.
    """
    f = np.asarray(frequency_hz, dtype=float)
    h = np.atleast_2d(np.asarray(frf, dtype=complex))
    lam = np.asarray(poles, dtype=complex).ravel()
    added: list[complex] = []
    if lam.size == 0:
        return np.array(added, dtype=complex)
    todo = np.ones(lam.size, dtype=bool) if refine is None else np.asarray(refine, dtype=bool)
    half_width, lo, hi = _reach(lam, line_hz)
    for group in _groups(lo, hi, todo):
        new = _one_more(f, h, lam, group, lo, hi, half_width, line_hz, MAX_DAMPING)
        if new is not None:
            added.append(new)
    return np.array(added, dtype=complex)


def missing_beside_heavy(
    frequency_hz: np.ndarray, frf: np.ndarray, poles: np.ndarray, line_hz: float
) -> tuple[np.ndarray, np.ndarray]:
    """((n_added,) complex rad/s, (n_added,) int): a pole for each heavily damped one (damping above
    MAX_DAMPING) whose wider window (HEAVY_WINDOW_SPAN half-widths) holds a mode LSCF
    missed, by missing()'s test (ADD_F) with the new pole damped up to
    HEAVY_ADD_MAX_DAMPING; each pole added lies at least a half-power half-width (its
    own or the other's, the larger) from every pole and from every pole added before it.

    Why: two overlapping heavily damped modes (150 and 170 Hz at 5 and 8 %, 3-10 hits at
    2-5 % noise) were one mode in 9 of 15 files: LSCF held no chain at 170 Hz at any
    order, and no caution said so. Beside a single heavy mode the best extra pole read F
    1.9-3.6 (four heavy poles of three known-truth files, 5 hits at 3 % noise; in a
    fourth, F 23 for an undamped pole, which ADD_MIN_HALF_WIDTH_LINES refuses), the
    missed mode 58-113.
    """
    f = np.asarray(frequency_hz, dtype=float)
    h = np.atleast_2d(np.asarray(frf, dtype=complex))
    lam = np.asarray(poles, dtype=complex).ravel()
    added: list[complex] = []
    parent: list[int] = []
    if lam.size == 0:
        return np.array(added, dtype=complex), np.array(parent, dtype=int)
    f_all, zeta_all = frequency_damping(lam)
    half_width, lo, hi = _reach(lam, line_hz, HEAVY_WINDOW_SPAN)
    for k in np.argsort(f_all):
        if zeta_all[k] <= MAX_DAMPING:
            continue
        new = _one_more(f, h, lam, [int(k)], lo, hi, half_width, line_hz, HEAVY_ADD_MAX_DAMPING)
        if new is None:
            continue
        f_new, zeta_new = abs(new) / (2 * np.pi), -new.real / abs(new)
        others = np.concatenate([lam, np.array(added, dtype=complex)])
        f_o, zeta_o = frequency_damping(others)
        if np.all(np.abs(f_o - f_new) >= np.maximum(zeta_new * f_new, zeta_o * f_o)):
            added.append(new)
            parent.append(int(k))
    return np.array(added, dtype=complex), np.array(parent, dtype=int)


def _one_more(f, h, lam, group, lo, hi, half_width, line_hz, max_damping) -> complex | None:
    """The pole (rad/s) ``group``'s window holds beside the group's poles, by missing()'s
    test, damped at most ``max_damping``; None where there is none."""
    window, fixed = _window(f, lam, lo, hi, group)
    n_frf = h.shape[0]
    if not _enough_lines(window, len(group) + 1, fixed.size, n_frf):
        return None
    fw = f[window]
    weights = _weights(h[:, window], None)
    hw = h[:, window] * weights
    whole = _solve_group(fw, hw, weights, lam[group], fixed)
    if whole is None:
        return None
    zeta0 = float(np.median(-lam[group].real / np.abs(lam[group])))
    middle = (fw.min() + ADD_MARGIN * np.ptp(fw), fw.max() - ADD_MARGIN * np.ptp(fw))
    best = None
    for f0 in np.linspace(*middle, ADD_STARTS):
        start = 2 * np.pi * f0 * complex(-zeta0, np.sqrt(1 - zeta0**2))
        trial = _solve_group(fw, hw, weights, np.append(whole[0], start), fixed)
        if trial is not None and (best is None or trial[2] < best[2]):
            best = trial
    if best is None:
        return None
    n_residuals = 2 * int(window.sum()) * n_frf
    n_unknowns = 2 * (len(group) + 1) + 2 * (len(group) + 1 + fixed.size + 2) * n_frf
    # Below round-off the misfits say nothing: on noise-free FRFs both fits are exact and
    # their ratio is the rounding's (50/51 Hz at 0.5 %: a third pole "lowered" 6.5e-26 to 2e-29).
    floor = ROUNDOFF**2 * float(np.sum(np.abs(hw) ** 2))
    misfit_whole, misfit_best = max(whole[2], floor), max(best[2], floor)
    variance = misfit_best / max(n_residuals - n_unknowns, 1)
    gain = (misfit_whole - misfit_best) / (2 + 2 * n_frf)
    # The fit may return the poles in any order: the new one is the farthest from
    # the group's own, in their half-widths; the rest are theirs, in frequency order.
    fitted = best[0][np.argsort(np.abs(best[0]))]
    group_sorted = sorted(group, key=lambda k: abs(lam[k]))
    f_group = np.abs(lam[group_sorted]) / (2 * np.pi)
    far = np.abs(np.abs(fitted)[:, None] / (2 * np.pi) - f_group[None, :]) / half_width[group_sorted]
    k_new = int(np.argmax(far.min(axis=1)))
    new, own = fitted[k_new], np.delete(fitted, k_new)
    f_new, zeta_new = abs(new) / (2 * np.pi), -new.real / abs(new)
    f_own = np.abs(own) / (2 * np.pi)
    shown = ADD_MIN_HALF_WIDTH_LINES * line_hz <= zeta_new * f_new and zeta_new <= max_damping
    apart = np.all(np.abs(f_own - f_new) >= np.maximum(zeta_new * f_new, half_width[group_sorted]))
    starts = zip(own, lam[group_sorted], half_width[group_sorted], strict=True)
    kept = all(_near(p, q, width, line_hz) for p, q, width in starts)
    if gain > ADD_F * variance and shown and middle[0] <= f_new <= middle[1] and apart and kept:
        return complex(new)
    return None


def _moved(new: np.ndarray, old: np.ndarray, half_width: np.ndarray) -> float:
    """The largest frequency shift from ``old`` to ``new`` poles, in half-widths."""
    return float(np.max(np.abs(np.abs(new) - np.abs(old)) / (2 * np.pi * half_width)))


def _reach(
    lam: np.ndarray, line_hz: float, span: float | np.ndarray = WINDOW_SPAN
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(half-power half-width zeta f (at least a line), window's low edge, high edge), Hz,
    of each pole (n_poles,), the window ``span`` (a number, or one per pole) half-widths
    either side."""
    fn = np.abs(lam) / (2 * np.pi)
    half = np.maximum(-lam.real / np.abs(lam) * fn, line_hz)
    reach = np.maximum(span * half, MIN_WINDOW_LINES * line_hz)
    return half, fn - reach, fn + reach


def _window(f, lam, lo, hi, group) -> tuple[np.ndarray, np.ndarray]:
    """(the lines of ``group``'s window (n_lines,) bool, the other poles inside it, kept
    fixed)."""
    fn = np.abs(lam) / (2 * np.pi)
    window = (f >= lo[group].min()) & (f <= hi[group].max())
    if not window.any():
        return window, lam[:0]
    inside = (fn >= f[window].min()) & (fn <= f[window].max())
    return window, lam[inside & ~np.isin(np.arange(lam.size), group)]


def _enough_lines(window: np.ndarray, n_free: int, n_fixed: int, n_frf: int) -> bool:
    """True when the window holds LINES_PER_UNKNOWN real values per real unknown."""
    n_unknowns = 2 * n_free + 2 * (n_free + n_fixed + 2) * n_frf
    return window.sum() * 2 * n_frf >= LINES_PER_UNKNOWN * n_unknowns


def _groups(lo: np.ndarray, hi: np.ndarray, todo: np.ndarray) -> list[list[int]]:
    """Indices of the poles to refine, in groups whose windows [lo, hi] overlap."""
    groups: list[list[int]] = []
    reach = -np.inf
    for k in (int(k) for k in np.argsort(lo) if todo[k]):
        if groups and lo[k] <= reach:
            groups[-1].append(k)
            reach = max(reach, hi[k])
        else:
            groups.append([k])
            reach = hi[k]
    return groups


def _weights(h: np.ndarray, noise: np.ndarray | None) -> np.ndarray:
    """(n_frf, n_lines) the weight of each line: 1 / the noise there, else 1 / each
    FRF's RMS over the window (FRFs of different levels counted alike)."""
    if noise is not None:
        finite = np.isfinite(noise) & (noise > 0)
        if finite.any():
            fill = float(np.median(noise[finite]))
            # An infinite noise is a line left out (weight 0: a bootstrap's resampling).
            return np.where(np.isposinf(noise), 0.0, 1.0 / np.where(finite, noise, fill))
    rms = np.sqrt(np.mean(np.abs(h) ** 2, axis=1, keepdims=True))
    rms[rms == 0] = 1.0
    return np.broadcast_to(1.0 / rms, h.shape)


def _fit_group(f, hw, weights, free, fixed) -> np.ndarray | None:
    """The ``free`` poles fitted to the weighted FRFs ``hw`` (n_frf, n_lines), the
    ``fixed`` ones kept; None when the fit fails or does not lower the misfit."""
    solved = _solve_group(f, hw, weights, free, fixed)
    if solved is None or not solved[2] < solved[1]:
        return None
    return solved[0]


def _solve_group(f, hw, weights, free, fixed) -> tuple[np.ndarray, float, float] | None:
    """(the ``free`` poles fitted, the sum of squared weighted misfits at the start, at
    the end) for the weighted FRFs ``hw`` (n_frf, n_lines), the ``fixed`` poles kept;
    None when the fit fails."""
    omega = 2 * np.pi * f
    jw = 1j * omega[:, None]
    slope = ((omega - omega.mean()) / (np.ptp(omega) or 1.0))[:, None]
    m = free.size
    shared = bool(np.all(weights == weights[:, :1]))

    def misfit(x: np.ndarray) -> np.ndarray:
        with np.errstate(all="ignore"):
            lam = np.concatenate([-np.exp(x[:m]) + 1j * x[m:], fixed])
            if not np.all(np.isfinite(lam)):
                # A step the search tried far out (a wide window's flat misfit): no model.
                return np.concatenate([hw.real, hw.imag], axis=1).ravel()
            p_plus, p_minus = 1.0 / (jw - lam[None, :]), 1.0 / (jw - np.conj(lam)[None, :])
        # A = a + j b: A/(jw - l) + conj(A)/(jw - conj l) = a (p+ + p-) + b j (p+ - p-).
        basis = np.concatenate(
            [p_plus + p_minus, 1j * (p_plus - p_minus), np.ones_like(slope), 1j * np.ones_like(slope),
             slope, 1j * slope], axis=1,
        )  # fmt: skip
        if shared:
            # Each FRF's weight one number over the lines: the scaled design is the same
            # for all of them, so one solve serves every FRF.
            stacked = np.concatenate([basis.real, basis.imag])
            norm = np.linalg.norm(stacked, axis=0)
            norm[norm == 0] = 1.0
            rhs = np.concatenate([hw.real, hw.imag], axis=1).T
            coef = np.linalg.lstsq(stacked / norm, rhs, rcond=None)[0]
            out = hw - ((basis / norm) @ coef).T
            return np.concatenate([out.real, out.imag], axis=1).ravel()
        out = np.empty_like(hw)
        for r in range(hw.shape[0]):
            design = basis * weights[r][:, None]
            stacked = np.concatenate([design.real, design.imag])
            norm = np.linalg.norm(stacked, axis=0)
            norm[norm == 0] = 1.0
            rhs = np.concatenate([hw[r].real, hw[r].imag])
            coef = np.linalg.lstsq(stacked / norm, rhs, rcond=None)[0]
            model = (design / norm) @ coef
            out[r] = hw[r] - model
        return np.concatenate([out.real, out.imag], axis=1).ravel()

    x0 = np.concatenate([np.log(-free.real), free.imag])
    scale = np.concatenate([np.ones(m), 1e-3 * np.abs(free.imag)])
    try:
        start = misfit(x0)
        if not np.all(np.isfinite(start)):
            return None
        sol = least_squares(misfit, x0, x_scale=scale, method="lm")
    except (ValueError, np.linalg.LinAlgError):
        return None
    if not np.all(np.isfinite(sol.x)):
        return None
    return -np.exp(sol.x[:m]) + 1j * sol.x[m:], float(np.sum(start**2)), float(np.sum(sol.fun**2))


def _near(new: complex, old: complex, half_width_hz: float, line_hz: float) -> bool:
    """True when ``new`` lies within MAX_SHIFT_HALF_WIDTHS of ``old``'s half-width (or a
    line) in frequency and within MAX_DAMPING_FACTOR of its damping."""
    f_new, f_old = abs(new) / (2 * np.pi), abs(old) / (2 * np.pi)
    z_new, z_old = -new.real / abs(new), -old.real / abs(old)
    shift_ok = abs(f_new - f_old) <= MAX_SHIFT_HALF_WIDTHS * max(half_width_hz, line_hz)
    return bool(shift_ok and 1 / MAX_DAMPING_FACTOR <= z_new / z_old <= MAX_DAMPING_FACTOR)
