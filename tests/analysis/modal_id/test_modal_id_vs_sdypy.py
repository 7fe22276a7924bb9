"""Cross-check of identify_modes against sdypy-EMA's LSCF on the same constructed FRFs."""

from __future__ import annotations

import contextlib
import io
import warnings

import numpy as np
import pytest

from analysis.modal_id import identify_modes

EMA = pytest.importorskip("sdypy.EMA")

F = np.linspace(0.0, 200.0, 801)


def accelerance(f, fn, zeta, modal_a, noise, seed=0):
    w = 2 * np.pi * f
    wn = 2 * np.pi * np.asarray(fn)
    z = np.asarray(zeta)
    lam = -z * wn + 1j * wn * np.sqrt(1 - z**2)
    a = np.atleast_2d(modal_a)
    jw = 1j * w[None, None, :]
    h = -(w**2) * np.sum(
        a[..., None] / ((jw - lam[None, :, None]) * (jw - np.conj(lam)[None, :, None])), axis=1
    )
    rng = np.random.default_rng(seed)
    rms = np.sqrt(np.mean(np.abs(h) ** 2, axis=1, keepdims=True))
    return h + noise * rms * (rng.standard_normal(h.shape) + 1j * rng.standard_normal(h.shape)) / np.sqrt(2)


def sdypy_modes(f, h, approx_hz, max_order):
    """sdypy-EMA LSCF, non-interactive: poles, closest stable poles, LSFD constants.

    lower=1 Hz: with lower=0 its band-limited sums are wrong (all poles move).
    """
    model = EMA.Model(frf=h, freq=f, lower=1.0, upper=f[-1], pol_order_high=max_order, pyfrf=False)
    with contextlib.redirect_stderr(io.StringIO()), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model.get_poles(show_progress=False)
        model.select_closest_poles(list(approx_hz))
        model.get_constants()
    return np.asarray(model.nat_freq), np.asarray(model.nat_xi)


def test_same_modes_as_sdypy_on_lightly_damped_frfs():
    fn, zeta = [36.0, 98.0, 150.0], [0.005, 0.01, 0.008]
    shapes = np.array([[1.0, -0.8, 0.6], [0.7, 0.5, -1.0]])
    h = accelerance(F, fn, zeta, shapes * shapes[0], noise=0.01)
    ours = identify_modes(F, h, max_order=30)
    f_ours = np.array([m.frequency_hz for m in ours.modes])
    z_ours = np.array([m.damping_ratio for m in ours.modes])
    f_sdy, z_sdy = sdypy_modes(F, h, f_ours, 30)
    np.testing.assert_allclose(f_ours, f_sdy, rtol=0.001)
    np.testing.assert_allclose(z_ours, z_sdy, rtol=0.10)
    np.testing.assert_allclose(f_ours, fn, rtol=0.001)


def test_heavily_damped_paper_case_ours_closer_to_truth():
    fn, zeta = np.array([5.589, 36.09, 96.48]), np.array([0.0361, 0.2032, 0.1620])
    h = accelerance(F, fn, zeta, [1.0, -2.0, 1.5], noise=0.01)
    ours = identify_modes(F, h, max_order=30)
    f_ours = np.array([m.frequency_hz for m in ours.modes])
    z_ours = np.array([m.damping_ratio for m in ours.modes])
    f_sdy, z_sdy = sdypy_modes(F, h, fn, 30)
    err_ours = np.abs(f_ours - fn) / fn + np.abs(z_ours - zeta) / zeta
    err_sdy = np.abs(f_sdy - fn) / fn + np.abs(z_sdy - zeta) / zeta
    # Where both agree (within 0.1 % / 10 %) nothing to arbitrate; elsewhere ours must be closer.
    agree = (np.abs(f_ours - f_sdy) <= 0.001 * fn) & (np.abs(z_ours - z_sdy) <= 0.1 * zeta)
    assert np.all(agree | (err_ours < err_sdy)), (f_ours, z_ours, f_sdy, z_sdy)
    assert np.all(err_ours < 0.1)
