"""What the simulated analyzer measures against the beam model and instrument facts.

The reference H(j w) comes from analysis.response (a direct modal sum), a path
independent of the simulator's pole-residue sampling, anti-alias filter and DSP.
"""

import numpy as np
import pytest

from analysis.response import frequency_response
from sims.scenarios import build_specimen
from tests.reference import EXACT_TABULATED_HZ
from tests.sims.wire import decode_trace


def _trace(conn, commands: str) -> tuple[np.ndarray, np.ndarray]:
    conn.write(commands.encode() + b"\n")
    return decode_trace(conn.read(timeout_s=5.0))


def _measure(conn, setup: str) -> None:
    conn.write(f"{setup};STRT\n".encode())
    assert conn.query("SMSD") == b"1\r\n", conn.query("STA?")
    assert conn.query("ERR?") == b'0,"No error"\r\n'


def _lines(header: np.ndarray) -> np.ndarray:
    return header[64] + np.arange(int(header[1])) * header[55]


# Spans where the response has died out within the record (400 / span seconds):
# seed mode 1 decays as exp(-1.26 t), realistic mode 1 as exp(-0.35 t). The
# pre-trigger (1/32 of the record) holds the spread the zero-phase decimating
# filters give the hammer pulse before the trigger (docs/simulator.md).
@pytest.mark.parametrize(
    ("scenario", "span_hz", "center_hz"),
    [("seed", 50.0, 25.0), ("realistic", 12.5, 6.25), ("seed", 12.5, 36.0), ("realistic", 12.5, 98.0)],
    ids=["seed-baseband", "realistic-baseband", "seed-zoom-mode2", "realistic-zoom-mode3"],
)
def test_frf_of_a_capture_equals_the_specimen_h(make_analyzer, connect, scenario, span_hz, center_hz):
    conn = connect(make_analyzer(scenario, seed=5, noise=False))
    _measure(
        conn,
        f"FRS {span_hz} HZ;CF {center_hz} HZ;TSRC CH1;TLVL 2 MV;TDLY {-400 / span_hz / 32} S;UNIF;"
        "NAVG 2;STBL;"
        "RNG1 20 MV;RNG2 0.5 V",
    )
    header, frf = _trace(conn, "FRSP;DDAN")
    assert header[3] == 2  # averages
    f = _lines(header)
    assert f[0] == pytest.approx(center_hz - span_hz / 2)
    spec = build_specimen(scenario)
    h = frequency_response(spec.model, spec.damping, f, "acceleration")
    strong = np.abs(h) > 0.01 * np.abs(h).max()
    strong[f == 0] = False  # 0 Hz: acceleration is 0 there
    rel = np.abs(frf - h)[strong] / np.abs(h)[strong]
    assert rel.max() < 0.01, f"worst {rel.max():.4f} at {f[strong][np.argmax(rel)]:.4f} Hz"


def test_realistic_frf_peaks_sit_on_the_exact_beam_frequencies_with_noise(make_analyzer, connect):
    conn = connect(make_analyzer("realistic", seed=11, noise=True))
    # The impact-test windows: force window on the hammer, exponential on the response.
    _measure(
        conn,
        "FRS 200 HZ;TSRC CH1;TLVL 2 MV;TDLY -20 MS;WIN1 FORC;FWD1 50 MS;WIN2 EXPO;EXD2 0.5 S;"
        "NAVG 5;STBL;RNG1 20 MV;RNG2 0.5 V",
    )
    header, frf = _trace(conn, "FRSP;DDAN")
    f = _lines(header)
    line = header[55]
    assert line == pytest.approx(0.5)
    magnitude = np.abs(frf)
    for exact in EXACT_TABULATED_HZ:  # 5.57, 34.90, 97.72, 191.49 Hz (docs/method.md)
        near = np.abs(f - exact) < 4.0
        peak = f[near][np.argmax(magnitude[near])]
        assert abs(peak - exact) <= line, f"peak at {peak} Hz, exact {exact} Hz"


def test_coherence_is_one_without_noise_and_drops_with_it(make_analyzer, connect):
    setup = "FRS 200 HZ;TSRC CH1;TLVL 2 MV;TDLY -20 MS;UNIF;NAVG 4;STBL;RNG1 20 MV;RNG2 0.5 V"
    quiet = connect(make_analyzer("seed", seed=2, noise=False))
    _measure(quiet, setup)
    _, coherence = _trace(quiet, "COHR;DDAN")
    assert np.all(coherence[1:] > 0.99)  # only quantisation is left to disturb it
    noisy = connect(make_analyzer("seed", seed=2, noise=True))
    noisy.write(b"SIM:HAMMER peak_force_n=0.5\n")  # a feeble tap: noise matters
    _measure(noisy, setup.replace("TLVL 2 MV", "TLVL 0.5 MV"))
    _, coherence = _trace(noisy, "COHR;DDAN")
    assert np.all((coherence >= 0) & (coherence <= 1 + 1e-12))
    assert coherence.min() < 0.9


def _records(conn):
    h1, force = _trace(conn, "TIM1;DDAN")
    h2, accel = _trace(conn, "TIM2;DDAN")
    return h1, force, h2, accel


@pytest.mark.parametrize("windows", ["UNIF", "HANN", "FLAT", "WIN1 FORC;FWD1 0.1 S;WIN2 EXPO;EXD2 0.5 S"])
def test_analyzer_frf_is_h1_of_its_own_time_records(make_analyzer, connect, windows):
    conn = connect(make_analyzer("seed", seed=4, noise=True))
    _measure(conn, f"FRS 200 HZ;TSRC CH1;TLVL 2 MV;TDLY -10 MS;{windows};AVOF;RNG1 20 MV;RNG2 0.5 V")
    h1, force, _, accel = _records(conn)
    n, fs = force.size, 2 * h1[52]
    k, t = np.arange(n), np.arange(n) / fs
    # Window definitions from sims/command_table.py and docs/instrument.md, written out here.
    shapes = {
        "UNIF": np.ones(n),
        "HANN": 0.5 - 0.5 * np.cos(2 * np.pi * k / n),
        "FLAT": 0.21557895
        - 0.41663158 * np.cos(2 * np.pi * k / n)
        + 0.277263158 * np.cos(4 * np.pi * k / n)
        - 0.083578947 * np.cos(6 * np.pi * k / n)
        + 0.006947368 * np.cos(8 * np.pi * k / n),
        "FORC": (t < 0.1).astype(float),
        "EXPO": np.exp(-t / 0.5),
    }
    if windows.startswith("WIN1"):
        w1, w2 = shapes["FORC"], shapes["EXPO"]
    else:
        w1 = w2 = shapes[windows]
    x1 = np.fft.rfft(force * w1)[:401]
    x2 = np.fft.rfft(accel * w2)[:401]
    _, frf = _trace(conn, "FRSP;DDAN")
    np.testing.assert_allclose(frf[1:], (x2 / x1)[1:], rtol=1e-9)
    _, lsp1 = _trace(conn, "LSP1;DDAN")
    peak = np.full(401, 2 / w1.sum())
    peak[0] /= 2
    np.testing.assert_allclose(lsp1, x1 * peak, rtol=1e-9, atol=1e-15)
    _, psp2 = _trace(conn, "PSP2;DDAN")
    scale2 = np.full(401, 2 / w2.sum())
    scale2[0] /= 2
    np.testing.assert_allclose(psp2, np.abs(x2 * scale2) ** 2, rtol=1e-9, atol=1e-20)


def test_records_are_16_bit_at_full_span_and_in_engineering_units(make_analyzer, connect):
    conn = connect(make_analyzer("seed", seed=1, noise=True))
    _measure(conn, "FRS 102.4 KHZ;TSRC FREE;RNG1 0.1 V;RNG2 1 V;SNS1 2.25 MV;SNS2 1.02 MV")
    _, force, _, accel = _records(conn)
    for values, sens, rng in ((force, 2.25e-3, 10 ** (-20 / 20)), (accel, 1.02e-3, 1.0)):
        codes = values * sens / (rng / 32768)
        np.testing.assert_allclose(codes, np.round(codes), atol=1e-6)
        assert np.abs(codes).max() <= 32768
        assert np.unique(np.round(codes)).size > 2  # noise spans several codes


def test_overload_clips_at_the_range_and_is_flagged(make_analyzer, connect):
    conn = connect(make_analyzer("seed", seed=3, noise=False))
    # The hammer gives ~5 N, 11 mV at 2.25 mV/N: a 5 mV range overloads channel 1.
    _measure(conn, "FRS 200 HZ;TSRC CH1;TLVL 2 MV;TDLY -10 MS;RNG1 5 MV;RNG2 1 V")
    assert conn.query("OVLD?") == b"1,0\r\n"
    assert int(conn.query("STA?")) & 4
    h1, force, _, _ = _records(conn)
    assert h1[5] == 1  # overflow word
    range_n = 10 ** (-46 / 20) / 2.25e-3  # 5 mV rounds up to -46 dBV, in newtons
    assert force.max() <= range_n * (1 + 1e-9)
    assert force.min() >= -range_n * (1 + 1e-9)
    header, _ = _trace(conn, "FRSP;DDAN")
    assert header[5] == 1


def test_double_hits_show_two_pulses(make_analyzer, connect):
    conn = connect(make_analyzer("seed", seed=8, noise=False))
    conn.write(b"SIM:HAMMER double_hit_probability=1\n")
    _measure(conn, "FRS 3.2 KHZ;TSRC CH1;TLVL 2 MV;TDLY -2 MS;RNG1 20 MV;RNG2 1 V")
    _, force, _, _ = _records(conn)
    above = force > 0.1 * force.max()
    rises = np.flatnonzero(above[1:] & ~above[:-1])
    assert rises.size == 2, rises


def test_pre_trigger_and_trigger_level(make_analyzer, connect):
    conn = connect(make_analyzer("seed", seed=6, noise=False))
    _measure(conn, "FRS 3.2 KHZ;TSRC CH1;TLVL 4 MV;TDLY -5 MS;RNG1 20 MV;RNG2 1 V")
    h1, force, _, _ = _records(conn)
    assert h1[64] == pytest.approx(-5e-3, abs=0.5 / 8192)  # start time: the pre-trigger
    t = h1[64] + np.arange(force.size) * h1[55]
    # 4 mV is 1.78 N: the force crosses it at the trigger (t = 0) on its way up.
    level_n = 4e-3 / 2.25e-3
    assert force[t < -1.5e-3].max() < 0.05 * level_n  # before the hit: nothing
    assert force[(t > 0) & (t < 2e-3)].max() > level_n
    # A level above every hit never triggers: the analyzer keeps waiting.
    conn.write(b"TLVL 1 V;STRT\n")
    assert int(conn.query("STA?")) & 2
    assert conn.query("SMSD") == b"0\r\n"


def test_same_seed_same_bytes_other_seed_other_bytes(make_analyzer, connect):
    def run(seed):
        conn = connect(make_analyzer("realistic", seed=seed, noise=True))
        _measure(conn, "FRS 200 HZ;TSRC CH1;TLVL 2 MV;TDLY -10 MS;NAVG 3;STBL;RNG1 20 MV;RNG2 1 V")
        conn.write(b"TIM2;DDAN\n")
        return conn.read(timeout_s=5.0)

    assert run(21) == run(21)
    assert run(21) != run(22)
