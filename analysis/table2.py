"""The seed's Table 2 redone: Ritz and exact-beam frequencies beside the published columns,
and the modal damping implied by a damping matrix."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from analysis.beam import TABLE_1, BeamProperties, SectionSource
from analysis.exact_beam import cantilever_frequencies_hz
from analysis.modal import DampedModes, damped_modes
from analysis.ritz import RitzBeam
from analysis.seed import TABLE_2_ANALYTICAL_HZ, TABLE_2_EXPERIMENTAL_HZ


@dataclass(frozen=True)
class Table2:
    """Natural frequencies (Hz) per mode; NaN where a column has no such mode.

    Every column has shape (n_rows,), n_rows = max(N, 3).
    """

    n_functions: int
    section: SectionSource
    ritz_hz: np.ndarray
    exact_tabulated_hz: np.ndarray
    exact_derived_hz: np.ndarray
    seed_analytical_hz: np.ndarray
    seed_experimental_hz: np.ndarray

    @property
    def n_rows(self) -> int:
        return self.ritz_hz.size

    def difference_pct(self, column: np.ndarray) -> np.ndarray:
        """100 (column - experimental) / experimental, NaN beyond the seed's 3 modes."""
        return 100.0 * (column - self.seed_experimental_hz) / self.seed_experimental_hz


def _padded(values: np.ndarray | tuple[float, ...], n: int) -> np.ndarray:
    out = np.full(n, np.nan)
    v = np.asarray(values, dtype=float)[:n]
    out[: v.size] = v
    return out


def table2(
    beam: BeamProperties = TABLE_1, n_functions: int = 3, section: SectionSource = "tabulated"
) -> Table2:
    """Ritz (N functions, A and I from ``section``) against the exact beam with tabulated
    and with derived A, I, and the seed's analytical and experimental columns."""
    n_rows = max(n_functions, len(TABLE_2_EXPERIMENTAL_HZ))
    ritz = RitzBeam.build(beam, n_functions, section).frequencies_hz()
    return Table2(
        n_functions=n_functions,
        section=section,
        ritz_hz=_padded(ritz, n_rows),
        exact_tabulated_hz=cantilever_frequencies_hz(beam.with_section("tabulated"), n_rows),
        exact_derived_hz=cantilever_frequencies_hz(beam.with_section("derived"), n_rows),
        seed_analytical_hz=_padded(TABLE_2_ANALYTICAL_HZ, n_rows),
        seed_experimental_hz=_padded(TABLE_2_EXPERIMENTAL_HZ, n_rows),
    )


@dataclass(frozen=True)
class DampingSummary:
    """What a damping matrix R does to the Ritz model of its own size N."""

    damping: np.ndarray  # (N, N), N s/m
    symmetric_eigenvalues: np.ndarray  # (N,) of (R + R^T)/2, ascending
    modes: DampedModes  # unbatched: arrays of shape (N,)

    @property
    def definiteness(self) -> str:
        """ "positive definite", "positive semi-definite" or "indefinite" (of the symmetric
        part, with a relative tolerance of 1e-12): only an indefinite R can feed energy in."""
        eig = self.symmetric_eigenvalues
        tol = 1e-12 * float(np.max(np.abs(eig))) if eig.size else 0.0
        if eig[0] > tol:
            return "positive definite"
        if eig[0] >= -tol:
            return "positive semi-definite"
        return "indefinite"

    @property
    def positive_definite(self) -> bool:
        return self.definiteness == "positive definite"

    @property
    def symmetric(self) -> bool:
        return bool(np.allclose(self.damping, self.damping.T, rtol=1e-12, atol=0.0))


def damping_summary(
    damping: np.ndarray, beam: BeamProperties = TABLE_1, section: SectionSource = "tabulated"
) -> DampingSummary:
    """Modal frequencies and damping ratios of the Ritz model with N = R's size."""
    r = np.asarray(damping, dtype=float)
    if r.ndim != 2 or r.shape[0] != r.shape[1] or r.shape[0] < 1:
        raise ValueError(f"a damping matrix must be square, got shape {r.shape}")
    model = RitzBeam.build(beam, r.shape[0], section).structure()
    return DampingSummary(
        damping=r,
        symmetric_eigenvalues=np.linalg.eigvalsh(0.5 * (r + r.T)),
        modes=damped_modes(model, r),
    )


@dataclass(frozen=True)
class IdentifiedTable2:
    """The seed's Table 2 for one run: the analytical columns beside the modes the run
    identified. Every column has shape (n_rows,); NaN where a column has no such mode.

    identified_hz, damping_ratio : the run's mode matched to each analytical mode
        (nearest in frequency, within ``tolerance`` relative of the exact beam).
    """

    n_functions: int
    section: SectionSource
    ritz_hz: np.ndarray
    exact_hz: np.ndarray
    identified_hz: np.ndarray
    damping_ratio: np.ndarray

    def difference_pct(self, column: np.ndarray) -> np.ndarray:
        """100 (identified - column) / column: how far the run is from a model."""
        return 100.0 * (self.identified_hz - column) / column


def identified_table2(
    frequency_hz: np.ndarray,
    damping_ratio: np.ndarray,
    beam: BeamProperties = TABLE_1,
    n_functions: int = 3,
    section: SectionSource = "tabulated",
    n_rows: int | None = None,
    tolerance: float = 0.25,
) -> IdentifiedTable2:
    """Ritz (N functions) and exact-beam frequencies (Hz) beside identified modes.

    frequency_hz, damping_ratio : (n_modes,) the run's modes. Each analytical mode
    takes the nearest identified mode within ``tolerance`` (relative to the exact
    frequency), each identified mode used once, lowest modes first.
    """
    n_rows = n_rows or max(n_functions, 3)
    ritz = _padded(RitzBeam.build(beam, n_functions, section).frequencies_hz(), n_rows)
    exact = cantilever_frequencies_hz(beam.with_section(section), n_rows)
    freqs = np.asarray(frequency_hz, dtype=float)
    zetas = np.asarray(damping_ratio, dtype=float)
    identified = np.full(n_rows, np.nan)
    damping = np.full(n_rows, np.nan)
    free = np.ones(freqs.size, dtype=bool)
    for row in range(n_rows):
        if not free.any():
            break
        distance = np.where(free, np.abs(freqs - exact[row]) / exact[row], np.inf)
        best = int(np.argmin(distance))
        if distance[best] <= tolerance:
            identified[row], damping[row] = freqs[best], zetas[best]
            free[best] = False
    return IdentifiedTable2(n_functions, section, ritz, exact, identified, damping)
