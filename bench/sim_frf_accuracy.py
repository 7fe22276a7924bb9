"""How closely the simulated analyzer's FRF follows the specimen's H(j w) (not a test):
`python bench/sim_frf_accuracy.py`.

One noiseless capture per case (uniform windows, 2 averages); the worst relative
error over the lines where |H| is above 1 % of its peak. Spans where the response
has not died out within the record (400 / span s) show leakage, as on the instrument.
"""

from __future__ import annotations

import numpy as np

from analysis.response import frequency_response
from sims.inprocess import InProcessConnection
from sims.instrument import Analyzer
from sims.scenarios import build_specimen
from sims.sources import PhysicsSource

CASES = [
    ("seed", 50.0, 25.0),
    ("seed", 100.0, 50.0),
    ("seed", 200.0, 100.0),
    ("seed", 12.5, 36.0),
    ("realistic", 12.5, 6.25),
    ("realistic", 25.0, 12.5),
    ("realistic", 100.0, 50.0),
    ("realistic", 3.125, 34.9),
    ("realistic", 12.5, 98.0),
]


def worst_error(scenario: str, span_hz: float, center_hz: float) -> tuple[float, float]:
    source = PhysicsSource(scenario, seed=5)
    source.set_noise(False)
    link = InProcessConnection(Analyzer(source))
    link.write(
        f"FRS {span_hz} HZ;CF {center_hz} HZ;TSRC CH1;TLVL 2 MV;TDLY -20 MS;UNIF;NAVG 2;STBL;"
        "RNG1 20 MV;RNG2 0.5 V;STRT;FRSP;DDAN\n".encode()
    )
    data = link.read(timeout_s=10.0)
    values = np.frombuffer(data[4:], dtype=">f8")
    header, body = values[:66], values[66:]
    frf = body[0::2] + 1j * body[1::2]
    f = header[64] + np.arange(401) * header[55]
    spec = build_specimen(scenario)
    h = frequency_response(spec.model, spec.damping, f, "acceleration")
    strong = (np.abs(h) > 0.01 * np.abs(h).max()) & (f > 0)
    rel = np.abs(frf - h)[strong] / np.abs(h)[strong]
    return float(rel.max()), float(f[strong][np.argmax(rel)])


def main() -> None:
    print(
        f"{'scenario':<10} {'span Hz':>8} {'center Hz':>9} {'record s':>8} {'worst error':>12} {'at Hz':>8}"
    )
    for scenario, span, center in CASES:
        error, where = worst_error(scenario, span, center)
        print(f"{scenario:<10} {span:>8g} {center:>9g} {400 / span:>8g} {100 * error:>11.3f}% {where:>8.3f}")


if __name__ == "__main__":
    main()
