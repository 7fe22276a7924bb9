"""Benchmark of the batched beam model (not a test): `make bench` or
`python bench/bench_model.py [--repeat N]`.

Times, on one core, what a genetic algorithm does every generation:
  * tip-acceleration time response of 50 damping matrices to a 1024-sample force;
  * H(j w) of 50 damping matrices on 401 lines;
and, for scale, scipy's one-member-at-a-time zero-order-hold simulation.
"""

from __future__ import annotations

import os

# One core, whatever BLAS the machine has: set before numpy loads.
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import platform  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
import scipy.signal  # noqa: E402

from analysis.response import frequency_response, time_response  # noqa: E402
from analysis.ritz import RitzBeam  # noqa: E402
from analysis.seed import eq18_damping_matrix  # noqa: E402


def _timeit(fn, repeat: int, number: int) -> tuple[float, float]:
    """Median and best seconds per call over `repeat` rounds of `number` calls."""
    fn()  # warm-up
    rounds = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(number):
            fn()
        rounds.append((time.perf_counter() - t0) / number)
    return statistics.median(rounds), min(rounds)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args()

    rng = np.random.default_rng(0)
    model = RitzBeam.build(n_functions=3).structure()
    # A population of stable members (symmetric positive definite, eq (18)'s scale):
    # the seed's [-10, 10] range would make half of them unstable, and timing
    # overflowing responses measures the wrong thing.
    a = rng.uniform(-2, 2, (50, 3, 3))
    population = a @ np.swapaxes(a, -1, -2) + 0.05 * np.eye(3)
    population[0] = eq18_damping_matrix()
    span_hz = 200.0
    sample_rate_hz = 2.56 * span_hz
    t = np.arange(1024) / sample_rate_hz
    force_n = np.where(t < 0.004, 150.0 * np.sin(np.pi * t / 0.004), 0.0)
    lines_hz = np.linspace(0.0, span_hz, 401)

    print(f"python {platform.python_version()}, numpy {np.__version__}, scipy {scipy.__version__}, 1 thread")
    rows = []
    med, best = _timeit(lambda: time_response(model, population, force_n, sample_rate_hz), args.repeat, 50)
    rows.append(("time response, 50 R x 1024 samples (target < 5 ms)", med, best))
    med, best = _timeit(lambda: frequency_response(model, population, lines_hz), args.repeat, 50)
    rows.append(("H(jw), 50 R x 401 lines", med, best))

    def scipy_loop() -> None:
        a, b, c, d = model.state_space(population)
        for p in range(population.shape[0]):
            sysd = scipy.signal.cont2discrete(
                (a[p], b[p][:, None], c[p][None, :], np.array([[d[p]]])), 1 / sample_rate_hz, "zoh"
            )
            scipy.signal.dlsim((*sysd[:4], 1 / sample_rate_hz), force_n)

    med, best = _timeit(scipy_loop, max(3, args.repeat // 2), 1)
    rows.append(("for scale: scipy cont2discrete + dlsim, 50 one by one", med, best))

    width = max(len(r[0]) for r in rows)
    print(f"{'':{width}}  {'median':>10}  {'best':>10}")
    for label, med, best in rows:
        print(f"{label:{width}}  {med * 1e3:8.3f} ms  {best * 1e3:8.3f} ms")


if __name__ == "__main__":
    main()
