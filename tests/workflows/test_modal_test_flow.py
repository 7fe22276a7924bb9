"""A whole multi-point modal test through the workflows (issue 23): seven points along
the `realistic` cantilever, measured by real `daq capture --sim` runs (real simulator
sockets, real HDF5 store) in this process, then analysed, exported and reduced to one
point.

Every number pinned here comes from outside the code: the Euler-Bernoulli cantilever of
the seed's Table 1 (E, rho, A, I, L), its textbook roots beta_n L and mass-normalised
shapes (Blevins, Formulas for Natural Frequency and Mode Shape, table 8-1), and the
modal damping the `realistic` scenario is said to have (1, 0.6, 0.4, 0.3 %).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy.optimize import brentq

from tests.cli_helpers import invoke_daq

# Table 1 of the seed paper: an aluminium cantilever.
E_PA = 7.1e10
RHO_KG_M3 = 2710.0
AREA_M2 = 10.46e-5
INERTIA_M4 = 9.493e-11
LENGTH_M = 0.7
#: Roots of cos(bL) cosh(bL) = -1 as textbooks give them.
BETA_L = (1.8751, 4.6941, 7.8548, 10.9955)
#: Modal damping of the `realistic` scenario, modes 1..4 (its description).
ZETA = (0.010, 0.006, 0.004, 0.003)

POSITIONS_M = (0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7)
POINTS = ",".join(f"p{k}={x}" for k, x in enumerate(POSITIONS_M, start=1))
HITS = 5


def cantilever_hz(beta_l: float) -> float:
    """f_n = (beta_n L)^2 / (2 pi L^2) sqrt(EI / (rho A))."""
    return beta_l**2 / (2 * math.pi * LENGTH_M**2) * math.sqrt(E_PA * INERTIA_M4 / (RHO_KG_M3 * AREA_M2))


def cantilever_shape(beta_l: float, x_m: np.ndarray) -> np.ndarray:
    """Mass-normalised clamped-free shape, 1/sqrt(kg):
    phi(x) = [cosh bx - cos bx - s (sinh bx - sin bx)] / sqrt(rho A L),
    s = (sinh bL - sin bL) / (cosh bL + cos bL); phi(L) = +-2 / sqrt(rho A L).
    The root is refined from its textbook value (the shape at the tip is sensitive to it)."""
    root = brentq(lambda b: math.cos(b) * math.cosh(b) + 1.0, beta_l - 1e-3, beta_l + 1e-3, xtol=1e-14)
    b = root / LENGTH_M
    bx = b * np.asarray(x_m, dtype=float)
    s = (math.sinh(root) - math.sin(root)) / (math.cosh(root) + math.cos(root))
    return (np.cosh(bx) - np.cos(bx) - s * (np.sinh(bx) - np.sin(bx))) / math.sqrt(
        RHO_KG_M3 * AREA_M2 * LENGTH_M
    )


def mac_value(a: np.ndarray, b: np.ndarray) -> float:
    return float(abs(np.vdot(a, b)) ** 2 / (np.vdot(a, a).real * np.vdot(b, b).real))


def _capture(store, *args: str) -> None:
    result = invoke_daq(
        "capture", "--sim", "--scenario", "realistic", "--yes", "--hits", str(HITS), "--time-scale", "0",
        "--store", str(store), *args,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr


@pytest.fixture(scope="module")
def realistic_store(tmp_path_factory):
    """Test b7: roving hammer over p1..p7, accelerometer at the tip, 5 hits a point."""
    store = tmp_path_factory.mktemp("modal-test") / "runs"
    result = invoke_daq("test", "new", "b7", "--points", POINTS, "--store", str(store))
    assert result.returncode == 0, result.stderr
    for seed in range(1, len(POSITIONS_M) + 1):
        _capture(store, "--test", "b7", "--next", "--seed", str(seed))
    return store


@pytest.fixture(scope="module")
def analysis(realistic_store):
    from daq.workflows.test_analysis import analyze_test

    return analyze_test(realistic_store, "b7")


@pytest.fixture(scope="module")
def info(analysis):
    from daq.workflows.test_analysis import test_analysis_json

    # Through JSON as `daq test analyze --json` prints it.
    return json.loads(json.dumps(test_analysis_json(analysis)))


def test_the_sim_moved_the_hammer_to_each_point(realistic_store):
    from daq.store import Store
    from daq.workflows.test import open_test

    test = open_test(realistic_store, "b7")
    store = Store(realistic_store)
    for point, x in zip(test.points, POSITIONS_M, strict=True):
        run = store.open(test.counted_run(point.name))
        assert run.points.test == "b7"
        assert run.points.force_point.position_m == pytest.approx(x)
        assert run.points.response_points[0].position_m == pytest.approx(LENGTH_M)
        assert int(run.hits.accepted.sum()) == HITS


def test_four_frequencies_within_0_2_percent_of_the_cantilever(info):
    expected = [cantilever_hz(b) for b in BETA_L]
    # Sanity of the formula itself: the first mode of this beam is about 5.57 Hz.
    assert expected[0] == pytest.approx(5.569, rel=1e-3)
    measured = [m["frequency_hz"] for m in info["modes"]]
    assert len(measured) == 4, measured
    for f, f_exact in zip(measured, expected, strict=True):
        assert f == pytest.approx(f_exact, rel=2e-3)


def test_damping_within_three_stated_uncertainties(info):
    for mode, zeta in zip(info["modes"], ZETA, strict=True):
        u = mode["damping_u"]
        assert u is not None
        assert u > 0
        assert abs(mode["damping_ratio"] - zeta) <= 3 * u, (mode["damping_ratio"], zeta, u)
        # and the looser bar
        assert mode["damping_ratio"] == pytest.approx(zeta, rel=0.10)


def test_the_tip_is_the_driving_point(info):
    assert info["driving_point"] == "p7"
    assert "unit modal mass" in info["shape_scaling"]


def test_unit_modal_mass_shapes_match_the_textbook_cantilever(info):
    x = np.array(POSITIONS_M)
    tip = 2 / math.sqrt(RHO_KG_M3 * AREA_M2 * LENGTH_M)
    assert tip == pytest.approx(4.49, abs=0.01)
    for mode, beta_l in zip(info["modes"], BETA_L, strict=True):
        exact = cantilever_shape(beta_l, x)
        assert abs(exact[-1]) == pytest.approx(tip, rel=1e-6)
        measured = np.array(mode["shape"]["real"]) + 1j * np.array(mode["shape"]["imag"])
        assert mode["mpc"] > 0.99
        # Turn the measured shape to the textbook one (a shape's sign is arbitrary).
        turn = np.vdot(measured, exact)
        measured = measured * turn / abs(turn)
        assert np.max(np.abs(measured - exact)) <= 0.03 * tip, np.round(measured.real, 3)
        assert mac_value(measured, exact) > 0.999


def test_mac_against_the_exact_beam_and_auto_mac(info):
    x = np.array(POSITIONS_M)
    exact = [cantilever_shape(b, x) for b in BETA_L]
    mac_exact = np.array(info["mac_exact"])
    for k in range(4):
        assert mac_exact[k, k] > 0.99
        assert info["modes"][k]["exact"]["mode"] == k + 1
    auto = np.array(info["auto_mac"])
    assert np.allclose(np.diag(auto), 1.0)
    for i in range(4):
        for j in range(4):
            if i != j:
                # 7 points do not make the shapes orthogonal: the textbook shapes' own
                # cross-MAC at these points is the reference (about 0.06 to 0.09).
                assert auto[i, j] < 0.15
                assert auto[i, j] == pytest.approx(mac_value(exact[i], exact[j]), abs=0.02)


def test_export_reads_back_with_pyuff_and_the_own_reader(analysis, tmp_path):
    import pyuff

    from daq.formats.uff_multipoint import read_multipoint_uff
    from daq.workflows.test_export import export_test

    path = tmp_path / "b7.uff"
    assert export_test(analysis, path) == (7, 4)
    sets = pyuff.UFF(str(path)).read_sets()
    sets = sets if isinstance(sets, list) else [sets]
    kinds = [s["type"] for s in sets]
    assert kinds.count(15) >= 1
    assert kinds.count(82) >= 1
    assert kinds.count(55) == 4, kinds
    functions = [int(s["func_type"]) for s in sets if s["type"] == 58]
    assert functions.count(4) == 7, functions  # the 7 FRFs (and their coherence, type 6)
    nodes = [n for s in sets if s["type"] == 15 for n in np.atleast_1d(s["node_nums"])]
    assert sorted(int(n) for n in nodes) == list(range(1, 8)), nodes  # the driving point is one node
    frfs = [s for s in sets if s["type"] == 58 and int(s["func_type"]) == 4]
    # Roving hammer: every FRF's response is the tip's node, the reference runs over the nodes.
    assert {int(s["rsp_node"]) for s in frfs} == {7}
    assert sorted(int(s["ref_node"]) for s in frfs) == list(range(1, 8))
    keep = np.all(np.isfinite(analysis.data.frf), axis=0)
    for s in frfs:
        k = int(s["ref_node"]) - 1
        np.testing.assert_allclose(s["x"], analysis.data.frequency_hz[keep], rtol=1e-6)
        np.testing.assert_allclose(s["data"], analysis.data.frf[k, keep], rtol=1e-5, atol=1e-9)
    back = read_multipoint_uff(path)
    assert back.frf.shape == (7, int(keep.sum()))
    np.testing.assert_allclose(back.frequency_hz, analysis.data.frequency_hz[keep], rtol=1e-9)
    np.testing.assert_allclose(back.frf, analysis.data.frf[:, keep], rtol=1e-6, atol=1e-12)
    assert [d.node for d in back.responses] == [7] * 7
    assert back.modes is not None
    assert back.modes.n_modes == 4


def test_a_one_point_test_gives_the_single_run_analysis(tmp_path):
    """Test `tip` with its only point at the tip: the same poles as `daq analyze RUN`.

    Not bit for bit: the test analysis scales each FRF by the exponential window's
    gain at the pulse (daq/workflows/point_frf.py), a constant the poles do not depend
    on, but LSCF's rounding does at the 1e-9 level; and the run analysis states its
    uncertainty from the scatter over hits, the test analysis by bootstrap, so only the
    run corrects the damping for the noise bias its hits show (its quality says by how
    much)."""
    from daq.workflows.test_analysis import analyze_test, test_analysis_json

    store = tmp_path / "runs"
    assert invoke_daq("test", "new", "tip", "--points", "tip=0.7", "--store", str(store)).returncode == 0
    _capture(store, "--test", "tip", "--point", "tip", "--seed", "11")
    analysis = analyze_test(store, "tip")
    one = test_analysis_json(analysis)
    (run_id,) = analysis.data.run_ids
    result = invoke_daq("analyze", run_id, "--json", "--store", str(store))
    assert result.returncode == 0, result.stderr
    (single,) = json.loads(result.stdout)
    assert [single["band"]["low_hz"], single["band"]["high_hz"]] == one["band_hz"]
    assert len(single["modes"]) == len(one["modes"]) == 4
    for a, b in zip(one["modes"], single["modes"], strict=True):
        assert a["frequency_hz"] == pytest.approx(b["frequency_hz"], rel=1e-9)
        bias = b["quality"].get("noise_bias_damping", 0.0)
        assert a["damping_ratio"] == pytest.approx(b["damping_ratio"] + bias, rel=1e-8)
        assert abs(bias) <= b["damping_u"]
    assert any("one point" in c for c in one["cautions"])
