"""The analyzer's own processing: windows, spectra and the average over accepted hits.

Kept apart from analysis/ on purpose: the simulator plays an instrument whose
results our analysis is later checked against.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.signal

from sims.settings import N_LINES


def window(
    kind: str, n_points: int, sample_rate_hz: float, force_width_s: float, exp_decay_s: float
) -> np.ndarray:
    """One channel's window over a record, shape (n_points,).

    Hanning and flat top are periodic (DFT-even), as a spectrum analyzer applies
    them: scipy's "hann" and its 5-term "flattop". FORC is 1 from the start of the
    record for ``force_width_s`` (at most the record), 0 after; EXPO is
    exp(-t / exp_decay_s) from the start of the record.
    """
    if kind == "UNIF":
        return np.ones(n_points)
    if kind == "HANN":
        return scipy.signal.get_window("hann", n_points, fftbins=True)
    if kind == "FLAT":
        return scipy.signal.get_window("flattop", n_points, fftbins=True)
    if kind == "FORC":
        return (np.arange(n_points) / sample_rate_hz < force_width_s).astype(float)
    if kind == "EXPO":
        decay_samples = exp_decay_s * sample_rate_hz
        return scipy.signal.windows.exponential(n_points, center=0, tau=decay_samples, sym=False)
    raise ValueError(f"unknown window {kind}")


def line_spectrum(record: np.ndarray, win: np.ndarray, n_lines: int = N_LINES) -> np.ndarray:
    """Unscaled spectrum of the windowed record on the lines, (n_lines + 1,) complex.

    A real (baseband) record of 2.56 x n_lines samples gives lines 0..n_lines of
    its FFT; a complex (zoom) record of 1.28 x n_lines points gives the
    n_lines + 1 lines centred on the mixed-down center (401 of 1024 or 512 on
    the 35660A).
    """
    if np.iscomplexobj(record):
        spectrum = np.fft.fftshift(np.fft.fft(record * win))
        middle = record.size // 2
        return spectrum[middle - n_lines // 2 : middle + n_lines // 2 + 1]
    return np.fft.rfft(record * win)[: n_lines + 1]


def peak_scale(win: np.ndarray, zoom: bool, n_lines: int = N_LINES) -> np.ndarray:
    """Per-line factor from an unscaled spectrum to peak amplitude, (n_lines + 1,).

    2 / sum(w) turns a sinusoid's line into its peak; the DC line of a real record
    takes 1 / sum(w). A zoom record carries each real sinusoid as one complex
    exponential of half its amplitude, so every zoom line takes 2 / sum(w).
    """
    total = float(win.sum())
    scale = np.full(n_lines + 1, 2.0 / total if total > 0 else 0.0)
    if not zoom:
        scale[0] /= 2
    return scale


@dataclass
class Average:
    """Running sums over the accepted hits (unscaled spectra, so that different
    windows on the two channels cannot bias ch2/ch1)."""

    n_lines: int = N_LINES
    count: int = 0
    overload: list[bool] = field(default_factory=lambda: [False, False])
    g11: np.ndarray = field(init=False)
    g22: np.ndarray = field(init=False)
    g21: np.ndarray = field(init=False)
    x1: np.ndarray = field(init=False)
    x2: np.ndarray = field(init=False)
    scale1: np.ndarray = field(init=False)
    scale2: np.ndarray = field(init=False)

    def __post_init__(self) -> None:
        n = self.n_lines + 1
        self.g11, self.g22 = np.zeros(n), np.zeros(n)
        self.g21, self.x1, self.x2 = np.zeros(n, complex), np.zeros(n, complex), np.zeros(n, complex)
        self.scale1, self.scale2 = np.ones(n), np.ones(n)

    def add(
        self,
        spec1: np.ndarray,
        spec2: np.ndarray,
        scale1: np.ndarray,
        scale2: np.ndarray,
        overload: tuple[bool, bool],
    ) -> None:
        self.count += 1
        self.g11 += np.abs(spec1) ** 2
        self.g22 += np.abs(spec2) ** 2
        self.g21 += np.conj(spec1) * spec2
        self.x1 += spec1
        self.x2 += spec2
        self.scale1, self.scale2 = scale1, scale2
        self.overload = [self.overload[0] or overload[0], self.overload[1] or overload[1]]

    def trace(self, function: str) -> np.ndarray:
        """The averaged display function on n_lines + 1 lines: complex for LSP/FRSP, real otherwise.

        Linear spectra are peak-scaled (see ``peak_scale``), EU; power spectra are
        their squared magnitude, EU^2; FRSP is H1 = G21 / G11; COHR is
        |G21|^2 / (G11 G22).
        """
        if self.count == 0:
            raise LookupError("no data")
        c = self.count
        if function in ("LSP1", "LSP2", "PSP1", "PSP2"):
            ch = int(function[-1])
            x, g, scale = (self.x1, self.g11, self.scale1) if ch == 1 else (self.x2, self.g22, self.scale2)
            if function.startswith("LSP"):
                return x / c * scale
            return g / c * scale**2
        with np.errstate(divide="ignore", invalid="ignore"):
            if function == "FRSP":
                return np.where(self.g11 > 0, self.g21 / np.where(self.g11 > 0, self.g11, 1.0), 0.0)
            if function == "COHR":
                den = self.g11 * self.g22
                return np.where(den > 0, np.abs(self.g21) ** 2 / np.where(den > 0, den, 1.0), 0.0)
        raise ValueError(f"not a spectral function: {function}")
