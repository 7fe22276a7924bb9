"""The simulator's hammer and accelerometer anywhere on the beam (issue 23).

The reference is the textbook cantilever written out here, from Table 1's numbers and
the roots of 1 + cos(bL) cosh(bL) = 0 found here: the exact clamped-free modes
phi_r(x) = cosh(b_r x) - cos(b_r x) - sigma_r (sinh(b_r x) - sin(b_r x)), normalised
to a modal mass rho A L, give the acceleration per newton between force point p and
sensor point s as

    H_sp(w) = sum_r -w^2 phi_r(s) phi_r(p) / (rho A L (w_r^2 - w^2 + 2j zeta_r w_r w)).

Nothing of sims/ or analysis/ computes it. Mode 2's node at x/L = 0.7834 is the
classical clamped-free figure; the first test finds it again on the shape written here.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.optimize

from sims.inprocess import InProcessConnection
from sims.instrument import Analyzer
from sims.scenarios import build_specimen, parse_damping_matrix
from sims.sources import PhysicsSource
from tests.reference import CANTILEVER_BETA_L, EQ18, EXACT_TABULATED_HZ, REALISTIC_DAMPING_RATIOS
from tests.sims.wire import decode_trace

# Table 1 (the seed paper): aluminium, SI.
DENSITY, YOUNG, AREA, SECOND_MOMENT, LENGTH = 2710.0, 7.1e10, 10.46e-5, 9.493e-11, 0.7
MODAL_MASS = DENSITY * AREA * LENGTH
#: realistic's modal damping, modes 1..6 (docs/simulator.md, "Scenarios").
ZETA = (*REALISTIC_DAMPING_RATIOS, 0.0025, 0.002)
#: Mode 2's node of a clamped-free beam, x / L.
MODE_2_NODE = 0.7834


def _beta_l(n: int) -> np.ndarray:
    roots = [
        scipy.optimize.brentq(lambda b: 1 + math.cos(b) * math.cosh(b), (r - 1) * math.pi, r * math.pi)
        for r in range(1, n + 1)
    ]
    return np.array(roots)


BETA_L = _beta_l(6)
OMEGA = BETA_L**2 * math.sqrt(YOUNG * SECOND_MOMENT / (DENSITY * AREA * LENGTH**4))


def _phi(x: float) -> np.ndarray:
    """Exact cantilever shapes at x (m), modes 1..6, unit mean square over the beam."""
    b = BETA_L / LENGTH
    sigma = (np.cosh(BETA_L) + np.cos(BETA_L)) / (np.sinh(BETA_L) + np.sin(BETA_L))
    return np.cosh(b * x) - np.cos(b * x) - sigma * (np.sinh(b * x) - np.sin(b * x))


def _theory(f_hz: np.ndarray, sensor_m: float, force_m: float) -> np.ndarray:
    w = 2 * np.pi * np.asarray(f_hz)[:, None]
    terms = (
        _phi(sensor_m) * _phi(force_m) / (MODAL_MASS * (OMEGA**2 - w**2 + 2j * np.array(ZETA) * OMEGA * w))
    )
    return -(w[:, 0] ** 2) * terms.sum(axis=1)


def test_the_reference_here_is_the_textbook_beam():
    assert BETA_L[:4] == pytest.approx(CANTILEVER_BETA_L, abs=1e-7)
    assert OMEGA[:4] / (2 * np.pi) == pytest.approx(EXACT_TABULATED_HZ, rel=1e-5)
    node = scipy.optimize.brentq(lambda x: _phi(x)[1], 0.6 * LENGTH, 0.9 * LENGTH)
    assert node / LENGTH == pytest.approx(MODE_2_NODE, abs=1e-4)
    assert abs(_phi(LENGTH)[0]) == pytest.approx(2.0, abs=1e-9)  # |phi_r(L)| = 2, every mode


# ------------------------------------------------------------------ helpers
def _connect(analyzer: Analyzer) -> InProcessConnection:
    return InProcessConnection(analyzer)


def _ask(conn: InProcessConnection, text: str) -> bytes:
    conn.write(text.encode("ascii") + b"\n")
    try:
        return conn.read(timeout_s=0.0)
    except TimeoutError:
        return b""


def _measure_frf(conn: InProcessConnection, span_hz: float, center_hz: float, navg: int = 1):
    """(frequencies (Hz), FRF (m/s^2/N)) of one measurement with a uniform window,
    neither input overloaded (``OVLD?``, docs/instrument.md)."""
    delay = -400 / span_hz / 32
    _ask(
        conn,
        f"FRS {span_hz} HZ;CF {center_hz} HZ;TSRC CH1;TLVL 2 MV;TDLY {delay} S;UNIF;"
        f"NAVG {navg};STBL;RNG1 20 MV;RNG2 0.5 V;STRT",
    )
    assert _ask(conn, "SMSD") == b"1\r\n"
    assert _ask(conn, "ERR?") == b'0,"No error"\r\n'
    assert _ask(conn, "OVLD?") == b"0,0\r\n"
    conn.write(b"FRSP;DDAN\n")
    header, frf = decode_trace(conn.read(timeout_s=5.0))
    f = header[64] + np.arange(int(header[1])) * header[55]
    return f, frf


def _analyzer(scenario="realistic", seed=4, noise=False, **where) -> Analyzer:
    source = PhysicsSource(scenario, seed=seed, **where)
    source.set_noise(noise)
    return Analyzer(source, time_scale=0.0)


# Bands where the record (400 / span s) outlasts the response: the first three modes.
BANDS = [(12.5, 6.25), (12.5, 35.0), (12.5, 97.7)]


@pytest.mark.parametrize(("span_hz", "center_hz"), BANDS, ids=["mode1", "mode2-zoom", "mode3-zoom"])
def test_frf_between_two_interior_points_is_the_exact_beam_within_noise(span_hz, center_hz):
    force, sensor = 0.25, 0.45
    analyzer = _analyzer(noise=True, force_at_m=force, sensor_at_m=sensor)
    conn = _connect(analyzer)
    # A hard hit, a force window (1.5 s of the 32 s record: the pulse with its
    # anti-alias spread and the 1 s pre-trigger) and 8 averages: the sensor noise
    # left is about 1 % a line, as an impact test in the lab would take it.
    _ask(conn, "SIM:HAMMER peak_force_n=50")
    _ask(
        conn,
        f"FRS {span_hz} HZ;CF {center_hz} HZ;TSRC CH1;TLVL 20 MV;TDLY {-400 / span_hz / 32} S;"
        "WIN1 FORC;FWD1 1.5 S;WIN2 UNIF;NAVG 8;STBL;RNG1 0.5 V;RNG2 5 V;STRT",
    )
    assert _ask(conn, "SMSD") == b"1\r\n"
    assert _ask(conn, "ERR?") == b'0,"No error"\r\n'
    assert analyzer.last_record.overload == (False, False)
    conn.write(b"FRSP;DDAN\n")
    header, frf = decode_trace(conn.read(timeout_s=5.0))
    f = header[64] + np.arange(int(header[1])) * header[55]
    h = _theory(f, sensor, force)
    strong = (np.abs(h) > 0.05 * np.abs(h).max()) & (f > 0)
    rel = np.abs(frf - h)[strong] / np.abs(h)[strong]
    assert np.median(rel) < 0.03, f"median {np.median(rel):.4f}"
    assert rel.max() < 0.1, f"worst {rel.max():.4f} at {f[strong][np.argmax(rel)]:.3f} Hz"
    # Not the tip's FRF: the positions matter far beyond the noise.
    tip = _theory(f, LENGTH, LENGTH)
    assert np.median(np.abs(tip[strong] - h[strong]) / np.abs(h[strong])) > 0.5


@pytest.mark.parametrize(("span_hz", "center_hz"), BANDS, ids=["mode1", "mode2-zoom", "mode3-zoom"])
def test_frf_between_two_interior_points_is_the_exact_beam_without_noise(span_hz, center_hz):
    force, sensor = 0.15, 0.6
    f, frf = _measure_frf(_connect(_analyzer(force_at_m=force, sensor_at_m=sensor)), span_hz, center_hz)
    h = _theory(f, sensor, force)
    strong = (np.abs(h) > 0.05 * np.abs(h).max()) & (f > 0)
    rel = np.abs(frf - h)[strong] / np.abs(h)[strong]
    assert rel.max() < 0.01, f"worst {rel.max():.4f} at {f[strong][np.argmax(rel)]:.3f} Hz"


@pytest.mark.parametrize("scenario", ["seed", "realistic", "custom"])
def test_reciprocity_force_at_a_sensor_at_b_equals_force_at_b_sensor_at_a(scenario):
    a, b = 0.2, 0.55
    # A non-proportional damping matrix: reciprocity rests on symmetry, not on modes.
    damping = (
        {"damping": [[3.0, 1.0, -0.5], [1.0, 2.0, 0.4], [-0.5, 0.4, 1.5]]} if scenario == "custom" else {}
    )
    frfs = []
    for force, sensor in ((a, b), (b, a)):
        conn = _connect(_analyzer(scenario, seed=9, force_at_m=force, sensor_at_m=sensor, **damping))
        frfs.append(
            _measure_frf(
                conn, 50.0 if scenario != "realistic" else 12.5, 25.0 if scenario != "realistic" else 6.25
            )[1]
        )
    assert np.max(np.abs(frfs[0] - frfs[1])) <= 1e-6 * np.max(np.abs(frfs[0]))


def test_a_sensor_on_mode_2s_node_does_not_see_mode_2():
    node = MODE_2_NODE * LENGTH
    peaks, spectra = {}, {}
    for sensor in (LENGTH, node):
        conn = _connect(_analyzer(sensor_at_m=sensor))
        f, frf = _measure_frf(conn, 12.5, 35.0)
        near = np.abs(f - EXACT_TABULATED_HZ[1]) < 0.5
        peaks[sensor], spectra[sensor] = np.abs(frf[near]).max(), frf
    # At the tip mode 2 stands |phi_2(L)|^2 / (2 zeta_2 rho A L) = 4 / (0.012 rho A L) high;
    # on its node only modes 1 and 3's tails remain, about 1 % of that.
    assert peaks[LENGTH] == pytest.approx(4 / (2 * ZETA[1] * MODAL_MASS), rel=0.02)
    assert peaks[node] < 0.012 * peaks[LENGTH]
    # No resonance left: within +-1 Hz of mode 2 (the half-power band is 0.42 Hz wide)
    # the FRF is the other modes' smooth tails, as the theory without mode 2 has it.
    near = np.abs(f - EXACT_TABULATED_HZ[1]) < 1.0
    w = 2 * np.pi * f[near]
    others = [0, *range(2, 6)]
    tails = -(w**2) * sum(
        _phi(node)[r] * _phi(LENGTH)[r] / (MODAL_MASS * (OMEGA[r] ** 2 - w**2 + 2j * ZETA[r] * OMEGA[r] * w))
        for r in others
    )
    assert np.max(np.abs(spectra[node][near] - tails) / np.abs(tails)) < 0.02
    magnitude = np.abs(spectra[node][near])
    assert magnitude.max() / magnitude.min() < 1.1
    # The sensor still sees mode 3 there (phi_3 is not zero at mode 2's node).
    conn = _connect(_analyzer(sensor_at_m=node))
    f, frf = _measure_frf(conn, 12.5, 97.7)
    h = _theory(f, node, LENGTH)
    peak = np.argmax(np.abs(h))
    assert abs(f[peak] - EXACT_TABULATED_HZ[2]) < 0.1
    assert abs(frf[peak] - h[peak]) < 0.01 * abs(h[peak])


def test_sim_force_mid_session_changes_the_next_hits_frf():
    conn = _connect(_analyzer(seed=2))
    assert _ask(conn, "SIM:FORCE?") == b"0.7\r\n"
    assert _ask(conn, "SIM:SENSOR?") == b"0.7\r\n"
    f, at_tip = _measure_frf(conn, 12.5, 6.25)
    _ask(conn, "SIM:FORCE 0.3;SIM:SENSOR 0.5 M")
    assert _ask(conn, "SIM:FORCE?") == b"0.3\r\n"
    assert _ask(conn, "SIM:SENSOR?") == b"0.5\r\n"
    assert _ask(conn, "ERR?") == b'0,"No error"\r\n'
    f, moved = _measure_frf(conn, 12.5, 6.25)
    for frf, (sensor, force) in ((at_tip, (LENGTH, LENGTH)), (moved, (0.5, 0.3))):
        h = _theory(f, sensor, force)
        strong = (np.abs(h) > 0.05 * np.abs(h).max()) & (f > 0)
        assert np.max(np.abs(frf - h)[strong] / np.abs(h)[strong]) < 0.01
    # The same connection moves on: another scenario keeps the positions.
    _ask(conn, "SIM:SCEN seed")
    assert _ask(conn, "SIM:FORCE?") == b"0.3\r\n"


def test_positions_work_on_a_scpi_model_too():
    source = PhysicsSource("realistic", seed=1)
    analyzer = Analyzer(source, time_scale=0.0, model="35670A")
    conn = _connect(analyzer)
    assert _ask(conn, "SIM:SENSOR 0.4;SIM:SENSOR?") == b"0.4\n"
    assert source.specimen.sensor_at_m == 0.4
    assert _ask(conn, "SIM:FORCE 1;SYST:ERR?").startswith(b"-224,")


@pytest.mark.parametrize(
    ("command", "fragment"),
    [
        ("SIM:FORCE 0", b"on the beam"),
        ("SIM:FORCE -0.1", b"on the beam"),
        ("SIM:SENSOR 0.71", b"on the beam"),
        ("SIM:SENSOR nan", b"on the beam"),
        ("SIM:FORCE inf", b"on the beam"),
        ("SIM:FORCE abc", b"metres"),
        ("SIM:SENSOR", b"metres"),
        ("SIM:DAMP 1,2,3", b"9 numbers"),
        ("SIM:DAMP 1,2,0,0,1,0,0,0,1", b"symmetric"),
        ("SIM:DAMP 1,0,0,0,-1,0,0,0,1", b"positive semi-definite"),
        ("SIM:SCEN custom", b"damping matrix"),
    ],
)
def test_bad_positions_and_matrices_are_refused_and_change_nothing(command, fragment):
    analyzer = _analyzer(force_at_m=0.3, sensor_at_m=0.6)
    conn = _connect(analyzer)
    before = analyzer.source.specimen
    assert _ask(conn, command) == b""
    error = _ask(conn, "ERR?")
    assert error.startswith(b"3,"), error
    assert fragment in error, error
    assert _ask(conn, "ERR?") == b'0,"No error"\r\n'  # one error, one line
    assert analyzer.source.specimen is before
    assert _ask(conn, "SIM:FORCE?;SIM:SENSOR?") == b"0.3\r\n0.6\r\n"


@pytest.mark.parametrize(
    ("kwargs", "fragment"),
    [
        ({"force_at_m": 0.0}, "force position"),
        ({"sensor_at_m": 0.7000001}, "sensor position"),
        ({"sensor_at_m": float("nan")}, "sensor position"),
        ({"damping": np.eye(2)}, "3 x 3"),
        ({"damping": [[1, 0.5, 0], [0, 1, 0], [0, 0, 1]]}, "symmetric"),
        ({"damping": np.diag([1.0, -1e-3, 1.0])}, "positive semi-definite"),
        ({"damping": np.diag([1.0, math.inf, 1.0])}, "non-finite"),
    ],
)
def test_build_specimen_refuses_what_is_not_a_beam(kwargs, fragment):
    with pytest.raises(ValueError, match=fragment):
        build_specimen("seed", **kwargs)


def test_a_damping_matrix_of_your_own_only_on_the_ritz_beam():
    with pytest.raises(ValueError, match="seed's Ritz beam"):
        build_specimen("realistic", damping=np.eye(3))
    with pytest.raises(ValueError, match="needs a damping matrix"):
        build_specimen("custom")


def test_custom_damping_is_the_truth_the_frf_follows():
    """Non-proportional R on the seed's Ritz N = 3 beam: the analyzer's FRF is the
    direct solve -w^2 c^T (K - w^2 M + j w R)^-1 b, written here from the Ritz model's
    matrices, and R's off-diagonal terms matter (eq (18) gives another FRF)."""
    from analysis.ritz import RitzBeam

    r = np.array([[6.0, -2.0, 1.0], [-2.0, 3.0, 0.5], [1.0, 0.5, 2.0]])
    force, sensor = 0.35, 0.6
    spec = build_specimen("seed", force, sensor, damping=r)
    assert spec.name == "custom"
    assert np.array_equal(spec.damping, r)
    conn = _connect(_analyzer("custom", seed=3, force_at_m=force, sensor_at_m=sensor, damping=r))
    f, frf = _measure_frf(conn, 50.0, 25.0)
    beam = RitzBeam.build(n_functions=3)
    b, c = beam.shapes(force), beam.shapes(sensor)
    w = 2 * np.pi * f
    h = np.array(
        [-(wi**2) * c @ np.linalg.solve(beam.stiffness - wi**2 * beam.mass + 1j * wi * r, b) for wi in w]
    )
    strong = (np.abs(h) > 0.05 * np.abs(h).max()) & (f > 0)
    assert np.max(np.abs(frf - h)[strong] / np.abs(h)[strong]) < 0.01
    h18 = np.array(
        [
            -(wi**2) * c @ np.linalg.solve(beam.stiffness - wi**2 * beam.mass + 1j * wi * np.array(EQ18), b)
            for wi in w
        ]
    )
    assert np.max(np.abs(h18 - h)[strong] / np.abs(h)[strong]) > 0.1


def test_sim_damp_switches_to_custom_in_band_at_the_same_positions():
    analyzer = _analyzer("seed", sensor_at_m=0.5)
    conn = _connect(analyzer)
    _ask(conn, "SIM:DAMP 2, 0.5, 0,  0.5, 1, 0,  0, 0, 1")
    assert _ask(conn, "ERR?") == b'0,"No error"\r\n'
    assert _ask(conn, "SIM:SCEN?") == b"custom\r\n"
    assert _ask(conn, "SIM:DAMP?") == b"2.0,0.5,0.0,0.5,1.0,0.0,0.0,0.0,1.0\r\n"
    assert _ask(conn, "SIM:SENSOR?") == b"0.5\r\n"
    _ask(conn, "SIM:FORCE 0.2")
    spec = analyzer.source.specimen
    assert (spec.name, spec.force_at_m, spec.sensor_at_m) == ("custom", 0.2, 0.5)
    assert np.array_equal(spec.damping, [[2, 0.5, 0], [0.5, 1, 0], [0, 0, 1]])
    _ask(conn, "SIM:SCEN seed")  # back to eq (18), the positions kept
    assert np.array_equal(analyzer.source.specimen.damping, np.array(EQ18))
    assert analyzer.source.specimen.force_at_m == 0.2


def test_parse_damping_matrix_takes_rows_files_and_comments():
    text = "# R, N s/m\n1, 0.5, 0\n0.5; 1 0\n0 0 1  # last row\n"
    assert np.array_equal(parse_damping_matrix(text), [[1, 0.5, 0], [0.5, 1, 0], [0, 0, 1]])
    with pytest.raises(ValueError, match="9 numbers"):
        parse_damping_matrix("1, 2, x")


@pytest.mark.parametrize("scenario", ["seed", "realistic"])
def test_the_tip_given_explicitly_is_the_tip_bit_for_bit(scenario):
    default = build_specimen(scenario)
    explicit = build_specimen(scenario, LENGTH, LENGTH)
    for m1, m2 in zip(
        default.model.state_space(default.damping), explicit.model.state_space(explicit.damping), strict=True
    ):
        assert np.array_equal(m1, m2)
    a1 = _analyzer(scenario, seed=7, noise=True)
    a2 = _analyzer(scenario, seed=7, noise=True, force_at_m=LENGTH, sensor_at_m=LENGTH)
    setup = "FRS 200 HZ;TSRC CH1;TLVL 2 MV;TDLY -10 MS;STRT"
    blocks = []
    for analyzer in (a1, a2):
        analyzer.execute(setup)
        assert analyzer.execute("SMSD")[0].data == b"1\r\n"
        blocks.append(analyzer.execute("TIM2;DDAN")[0].data)
    assert blocks[0] == blocks[1]


def test_noise_windows_and_faults_still_act_at_interior_points():
    # Force and exponential windows, noise on, a truncating fault armed: as at the tip.
    analyzer = _analyzer(noise=True, force_at_m=0.3, sensor_at_m=0.4)
    conn = InProcessConnection(analyzer, faults=["truncate,keep=0.5"])
    _ask(
        conn,
        "FRS 200 HZ;TSRC CH1;TLVL 2 MV;TDLY -20 MS;WIN1 FORC;FWD1 50 MS;WIN2 EXPO;EXD2 0.5 S;"
        "NAVG 3;STBL;STRT",
    )
    assert _ask(conn, "SMSD") == b"1\r\n"
    _ask(conn, "SIM:FAULT CLEAR")
    conn.write(b"COHR;DDAN\n")
    _, coherence = decode_trace(conn.read(timeout_s=5.0))
    assert coherence.min() < 0.999  # the noise is there
    conn2 = InProcessConnection(analyzer, faults=["truncate,keep=0.5"])
    conn2.write(b"FRSP;DDAN\n")
    data = conn2.read(timeout_s=5.0)
    assert len(data) < 4 + 8 * (66 + 2 * 401)  # truncated, as at the tip


# ------------------------------------------- the application's entry points (connect.py)
def test_open_analyzer_and_serve_simulator_take_the_positions():
    import contextlib

    import pyvisa

    from daq.workflows.connect import open_analyzer, serve_simulator, simulator_source

    with open_analyzer("sim:realistic", force_at_m=0.3, sensor_at_m=0.5) as drv:
        assert (drv.query("SIM:FORCE?"), drv.query("SIM:SENSOR?")) == ("0.3", "0.5")
    with open_analyzer("sim") as drv:  # the default is the tip, as before
        assert (drv.query("SIM:FORCE?"), drv.query("SIM:SENSOR?")) == ("0.7", "0.7")
    r = [[3.0, 1.0, -0.5], [1.0, 2.0, 0.4], [-0.5, 0.4, 1.5]]
    with open_analyzer("sim", damping=r, sensor_at_m=0.2) as drv:
        assert drv.query("SIM:SCEN?") == "custom"
        assert drv.query("SIM:DAMP?") == "3.0,1.0,-0.5,1.0,2.0,0.4,-0.5,0.4,1.5"
    for bad, fragment in (
        ({"force_at_m": 0.0}, "force position"),
        ({"sensor_at_m": 0.8}, "sensor position"),
        ({"damping": np.diag([1.0, -1.0, 1.0])}, "positive semi-definite"),
    ):
        with pytest.raises(ValueError, match=fragment):
            open_analyzer("sim", **bad)
    with pytest.raises(ValueError, match="simulator"):
        open_analyzer("TCPIP::127.0.0.1::1::SOCKET", force_at_m=0.3)

    # Served over a real socket, as `daq capture --sim` serves it: positions given there.
    with contextlib.ExitStack() as stack:
        source = simulator_source("realistic", seed=2, hammer="peak_force_n=3")
        resource = serve_simulator(stack, source, 0.0, force_at_m=0.25, sensor_at_m=0.4)
        rm = pyvisa.ResourceManager("@py")
        stack.callback(rm.close)
        inst = rm.open_resource(resource, read_termination="\r\n", write_termination="\n", timeout=5000)
        stack.callback(inst.close)
        assert (inst.query("SIM:FORCE?"), inst.query("SIM:SENSOR?")) == ("0.25", "0.4")
        assert source.hammer.peak_force_n == 3
    with pytest.raises(ValueError, match="on the beam"), contextlib.ExitStack() as stack:
        serve_simulator(stack, simulator_source(), 0.0, sensor_at_m=-1.0)
