"""Numbers from outside the code: the project's design notes (docs/method.md,
"Reproduced numbers") and the seed paper.

Each was computed or looked up before any code of this project existed.
"""

# Ritz, Table 1 with tabulated A, I (docs/method.md), Hz.
RITZ_N3_HZ = (5.57206, 35.20718, 99.18859)
RITZ_N6_HZ = (5.56925, 34.93745, 98.04948)
RITZ_N10_HZ = (5.56884, 34.90795, 97.78995)

# Roots of 1 + cos(bL) cosh(bL) = 0.
CANTILEVER_BETA_L = (1.8751041, 4.6940911, 7.8547574, 10.9955407)

# Exact Euler-Bernoulli cantilever, Hz.
EXACT_TABULATED_HZ = (5.56872, 34.89856, 97.71698, 191.48628)
EXACT_DERIVED_HZ = (5.56856, 34.89755, 97.71415)

# phi_i(L) of the seed's eq (6), i = 1, 2, 3.
PHI_AT_TIP = (6.934802, -19.739209, 46.413220)

# The seed's eq (18) damping matrix, N s/m (paper, section 6).
EQ18 = (
    (4.9582, 4.1824, 2.9015),
    (4.1824, 4.0732, 1.9945),
    (2.9015, 1.9945, 2.7482),
)
EQ18_EIGENVALUES = (0.1343, 1.3126, 10.333)
EQ18_POLE_MAGNITUDE_HZ = (5.58862, 36.08886, 96.47856)
EQ18_DAMPING_RATIOS = (0.036058, 0.203226, 0.161986)

# The simulator's realistic scenario: its modal damping ratios, modes 1-4
# (docs/simulator.md; set in sims/scenarios.py, the truth an identification must find).
REALISTIC_DAMPING_RATIOS = (0.010, 0.006, 0.004, 0.003)

# The seed's Table 2.
SEED_ANALYTICAL_HZ = (5.1639344, 29.644809, 84.726776)
SEED_EXPERIMENTAL_HZ = (5.5685326, 34.897681, 97.715208)
