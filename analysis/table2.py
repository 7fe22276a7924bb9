"""The seed's Table 2 redone: Ritz and exact-beam frequencies beside the published columns,
and the modal damping implied by a damping matrix."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from analysis.beam import TABLE_1, BeamProperties, SectionSource
from analysis.beam_shapes import exact_shapes, ritz_shapes
from analysis.exact_beam import cantilever_frequencies_hz
from analysis.mac import auto_mac, mac
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


@dataclass(frozen=True)
class ModalTestTable2:
    """Table 2 of a multi-point test: per measured mode (rows, n_modes of them, by
    frequency), the measured frequency and damping with their standard uncertainty, the
    paired exact-beam and Ritz modes and the MAC of the measured shape against each.

    frequency_hz, frequency_std_hz (Hz), damping_ratio, damping_std (fractions of
    critical), mpc : (n_modes,) as measured; NaN where not given.
    exact_mode, ritz_mode : (n_modes,) int, the paired model mode (0-based), -1 if none:
        the model mode nearest in frequency within ``tolerance`` (relative to the model
        frequency), each model mode used once, lowest measured modes first.
    exact_hz, ritz_hz : (n_modes,) the paired model modes' frequencies, Hz (NaN: none).
    mac_exact, mac_ritz : (n_modes,) MAC of the measured shape against the paired
        model mode at the test's points (NaN: none).
    mac_exact_matrix (n_modes, n_exact), mac_ritz_matrix (n_modes, N): every measured
        shape against every model mode. auto_mac (n_modes, n_modes).
    """

    n_functions: int
    section: SectionSource
    positions_m: np.ndarray
    frequency_hz: np.ndarray
    frequency_std_hz: np.ndarray
    damping_ratio: np.ndarray
    damping_std: np.ndarray
    mpc: np.ndarray
    exact_mode: np.ndarray
    exact_hz: np.ndarray
    ritz_mode: np.ndarray
    ritz_hz: np.ndarray
    mac_exact: np.ndarray
    mac_ritz: np.ndarray
    mac_exact_matrix: np.ndarray
    mac_ritz_matrix: np.ndarray
    auto_mac: np.ndarray

    def difference_pct(self, column: np.ndarray) -> np.ndarray:
        """100 (measured - column) / column: how far the test is from a model."""
        return 100.0 * (self.frequency_hz - column) / column


def _pair_by_frequency(measured_hz: np.ndarray, model_hz: np.ndarray, tolerance: float) -> np.ndarray:
    """(n_measured,) index of the model mode paired with each measured mode, -1: none."""
    pair = np.full(measured_hz.size, -1, dtype=int)
    free = np.ones(model_hz.size, dtype=bool)
    for k in np.argsort(measured_hz):
        distance = np.where(free, np.abs(model_hz - measured_hz[k]) / model_hz, np.inf)
        best = int(np.argmin(distance)) if distance.size else 0
        if distance.size and distance[best] <= tolerance:
            pair[k] = best
            free[best] = False
    return pair


def _optional(values: np.ndarray | None, n: int, name: str) -> np.ndarray:
    if values is None:
        return np.full(n, np.nan)
    v = np.asarray(values, dtype=float).ravel()
    if v.size != n:
        raise ValueError(f"{name} must have one value per mode ({n}), got {v.size}")
    return v


def modal_test_table2(
    frequency_hz: np.ndarray,
    damping_ratio: np.ndarray,
    shapes: np.ndarray,
    positions_m: np.ndarray,
    beam: BeamProperties = TABLE_1,
    n_functions: int = 3,
    section: SectionSource = "tabulated",
    *,
    frequency_std_hz: np.ndarray | None = None,
    damping_std: np.ndarray | None = None,
    mpc: np.ndarray | None = None,
    n_exact_modes: int | None = None,
    tolerance: float = 0.25,
) -> ModalTestTable2:
    """Table 2 of a multi-point test (see ModalTestTable2).

    frequency_hz, damping_ratio : (n_modes,) the test's modes (Hz, fraction of
    critical). shapes (n_modes, n_points) complex, measured at positions_m (n_points,)
    m from the clamp (any scaling: MAC ignores it). The exact beam is taken to
    n_exact_modes modes (default max(n_modes, N) + 2), the Ritz model has N =
    n_functions. A mode's ± (frequency_std_hz, damping_std) and mpc are carried as given
    (e.g. from analysis.modal_id.shapes.ModeShapes or the run's uncertainty).
    """
    freqs = np.asarray(frequency_hz, dtype=float).ravel()
    zetas = np.asarray(damping_ratio, dtype=float).ravel()
    n = freqs.size
    s = np.asarray(shapes)
    if s.ndim == 1 and n == 1:
        s = s[np.newaxis, :]
    x = np.atleast_1d(np.asarray(positions_m, dtype=float))
    if zetas.size != n or s.ndim != 2 or s.shape != (n, x.size):
        raise ValueError(
            f"expected {n} damping ratios and shapes of shape ({n}, {x.size}); got {zetas.size} and {s.shape}"
        )
    n_exact = n_exact_modes or max(n, n_functions) + 2
    exact = exact_shapes(x, n_exact, beam, section)
    ritz = ritz_shapes(x, n_functions, beam, section)
    mac_e = mac(s, exact.shapes) if n else np.empty((0, n_exact))
    mac_r = mac(s, ritz.shapes) if n else np.empty((0, n_functions))
    pe = _pair_by_frequency(freqs, exact.frequencies_hz, tolerance)
    pr = _pair_by_frequency(freqs, ritz.frequencies_hz, tolerance)
    rows = np.arange(n)

    def pick(table: np.ndarray, pair: np.ndarray) -> np.ndarray:
        return np.where(pair >= 0, table[rows, np.maximum(pair, 0)], np.nan) if n else np.empty(0)

    return ModalTestTable2(
        n_functions=n_functions,
        section=section,
        positions_m=x,
        frequency_hz=freqs,
        frequency_std_hz=_optional(frequency_std_hz, n, "frequency_std_hz"),
        damping_ratio=zetas,
        damping_std=_optional(damping_std, n, "damping_std"),
        mpc=_optional(mpc, n, "mpc"),
        exact_mode=pe,
        exact_hz=np.where(pe >= 0, exact.frequencies_hz[np.maximum(pe, 0)], np.nan),
        ritz_mode=pr,
        ritz_hz=np.where(pr >= 0, ritz.frequencies_hz[np.maximum(pr, 0)], np.nan),
        mac_exact=pick(mac_e, pe),
        mac_ritz=pick(mac_r, pr),
        mac_exact_matrix=mac_e,
        mac_ritz_matrix=mac_r,
        auto_mac=auto_mac(s) if n else np.empty((0, 0)),
    )
