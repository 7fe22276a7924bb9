"""The frequency-domain objective of runs with hits (analysis/damping/hit_frf.py): the
model's FRF made from its response to the hits through the same windows, exact where
the windowed model exp(-sigma t_p) H(j omega + sigma) (windowed_frf) is not."""

from __future__ import annotations

import numpy as np
import pytest

from analysis.beam import TABLE_1
from analysis.damping import bandlimited, fit_least_squares, hit_frf, windowed_frf
from analysis.ritz import RitzBeam
from analysis.seed import eq18_damping_matrix
from analysis.windows import WindowSpec, window

FS, N, PULSE_AT = 512.0, 1024, 32  # the simulated seed capture's record: 200 Hz, 1/16 s pre-trigger
DECAY_S = 1 / 3


def _noise_free_hits(n_hits: int = 3) -> tuple[object, np.ndarray, np.ndarray]:
    """(model, force, response): half-sine hammer pulses of 2-4 ms at sample PULSE_AT and
    the seed beam's band-limited response with eq (18), no noise."""
    model = RitzBeam.build(TABLE_1, 3).structure(None, None)
    t = np.arange(N) / FS
    force = np.zeros((n_hits, N))
    for k in range(n_hits):
        width = 0.002 + 0.001 * k
        on = (t >= PULSE_AT / FS) & (t < PULSE_AT / FS + width)
        force[k, on] = 100.0 * np.sin(np.pi * (t[on] - PULSE_AT / FS) / width)
    records = bandlimited.BandLimitedData(model, force, force, FS)
    response = bandlimited.model_response(records, eq18_damping_matrix()[None])[0]
    return model, force, response


def _fit(module, data) -> np.ndarray:
    fit = fit_least_squares(
        lambda m: module.residuals(data, m),
        eq18_damping_matrix() * 1.2,
        psd=False,
        batched_residuals=lambda m: module.batched_residuals(data, m),
    )
    return np.asarray(fit.damping_matrix)


@pytest.fixture(scope="module")
def hits():
    return _noise_free_hits()


def test_noise_free_hits_give_eq18_back_through_force_and_exponential_windows(hits):
    model, force, response = hits
    data = hit_frf.HitFrfData(
        model, force, response, FS,
        window(WindowSpec("force", force_width_s=0.125), N, FS),
        window(WindowSpec("exponential", exp_decay_s=DECAY_S), N, FS),
    )  # fmt: skip
    assert data.frequency_hz[0] == pytest.approx(0.5)
    assert data.frequency_hz[-1] == pytest.approx(200.0)
    assert np.max(np.abs(hit_frf.residuals(data, eq18_damping_matrix()))) < 1e-9 * np.max(np.abs(data.frf))
    assert _fit(hit_frf, data) == pytest.approx(eq18_damping_matrix(), abs=1e-4)


def test_the_windowed_model_misreads_the_same_hits(hits):
    """Why the FRF of a run with hits is no longer fitted with the windowed model: on the
    same noise-free hits its small line errors move R's poorly determined terms."""
    model, force, response = hits
    w_f = window(WindowSpec("force", force_width_s=0.125), N, FS)
    w_r = window(WindowSpec("exponential", exp_decay_s=DECAY_S), N, FS)
    exact = hit_frf.HitFrfData(model, force, response, FS, w_f, w_r)
    windowed = windowed_frf.WindowedFrfData(
        model, exact.frequency_hz, exact.frf, None, 1 / DECAY_S, PULSE_AT / FS
    )
    model_lines = windowed_frf.model_frf(windowed, eq18_damping_matrix())[0]
    assert np.max(np.abs(model_lines / exact.frf - 1)) > 1e-3  # the windowed model's own error
    r = _fit(windowed_frf, windowed)
    assert abs(r[2, 2] - eq18_damping_matrix()[2, 2]) > 0.1 * eq18_damping_matrix()[2, 2]


def test_one_hit_is_its_own_frf_with_coherence_one(hits):
    model, force, response = hits
    w = np.ones(N)
    data = hit_frf.HitFrfData(model, force, response, FS, w, w)
    one = data.hit(1)
    assert one.n_hits == 1
    assert np.allclose(one.weights, 1.0)
    spectrum = np.fft.rfft(response[1]) / np.fft.rfft(force[1])
    assert one.frf == pytest.approx(spectrum[1 : one.frf.size + 1])


def test_per_hit_refits_run_in_the_frequency_domain(hits):
    from analysis.damping.checks import per_hit_std

    model, force, response = hits
    rng = np.random.default_rng(0)
    noisy = response + 0.01 * np.std(response) * rng.standard_normal(response.shape)
    w = np.ones(N)
    data = hit_frf.HitFrfData(model, force, noisy, FS, w, w)
    std = per_hit_std(data, eq18_damping_matrix(), psd=False)
    assert std is not None
    assert std.shape == (6,)
    assert np.all(np.isfinite(std))
    assert np.all(std > 0)
