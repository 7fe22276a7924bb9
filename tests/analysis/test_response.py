import numpy as np
import pytest
import scipy.signal

from analysis.exact_beam import ExactCantilever
from analysis.response import frequency_response, time_response
from analysis.ritz import RitzBeam
from tests.reference import EQ18

QUANTITIES = ("displacement", "velocity", "acceleration")


@pytest.fixture(scope="module")
def ritz3():
    return RitzBeam.build(n_functions=3).structure()


def _population(n, rng):
    """Symmetric positive definite damping matrices around eq (18)'s scale."""
    a = rng.uniform(-2, 2, (n, 3, 3))
    return a @ np.swapaxes(a, -1, -2) + 0.05 * np.eye(3)


def _hammer(n, fs, width_s=0.004, peak_n=120.0, delay_s=0.01):
    t = np.arange(n) / fs
    pulse = np.sin(np.pi * (t - delay_s) / width_s)
    return np.where((t >= delay_s) & (t <= delay_s + width_s), peak_n * pulse, 0.0)


def _scipy_zoh(model, damping, force, fs, output):
    a, b, c, d = model.state_space(damping, output)
    discrete = scipy.signal.cont2discrete((a, b[:, None], c[None, :], np.array([[d]])), 1 / fs, method="zoh")
    _, y, _ = scipy.signal.dlsim((*discrete[:4], 1 / fs), force)
    return y[:, 0]


@pytest.mark.parametrize("output", QUANTITIES)
def test_batched_time_response_equals_scipy_for_every_member(ritz3, output):
    rng = np.random.default_rng(3)
    damping = np.concatenate([np.array(EQ18)[None], _population(11, rng)])
    fs, n = 512.0, 1024
    force = _hammer(n, fs) + rng.normal(0, 0.5, n)
    y = time_response(ritz3, damping, force, fs, output)
    assert y.shape == (12, n)
    for p in range(damping.shape[0]):
        ref = _scipy_zoh(ritz3, damping[p], force, fs, output)
        assert np.max(np.abs(y[p] - ref)) <= 1e-8 * np.max(np.abs(ref))


def test_lightly_damped_six_mode_exact_beam_equals_scipy():
    beam = ExactCantilever.build(n_modes=6)
    model = beam.structure()
    damping = beam.modal_damping_matrix([0.002, 0.003, 0.005, 0.007, 0.009, 0.01])
    fs, n = 2560.0, 1024
    force = _hammer(n, fs, width_s=0.001)
    y = time_response(model, damping, force, fs)
    ref = _scipy_zoh(model, damping, force, fs, "acceleration")
    assert np.max(np.abs(y - ref)) <= 1e-8 * np.max(np.abs(ref))


def test_defective_member_takes_the_fallback_and_still_matches(ritz3):
    # A critically damped single-DOF-like case: a repeated real pole makes the
    # eigenvector matrix singular. The result must still be right.
    from analysis.structure import StructuralModel

    m, k = 2.0, 800.0
    single = StructuralModel(np.array([[m]]), np.array([[k]]), np.array([1.0]), np.array([1.0]))
    critical = np.array([[[2 * np.sqrt(k * m)]], [[5.0]]])
    fs, n = 1000.0, 400
    force = _hammer(n, fs)
    y = time_response(single, critical, force, fs, "velocity")
    for p in range(2):
        ref = _scipy_zoh(single, critical[p], force, fs, "velocity")
        assert np.max(np.abs(y[p] - ref)) <= 1e-8 * np.max(np.abs(ref))
    h = frequency_response(single, critical, np.linspace(0, 50, 11), "displacement")
    s = 2j * np.pi * np.linspace(0, 50, 11)
    np.testing.assert_allclose(h[0], 1 / (m * s**2 + critical[0, 0, 0] * s + k), rtol=1e-10)


def test_force_per_member_and_leading_batch_dims(ritz3):
    rng = np.random.default_rng(5)
    damping = _population(6, rng).reshape(2, 3, 3, 3)
    fs, n = 256.0, 300
    forces = rng.normal(0, 1, (2, 3, n))
    y = time_response(ritz3, damping, forces, fs, "displacement")
    assert y.shape == (2, 3, n)
    ref = _scipy_zoh(ritz3, damping[1, 2], forces[1, 2], fs, "displacement")
    assert np.max(np.abs(y[1, 2] - ref)) <= 1e-8 * np.max(np.abs(ref))


def test_unstable_member_does_not_spoil_the_others(ritz3):
    damping = np.stack([np.array(EQ18), -10 * np.eye(3)])
    fs, n = 512.0, 1024
    force = _hammer(n, fs)
    y = time_response(ritz3, damping, force, fs)
    ref = _scipy_zoh(ritz3, damping[0], force, fs, "acceleration")
    assert np.max(np.abs(y[0] - ref)) <= 1e-8 * np.max(np.abs(ref))


@pytest.mark.parametrize("output", QUANTITIES)
def test_frequency_response_equals_direct_dynamic_stiffness_solve(ritz3, output):
    rng = np.random.default_rng(11)
    damping = np.concatenate([np.array(EQ18)[None], _population(5, rng)])
    f = np.linspace(0, 200, 401)
    h = frequency_response(ritz3, damping, f, output)
    s = 2j * np.pi * f
    order = QUANTITIES.index(output)
    for p in range(damping.shape[0]):
        z = s[:, None, None] ** 2 * ritz3.mass + s[:, None, None] * damping[p] + ritz3.stiffness
        rhs = np.broadcast_to(ritz3.force_shape.astype(complex), (f.size, 3))[..., None]
        q = np.linalg.solve(z, rhs)[..., 0]
        expected = (q @ ritz3.sensor_shape) * s**order
        np.testing.assert_allclose(h[p], expected, rtol=1e-9, atol=1e-12 * np.abs(expected).max())


def test_frequency_response_equals_scipy_freqresp(ritz3):
    f = np.linspace(1, 150, 60)
    h = frequency_response(ritz3, np.array(EQ18), f)
    a, b, c, d = ritz3.state_space(np.array(EQ18))
    _, ref = scipy.signal.freqresp(scipy.signal.StateSpace(a, b[:, None], c[None, :], [[d]]), 2 * np.pi * f)
    np.testing.assert_allclose(h, ref, rtol=1e-9)


@pytest.mark.parametrize("output", QUANTITIES)
def test_frequency_response_is_the_fft_of_the_impulse_response(ritz3, output):
    """A unit-area one-sample force; the ZOH turns it into a rectangle of width dt,
    whose spectrum sinc(f dt) e^(-j pi f dt) is divided out. What remains is the
    aliasing of the sampled response: it must shrink as dt^2."""
    damping = np.array(EQ18)
    _, _, _, d = ritz3.state_space(damping, output)
    errors = []
    for fs in (1024.0, 4096.0):
        n = int(16 * fs)  # 16 s: every mode has decayed below 1e-8
        force = np.zeros(n)
        force[0] = fs
        # The feed-through of acceleration samples a discontinuous rectangle; compare the
        # strictly proper part, which is continuous.
        y = time_response(ritz3, damping, force, fs, output) - d * force
        f = np.fft.rfftfreq(n, 1 / fs)
        rect = np.sinc(f / fs) * np.exp(-1j * np.pi * f / fs)
        estimate = np.fft.rfft(y) / fs / rect
        h = frequency_response(ritz3, damping, f, output) - d
        band = (f > 0) & (f <= 200)
        errors.append(np.max(np.abs(estimate - h)[band]) / np.max(np.abs(h[band])))
    assert errors[1] < 1e-3
    assert errors[1] < errors[0] / 8  # second-order convergence in dt


def test_input_validation(ritz3):
    damping = np.array(EQ18)
    with pytest.raises(ValueError, match="sample_rate_hz"):
        time_response(ritz3, damping, np.ones(8), 0.0)
    with pytest.raises(ValueError, match="force_n"):
        time_response(ritz3, damping, np.array([1.0, np.nan]), 100.0)
    with pytest.raises(ValueError, match="does not broadcast"):
        time_response(ritz3, np.stack([damping] * 3), np.ones((2, 8)), 100.0)
    with pytest.raises(ValueError, match="unknown output"):
        frequency_response(ritz3, damping, [1.0], "jerk")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="frequencies_hz"):
        frequency_response(ritz3, damping, [[1.0]])
    with pytest.raises(ValueError, match="sample_rate_hz must be a number"):
        time_response(ritz3, damping, np.ones(8), "fast")  # type: ignore[arg-type]


def test_empty_batch(ritz3):
    assert time_response(ritz3, np.zeros((0, 3, 3)), np.ones(8), 100.0).shape == (0, 8)
    assert frequency_response(ritz3, np.zeros((0, 3, 3)), [1.0, 2.0]).shape == (0, 2)


def test_structural_model_rejects_a_bad_mass_matrix():
    from analysis.structure import StructuralModel

    with pytest.raises(ValueError, match="symmetric"):
        StructuralModel(np.array([[1.0, 0.5], [0.0, 1.0]]), np.eye(2), np.ones(2), np.ones(2))
    with pytest.raises(ValueError, match="positive definite"):
        StructuralModel(np.diag([1.0, -1.0]), np.eye(2), np.ones(2), np.ones(2))
