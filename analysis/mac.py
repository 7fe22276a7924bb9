"""Modal Assurance Criterion between mode-shape sets, complex shapes allowed.

    MAC(a, b) = |a^H b|^2 / ((a^H a) (b^H b)),   0 <= MAC <= 1,

a, b the shape vectors at the same points (any scaling, any complex factor: MAC is
invariant to multiplying either shape by a non-zero complex number). 1: the shapes are
proportional; 0: orthogonal over the points. A shape that is zero at every point has
no direction: its MAC is NaN.
"""

from __future__ import annotations

import numpy as np


def _as_set(shapes: np.ndarray, name: str) -> np.ndarray:
    s = np.asarray(shapes)
    if s.ndim == 1:
        s = s[np.newaxis, :]
    if s.ndim != 2 or s.shape[1] == 0:
        raise ValueError(f"{name} must have shape (n_modes, n_points) or (n_points,), got {s.shape}")
    s = s.astype(complex)
    if not np.all(np.isfinite(s)):
        raise ValueError(f"{name} holds non-finite values")
    return s


def mac(shapes_a: np.ndarray, shapes_b: np.ndarray) -> np.ndarray:
    """MAC of every shape of ``shapes_a`` against every shape of ``shapes_b``.

    shapes_a (n_a, n_points) or (n_points,), shapes_b (n_b, n_points) or (n_points,),
    real or complex, any units (each shape's scale cancels). Returns (n_a, n_b) real in
    [0, 1]; NaN where a shape is zero at every point.
    """
    a = _as_set(shapes_a, "shapes_a")
    b = _as_set(shapes_b, "shapes_b")
    if a.shape[1] != b.shape[1]:
        raise ValueError(f"the shape sets are at different numbers of points: {a.shape[1]} and {b.shape[1]}")
    cross = np.abs(np.conj(a) @ b.T) ** 2  # (n_a, n_b): |a^H b|^2
    na = np.sum(np.abs(a) ** 2, axis=1)
    nb = np.sum(np.abs(b) ** 2, axis=1)
    denom = na[:, None] * nb[None, :]
    with np.errstate(invalid="ignore", divide="ignore"):
        out = np.where(denom > 0, cross / np.where(denom > 0, denom, 1.0), np.nan)
    # Round-off can push a proportional pair a few ulps above 1.
    return np.minimum(out, 1.0)


def auto_mac(shapes: np.ndarray) -> np.ndarray:
    """MAC of a shape set against itself, (n_modes, n_modes): 1 on the diagonal; the
    off-diagonal terms say how distinct the modes are at these points (large: the points
    cannot tell the modes apart, too few or badly placed)."""
    return mac(shapes, shapes)


def align(shapes: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """Each shape multiplied by the unit complex number e^{j theta} that brings it
    closest (least squares) to the reference shape of the same row: theta = arg(s^H r).

    shapes, reference (n_modes, n_points) or (n_points,); returns the shape of
    ``shapes``. Only the phase (for real shapes: the sign) changes, never the magnitude;
    use it before comparing shapes value by value (a mode shape's sign is arbitrary).
    """
    s = _as_set(shapes, "shapes")
    r = _as_set(reference, "reference")
    if s.shape != r.shape:
        raise ValueError(f"shapes {s.shape} and reference {r.shape} must have the same shape")
    inner = np.sum(np.conj(s) * r, axis=1)
    phase = np.where(np.abs(inner) > 0, inner / np.where(np.abs(inner) > 0, np.abs(inner), 1.0), 1.0)
    out = s * phase[:, None]
    return out[0] if np.ndim(shapes) == 1 else out
