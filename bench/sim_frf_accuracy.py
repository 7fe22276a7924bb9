"""How closely the simulated analyzer's FRF follows the specimen's model (not a test):
`python bench/sim_frf_accuracy.py`.

One noiseless capture of 3 hits per case, the worst relative error over the lines
where |H| is above 1 % of its peak, in two setups:

* uniform: uniform windows on both channels, the driver's default pre-trigger
  (1/32 of the record), against the model's H(jw);
* impact: the driver's default impact settings (force window on the hammer,
  exponential on the accelerometer), against e^(-pre/tau) H(jw + 1/tau), the model
  with the exponential window's added damping (tests/sims/test_sim_frf_with_impact_defaults.py).

With uniform windows a response that has not died out within the record
(400 / span s) shows leakage, as on the instrument.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from drivers.settings import ChannelSetup, ImpactSettings, Window
from sims.inprocess import InProcessConnection
from sims.instrument import Analyzer
from sims.scenarios import build_specimen
from sims.sources import PhysicsSource

CASES = [
    ("seed", 12.5, None),
    ("seed", 50.0, None),
    ("seed", 100.0, None),
    ("seed", 200.0, None),
    ("seed", 12.5, 36.0),
    ("realistic", 12.5, None),
    ("realistic", 50.0, None),
    ("realistic", 200.0, None),
    ("realistic", 3.125, 34.9),
    ("realistic", 12.5, 98.0),
]


def accelerance(scenario: str, s: np.ndarray) -> np.ndarray:
    """The specimen's tip accelerance at complex frequencies s (rad/s), (m/s^2)/N."""
    spec = build_specimen(scenario)
    m = spec.model
    return np.array(
        [
            sk**2
            * (
                m.sensor_shape
                @ np.linalg.solve(m.mass * sk**2 + spec.damping * sk + m.stiffness, m.force_shape)
            )
            for sk in s
        ]
    )


def worst_error(scenario: str, settings: ImpactSettings) -> tuple[float, float]:
    source = PhysicsSource(scenario, seed=5)
    source.set_noise(False)
    link = InProcessConnection(Analyzer(source))
    link.write(b";".join([*settings.commands(), b"PRVW 0", b"STRT", b"FRSP", b"DDAN"]) + b"\n")
    values = np.frombuffer(link.read(timeout_s=30.0)[4:], dtype=">f8")
    header, body = values[:66], values[66:]
    frf = body[0::2] + 1j * body[1::2]
    f = header[64] + np.arange(frf.size) * header[55]
    s = 2j * np.pi * f
    if settings.accelerometer.window is Window.EXPONENTIAL:
        tau = settings.accelerometer.exp_decay_s
        h = np.exp(-settings.pre_trigger_s / tau) * accelerance(scenario, s + 1 / tau)
    else:
        h = accelerance(scenario, s)
    strong = (np.abs(h) > 0.01 * np.abs(h).max()) & (f > 0)
    rel = np.abs(frf - h)[strong] / np.abs(h)[strong]
    return float(rel.max()), float(f[strong][np.argmax(rel)])


def main() -> None:
    print(
        f"{'scenario':<10} {'span Hz':>8} {'center Hz':>9} {'record s':>8}   {'uniform':>16}   {'impact':>16}"
    )
    for scenario, span, center in CASES:
        impact = ImpactSettings(span_hz=span, center_hz=center, averages=3)
        uniform = replace(
            impact,
            hammer=ChannelSetup(Window.UNIFORM, impact.hammer.sensitivity_v_per_eu, impact.hammer.range_v),
            accelerometer=ChannelSetup(
                Window.UNIFORM, impact.accelerometer.sensitivity_v_per_eu, impact.accelerometer.range_v
            ),
        )
        cells = []
        for settings in (uniform, impact):
            error, where = worst_error(scenario, settings)
            cells.append(f"{100 * error:7.3f}% @{where:7.2f}")
        center_text = "base" if center is None else f"{center:g}"
        print(
            f"{scenario:<10} {span:>8g} {center_text:>9} {400 / span:>8g}   {cells[0]:>16}   {cells[1]:>16}"
        )


if __name__ == "__main__":
    main()
