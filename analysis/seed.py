"""Numbers published in the seed paper, kept verbatim so reports can quote them.

The paper: "Experimental damping identification of a cantilevered beam" (Linear
and Non-Linear Vibrations Laboratory, University of Taubaté); docs/method.md
says what it holds. Nothing here is computed.
"""

from __future__ import annotations

import numpy as np

#: Table 2, "Analytical" column (Hz). It cannot be reproduced from the paper's own
#: eqs (10)-(11) and Table 1 (docs/method.md, "Reproduced numbers"): reported, never fitted to.
TABLE_2_ANALYTICAL_HZ = (5.1639344, 29.644809, 84.726776)

#: Table 2, "Experimental" column (Hz): matches exact Euler-Bernoulli theory to ~0.001 %.
TABLE_2_EXPERIMENTAL_HZ = (5.5685326, 34.897681, 97.715208)

#: Eq (18): the damping matrix the paper's genetic algorithm identified (N s/m in
#: generalized coordinates of the eq (6) admissible functions, N = 3).
EQ_18_DAMPING = (
    (4.9582, 4.1824, 2.9015),
    (4.1824, 4.0732, 1.9945),
    (2.9015, 1.9945, 2.7482),
)


def eq18_damping_matrix() -> np.ndarray:
    """The seed's eq (18) damping matrix as a fresh (3, 3) float array."""
    return np.array(EQ_18_DAMPING, dtype=float)


#: Table 3: the paper's GA settings, as printed (the labels of the two rates look
#: swapped against the text, which says mutation 0.15 and crossover 0.45).
TABLE_3_GA = {
    "population_size": 50,
    "generations": 30,
    "initial_mutation": 0.45,
    "mutation_decrement": 0.15,
    "selection": "roulette",
    "crossover": "random",
    "precision_digits": 4,
    "variable_range": (-10.0, 10.0),
}
