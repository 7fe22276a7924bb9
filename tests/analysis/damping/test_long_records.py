"""Long time records: the band-limited objective's FFT length and its chunked batches."""

import numpy as np

from analysis.beam import TABLE_1
from analysis.damping import bandlimited
from analysis.damping.bandlimited import PAD, BandLimitedData, batched_residuals, fft_length, psi
from analysis.ritz import RitzBeam
from analysis.seed import eq18_damping_matrix


def test_fft_length_keeps_power_of_two_records_and_avoids_prime_lengths():
    for n in (1024, 2048, 4096, 8192, 25600):
        assert fft_length(n) == PAD * n
    assert fft_length(8191) == 65536  # 8 x 8191 has the prime 8191 as a factor


def test_chunked_batches_equal_one_member_at_a_time(monkeypatch):
    model = RitzBeam.build(TABLE_1, 3).structure(None, None)
    rng = np.random.default_rng(0)
    data = BandLimitedData(model, rng.normal(size=(2, 301)), rng.normal(size=(2, 301)), 512.0)
    r = eq18_damping_matrix()
    batch = np.stack([r, 1.1 * r, 0.9 * r])
    whole = batched_residuals(data, batch)
    monkeypatch.setattr(bandlimited, "_CHUNK_BYTES", 1)  # one member per chunk
    assert batched_residuals(data, batch).shape == (3, 602)
    np.testing.assert_array_equal(batched_residuals(data, batch), whole)
    np.testing.assert_allclose(psi(data, batch), np.linalg.norm(whole, axis=1) / 602)
