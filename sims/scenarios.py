"""Specimens (test articles) the simulated analyzer measures, built from analysis/.

* ``seed``: the seed paper's model, Ritz N = 3 with Table 1 and the eq (18)
  damping matrix. An identification on its data should return eq (18)'s modal
  damping (3.6 %, 20 %, 16 %).
* ``realistic``: the exact continuous cantilever truncated to 6 modes with light
  modal damping (1 % falling to 0.2 %), so that a 3-function model meets a real
  model error, as in the paper's lab.
"""

from __future__ import annotations

from dataclasses import dataclass

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


@dataclass(frozen=True)
class Specimen:
    """A structure with its damping, force and accelerometer at fixed positions."""

    name: str
    description: str
    model: StructuralModel
    damping: np.ndarray  # (N, N), N s/m

    def acceleration_system(self) -> PoleResidueSystem:
        """Force (N) at x_f to acceleration (m/s^2) at x_s."""
        a, b, c, d = self.model.state_space(self.damping, "acceleration")
        return PoleResidueSystem.from_state_space(a, b, c, float(d))

    def frequency_response(self, frequencies_hz: np.ndarray) -> np.ndarray:
        """H(j w), (m/s^2)/N, shape (F,): the reference the analyzer's FRF should match."""
        return frequency_response(self.model, self.damping, frequencies_hz, "acceleration")

    def natural_frequencies_hz(self) -> np.ndarray:
        return damped_modes(self.model, self.damping).natural_frequencies_hz


def build_specimen(
    name: str = "seed", force_at_m: float | None = None, sensor_at_m: float | None = None
) -> Specimen:
    """One of ``SCENARIOS``; positions default to the tip, as in the seed's setup."""
    if name == "seed":
        beam = RitzBeam.build(n_functions=3)
        return Specimen(
            name,
            "seed paper: Ritz N=3 (Table 1), eq (18) damping",
            beam.structure(force_at_m, sensor_at_m),
            eq18_damping_matrix(),
        )
    if name == "realistic":
        beam = ExactCantilever.build(n_modes=len(REALISTIC_DAMPING_RATIOS))
        return Specimen(
            name,
            "exact cantilever, 6 modes, 0.2-1 % modal damping",
            beam.structure(force_at_m, sensor_at_m),
            beam.modal_damping_matrix(REALISTIC_DAMPING_RATIOS),
        )
    raise ValueError(f"unknown scenario {name!r}; choose one of {', '.join(SCENARIOS)}")
