"""R from complex modes in the Ritz basis: Adhikari-Woodhouse (2001) first-order method,
its symmetric variant, and Lancaster's formula with residue-scaled modes.

The exact complex modes are computed here from the state matrix (scipy.linalg.eig), not
through the project's modal code. Theory pinned: proportional damping is recovered
exactly (the imaginary parts vanish), the first-order method's neglected part of the
imaginary shapes is third order in the damping so its relative error in R falls with
the square of the damping (ratio 1/4 when the damping halves), and Lancaster's formula
is exact.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg

from analysis.damping import complex_modes as cm
from analysis.ritz import RitzBeam

BEAM = RitzBeam.build(n_functions=3)
M, K = BEAM.mass, BEAM.stiffness
LENGTH = BEAM.beam.length_m
POINTS = LENGTH * np.arange(1, 8) / 7
BASIS = BEAM.shapes(POINTS).T  # (7 points, 3 functions)
#: Non-proportional: in the undamped modal basis its off-diagonal terms are 0.3-0.9 of
#: the geometric mean of the diagonal ones.
R_SHAPE = np.array([[1.0, 0.6, -0.3], [0.6, 0.8, 0.2], [-0.3, 0.2, 0.5]])


def _exact_modes(damping):
    """Poles (upper half-plane, ascending |s|) and Ritz-coordinate shapes (3, 3),
    scaled so that q^T (2 s M + R) q = 1 (the displacement FRF's residue is q q^T)."""
    n = 3
    a = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(M, K), -np.linalg.solve(M, damping)]])
    lam, vec = scipy.linalg.eig(a)
    up = lam.imag > 0
    lam, q = lam[up], vec[:n, up]
    order = np.argsort(np.abs(lam))
    lam, q = lam[order], q[:, order]
    norm = np.array([q[:, j] @ (2 * lam[j] * M + damping) @ q[:, j] for j in range(n)])
    return lam, q / np.sqrt(norm)


def _rel(a, b):
    return np.linalg.norm(a - b) / np.linalg.norm(b)


def test_adhikari_woodhouse_recovers_r_to_first_order():
    errors, errors_sym = [], []
    for eps in (1.0, 0.5, 0.25):
        r = eps * R_SHAPE
        s, q = _exact_modes(r)
        zeta = -s.real / np.abs(s)
        # Arbitrary phase and scale per mode, as a measurement gives them.
        shapes = BASIS @ q * np.array([2.0 * np.exp(0.3j), -0.5j, 7.0 * np.exp(2.0j)])
        plain = cm.adhikari_woodhouse(s, shapes, BASIS, M)
        sym = cm.adhikari_woodhouse(s, shapes, BASIS, M, symmetric=True)
        assert np.max(plain.mapping_residual) < 1e-10  # the shapes are Ritz shapes
        assert sym.asymmetry == 0.0
        assert np.array_equal(sym.damping_matrix, sym.damping_matrix.T)
        assert plain.asymmetry > 0  # the plain method is not symmetric in general
        # C' in the basis of the undamped modes: its diagonal is exact (2 zeta omega).
        np.testing.assert_allclose(np.diag(plain.modal_damping), 2 * zeta * np.abs(s), rtol=1e-12)
        errors.append(_rel(plain.damping_matrix, r))
        errors_sym.append(_rel(sym.damping_matrix, r))
        if eps == 0.25:  # damping 0.18, 0.86, 1.5 %
            assert np.max(zeta) < 0.02
            assert errors[-1] < 0.01
            assert errors_sym[-1] < 0.01
    for errs in (errors, errors_sym):
        ratios = np.array(errs[1:]) / np.array(errs[:-1])
        assert np.all((ratios > 0.2) & (ratios < 0.3)), ratios  # quadratic: 1/4 per halving


def test_proportional_damping_is_exact():
    _w2, x = scipy.linalg.eigh(K, M)
    r = M @ x @ np.diag([0.5, 2.0, 5.0]) @ x.T @ M
    s, q = _exact_modes(r)
    for sym in (False, True):
        out = cm.adhikari_woodhouse(s, BASIS @ q, BASIS, M, symmetric=sym)
        assert _rel(out.damping_matrix, r) < 1e-10


def test_lancaster_is_exact_with_residue_scaled_modes():
    r = 3.0 * R_SHAPE  # heavy: damping up to 18 %, where the first-order method is off
    s, q = _exact_modes(r)
    assert _rel(cm.adhikari_woodhouse(s, BASIS @ q, BASIS, M).damping_matrix, r) > 0.3
    out = cm.identify(s, BASIS @ q * np.array([1, -1, 1]), BASIS, M, method="lancaster")
    assert _rel(out.damping_matrix, r) < 1e-8
    # Accelerance residues are s^2 times the receptance ones: shapes scaled by s.
    acc = cm.identify(s, BASIS @ q * s, BASIS, M, method="lancaster", quantity="acceleration")
    assert _rel(acc.damping_matrix, r) < 1e-8


def test_bad_inputs():
    s, q = _exact_modes(R_SHAPE)
    with pytest.raises(ValueError, match="need n_points >= N"):
        cm.adhikari_woodhouse(s, (BASIS @ q)[:2], BASIS[:2], M)
    with pytest.raises(ValueError, match="positive imaginary"):
        cm.adhikari_woodhouse(s.conj(), BASIS @ q, BASIS, M)
    with pytest.raises(ValueError, match="needs N = 3 modes"):
        cm.adhikari_woodhouse(s[:2], (BASIS @ q)[:, :2], BASIS, M)
    with pytest.raises(ValueError, match="unknown method"):
        cm.identify(s, BASIS @ q, BASIS, M, method="modal")
