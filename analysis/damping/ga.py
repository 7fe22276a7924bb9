"""The seed paper's binary genetic algorithm for the damping matrix (its Table 3).

Coding: each of the P = N (N + 1) / 2 entries of theta (analysis.damping.params) is an
unsigned binary integer of ``bits`` bits on [lo, hi], with bits the smallest count
that resolves the paper's 4-decimal precision, ceil(log2((hi - lo) 10^4 + 1)) = 18 on
[-10, 10]. It decodes as x = lo + k (hi - lo) / (2^bits - 1), then rounded to 4
decimals (the grid step 20 / (2^18 - 1) = 7.6e-5 is finer than 1e-4, so every
4-decimal value in range is reachable and the GA only ever sees those).

One generation: roulette-wheel selection of the whole population, single-point
crossover of consecutive pairs of the selected (probability 0.45 per pair, cut
anywhere along the concatenated chromosome), then mutation.

Interpretations where the paper is not explicit (docs: analysis.seed.TABLE_3_GA):

* Fitness. The paper maximises a fitness and minimises Psi (eq 17); roulette
  needs positive weights that grow as Psi falls. We use fitness = 1 / (Psi + eps):
  it is scale-free (no "max minus" offset that depends on the worst member, which
  an unstable member would make infinite), and an unstable member (Psi = inf) gets 0.
* Mutation. "Mutation rate 0.15 with a decrement per generation": each offspring
  bit string mutates with probability p_g (one uniformly chosen bit is flipped);
  p_g falls linearly from ``mutation`` in the first offspring generation to
  ``mutation_floor`` in the last.
* Budget. ``generations`` counts evaluated populations, the random initial one
  included: 50 x 30 = 1,500 evaluations, the paper's budget.
* Elitism. The paper mentions none, so it is off by default; with ``elitism=True``
  the previous generation's best replaces the new generation's worst.

Each generation is one call of ``objective`` on the whole population (B, N, N).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from analysis.damping.params import n_params, theta_to_matrix
from analysis.damping.result import FitResult

#: Decimal places of the paper's coding.
DECIMALS = 4
#: Keeps 1 / (Psi + eps) finite at Psi = 0 (a noise-free exact fit).
FITNESS_EPS = 1e-300


def bits_per_variable(bounds: tuple[float, float] = (-10.0, 10.0), decimals: int = DECIMALS) -> int:
    """Smallest bit count resolving 10^-decimals on [lo, hi]: 18 for [-10, 10] and 4 decimals."""
    lo, hi = _check_bounds(bounds)
    return math.ceil(math.log2((hi - lo) * 10**decimals + 1))


def _check_bounds(bounds: tuple[float, float]) -> tuple[float, float]:
    lo, hi = float(bounds[0]), float(bounds[1])
    if not (np.isfinite(lo) and np.isfinite(hi) and hi > lo):
        raise ValueError(f"bounds must be finite with lo < hi, got {bounds!r}")
    return lo, hi


def decode(chromosomes: np.ndarray, n_vars: int, bounds: tuple[float, float], n_bits: int) -> np.ndarray:
    """Bit strings (B, n_vars * n_bits) of 0/1, most significant bit first -> values (B, n_vars).

    Values are lo + k (hi - lo) / (2^n_bits - 1) rounded to 4 decimals.
    """
    lo, hi = _check_bounds(bounds)
    bits = np.asarray(chromosomes, dtype=np.int64).reshape(-1, n_vars, n_bits)
    weights = 2 ** np.arange(n_bits - 1, -1, -1, dtype=np.int64)
    k = bits @ weights
    return np.round(lo + k * ((hi - lo) / (2**n_bits - 1)), DECIMALS)


def _roulette(fitness: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Indices of len(fitness) members drawn with probability proportional to fitness."""
    total = fitness.sum()
    if not (np.isfinite(total) and total > 0):
        return rng.integers(0, fitness.size, fitness.size)  # nothing to prefer
    return rng.choice(fitness.size, size=fitness.size, p=fitness / total)


def _crossover(parents: np.ndarray, probability: float, rng: np.random.Generator) -> np.ndarray:
    """Single-point crossover of pairs (0, 1), (2, 3), ...; an odd last member passes through."""
    children = parents.copy()
    n_pairs = parents.shape[0] // 2
    length = parents.shape[1]
    mate = rng.uniform(size=n_pairs) < probability
    cut = rng.integers(1, length, size=n_pairs)
    tail = (np.arange(length) >= cut[:, None]) & mate[:, None]  # (pairs, L) bits to swap
    a, b = parents[0 : 2 * n_pairs : 2], parents[1 : 2 * n_pairs : 2]
    children[0 : 2 * n_pairs : 2] = np.where(tail, b, a)
    children[1 : 2 * n_pairs : 2] = np.where(tail, a, b)
    return children


def _mutate(population: np.ndarray, probability: float, rng: np.random.Generator) -> np.ndarray:
    """With the given probability per bit string, flip one uniformly chosen bit."""
    out = population.copy()
    hit = np.flatnonzero(rng.uniform(size=out.shape[0]) < probability)
    where = rng.integers(0, out.shape[1], size=hit.size)
    out[hit, where] ^= True
    return out


def fit_ga(
    objective: Callable[[np.ndarray], np.ndarray],
    n: int,
    seed: int = 0,
    bounds: tuple[float, float] = (-10.0, 10.0),
    population: int = 50,
    generations: int = 30,
    crossover: float = 0.45,
    mutation: float = 0.15,
    mutation_floor: float = 0.01,
    elitism: bool = False,
    psd: bool = False,
    cache: bool = True,
) -> FitResult:
    """Minimise objective(R) over symmetric N x N damping matrices with the seed's GA.

    Parameters
    ----------
    objective : (B, N, N) damping matrices (N s/m) -> (B,) Psi, smaller is better;
        inf for a member it rejects. Called once per generation.
    n : N. seed : seeds ``numpy.random.default_rng``: same seed, same result.
    bounds : (lo, hi) of every entry of theta (N s/m; sqrt(N s/m) with psd).
    population, generations : members and evaluated populations (initial included).
    crossover : probability a pair of parents exchanges tails.
    mutation, mutation_floor : per-bit-string mutation probability in the first and
        last offspring generations (linear in between).
    elitism : carry the best member over (off in the paper).
    psd : theta codes a Cholesky factor (always dissipative R); the paper codes R.
    cache : evaluate each distinct member once. Selection and crossover copy
        members unchanged, so only a third to a half of the 1,500 members of the
        seed's budget are new; the search and its result are the same either way.

    Returns
    -------
    FitResult with the best member ever evaluated; ``history`` (generations,) is the
    best Psi of each generation's population (non-increasing only with elitism).
    """
    if population < 2 or generations < 1:
        raise ValueError("population must be >= 2 and generations >= 1")
    if not (0 <= crossover <= 1 and 0 <= mutation_floor <= mutation <= 1):
        raise ValueError("need 0 <= crossover <= 1 and 0 <= mutation_floor <= mutation <= 1")
    rng = np.random.default_rng(seed)
    n_vars = n_params(n)
    n_bits = bits_per_variable(bounds)
    pop = rng.integers(0, 2, size=(population, n_vars * n_bits)).astype(bool)

    known: dict[bytes, float] = {}  # Psi of every distinct member evaluated so far

    def call(theta: np.ndarray) -> np.ndarray:
        values = np.asarray(objective(theta_to_matrix(theta, n, psd)), dtype=float).reshape(-1)
        if values.shape != (theta.shape[0],):
            raise ValueError(f"objective returned shape {values.shape} for {theta.shape[0]} members")
        return np.where(np.isnan(values), np.inf, values)

    def evaluate(chromosomes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        theta = decode(chromosomes, n_vars, bounds, n_bits)
        if not cache:
            return theta, call(theta)
        # Keyed by the decoded values: bit strings that round to the same 4 decimals
        # are the same member.
        keys = [row.tobytes() for row in theta]
        new = {key: i for i, key in enumerate(keys) if key not in known}
        if new:
            index = np.fromiter(new.values(), dtype=np.intp, count=len(new))
            known.update(zip(new, call(theta[index]), strict=True))
        return theta, np.array([known[key] for key in keys])

    theta, values = evaluate(pop)
    best_i = int(np.argmin(values))
    best_theta, best_value = theta[best_i].copy(), float(values[best_i])
    history = [best_value]
    n_offspring = generations - 1
    for g in range(n_offspring):
        rate = mutation - (mutation - mutation_floor) * (g / max(n_offspring - 1, 1))
        fitness = 1.0 / (values + FITNESS_EPS)  # inf -> 0
        children = _crossover(pop[_roulette(fitness, rng)], crossover, rng)
        children = _mutate(children, rate, rng)
        if elitism:
            elite = pop[int(np.argmin(values))]
        theta, new_values = evaluate(children)
        if elitism:
            worst = int(np.argmax(new_values))
            children[worst] = elite
            theta[worst] = decode(elite[None], n_vars, bounds, n_bits)[0]
            new_values[worst] = np.min(values)
        pop, values = children, new_values
        i = int(np.argmin(values))
        if values[i] < best_value:
            best_theta, best_value = theta[i].copy(), float(values[i])
        history.append(float(values[i]))
    return FitResult(
        method="ga",
        damping_matrix=theta_to_matrix(best_theta, n, psd),
        theta=best_theta,
        psi=best_value,
        n_evaluations=population * generations,
        history=np.array(history),
        success=bool(np.isfinite(best_value)),
        message=f"{generations} generations of {population}"
        + (f" ({len(known)} distinct members computed)" if cache else ""),
        psd=psd,
    )
