"""analysis.spectra against pyFRF (same data, same windows), an analytic SDOF accelerance
(time responses computed exactly in the time domain), known sinusoids and delays, and
the simulated analyzer's own FRF of the same hits."""

from __future__ import annotations

import numpy as np
import pyFRF
import pytest
import scipy.signal

from analysis.spectra import (
    FrfEstimate,
    Spectra,
    convert_form,
    frf_estimate,
    linear_spectra,
    per_hit_frf,
)
from analysis.windows import WindowSpec
from sims.dsp import Average, line_spectrum, peak_scale
from sims.dsp import window as analyzer_window
from sims.settings import AnalyzerSettings
from sims.sources import PhysicsSource

UNIFORM = WindowSpec("uniform")
RNG_SEED = 20240611


# ----------------------------------------------------------------- helpers


def accelerance(freq_hz: np.ndarray, m: float, c: float, k: float) -> np.ndarray:
    """Analytic SDOF accelerance -w^2 / (k - m w^2 + j c w), (m/s^2)/N."""
    w = 2 * np.pi * np.asarray(freq_hz)
    return -(w**2) / (k - m * w**2 + 1j * c * w)


def sdof(f_n: float, zeta: float, m: float = 0.5) -> tuple[float, float, float]:
    w_n = 2 * np.pi * f_n
    return m, 2 * zeta * m * w_n, m * w_n**2


def sdof_response(force: np.ndarray, fine_rate_hz: float, m: float, c: float, k: float) -> np.ndarray:
    """Acceleration of m x'' + c x' + k x = f(t), x(0) = x'(0) = 0, at the samples of ``force``.

    The state-space model is discretised with the first-order hold, which is exact for an
    input that is linear between samples: the response is exact for that input. The force
    is sampled finely (fine_rate_hz), so the hold's deviation from the smooth pulse is
    below 1e-4 at the frequencies checked.
    """
    # a = x'' = (f - c x' - k x) / m: the biproper accelerance s^2 / (m s^2 + c s + k).
    num_d, den_d, _ = scipy.signal.cont2discrete(([1.0, 0.0, 0.0], [m, c, k]), 1 / fine_rate_hz, method="foh")
    return scipy.signal.lfilter(np.ravel(num_d), den_d, force, axis=-1)


def gaussian_pulses(t: np.ndarray, starts_s, width_s: float, amplitudes) -> np.ndarray:
    """(n_hits, t.size) Gaussian force pulses, N: nearly band-limited, so sampling keeps them."""
    starts = np.asarray(starts_s)[:, None]
    return np.asarray(amplitudes)[:, None] * np.exp(-0.5 * ((t - starts) / width_s) ** 2)


def relative_error(got: np.ndarray, expected: np.ndarray) -> float:
    return float(np.max(np.abs(got - expected) / np.abs(expected)))


# ----------------------------------------------------------------- scaling and axes


@pytest.mark.parametrize("spec", [UNIFORM, WindowSpec("hann"), WindowSpec("flattop")])
def test_a_sinusoid_on_a_line_reads_its_peak_amplitude(spec):
    rate, n = 2560.0, 1024  # 2.5 Hz lines
    t = np.arange(n) / rate
    record = 0.7 + 3.0 * np.cos(2 * np.pi * 100.0 * t + 0.4)  # line 40
    s = linear_spectra(record, record, rate, spec, spec)
    assert s.frequency_hz.shape == (401,)
    assert s.frequency_hz[0] == 0.0
    assert s.frequency_hz[-1] == pytest.approx(1000.0, rel=1e-14)
    assert s.force.shape == (1, 401)
    assert abs(s.force[0, 40]) == pytest.approx(3.0, rel=1e-12)
    assert np.angle(s.force[0, 40]) == pytest.approx(0.4, abs=1e-12)
    # These periodic windows' DFTs vanish 40 bins away: no leakage between DC and line 40.
    assert s.force[0, 0].real == pytest.approx(0.7, rel=1e-12)


def test_zoom_lines_span_the_band_and_read_the_real_sinusoids_amplitude():
    span, center = 400.0, 1000.0
    rate, n = 1.28 * span, 512  # 1 Hz lines
    t = np.arange(n) / rate
    # A real 3 N cosine at 1010 Hz mixed down by 1000 Hz: one exponential of half its amplitude.
    envelope = 1.5 * np.exp(1j * (2 * np.pi * 10.0 * t + 0.3))
    s = linear_spectra(envelope, envelope, rate, UNIFORM, UNIFORM, center_hz=center)
    assert s.frequency_hz.shape == (401,)
    assert s.frequency_hz[0] == pytest.approx(center - span / 2, rel=1e-14)
    assert s.frequency_hz[-1] == pytest.approx(center + span / 2, rel=1e-14)
    np.testing.assert_allclose(np.diff(s.frequency_hz), span / 400, rtol=1e-12)
    line = int(np.argmin(np.abs(s.frequency_hz - 1010.0)))
    assert abs(s.force[0, line]) == pytest.approx(3.0, rel=1e-12)
    assert np.angle(s.force[0, line]) == pytest.approx(0.3, abs=1e-12)


def test_max_frequency_picks_the_lines():
    record = np.random.default_rng(1).normal(size=(2, 1024))
    s = linear_spectra(record, record, 1024.0, UNIFORM, UNIFORM, max_frequency_hz=100.0)
    assert s.frequency_hz.shape == (101,)
    s = linear_spectra(record, record, 1024.0, UNIFORM, UNIFORM, max_frequency_hz=512.0)
    assert s.frequency_hz[-1] == 512.0  # Nyquist line of an even record


# ----------------------------------------------------------------- against pyFRF


def _noisy_delayed_hits(n_hits: int = 6, n: int = 1024, delay: int = 3):
    """Random force; response = the force delayed by ``delay`` samples (circularly) plus noise on both."""
    rng = np.random.default_rng(RNG_SEED)
    force = rng.normal(size=(n_hits, n))
    response = 2.0 * np.roll(force, delay, axis=1) + 0.3 * rng.normal(size=(n_hits, n))
    force = force + 0.1 * rng.normal(size=(n_hits, n))
    # Zero mean: pyFRF detrends each segment (subtracts its mean), which only touches DC.
    return force - force.mean(axis=1, keepdims=True), response - response.mean(axis=1, keepdims=True)


def test_h1_phase_sign_of_a_known_delay():
    """A response that lags the force by d samples has H = 2 exp(-j 2 pi f d / fs): negative phase."""
    rate, n, d = 2560, 1024, 3
    force = np.random.default_rng(7).normal(size=(4, n))
    response = 2.0 * np.roll(force, d, axis=1)
    est = frf_estimate(linear_spectra(force, response, rate, UNIFORM, UNIFORM))
    expected = 2.0 * np.exp(-2j * np.pi * est.frequency_hz * d / rate)
    np.testing.assert_allclose(est.h1, expected, rtol=1e-12)
    np.testing.assert_allclose(est.h2, expected, rtol=1e-12)
    np.testing.assert_allclose(est.hv, expected, rtol=1e-12)
    np.testing.assert_allclose(est.coherence, 1.0, rtol=1e-12)
    assert np.angle(est.h1[10]) < 0


def _pyfrf(force, response, rate, window):
    frf = pyFRF.FRF(rate, force, response, exc_type="f", resp_type="a", window=window)
    estimate = {name: frf.get_FRF(name, frf_form="accelerance")[0, 0] for name in ("H1", "H2", "Hv")}
    return frf, estimate, frf.get_coherence()[0]


@pytest.mark.parametrize(
    ("pyfrf_window", "ours"),
    [
        ("none", (UNIFORM, UNIFORM)),
        # pyFRF: w = exp(ln(0.01) n / (N - 1)); ours exp(-t / tau): tau = -(N - 1) / (ln(0.01) fs).
        (
            ("exponential:0.01", "exponential:0.01"),
            (
                WindowSpec("exponential", exp_decay_s=-1023 / (np.log(0.01) * 2560)),
                WindowSpec("exponential", exp_decay_s=-1023 / (np.log(0.01) * 2560)),
            ),
        ),
    ],
)
def test_h1_h2_hv_coherence_equal_pyfrfs(pyfrf_window, ours):
    rate = 2560
    force, response = _noisy_delayed_hits()
    _, theirs, coherence = _pyfrf(force, response, rate, pyfrf_window)
    est = frf_estimate(linear_spectra(force, response, rate, *ours))
    lines = slice(1, 401)  # pyFRF's DC line is NaN (detrending; its accelerance divides by w = 0)
    np.testing.assert_allclose(est.h1[lines], theirs["H1"][lines], rtol=1e-10)
    np.testing.assert_allclose(est.h2[lines], theirs["H2"][lines], rtol=1e-10)
    np.testing.assert_allclose(est.hv[lines], theirs["Hv"][lines], rtol=1e-10)
    np.testing.assert_allclose(est.coherence[lines], coherence[lines], rtol=1e-10)
    # Noise makes the estimators differ (H1 <= Hv <= H2 in magnitude) and coherence < 1: the
    # comparison is not between identical trivial numbers.
    assert np.all(np.abs(est.h1[lines]) <= np.abs(est.hv[lines]) * (1 + 1e-12))
    assert np.all(np.abs(est.hv[lines]) <= np.abs(est.h2[lines]) * (1 + 1e-12))
    assert np.median(est.coherence[lines]) < 0.99
    # And the sign: the 3-sample delay gives a phase of about -2 pi f 3 / fs.
    phase = np.unwrap(np.angle(est.h1[lines]))
    slope = np.polyfit(2 * np.pi * est.frequency_hz[lines], phase, 1)[0]
    assert slope == pytest.approx(-3 / rate, rel=0.05)


def test_force_and_exponential_windows_differ_from_pyfrf_only_by_its_amplitude_correction():
    """pyFRF multiplies H by the ratio of its windows' amplitude corrections (2/N for its
    force window, 2/sum(w) for the exponential); the analyzer and we do not (transient FRF).
    """
    rate, n = 2560, 1024
    force, response = _noisy_delayed_hits()
    frf, theirs, coherence = _pyfrf(force, response, rate, ("force:0.1", "exponential:0.01"))
    # pyFRF's force window is 1 on samples 0..int(0.1 N) - 1 = 0..101.
    ours = (
        WindowSpec("force", force_width_s=101.5 / rate),
        WindowSpec("exponential", exp_decay_s=-(n - 1) / (np.log(0.01) * rate)),
    )
    est = frf_estimate(linear_spectra(force, response, rate, *ours))
    lines = slice(1, 401)
    exp_window = np.exp(np.log(0.01) * np.arange(n) / (n - 1))
    norm = n / exp_window.sum()  # pyFRF's frf_norm = (2 / sum(w_exp)) / (2 / N)
    assert frf.frf_norm == pytest.approx(norm, rel=1e-14)
    for name, ours_h in (("H1", est.h1), ("H2", est.h2)):
        np.testing.assert_allclose(ours_h[lines] * norm, theirs[name][lines], rtol=1e-10)
    np.testing.assert_allclose(est.coherence[lines], coherence[lines], rtol=1e-10)


def test_hv_is_the_smallest_eigenvalues_eigenvector():
    force, response = _noisy_delayed_hits()
    # Make the response channel dominate on some lines and the force on others.
    est = frf_estimate(linear_spectra(force, 30 * response, 2560.0, UNIFORM, UNIFORM))
    est_small = frf_estimate(linear_spectra(force, response / 30, 2560.0, UNIFORM, UNIFORM))
    for e in (est, est_small):
        matrix = np.stack(
            [np.stack([e.g_ff, np.conj(e.g_fa)], -1), np.stack([e.g_fa, e.g_aa], -1)], -2
        )  # [[G_ff, G_af], [G_fa, G_aa]] per line
        _, vectors = np.linalg.eigh(matrix)
        v = vectors[..., 0]  # eigenvalues ascending
        # conj(v) . (F, A) = 0 on the noise-free line: A = -conj(v_f / v_a) F.
        expected = -np.conj(v[:, 0] / v[:, 1])
        np.testing.assert_allclose(e.hv, expected, rtol=1e-9)


# ----------------------------------------------------------------- against the analytic FRF


def test_h1_of_transient_hits_equals_the_analytic_accelerance():
    rate, n, oversample = 2560.0, 1024, 64
    m, c, k = sdof(200.0, 0.04)  # decay 50 1/s: exp(-20) left at the record end
    fine_t = np.arange(n * oversample) / (rate * oversample)
    force_fine = gaussian_pulses(fine_t, [4e-3, 6e-3, 5e-3], 6.2e-4, [40.0, 25.0, 60.0])
    response_fine = sdof_response(force_fine, rate * oversample, m, c, k)
    force, response = force_fine[:, ::oversample], response_fine[:, ::oversample]
    est = frf_estimate(linear_spectra(force, response, rate, UNIFORM, UNIFORM))
    assert est.n_averages == 3
    assert est.h1.shape == est.frequency_hz.shape == (401,)
    expected = accelerance(est.frequency_hz, m, c, k)
    assert relative_error(est.h1[1:], expected[1:]) < 1e-3
    assert abs(est.h1[0]) < 1e-6  # accelerance vanishes at DC
    # Every hit on its own gives the same FRF (noise-free).
    hits = per_hit_frf(linear_spectra(force, response, rate, UNIFORM, UNIFORM))
    assert hits.shape == (3, 401)
    assert relative_error(hits[:, 1:], expected[1:]) < 1e-3
    np.testing.assert_allclose(est.coherence[1:], 1.0, atol=1e-9)


def test_h1_of_a_51k2_hit_equals_the_analytic_accelerance():
    rate, n, oversample = 51200.0, 51200, 64
    m, c, k = sdof(2000.0, 0.01, m=0.05)
    fine_t = np.arange(n * oversample) / (rate * oversample)
    force_fine = gaussian_pulses(fine_t, [3e-4], 3.1e-5, [100.0])
    response_fine = sdof_response(force_fine, rate * oversample, m, c, k)
    force, response = force_fine[:, ::oversample], response_fine[:, ::oversample]
    s = linear_spectra(force, response, rate, UNIFORM, UNIFORM)
    assert s.frequency_hz.shape == (20001,)  # 1 Hz lines to 51200 / 2.56 = 20 kHz
    assert s.force.shape == s.response.shape == (1, 20001)
    est = frf_estimate(s)
    assert est.h1.shape == (20001,)
    assert relative_error(est.h1[1:], accelerance(est.frequency_hz[1:], m, c, k)) < 1e-3


def test_zoom_h1_of_mixed_down_decimated_records_equals_the_analytic_accelerance():
    """The test plays the zoom analyzer: a fine-grid hit is mixed down by the center,
    low-passed (Kaiser FIR, zero phase, same filter on both channels) and decimated to
    1.28 x span, 512 complex samples."""
    span, center = 400.0, 1000.0
    rate = 1.28 * span  # 512 Hz
    decimation = 256
    fine_rate = rate * decimation
    n_fine = 512 * decimation
    m, c, k = sdof(1030.0, 0.01)
    fine_t = np.arange(n_fine) / fine_rate
    force_fine = gaussian_pulses(fine_t, [0.05, 0.06], 1e-4, [30.0, 50.0])
    response_fine = sdof_response(force_fine, fine_rate, m, c, k)
    taps = scipy.signal.firwin(9001, span * 0.64, window=("kaiser", 12.0), fs=fine_rate)
    mixer = np.exp(-2j * np.pi * center * fine_t)

    def zoom(x: np.ndarray) -> np.ndarray:
        low = scipy.signal.fftconvolve(x * mixer, taps[None, :], mode="same", axes=-1)
        return low[:, ::decimation]

    force, response = zoom(force_fine), zoom(response_fine)
    assert force.shape == (2, 512)
    assert force.dtype == np.complex128
    s = linear_spectra(force, response, rate, UNIFORM, UNIFORM, center_hz=center)
    assert s.frequency_hz[0] == pytest.approx(800.0, rel=1e-14)
    assert s.frequency_hz[-1] == pytest.approx(1200.0, rel=1e-14)
    assert s.frequency_hz.size == 401
    est = frf_estimate(s)
    assert relative_error(est.h1, accelerance(est.frequency_hz, m, c, k)) < 1e-3
    peak = est.frequency_hz[np.argmax(np.abs(est.h1))]
    assert peak == pytest.approx(1030.0, abs=1.0)


# ----------------------------------------------------------------- the simulated analyzer


@pytest.mark.parametrize(
    ("span_hz", "center_hz"),
    [(1600.0, 800.0), (200.0, 500.0)],  # baseband, zoom
)
def test_frf_of_simulated_hits_equals_the_simulated_analyzers(span_hz, center_hz):
    """Force and exponential windows as set on the analyzer: our H1 and coherence from the
    captured records agree with what the (simulated) analyzer averages itself."""
    settings = AnalyzerSettings(
        span_hz=span_hz,
        center_hz=center_hz,
        window1="FORC",
        window2="EXPO",
        force_width1_s=0.1 * 400 / span_hz,
        exp_decay2_s=0.3 * 400 / span_hz,
        trigger_source="CH1",
        trigger_level_v=0.01,
        trigger_delay_s=-0.01 * 400 / span_hz,
    )
    source = PhysicsSource("seed", seed=3)
    records = [source.next_record(settings).record for _ in range(4)]
    rate, n = records[0].sample_rate_hz, records[0].force_n.size
    windows = [
        analyzer_window(w, n, rate, width, decay)
        for w, width, decay in (("FORC", settings.force_width1_s, 1.0), ("EXPO", 1.0, settings.exp_decay2_s))
    ]
    zoom = np.iscomplexobj(records[0].force_n)
    assert zoom == settings.zoom
    average = Average()
    for r in records:
        average.add(
            line_spectrum(r.force_n, windows[0]),
            line_spectrum(r.acceleration_m_s2, windows[1]),
            peak_scale(windows[0], zoom),
            peak_scale(windows[1], zoom),
            r.overload,
        )
    s = linear_spectra(
        np.stack([r.force_n for r in records]),
        np.stack([r.acceleration_m_s2 for r in records]),
        rate,
        WindowSpec("force", force_width_s=settings.force_width1_s),
        WindowSpec("exponential", exp_decay_s=settings.exp_decay2_s),
        center_hz=center_hz if zoom else 0.0,
    )
    est = frf_estimate(s)
    np.testing.assert_allclose(est.h1, average.trace("FRSP"), rtol=1e-10)
    np.testing.assert_allclose(est.coherence, average.trace("COHR"), rtol=1e-10, atol=1e-14)
    np.testing.assert_allclose(s.force.mean(axis=0), average.trace("LSP1"), rtol=1e-10)
    np.testing.assert_allclose(s.response.mean(axis=0), average.trace("LSP2"), rtol=1e-10)
    np.testing.assert_allclose(
        s.frequency_hz, settings.start_hz + np.arange(401) * settings.line_spacing_hz, rtol=1e-12
    )


# ----------------------------------------------------------------- selection, NaN, forms


def test_hit_selection_by_indices_and_mask():
    force, response = _noisy_delayed_hits()
    s = linear_spectra(force, response, 2560.0, UNIFORM, UNIFORM)
    by_index = frf_estimate(s, np.array([0, 2, 5]))
    by_mask = frf_estimate(s, np.array([True, False, True, False, False, True]))
    alone = frf_estimate(linear_spectra(force[[0, 2, 5]], response[[0, 2, 5]], 2560.0, UNIFORM, UNIFORM))
    assert by_index.n_averages == by_mask.n_averages == 3
    np.testing.assert_array_equal(by_index.h1, by_mask.h1)
    np.testing.assert_allclose(by_index.h1, alone.h1, rtol=1e-14)
    # H1 of a single hit is its per-hit FRF.
    np.testing.assert_allclose(frf_estimate(s, [4]).h1, per_hit_frf(s)[4], rtol=1e-12)


def test_lines_without_force_are_nan_without_warnings():
    # filterwarnings = error: a divide warning would fail this test.
    spectra = Spectra(
        frequency_hz=np.array([0.0, 1.0, 2.0]),
        force=np.array([[0.0, 1.0, 0.0], [0.0, 2.0, 0.0]], dtype=complex),
        response=np.array([[1.0, 2.0, 0.0], [1.0, 4.0, 0.0]], dtype=complex),
    )
    est = frf_estimate(spectra)
    assert isinstance(est, FrfEstimate)
    for values in (est.h1, est.hv, est.coherence):
        assert np.isnan(values[0])
        assert np.isnan(values[2])
    assert est.h1[1] == pytest.approx(2.0)
    assert np.isnan(est.h2[0])  # G_af == 0
    assert np.isnan(per_hit_frf(spectra)[:, 0]).all()


def test_convert_form_to_mobility_and_receptance_equal_analytic():
    m, c, k = sdof(50.0, 0.02)
    freq = np.linspace(0.0, 200.0, 401)
    w = 2 * np.pi * freq
    acc = accelerance(freq, m, c, k)
    mobility = convert_form(acc, freq, "mobility")
    receptance = convert_form(acc, freq, "receptance")
    assert np.isnan(mobility[0])
    assert np.isnan(receptance[0])
    np.testing.assert_allclose(mobility[1:], (1j * w / (k - m * w**2 + 1j * c * w))[1:], rtol=1e-12)
    np.testing.assert_allclose(receptance[1:], (1 / (k - m * w**2 + 1j * c * w))[1:], rtol=1e-12)
    np.testing.assert_allclose(
        convert_form(receptance, freq, "accelerance", "receptance")[1:], acc[1:], rtol=1e-12
    )
    # Works on stacks of FRFs (per hit).
    assert convert_form(np.stack([acc, acc]), freq, "mobility").shape == (2, 401)


# ----------------------------------------------------------------- bad inputs


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"response_m_s2": np.zeros((2, 512))}, "same shape"),
        ({"force_n": np.zeros((2, 3, 4)), "response_m_s2": np.zeros((2, 3, 4))}, "n_hits, n_samples"),
        (
            {"force_n": np.zeros((2, 1024), complex), "response_m_s2": np.zeros((2, 1024), complex)},
            "center_hz > 0",
        ),
        ({"response_m_s2": np.zeros((2, 1024), complex)}, "must both be real"),
        ({"center_hz": 100.0}, "baseband"),
        ({"sample_rate_hz": 0.0}, "sample_rate_hz"),
        ({"max_frequency_hz": 5000.0}, "max_frequency_hz"),
        ({"force_n": np.full((2, 1024), np.nan)}, "NaN"),
        (
            {
                "force_n": np.zeros((2, 512), complex),
                "response_m_s2": np.zeros((2, 512), complex),
                "center_hz": 100.0,
            },
            "below 0 Hz",
        ),
    ],
)
def test_bad_records_raise(kwargs, message):
    args = {
        "force_n": np.zeros((2, 1024)),
        "response_m_s2": np.zeros((2, 1024)),
        "sample_rate_hz": 2560.0,
        "force_window": UNIFORM,
        "response_window": UNIFORM,
    }
    args.update(kwargs)
    with pytest.raises(ValueError, match=message):
        linear_spectra(**args)


def test_bad_selections_and_forms_raise():
    force, response = _noisy_delayed_hits()
    s = linear_spectra(force, response, 2560.0, UNIFORM, UNIFORM)
    with pytest.raises(ValueError, match="no hits"):
        frf_estimate(s, np.zeros(6, bool))
    with pytest.raises(ValueError, match="mask"):
        frf_estimate(s, np.ones(5, bool))
    with pytest.raises(ValueError, match=r"0\.\.5"):
        frf_estimate(s, [6])
    with pytest.raises(ValueError, match="repeated"):
        frf_estimate(s, [1, 1])
    with pytest.raises(ValueError, match="one of"):
        convert_form(np.ones(3), np.arange(3.0), "inertance")
    with pytest.raises(ValueError, match="last axis"):
        convert_form(np.ones(3), np.arange(4.0), "mobility")
