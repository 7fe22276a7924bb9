"""With the driver's default impact settings (force window on the hammer, exponential
window on the accelerometer), the simulated analyzer's FRF is the specimen's model
H(jw), corrected for what the exponential window adds, at every span and in zoom.

The correction, from the window's definition alone (docs/simulator.md, "Windows"):
the exponential window exp(-t / tau), t from the record's start, multiplies the
response record. The response to a short pulse at the trigger point (t = pre) is
h * f, and (h * f)(t) e^(-t/tau) = (h e^(-t/tau)) * (f e^(-t/tau)); the force
window leaves the pulse whole, so the measured FRF is e^(-pre/tau) H(jw + 1/tau):
every pole moved left by 1/tau, the added damping that analysis later removes.
The model's H(s) is written out here from M, K, R and the force and sensor shapes.
"""

from __future__ import annotations

import numpy as np
import pytest

from drivers.settings import ImpactSettings
from sims.inprocess import InProcessConnection
from sims.instrument import Analyzer
from sims.scenarios import build_specimen
from sims.sources import PhysicsSource

CASES = [
    ("seed", 12.5, None),
    ("seed", 50.0, None),
    ("seed", 200.0, None),
    ("realistic", 12.5, None),
    ("realistic", 50.0, None),
    ("realistic", 200.0, None),
    ("seed", 12.5, 36.0),  # zoom on mode 2
    ("realistic", 12.5, 98.0),  # zoom on mode 3
    ("realistic", 3.125, 34.9),  # a narrow zoom on mode 2
]


def _model_accelerance(scenario: str, s: np.ndarray) -> np.ndarray:
    """Tip accelerance s^2 phi_s^T (M s^2 + R s + K)^-1 phi_f at complex s, (m/s^2)/N."""
    spec = build_specimen(scenario)
    m = spec.model
    out = np.empty(s.shape, complex)
    for i, sk in enumerate(s):
        q = np.linalg.solve(m.mass * sk**2 + spec.damping * sk + m.stiffness, m.force_shape)
        out[i] = sk**2 * (m.sensor_shape @ q)
    return out


def _measure(scenario: str, settings: ImpactSettings) -> tuple[np.ndarray, np.ndarray]:
    """Run the settings' own messages on a noise-free simulated analyzer; FRF and its lines."""
    source = PhysicsSource(scenario, seed=11)
    source.set_noise(False)
    link = InProcessConnection(Analyzer(source))
    message = b";".join([*settings.commands(), b"PRVW 0", b"STRT", b"FRSP", b"DDAN"])
    link.write(message + b"\n")
    raw = link.read(timeout_s=30.0)
    assert raw[:2] == b"#A"
    values = np.frombuffer(raw[4:], dtype=">f8")
    header, body = values[:66], values[66:]
    frf = body[0::2] + 1j * body[1::2]
    return header[64] + np.arange(frf.size) * header[55], frf


@pytest.mark.parametrize(("scenario", "span_hz", "center_hz"), CASES)
def test_frf_with_default_impact_settings_equals_the_window_corrected_model(scenario, span_hz, center_hz):
    settings = ImpactSettings(span_hz=span_hz, center_hz=center_hz, averages=3)
    assert settings.hammer.window.value == "FORC"
    assert settings.accelerometer.window.value == "EXPO"
    f_hz, frf = _measure(scenario, settings)
    tau_s = settings.accelerometer.exp_decay_s
    expected = np.exp(-settings.pre_trigger_s / tau_s) * _model_accelerance(
        scenario, 2j * np.pi * f_hz + 1 / tau_s
    )
    strong = (np.abs(expected) > 0.01 * np.abs(expected).max()) & (f_hz > 0)
    rel = np.abs(frf - expected)[strong] / np.abs(expected)[strong]
    worst = int(np.argmax(rel))
    assert rel[worst] < 0.01, f"{100 * rel[worst]:.2f} % at {f_hz[strong][worst]:.3f} Hz"
