"""Specimens (test articles) the simulated analyzer measures, built from analysis/.

* ``seed``: the seed paper's model, Ritz N = 3 with Table 1 and the eq (18)
  damping matrix. An identification on its data should return eq (18)'s modal
  damping (3.6 %, 20 %, 16 %).
* ``realistic``: the exact continuous cantilever truncated to 6 modes with light
  modal damping (1 % falling to 0.2 %), so that a 3-function model meets a real
  model error, as in the paper's lab.
* ``custom``: the seed's Ritz N = 3 beam with a damping matrix the user chooses
  (symmetric positive semi-definite, N s/m, not necessarily proportional), so
  that a test knows the truth an identification must find.

The hammer (force) and the accelerometer (sensor) sit anywhere on the beam,
0 < x <= L from the clamp (L = 0.7 m for Table 1); both default to the tip.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from analysis.exact_beam import ExactCantilever
from analysis.modal import damped_modes
from analysis.response import frequency_response
from analysis.ritz import RitzBeam
from analysis.seed import eq18_damping_matrix
from analysis.structure import StructuralModel
from sims.pole_residue import PoleResidueSystem

#: Modal damping ratios of the ``realistic`` scenario, modes 1..6.
REALISTIC_DAMPING_RATIOS = (0.010, 0.006, 0.004, 0.003, 0.0025, 0.002)

SCENARIOS = ("seed", "realistic")
#: The scenario with a user-chosen damping matrix on the seed's Ritz N = 3 beam.
CUSTOM = "custom"
#: Generalized coordinates of the ``seed`` and ``custom`` beams (the damping matrix is N x N).
RITZ_FUNCTIONS = 3


@dataclass(frozen=True)
class Specimen:
    """A structure with its damping, force and accelerometer at fixed positions."""

    name: str
    description: str
    model: StructuralModel
    damping: np.ndarray  # (N, N), N s/m
    force_at_m: float = math.nan  # hammer position, m from the clamp
    sensor_at_m: float = math.nan  # accelerometer position, m from the clamp
    length_m: float = math.nan  # the beam's length, m

    def moved(self, force_at_m: float | None = None, sensor_at_m: float | None = None) -> Specimen:
        """The same specimen (beam and damping) with the hammer and/or the accelerometer
        elsewhere, m from the clamp; None keeps a position. ValueError off the beam."""
        return build_specimen(
            self.name,
            self.force_at_m if force_at_m is None else force_at_m,
            self.sensor_at_m if sensor_at_m is None else sensor_at_m,
            damping=self.damping if self.name == CUSTOM else None,
        )

    def acceleration_system(self) -> PoleResidueSystem:
        """Force (N) at x_f to acceleration (m/s^2) at x_s."""
        a, b, c, d = self.model.state_space(self.damping, "acceleration")
        return PoleResidueSystem.from_state_space(a, b, c, float(d))

    def frequency_response(self, frequencies_hz: np.ndarray) -> np.ndarray:
        """H(j w), (m/s^2)/N, shape (F,): the reference the analyzer's FRF should match."""
        return frequency_response(self.model, self.damping, frequencies_hz, "acceleration")

    def natural_frequencies_hz(self) -> np.ndarray:
        return damped_modes(self.model, self.damping).natural_frequencies_hz


def check_position(what: str, x_m: float | None, length_m: float) -> float:
    """A hammer or accelerometer position, m from the clamp: ``length_m`` (the tip) for
    None; ValueError unless 0 < x <= length_m (at the clamp nothing moves)."""
    if x_m is None:
        return float(length_m)
    try:
        x = float(x_m)
    except (TypeError, ValueError):
        raise ValueError(f"{what} position must be a number of metres, got {x_m!r}") from None
    if not (math.isfinite(x) and 0.0 < x <= length_m):
        raise ValueError(
            f"{what} position must lie on the beam, 0 < x <= {length_m:g} m from the clamp, got {x_m!r}"
        )
    return x


def check_damping_matrix(damping: object, n: int = RITZ_FUNCTIONS) -> np.ndarray:
    """A user's damping matrix as (n, n) float, N s/m; ValueError unless it is finite,
    symmetric and positive semi-definite (a passive damper dissipates, never feeds)."""
    try:
        r = np.array(damping, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"the damping matrix must be {n} x {n} numbers (N s/m)") from None
    if r.shape == (n * n,):
        r = r.reshape(n, n)
    if r.shape != (n, n):
        raise ValueError(f"the damping matrix must be {n} x {n} (N s/m), got shape {r.shape}")
    if not np.all(np.isfinite(r)):
        raise ValueError("the damping matrix holds non-finite values")
    scale = float(np.max(np.abs(r))) if r.size else 0.0
    if not np.allclose(r, r.T, rtol=1e-12, atol=1e-12 * scale):
        raise ValueError("the damping matrix must be symmetric")
    r = 0.5 * (r + r.T)
    lowest = float(np.linalg.eigvalsh(r)[0])
    if lowest < -1e-12 * max(scale, 1e-300):
        raise ValueError(f"the damping matrix must be positive semi-definite (an eigenvalue is {lowest:.4g})")
    return r


def parse_damping_matrix(text: str, n: int = RITZ_FUNCTIONS) -> np.ndarray:
    """``n*n`` numbers, row-major, N s/m, separated by commas, semicolons or white space
    (as typed or as a small text file holds them; ``#`` starts a comment): the checked
    (n, n) matrix (``check_damping_matrix``). ValueError for anything else."""
    words = []
    for line in str(text).splitlines():
        words += line.partition("#")[0].replace(",", " ").replace(";", " ").split()
    try:
        values = [float(w) for w in words]
    except ValueError:
        raise ValueError(f"the damping matrix must be {n * n} numbers, N s/m, row by row") from None
    if len(values) != n * n:
        raise ValueError(
            f"the damping matrix must be {n * n} numbers ({n} x {n}, row by row), got {len(values)}"
        )
    return check_damping_matrix(values, n)


def read_damping_matrix(spec: str, n: int = RITZ_FUNCTIONS) -> np.ndarray:
    """``spec`` is the numbers themselves (``parse_damping_matrix``) or the path of a
    text file holding them; the checked (n, n) matrix, N s/m."""
    path = Path(spec)
    try:
        is_file = path.is_file()
    except (OSError, ValueError):  # numbers too long for a file name, a NUL
        is_file = False
    if is_file:
        try:
            text = path.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as exc:
            raise ValueError(f"cannot read {spec}: {exc}") from None
        return parse_damping_matrix(text, n)
    try:
        return parse_damping_matrix(spec, n)
    except ValueError as exc:
        if any(c.isalpha() and c not in "eE" for c in spec) or "/" in spec:
            raise ValueError(f"no file {spec} (and not {n * n} numbers either)") from None
        raise ValueError(str(exc)) from None


def build_specimen(
    name: str = "seed",
    force_at_m: float | None = None,
    sensor_at_m: float | None = None,
    damping: np.ndarray | None = None,
) -> Specimen:
    """One of ``SCENARIOS`` or ``CUSTOM``, hammer at ``force_at_m`` and accelerometer at
    ``sensor_at_m`` (m from the clamp, 0 < x <= L; None: the tip, as in the seed's setup).

    damping : (3, 3) N s/m, symmetric positive semi-definite, for the seed's Ritz N = 3
        beam; given, the scenario is ``custom`` (``name`` must be ``seed`` or ``custom``).
        ``custom`` needs it.
    """
    name = str(name).strip().lower()
    if damping is not None:
        if name not in ("seed", CUSTOM):
            raise ValueError(f"a damping matrix of your own goes with the seed's Ritz beam, not {name!r}")
        name = CUSTOM
    if name in ("seed", CUSTOM):
        if name == CUSTOM and damping is None:
            raise ValueError("scenario custom needs a damping matrix (3 x 3, N s/m)")
        beam = RitzBeam.build(n_functions=RITZ_FUNCTIONS)
        length = beam.beam.length_m
        x_f = check_position("force", force_at_m, length)
        x_s = check_position("sensor", sensor_at_m, length)
        if name == "seed":
            description, matrix = "seed paper: Ritz N=3 (Table 1), eq (18) damping", eq18_damping_matrix()
        else:
            description, matrix = (
                "seed paper's Ritz N=3 beam (Table 1), your damping matrix",
                check_damping_matrix(damping),
            )
        return Specimen(name, description, beam.structure(x_f, x_s), matrix, x_f, x_s, length)
    if name == "realistic":
        beam = ExactCantilever.build(n_modes=len(REALISTIC_DAMPING_RATIOS))
        length = beam.beam.length_m
        x_f = check_position("force", force_at_m, length)
        x_s = check_position("sensor", sensor_at_m, length)
        return Specimen(
            name,
            "exact cantilever, 6 modes, 0.2-1 % modal damping",
            beam.structure(x_f, x_s),
            beam.modal_damping_matrix(REALISTIC_DAMPING_RATIOS),
            x_f,
            x_s,
            length,
        )
    raise ValueError(f"unknown scenario {name!r}; choose one of {', '.join((*SCENARIOS, CUSTOM))}")
