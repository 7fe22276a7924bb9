"""Mode shapes of a multi-point test (analysis.modal_id.shapes) on FRFs synthesised here
from the textbook cantilever: unit-modal-mass shapes (cosh - cos - sigma (sinh - sin)) /
sqrt(rho A L), modal damping, the hammer roved over 7 points and the accelerometer at
the tip (the 7th point: the driving point). Nothing of the truth comes from our modules."""

from __future__ import annotations

import numpy as np
import pytest

from analysis.beam import TABLE_1
from analysis.mac import auto_mac, mac
from analysis.modal_id import identify_modes
from analysis.modal_id.shapes import mean_phase_deviation_deg, modal_phase_collinearity, mode_shapes

BETA_L = np.array([1.8751040687, 4.6940911330, 7.8547574382, 10.9955407349, 14.1371683910, 17.2787595321])
LENGTH = TABLE_1.length_m
WN = BETA_L**2 * np.sqrt(TABLE_1.flexural_rigidity_n_m2 / (TABLE_1.mass_per_length_kg_m * LENGTH**4))
ZETA = np.array([0.02, 0.01, 0.008, 0.006, 0.005, 0.005])
POINTS = LENGTH * np.arange(1, 8) / 7
TIP = 6  # the driving point: the hammer at the sensor


def textbook(x, n: int = 6) -> np.ndarray:
    """(n, x.size) unit-modal-mass shapes, 1/sqrt(kg), each made positive at the tip."""
    k = BETA_L[:n, None]
    sigma = (np.cosh(k) + np.cos(k)) / (np.sinh(k) + np.sin(k))
    u = k * np.atleast_1d(x)[None, :] / LENGTH
    phi = (np.cosh(u) - np.cos(u) - sigma * (np.sinh(u) - np.sin(u))) / np.sqrt(TABLE_1.mass_kg)
    return phi * np.array([1, -1, 1, -1, 1, -1])[:n, None]


def poles(n: int) -> np.ndarray:
    return -ZETA[:n] * WN[:n] + 1j * WN[:n] * np.sqrt(1 - ZETA[:n] ** 2)


def roving_hammer(f_hz, n_modes: int, power: int = 2, points=POINTS, sensor_m=LENGTH) -> np.ndarray:
    """(n_points, n_lines): force at each point, sensor at sensor_m; power 0, 1, 2:
    receptance, mobility, accelerance ((jw)^power times receptance), SI units."""
    s = 2j * np.pi * np.asarray(f_hz)
    u, us = textbook(points, n_modes), textbook(sensor_m, n_modes)[:, 0]
    wn, z = WN[:n_modes, None], ZETA[:n_modes, None]
    receptance = np.einsum("rk,r,rf->kf", u, us, 1.0 / (wn**2 + s**2 + 2 * z * wn * s))
    return s**power * receptance


def noisy_hits(h: np.ndarray, n_hits: int, level: float, rng: np.random.Generator) -> np.ndarray:
    """(n_points, n_hits, n_lines): each hit's FRF with complex white noise of ``level``
    times each FRF's RMS."""
    sigma = level * np.sqrt(np.mean(np.abs(h) ** 2, axis=1))[:, None, None]
    shape = (h.shape[0], n_hits, h.shape[1])
    return h[:, None, :] + sigma * (rng.standard_normal(shape) + 1j * rng.standard_normal(shape)) / np.sqrt(2)


def test_roving_hammer_recovers_unit_modal_mass_shapes():
    """6 modes in the structure, 4 in the band 1-220 Hz, 5 hits per point, 1 % noise per
    hit: identify_modes on all FRFs together, then the shapes at its poles."""
    f = np.arange(1.0, 220.0, 0.0625)
    hits = noisy_hits(roving_hammer(f, 6), 5, 0.01, np.random.default_rng(7))
    h = hits.mean(axis=1)
    found = identify_modes(f, h)
    assert len(found.modes) == 4
    lam = np.array([m.pole for m in found.modes])
    np.testing.assert_allclose(np.abs(lam) / (2 * np.pi), WN[:4] / (2 * np.pi), rtol=1e-4)
    ms = mode_shapes(f, h, lam, "accelerance", TIP, per_hit_frf=hits)
    truth = textbook(POINTS, 4)
    assert ms.shapes.shape == ms.shape_std.shape == (4, 7)
    assert "unit modal mass" in ms.scaling
    assert ms.uncertainty_from.startswith("bootstrap over hits")
    # Value by value, within 0.3 % of the tip value (2/sqrt(m) = 4.49 /sqrt(kg)).
    np.testing.assert_allclose(ms.shapes.real, truth, atol=0.003 * truth[0, -1])
    assert np.max(np.abs(ms.shapes.imag)) < 0.003 * truth[0, -1]
    # Driving-point residue: the unit-modal-mass tip value within 0.2 %.
    np.testing.assert_allclose(ms.shapes[:, TIP].real, truth[:, -1], rtol=2e-3)
    assert np.all(np.diag(mac(ms.shapes, truth)) > 0.9999)
    off = auto_mac(ms.shapes)[~np.eye(4, dtype=bool)]
    assert off.max() < 0.1
    assert np.all(ms.mpc > 0.9999)
    assert np.all(ms.mpd_deg < 0.5)
    assert np.all(ms.shape_std > 0)
    assert np.all(ms.shape_std < 0.003 * truth[0, -1])
    assert np.all(ms.frequency_std_hz > 0)
    assert np.all(ms.damping_std > 0)
    assert ms.cautions == []


@pytest.mark.parametrize(("power", "form"), [(0, "receptance"), (1, "mobility"), (2, "accelerance")])
def test_each_form_gives_the_same_shapes(power, form):
    """Noise-free, every mode in the band: the residue of s^p H is lambda^p times the
    receptance's, and the shapes come out exact in every form (a -w^2 at a line, or
    -w_n^2, instead of lambda^2 would miss by about 2 zeta: 4 % on mode 1)."""
    f = np.arange(0.5, 220.0, 0.0625)
    h = roving_hammer(f, 4, power)
    ms = mode_shapes(f, h, poles(4), form, TIP, n_bootstrap=0, refit_poles=False)
    np.testing.assert_allclose(ms.shapes, textbook(POINTS, 4), atol=1e-7 * textbook(LENGTH, 1)[0, 0])
    if power == 2:
        receptance = mode_shapes(f, roving_hammer(f, 4, 0), poles(4), "receptance", TIP, n_bootstrap=0)
        ratio = ms.residues / receptance.residues
        np.testing.assert_allclose(ratio, np.broadcast_to(poles(4)[:, None] ** 2, ratio.shape), rtol=1e-7)
        assert np.all(np.abs(poles(4) ** 2 / -(WN[:4] ** 2) - 1) > 1.9 * ZETA[:4])


def test_without_a_driving_point_the_largest_component_is_one():
    f = np.arange(0.5, 220.0, 0.0625)
    h = roving_hammer(f, 4)[:TIP]  # the tip point not measured
    ms = mode_shapes(f, h, poles(4), "accelerance", None, n_bootstrap=0)
    assert "unit largest component" in ms.scaling
    np.testing.assert_allclose(np.max(np.abs(ms.shapes), axis=1), 1.0, rtol=1e-12)
    truth = textbook(POINTS[:TIP], 4)
    expected = truth / truth[np.arange(4), np.argmax(np.abs(truth), axis=1)][:, None]
    np.testing.assert_allclose(ms.shapes, expected, atol=1e-7)


def test_one_point_reduces_to_identify_modes():
    """The tip FRF alone: the same frequencies, dampings and residues as identify_modes
    of that FRF (given poles kept), and the driving-point value of a unit-modal-mass
    cantilever, 2/sqrt(rho A L)."""
    f = np.arange(1.0, 220.0, 0.0625)
    hits = noisy_hits(roving_hammer(f, 6)[TIP:], 5, 0.01, np.random.default_rng(3))
    h = hits.mean(axis=1)
    found = identify_modes(f, h)
    lam = np.array([m.pole for m in found.modes])
    ms = mode_shapes(f, h, lam, "accelerance", 0, per_hit_frf=hits, refit_poles=False)
    np.testing.assert_allclose(ms.frequency_hz, [m.frequency_hz for m in found.modes], rtol=1e-14)
    np.testing.assert_allclose(ms.damping_ratio, [m.damping_ratio for m in found.modes], rtol=1e-12)
    np.testing.assert_allclose(ms.residues[:, 0], [m.modal_constant[0] for m in found.modes], rtol=1e-10)
    np.testing.assert_allclose(ms.shapes[:, 0].real, 2 / np.sqrt(TABLE_1.mass_kg), rtol=5e-3)
    np.testing.assert_allclose(ms.mpc, 1.0, rtol=1e-12)  # one point: nothing to scatter
    refit = mode_shapes(f, h, lam, "accelerance", 0, n_bootstrap=0)
    # The refit (least squares on the pole-residue model) moves the poles a little.
    np.testing.assert_allclose(refit.frequency_hz, ms.frequency_hz, rtol=3e-4)
    np.testing.assert_allclose(refit.damping_ratio, ms.damping_ratio, rtol=0.03)


def test_non_proportional_damping_gives_complex_modes():
    """A dashpot of 5 N s/m at 0.35 m couples the modes: complex modes computed here
    from the state space (receptance = sum psi psi^T / (a_r (s - lambda_r)) + c.c.,
    a_r = psi^T (2 lambda_r M + C) psi). Their MPC is recovered, and the shapes are the
    truth scaled by sqrt(2 j w_d / a_r)."""
    n = 4
    c = np.diag(2 * 0.005 * WN[:n]) + 5.0 * textbook(0.35, n) @ textbook(0.35, n).T
    a_matrix = np.block([[np.zeros((n, n)), np.eye(n)], [-np.diag(WN[:n] ** 2), -c]])
    lam, vec = np.linalg.eig(a_matrix)
    keep = lam.imag > 0
    lam, vec = lam[keep], vec[:n, keep]
    order = np.argsort(lam.imag)
    lam, vec = lam[order], vec[:, order]
    a_r = np.einsum("ir,ir->r", vec, 2 * lam * vec + c @ vec)
    psi = textbook(POINTS, n).T @ vec  # (7, n) complex shapes at the points
    f = np.arange(0.5, 260.0, 0.0625)
    s = 2j * np.pi * f
    terms = psi[:, None, :] * psi[TIP, None, :] / a_r
    h = s**2 * (
        np.einsum("kr,rf->kf", terms[:, 0, :], 1 / (s[None, :] - lam[:, None]))
        + np.einsum("kr,rf->kf", np.conj(terms[:, 0, :]), 1 / (s[None, :] - np.conj(lam)[:, None]))
    )
    ms = mode_shapes(f, h, lam, "accelerance", TIP, n_bootstrap=0)
    truth = (psi * np.sqrt(2j * lam.imag / a_r)).T
    truth *= np.where(truth[:, TIP].real < 0, -1, 1)[:, None]
    np.testing.assert_allclose(ms.shapes, truth, atol=1e-5 * np.abs(truth).max())
    mpc_truth = modal_phase_collinearity(truth)
    assert mpc_truth[1] < 0.96  # mode 2 is markedly complex
    np.testing.assert_allclose(ms.mpc, mpc_truth, atol=1e-6)
    assert ms.mpc[1] < 0.96
    assert ms.mpd_deg[1] > 3.0
    # The same beam with proportional damping: MPC 1, MPD 0.
    real = mode_shapes(f, roving_hammer(f, 4), poles(4), "accelerance", TIP, n_bootstrap=0)
    assert np.all(real.mpc > 1 - 1e-9)
    assert np.all(real.mpd_deg < 1e-3)


def test_mpc_and_mpd_by_hand():
    assert modal_phase_collinearity(np.array([1.0, -2.0, 3.0])) == pytest.approx(1.0)
    assert modal_phase_collinearity(np.array([1.0, 1j])) == pytest.approx(0.0)  # 90 deg apart, equal
    # One component 45 deg off the line of the other two (equal magnitudes): MPD 15 deg.
    shape = np.array([1.0, 1.0, np.exp(1j * np.pi / 4)]) * np.exp(0.3j)
    axis = 0.5 * np.angle(np.sum(shape**2))
    dev = np.degrees(np.abs(np.angle(shape * np.exp(-1j * axis))))
    assert mean_phase_deviation_deg(shape) == pytest.approx(np.mean(dev))
    assert 10 < mean_phase_deviation_deg(shape) < 20
    assert mean_phase_deviation_deg(np.array([2.0, -1.0]) * 1j) == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("source", ["lines", "hits"])
def test_uncertainty_coverage(source):
    """Over 16 noisy realisations of a 3-mode roving-hammer test (2 % noise per hit),
    the truth lies within +-1 standard uncertainty about 68 % of the time and within +-2
    about 95 % (real and imaginary parts of 7 x 3 shape values each). The poles start
    off the truth (+0.01 % frequency, +1 % damping: LSCF's kind of bias) and are refitted.
    By hits: 12 hits per point (with 5, the stated std has 4 degrees of freedom and +-2
    of it covers 88 %, as Student's t says)."""
    f = np.arange(1.0, 125.0, 0.1)
    h_true = roving_hammer(f, 3)
    truth = textbook(POINTS, 3)
    start = poles(3) * (1 + 1e-4) + 0.01 * poles(3).real
    rng = np.random.default_rng(11)
    z = []
    for k in range(16):
        hits = noisy_hits(h_true, 12 if source == "hits" else 5, 0.02, rng)
        ms = mode_shapes(
            f, hits.mean(axis=1), start, "accelerance", TIP,
            per_hit_frf=hits if source == "hits" else None, rng=k, n_bootstrap=25,
        )  # fmt: skip
        assert ms.uncertainty_from.startswith(f"bootstrap over {source}")
        z.append(((ms.shapes.real - truth) / ms.shape_std).ravel())
        z.append((ms.shapes.imag / ms.shape_std_imag).ravel())
    z = np.abs(np.concatenate(z))
    within1, within2 = np.mean(z < 1), np.mean(z < 2)
    assert 0.58 <= within1 <= 0.78, within1
    assert 0.88 <= within2 <= 0.99, within2


def test_driving_point_near_a_node_is_flagged():
    """Sensor (and driving point) at the node of mode 2, x/L = 0.7834: mode 2's unit
    modal mass cannot be had through it, and the result says so."""
    node = 0.7834 * LENGTH
    points = np.array([0.2, 0.4, node, LENGTH])
    f = np.arange(0.5, 220.0, 0.0625)
    h = roving_hammer(f, 4, points=points, sensor_m=node)
    ms = mode_shapes(f, h, poles(4), "accelerance", 2, n_bootstrap=0)
    assert len(ms.cautions) == 1
    assert "near a node of the mode at 34.898" in ms.cautions[0]


def test_a_caution_names_the_mode_as_given_when_the_refit_moves_its_pole():
    """The poles are refitted before the residues; a caution names the mode by the
    frequency it was given with (the one a test's table lists), not the refitted one.
    Sensor at the node of mode 2, as above; mode 2 given one half-power half-width high."""
    node = 0.7834 * LENGTH
    points = np.array([0.2, 0.4, node, LENGTH])
    f = np.arange(0.5, 220.0, 0.0625)
    h = roving_hammer(f, 4, points=points, sensor_m=node)
    given = poles(4).copy()
    given[1] = given[1] - given[1].real * 1j  # Im up by zeta w_n: 0.5 % of 34.898 Hz
    ms = mode_shapes(f, h, given, "accelerance", 2, n_bootstrap=0)
    named = f"{abs(given[1]) / (2 * np.pi):.6g}"
    assert named != "34.898"
    assert f"near a node of the mode at {named} Hz" in ms.cautions[0], ms.cautions


def test_bad_inputs_are_refused():
    f = np.arange(0.5, 50.0, 0.25)
    h = roving_hammer(f, 2)
    with pytest.raises(ValueError, match="driving_index"):
        mode_shapes(f, h, poles(2), "accelerance", 7)
    with pytest.raises(ValueError, match="Im > 0 and Re < 0"):
        mode_shapes(f, h, np.conj(poles(2)), "accelerance", TIP)
    with pytest.raises(ValueError, match="form"):
        mode_shapes(f, h, poles(2), "inertance", TIP)
    with pytest.raises(ValueError, match="one set of hits per FRF"):
        mode_shapes(f, h, poles(2), "accelerance", TIP, per_hit_frf=[h[:, None, :]] * 3)
    with pytest.raises(ValueError, match="frf must have shape"):
        mode_shapes(f, h[:, :-1], poles(2), "accelerance", TIP)
