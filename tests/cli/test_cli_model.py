"""`daq model` as a technician runs it, in-process (daq.cli.app.main); tests/test_cli_basics.py
runs the real console script."""

import json

import numpy as np
import pytest

from tests.cli_helpers import assert_one_line_error, invoke_daq
from tests.reference import (
    EQ18,
    EQ18_DAMPING_RATIOS,
    EQ18_POLE_MAGNITUDE_HZ,
    EXACT_DERIVED_HZ,
    EXACT_TABULATED_HZ,
    RITZ_N3_HZ,
    RITZ_N10_HZ,
    SEED_ANALYTICAL_HZ,
    SEED_EXPERIMENTAL_HZ,
)


def _json(*args):
    result = invoke_daq("model", "--json", *args)
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""
    return json.loads(result.stdout)


def test_table_prints_every_column():
    result = invoke_daq("model")
    assert result.returncode == 0, result.stderr
    out = result.stdout
    for value in (*RITZ_N3_HZ, *EXACT_TABULATED_HZ[:3], *EXACT_DERIVED_HZ, *EQ18_POLE_MAGNITUDE_HZ):
        assert f"{value:.5f}" in out
    for value in (*SEED_ANALYTICAL_HZ, *SEED_EXPERIMENTAL_HZ):
        assert f"{value:.5f}" in out
    for ratio in EQ18_DAMPING_RATIOS:
        assert f"{ratio:.6f}" in out
    assert "0.1-1 %" in out  # the plausibility note on eq (18)


def test_json_table2_and_differences():
    report = _json()
    rows = report["table2"]["rows"]
    assert len(rows) == 3
    for k, row in enumerate(rows):
        assert row["ritz_hz"] == pytest.approx(RITZ_N3_HZ[k], abs=1e-4)
        assert row["exact_tabulated_hz"] == pytest.approx(EXACT_TABULATED_HZ[k], abs=1e-5)
        assert row["exact_derived_hz"] == pytest.approx(EXACT_DERIVED_HZ[k], abs=1e-5)
        assert row["seed_analytical_hz"] == SEED_ANALYTICAL_HZ[k]
        assert row["seed_experimental_hz"] == SEED_EXPERIMENTAL_HZ[k]
        expected_pct = 100 * (RITZ_N3_HZ[k] - SEED_EXPERIMENTAL_HZ[k]) / SEED_EXPERIMENTAL_HZ[k]
        assert row["ritz_diff_pct"] == pytest.approx(expected_pct, abs=2e-3)


def test_json_damping_defaults_to_eq18():
    damping = _json()["damping"]
    assert damping["source"] == "seed eq (18)"
    assert damping["matrix_n_s_per_m"] == [list(r) for r in EQ18]
    assert damping["positive_definite"] is True
    got = [(m["natural_frequency_hz"], m["damping_ratio"]) for m in damping["modes"]]
    np.testing.assert_allclose([g[0] for g in got], EQ18_POLE_MAGNITUDE_HZ, atol=1e-5)
    np.testing.assert_allclose([g[1] for g in got], EQ18_DAMPING_RATIOS, atol=1e-5)


def test_modes_n_selects_the_ritz_size():
    rows = _json("--functions", "10")["table2"]["rows"]
    assert len(rows) == 10
    np.testing.assert_allclose([r["ritz_hz"] for r in rows[:3]], RITZ_N10_HZ, atol=1e-4)
    assert rows[5]["seed_experimental_hz"] is None


def test_section_derived_changes_the_ritz_column():
    rows = _json("--section", "derived")["table2"]["rows"]
    tabulated = _json()["table2"]["rows"]
    assert rows[0]["ritz_hz"] != tabulated[0]["ritz_hz"]
    assert rows[0]["exact_derived_hz"] == tabulated[0]["exact_derived_hz"]


@pytest.mark.parametrize("suffix", [".txt", ".csv", ".json", ".npy"])
def test_damping_matrix_from_file(tmp_path, suffix):
    r = np.diag([0.5, 1.0, 2.0])
    path = tmp_path / f"r{suffix}"
    if suffix == ".npy":
        np.save(path, r)
    elif suffix == ".json":
        path.write_text(json.dumps({"damping_matrix": r.tolist()}))
    else:
        sep = ", " if suffix == ".csv" else "  "
        path.write_text("# diagonal test matrix\n" + "\n".join(sep.join(str(v) for v in row) for row in r))
    damping = _json("--damping", str(path))["damping"]
    assert damping["source"] == str(path)
    assert damping["matrix_n_s_per_m"] == r.tolist()
    assert len(damping["modes"]) == 3
    assert all(0 < m["damping_ratio"] < 0.05 for m in damping["modes"])


def test_damping_matrix_of_another_size_uses_that_ritz_size(tmp_path):
    path = tmp_path / "r2.txt"
    path.write_text("0 0\n0 0\n")
    damping = _json("--damping", str(path))["damping"]
    assert damping["n_functions"] == 2
    # Undamped N=2 Ritz model: the ratios vanish.
    assert all(abs(m["damping_ratio"]) < 1e-9 for m in damping["modes"])


def test_indefinite_matrix_is_flagged(tmp_path):
    path = tmp_path / "neg.txt"
    path.write_text("-1 0 0\n0 1 0\n0 0 1\n")
    result = invoke_daq("model", "--damping", str(path))
    assert result.returncode == 0
    assert "indefinite: the model can gain energy" in result.stdout
    assert "positive real part: unstable" in result.stdout
    damping = _json("--damping", str(path))["damping"]
    assert damping["definiteness"] == "indefinite"
    assert damping["n_unstable_poles"] > 0


@pytest.mark.parametrize("matrix", ["0 0 0\n0 0 0\n0 0 0\n", "1 1 0\n1 1 0\n0 0 1\n"])
def test_semi_definite_matrix_is_not_called_unstable(tmp_path, matrix):
    path = tmp_path / "psd.txt"
    path.write_text(matrix)
    result = invoke_daq("model", "--damping", str(path))
    assert result.returncode == 0
    assert "positive semi-definite" in result.stdout
    assert "unstable" not in result.stdout
    assert "-0.000000" not in result.stdout
    assert _json("--damping", str(path))["damping"]["n_unstable_poles"] == 0


def test_asymmetric_matrix_is_noted(tmp_path):
    path = tmp_path / "asym.txt"
    path.write_text("1 0.5 0\n0 1 0\n0 0 1\n")
    result = invoke_daq("model", "--damping", str(path))
    assert "not symmetric" in result.stdout
    assert _json("--damping", str(path))["damping"]["symmetric"] is False


@pytest.mark.parametrize(
    ("name", "content", "fragment"),
    [
        ("rect.txt", "1 2 3\n4 5 6\n", "must be square, got 2x3"),
        ("ragged.txt", "1 2\n3\n", "different lengths"),
        ("words.txt", "1 2\nx 4\n", "not a row of numbers"),
        ("nan.txt", "1 nan\n0 1\n", "non-finite"),
        ("empty.txt", "# nothing\n", "non-empty list of rows"),
        ("bad.json", "{not json", "invalid JSON"),
        ("obj.json", '{"R": [[1]]}', "damping_matrix"),
        ("bools.json", "[[true, false], [false, true]]", "must be a number"),
        ("strings.json", '[["1.5"]]', "must be a number"),
        ("huge.json", "[[" + "9" * 400 + "]]", "finite number"),
        ("bom.csv", "\ufeff1, 0\n0, 1\n", None),
    ],
)
def test_bad_damping_files_are_one_line_errors(tmp_path, name, content, fragment):
    path = tmp_path / name
    path.write_text(content, encoding="utf-8")
    result = invoke_daq("model", "--damping", str(path))
    if fragment is None:  # accepted
        assert result.returncode == 0, result.stderr
    else:
        assert_one_line_error(result, fragment)


def test_missing_damping_file(tmp_path):
    assert_one_line_error(invoke_daq("model", "--damping", str(tmp_path / "nope.txt")), "no such file")


@pytest.mark.parametrize(
    ("make", "fragment"),
    [
        (lambda p: p.write_bytes(b"\x00\x01garbage"), "not a readable .npy"),
        (lambda p: p.write_bytes(b""), "not a readable .npy"),
        (lambda p: np.save(p, np.eye(2) * (1 + 1j)), "real numbers"),
        (lambda p: np.save(p, np.zeros((0, 0))), "1x1"),
        (lambda p: np.save(p, np.full((2, 2), 1e308)), "cannot be evaluated"),
    ],
)
def test_bad_npy_files(tmp_path, make, fragment):
    path = tmp_path / "r.npy"
    make(path)
    assert_one_line_error(invoke_daq("model", "--damping", str(path)), fragment)


def test_not_a_regular_file(tmp_path):
    assert_one_line_error(invoke_daq("model", "--damping", "/dev/zero"), "not a regular file")
    assert_one_line_error(invoke_daq("model", "--damping", str(tmp_path)), "is a directory")


def test_beam_file_with_new_cross_section_derives_a_and_i(tmp_path):
    # Width and height alone must reach the Ritz model too: exact beam frequencies
    # scale with h (f ~ sqrt(E I / rho A) ~ h), so doubling h doubles them.
    path = tmp_path / "beam.toml"
    path.write_text("width_m = 0.0317\nheight_m = 0.0066\n")
    rows = _json("--beam", str(path))["table2"]["rows"]
    assert rows[0]["exact_tabulated_hz"] == pytest.approx(2 * EXACT_DERIVED_HZ[0], rel=1e-6)
    assert rows[0]["ritz_hz"] == pytest.approx(
        2 * RITZ_N3_HZ[0] * EXACT_DERIVED_HZ[0] / EXACT_TABULATED_HZ[0], rel=1e-4
    )


def test_beam_file(tmp_path):
    path = tmp_path / "beam.toml"
    path.write_text("[beam]\nlength_m = 0.35\n")
    rows = _json("--beam", str(path))["table2"]["rows"]
    # Halving L multiplies every frequency by 4.
    assert rows[0]["exact_tabulated_hz"] == pytest.approx(4 * EXACT_TABULATED_HZ[0], rel=1e-5)


@pytest.mark.parametrize(
    ("content", "fragment"),
    [
        ("lenght_m = 0.3\n", "unknown beam property lenght_m"),
        ("length_m = -1\n", "positive"),
        ("x = [", "TOML"),
        ("length_m = 0.35\n[beam]\nwidth_m = 0.03\n", "keys outside the [beam] table: length_m"),
        ("height_m = 1e200\n", "out of range"),
        ("length_m = 1e-300\n", "out of range"),
        ("length_m = " + "9" * 400 + "\n", "too large"),
    ],
)
def test_bad_beam_file(tmp_path, content, fragment):
    path = tmp_path / "beam.toml"
    path.write_text(content)
    assert_one_line_error(invoke_daq("model", "--beam", str(path)), fragment)


@pytest.mark.parametrize(
    ("args", "fragment"), [(("--modes-n", "0"), "--modes-n"), (("--section", "x"), "--section")]
)
def test_bad_options(args, fragment):
    result = invoke_daq("model", *args)
    assert_one_line_error(result, fragment)
    assert result.returncode == 2
