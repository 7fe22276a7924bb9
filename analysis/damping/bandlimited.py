"""The time-domain objective with a band-limited model response, for records taken
through an analyzer's anti-alias filters.

eq (17) compares the measured tip acceleration with the model's response to the
measured force. The samples of an analyzer's force record are band-limited (its
filters pass the span and stop well before the sample rate), and the measured
response went through the same filters. A zero-order-hold model of the force holds
each sample for a whole step, which a hammer pulse shorter than a sample is not:
on the simulated seed beam that left a residual 14 times the sensor noise at the
true R and moved the third mode's damping from 16 % to 25 %. Here the force is
taken as the band-limited signal its samples define, and the model's response is
its product with H(j omega) in the frequency domain:

    y_model = irfft( rfft(f, L) * H(j omega_k), L )[:n],

with the record zero-padded to L >= PAD x n samples so that the model's response
to the hits decays before it could wrap around (PAD = 8: a 1 % damped 5.6 Hz mode
falls to e^-5.6 over 8 records of 2 s). L is the first length of at least PAD x n
whose FFT is fast (``fft_length``): PAD x n itself for the analyzers' records of 2^k
samples, but a record of 8,191 samples (a prime) made 8n = 65,528 an FFT 16 times
slower than 65,536. Filtering the response again is not needed:
filter(system(force)) = system(filter(force)) for linear systems.

The residuals of a batch of damping matrices are computed a few members at a time
(``_CHUNK_BYTES`` of spectra), so that memory stays bounded whatever the record
length and the batch (a Jacobian of a 10 x 10 R is 56 matrices; at 5 x 25,600
samples the whole batch at once took 2 GB).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.fft

from analysis.response import frequency_response
from analysis.structure import StructuralModel

PAD = 8
#: Bytes of complex spectra ``batched_residuals`` handles at once: temporaries past
#: glibc's 32 MiB mmap limit are mapped and faulted in afresh on every call (a DE run
#: spent a quarter of its time there), and a whole Jacobian's spectra of long records
#: take gigabytes.
_CHUNK_BYTES = 8 * 2**20


def fft_length(n_samples: int) -> int:
    """L: the zero-padded length of a record of ``n_samples``, PAD x n_samples or the
    next length whose real FFT is fast (only 2, 3, 5 and 7 as factors)."""
    return scipy.fft.next_fast_len(PAD * int(n_samples), real=True)


@dataclass(frozen=True)
class BandLimitedData:
    """model; force_n, response_m_s2 : (n_hits, n_samples) N and m/s^2 (raw records);
    sample_rate_hz : Hz; keep : (n_hits * n_samples,) bool, the samples compared
    (None = all)."""

    model: StructuralModel
    force_n: np.ndarray
    response_m_s2: np.ndarray
    sample_rate_hz: float
    keep: np.ndarray | None = None

    def __post_init__(self) -> None:
        force = np.asarray(self.force_n, dtype=float)
        response = np.asarray(self.response_m_s2, dtype=float)
        if force.ndim != 2 or force.shape != response.shape:
            raise ValueError(
                f"force and response must both be (n_hits, n_samples), got {force.shape}, {response.shape}"
            )
        length = fft_length(force.shape[1])
        object.__setattr__(self, "force_n", force)
        object.__setattr__(self, "response_m_s2", response)
        object.__setattr__(self, "_force_spectrum", np.fft.rfft(force, length, axis=1))
        object.__setattr__(self, "_frequency_hz", np.fft.rfftfreq(length, 1.0 / self.sample_rate_hz))

    @property
    def n_compared(self) -> int:
        return int(self.force_n.size if self.keep is None else np.count_nonzero(self.keep))


def model_response(data: BandLimitedData, damping: np.ndarray) -> np.ndarray:
    """(B, n_hits, n_samples) model acceleration for damping matrices (B, N, N), m/s^2."""
    r = np.asarray(damping, dtype=float).reshape(-1, *np.shape(damping)[-2:])
    h = frequency_response(data.model, r, data._frequency_hz, "acceleration")  # (B, F)
    n = data.force_n.shape[1]
    with np.errstate(all="ignore"):
        y = np.fft.irfft(h[:, None, :] * data._force_spectrum[None], fft_length(n), axis=2)
    return y[:, :, :n]


def _members_per_chunk(data: BandLimitedData) -> int:
    """Damping matrices whose spectra over all hits fit in _CHUNK_BYTES (at least 1)."""
    return max(1, _CHUNK_BYTES // (16 * data._force_spectrum.size))


def batched_residuals(data: BandLimitedData, damping: np.ndarray) -> np.ndarray:
    """(B, n_compared) measured minus model, over the compared samples; m/s^2.
    Computed _members_per_chunk matrices at a time into the result."""
    r = np.asarray(damping, dtype=float)
    r = r.reshape(-1, *r.shape[-2:])
    out = np.empty((r.shape[0], data.n_compared))
    step = _members_per_chunk(data)
    for i in range(0, r.shape[0], step):
        chunk = (data.response_m_s2[None] - model_response(data, r[i : i + step])).reshape(
            -1, data.force_n.size
        )
        out[i : i + step] = chunk if data.keep is None else chunk[:, data.keep]
    return out


def residuals(data: BandLimitedData, damping: np.ndarray) -> np.ndarray:
    """(n_compared,) for one damping matrix (N, N)."""
    return batched_residuals(data, np.asarray(damping, dtype=float)[None])[0]


def psi(data: BandLimitedData, damping: np.ndarray) -> np.ndarray:
    """eq (17) over the compared samples, (...,) for damping (..., N, N); unstable -> inf."""
    r = np.asarray(damping, dtype=float)
    flat = r.reshape(-1, *r.shape[-2:])
    # A few members at a time (_CHUNK_BYTES): one member's spectra over all hits take
    # hits x 4n x 16 bytes.
    step = _members_per_chunk(data)
    value = np.empty(flat.shape[0])
    with np.errstate(all="ignore"):
        for i in range(0, flat.shape[0], step):
            res = batched_residuals(data, flat[i : i + step])
            value[i : i + step] = np.sqrt(np.einsum("bi,bi->b", res, res)) / data.n_compared
    return np.where(np.isfinite(value), value, np.inf).reshape(r.shape[:-2])
