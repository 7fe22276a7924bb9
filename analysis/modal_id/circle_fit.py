"""Circle fit (Kennedy-Pancu) of one mode, on MOBILITY.

For viscous damping the mobility of one mode, Y = j w A / (w_n^2 - w^2 + 2 j zeta w_n w),
is an exact circle through the origin: Y = (D/2)(1 + e^(-2 j phi)) with diameter
D = A / (2 zeta w_n) and tan(phi) = (w - w_n^2 / w) / (2 zeta w_n). (Receptance and
accelerance circles are only approximately circles.) Receptance and accelerance are
therefore converted to mobility first (times j w, divided by j w). Nearby modes add a
locally constant offset, which moves the centre but not the shape.

Steps: a peak near the guess; lines around it (the half-power band, widened to at
least ``min_points``); an algebraic (Kasa) least-squares circle; then the angles of
the points seen from the centre are fitted with
    alpha_k = psi - 2 arctan((w_k - w_n^2 / w_k) / (2 zeta w_n))
for (w_n, zeta, psi), started from the point of fastest angle sweep (Ewins' rule).
The modal constant (mobility circle) is A = 2 zeta w_n * D, D = 2 R e^(j psi); as a
pole residue (H ~ A_r / (j w - lambda) + ...): receptance A / (2 j w_d), times lambda
for mobility, times lambda^2 for accelerance (the near-resonance equivalents).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from analysis.modal_id.lsfd import FORMS


@dataclass(frozen=True)
class CircleFit:
    """frequency_hz: undamped natural frequency; damping_ratio; pole (rad/s);
    modal_constant (n_frf,) complex pole residue in the FRF's units times rad/s;
    centre (n_frf,) complex and radius (n_frf,) of each mobility circle (m/s/N for
    accelerance data in m/s^2/N); n_points used."""

    frequency_hz: float
    damping_ratio: float
    pole: complex
    modal_constant: np.ndarray
    centre: np.ndarray
    radius: np.ndarray
    n_points: int


def _kasa(y: np.ndarray) -> tuple[complex, float]:
    """Least-squares circle x^2 + y^2 + D x + E y + F = 0 through complex points y."""
    x, v = y.real, y.imag
    a = np.column_stack([x, v, np.ones_like(x)])
    d, e, g = np.linalg.lstsq(a, -(x * x + v * v), rcond=None)[0]
    c = complex(-d / 2, -e / 2)
    return c, float(np.sqrt(max(abs(c) ** 2 - g, 0.0)))


def _to_mobility(omega: np.ndarray, h: np.ndarray, form: str) -> np.ndarray:
    if form == "receptance":
        return h * (1j * omega)
    if form == "accelerance":
        return h / (1j * omega)
    if form == "mobility":
        return h
    raise ValueError(f"form must be one of {', '.join(FORMS)}, got {form!r}")


def circle_fit(
    frequency_hz: np.ndarray,
    frf: np.ndarray,
    frequency_guess_hz: float,
    form: str = "accelerance",
    search_rel: float = 0.05,
    min_points: int = 7,
) -> CircleFit:
    """Kennedy-Pancu circle fit of the mode nearest ``frequency_guess_hz``.

    frequency_hz (n_lines,) Hz; frf (n_lines,) or (n_frf, n_lines). The peak is looked
    for within +-search_rel of the guess, on the FRF with the largest mobility there;
    frequency and damping come from that FRF's circle, the modal constants of the others
    from their own circles over the same lines.
    """
    f = np.asarray(frequency_hz, dtype=float)
    h = np.atleast_2d(np.asarray(frf, dtype=complex))
    if f.ndim != 1 or h.shape[1] != f.size:
        raise ValueError("frf must have shape (n_lines,) or (n_frf, n_lines) matching frequency_hz")
    omega = 2 * np.pi * f
    with np.errstate(all="ignore"):
        y = _to_mobility(omega, h, form)
    y[:, omega == 0] = 0.0
    window = np.flatnonzero(np.abs(f - frequency_guess_hz) <= search_rel * frequency_guess_hz)
    if window.size == 0:
        raise ValueError(f"no lines within {search_rel:.0%} of {frequency_guess_hz} Hz")
    mag = np.abs(y[:, window])
    best = int(np.argmax(mag.max(axis=1)))
    k = int(window[np.argmax(mag[best])])
    peak = np.abs(y[best, k])
    lo, hi = k, k
    while lo > 0 and np.abs(y[best, lo - 1]) >= peak / np.sqrt(2):
        lo -= 1
    while hi < f.size - 1 and np.abs(y[best, hi + 1]) >= peak / np.sqrt(2):
        hi += 1
    while hi - lo + 1 < min_points and (lo > 0 or hi < f.size - 1):
        lo, hi = max(lo - 1, 0), min(hi + 1, f.size - 1)
    sel = np.arange(lo, hi + 1)
    sel = sel[omega[sel] > 0]
    if sel.size < 4:
        raise ValueError("too few lines around the peak for a circle fit")
    w = omega[sel]
    centre, radius = zip(*(_kasa(y[o, sel]) for o in range(h.shape[0])), strict=True)
    centre, radius = np.array(centre), np.array(radius)
    ang = np.unwrap(np.angle(y[best, sel] - centre[best]))
    # Start: fastest sweep of angle per rad/s between neighbouring points.
    rate = np.abs(np.diff(ang) / np.diff(w))
    j = int(np.argmax(rate))
    wn0 = 0.5 * (w[j] + w[j + 1])
    zeta0 = max(2.0 / (wn0 * rate[j]), 1e-5)  # |d alpha / dw| = 2 / (zeta w_n) at w_n
    psi0 = 0.5 * (ang[j] + ang[j + 1])

    def residual(x):
        wn, zeta, psi = x
        model = psi - 2 * np.arctan((w - wn**2 / w) / (2 * zeta * wn))
        return np.angle(np.exp(1j * (ang - model)))

    sol = least_squares(
        residual, [wn0, zeta0, psi0], bounds=([w[0], 1e-6, -np.inf], [w[-1], 1.0, np.inf]), x_scale="jac"
    )
    wn, zeta, _ = sol.x
    wd = wn * np.sqrt(1 - zeta**2)
    lam = complex(-zeta * wn, wd)
    # Diameter direction of each FRF's circle: from the centre to the point at w_n.
    a_mob = np.empty(h.shape[0], dtype=complex)
    for o in range(h.shape[0]):  # one circle per FRF, n_frf <= a few
        ang_o = np.unwrap(np.angle(y[o, sel] - centre[o]))
        phi = np.arctan((w - wn**2 / w) / (2 * zeta * wn))
        psi_o = np.angle(np.mean(np.exp(1j * (ang_o + 2 * phi))))
        a_mob[o] = 2 * zeta * wn * 2 * radius[o] * np.exp(1j * psi_o)
    residue = a_mob / (2j * wd)  # receptance pole residue
    if form == "mobility":
        residue = residue * lam
    elif form == "accelerance":
        residue = residue * lam**2
    return CircleFit(float(wn / (2 * np.pi)), float(zeta), lam, residue, centre, radius, int(sel.size))
