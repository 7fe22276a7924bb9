"""What `daq analyze`, `daq test ...` and the reports print, as a new user read it: numbers
written out ("100 %", "51200 Hz", never "1e+02 %" or "5.12e+04 Hz"), "1 accepted hit",
a band whose ends are exponents joined by " to ", `daq analyze --all` with runs apart
and failures as `daq: error:` lines, one caution when a test has fewer points than
modes, no MAC columns on a free structure, a test filled from files going on with
`daq import`, and `daq test report` refusing a test it cannot draw before analysing it.

Every run here comes from a file written by the test (headerless FRF tables, a CSV time
record) through `daq import`, or is sealed into the store as an import would be.
"""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

from daq.cli.commands.analyze import _mode_text
from daq.store import MeasuredFrf, Store, seal
from tests.cli_helpers import assert_one_line_error, invoke_daq
from tests.store.store_helpers import make_run

#: Five modes (Hz, damping ratio) and their shapes at two points.
MODES = ((300.0, 0.02), (700.0, 0.02), (1200.0, 0.02), (1800.0, 0.02), (2500.0, 0.02))
SHAPES = ((1.0, 0.8, 0.6, 0.5, 0.4), (0.5, -0.6, 0.7, -0.3, 0.2))


def frf_table(path, shape, modes=MODES) -> None:
    """A headerless frequency, Re, Im receptance table (m/N) of ``modes``, 0-3000 Hz in
    1 Hz steps, each mode's residue scaled by ``shape``."""
    f = np.arange(0.0, 3001.0)
    w = 2 * np.pi * f
    h = sum(
        a * 1e-2 / ((2 * np.pi * fn) ** 2 - w**2 + 2j * z * 2 * np.pi * fn * w)
        for (fn, z), a in zip(modes, shape, strict=True)
    )
    path.write_text("".join(f"{x:.6e}\t{v.real:.6e}\t{v.imag:.6e}\n" for x, v in zip(f, h, strict=True)))


def hit_csv(path, rate_hz: float = 51200.0, n: int = 4096) -> None:
    """One hammer hit as a time, force, response CSV sampled at ``rate_hz``: a 0.2 ms
    half-sine pulse and the decaying response of modes at 300 and 1100 Hz."""
    t = np.arange(n) / rate_hz
    force = np.where(t < 2e-4, 100 * np.sin(np.pi * t / 2e-4), 0.0)
    response = sum(
        a * np.exp(-z * 2 * np.pi * fn * t) * np.sin(2 * np.pi * fn * t)
        for fn, z, a in ((300.0, 0.02, 5.0), (1100.0, 0.03, 3.0))
    )
    rows = "".join(f"{a:.9g},{b:.9g},{c:.9g}\n" for a, b, c in zip(t, force, response, strict=True))
    path.write_text("time,force,response\n" + rows)


def daq_ok(*args: str):
    result = invoke_daq(*args)
    assert result.returncode == 0, result.stderr
    return result


def imported_id(result) -> str:
    """The run id an `Imported ... as run ID: path` line names."""
    return re.search(r"as run (\S+):", result.stdout).group(1)


def page_text(path) -> str:
    """The report page without its embedded images (whose base64 may hold anything)."""
    return re.sub(r'src="data:image/png;base64,[^"]*"', "", path.read_text())


# ------------------------------------------------------------------- single runs


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """(store, {"table": id, "hit": id, "flat": id}): a one-mode FRF table, one hit at
    51.2 kHz, and a record whose force is constant, which no FRF can be made of."""
    folder = tmp_path_factory.mktemp("wording")
    store = str(folder / "runs")
    frf_table(folder / "Point_1.txt", (1.0,), MODES[:1])
    hit_csv(folder / "hit.csv")
    (folder / "flat.csv").write_text(
        "time,force,response\n" + "".join(f"{k / 1000},1,{np.sin(k)}\n" for k in range(256))
    )
    ids = {
        "table": imported_id(daq_ok("import", str(folder / "Point_1.txt"), "--frf-form", "receptance",
                                    "--store", store)),
        "hit": imported_id(daq_ok("import", str(folder / "hit.csv"), "--store", store)),
        "flat": imported_id(daq_ok("import", str(folder / "flat.csv"), "--store", store)),
    }  # fmt: skip
    return store, ids


def test_analyze_all_keeps_runs_apart_and_says_a_failure_as_an_error(runs):
    store, ids = runs
    result = invoke_daq("analyze", "--all", "--jobs", "1", "--store", store)
    assert result.returncode == 1
    blocks = result.stdout.rstrip("\n").split("\n\n")
    assert [block.split(" ", 2)[1] for block in blocks] == sorted([ids["table"], ids["hit"]])
    assert all(block.startswith("Run ") and "\n\n" not in block for block in blocks)
    errors = result.stderr.splitlines()
    assert len(errors) == 2, result.stderr
    assert errors[0].startswith(f"daq: error: run {ids['flat']}: "), errors[0]
    assert "hold a finite FRF" in errors[0]
    assert errors[1] == "daq: error: 1 of 3 runs could not be analysed"
    assert "daq analyze:" not in result.stderr


def test_json_estimator_agrees_with_its_options(runs):
    store, ids = runs
    (table,) = json.loads(daq_ok("analyze", ids["table"], "--json", "--store", store).stdout)
    assert table["source"] == "measured_frf"
    assert table["estimator"] is None
    assert table["options"]["estimator"] is None
    (hit,) = json.loads(daq_ok("analyze", ids["hit"], "--json", "--store", store).stdout)
    assert hit["source"] == "hits"
    assert hit["estimator"] == hit["options"]["estimator"] == "h1"
    # Both kinds say what was analysed: hits are made into accelerance, nothing converted.
    assert table["form"]["analysed"] == "accelerance"
    assert hit["form"] == {"stored": "time records", "analysed": "accelerance"}
    # The stored result keeps what was asked: it is part of the cache key.
    stored = Store(store).read_result(ids["table"], "analysis")["summary"]
    assert stored["options"]["estimator"] == "h1"


def test_the_report_of_one_hit_writes_its_numbers_out(runs, tmp_path):
    store, ids = runs
    daq_ok("report", ids["hit"], "-o", str(tmp_path / "r"), "--store", store)
    page = page_text(tmp_path / "r" / "index.html")
    assert "<th>sample rate</th><td>51200 Hz</td>" in page
    assert "From 1 accepted hit, h1." in page
    assert "1 accepted hits" not in page
    assert not re.search(r"\de\+\d", page), re.findall(r".{40}\de\+\d.{20}", page)


def test_a_mode_near_all_of_the_synthesis_reads_100_percent():
    mode = {"frequency_hz": 30.0, "damping_ratio": 0.02, "frequency_u_hz": 123.0, "damping_u": 0.0001}
    text = _mode_text({**mode, "quality": {"n_stable_orders": 27, "synthesis_share": 0.996}})
    assert text == (
        "30 Hz ± 120 Hz, damping 2.000 % ± 0.010 %; stable over 27 orders, 100 % of the synthesis"
    )


def test_a_band_whose_ends_are_exponents_is_joined_by_to(tmp_path):
    """A table read as an FRF with a step of 2e-5 Hz (a time column taken for frequency):
    the band's low end keeps its exponent, and a hyphen would run into its minus."""
    f = np.arange(3001) * 2e-5
    w = 2 * np.pi * f
    wn = 2 * np.pi * 0.03
    h = -(w**2) / (wn**2 - w**2 + 2j * 0.02 * wn * w)
    run = make_run(kind="imported", measured=MeasuredFrf(f, h[np.newaxis, :], None, ["H"]))
    seal(run, tmp_path)
    printed = daq_ok("analyze", run.run_id, "--store", str(tmp_path)).stdout
    assert "\n  band 2e-05 to 0.06 Hz: " in printed
    assert not re.search(r"e-\d+-\d", printed)
    daq_ok("report", run.run_id, "-o", str(tmp_path / "r"), "--store", str(tmp_path))
    assert "Band 2e-05 to 0.06 Hz: " in page_text(tmp_path / "r" / "index.html")


# ----------------------------------------------------------------------- tests


@pytest.fixture(scope="module")
def two_points(tmp_path_factory):
    """Test `two` on the seed beam (points p1, p2, p3), p1 and p2 imported from five-mode
    receptance tables: {"store", "folder", "shown": `daq test show two` after each import,
    "printed": `daq test analyze two`, "info": its --json}."""
    folder = tmp_path_factory.mktemp("two-points")
    store = str(folder / "runs")
    daq_ok("test", "new", "two", "--points", "p1=0.7,p2=0.5,p3=0.3", "--store", store)
    shown = []
    for k, shape in enumerate(SHAPES, start=1):
        frf_table(folder / f"P{k}.txt", shape)
        daq_ok("import", str(folder / f"P{k}.txt"), "--test", "two", "--point", f"p{k}",
               "--frf-form", "receptance", "--store", store)  # fmt: skip
        shown.append(daq_ok("test", "show", "two", "--store", store).stdout)
    printed = daq_ok("test", "analyze", "two", "--store", store).stdout
    info = json.loads(daq_ok("test", "analyze", "two", "--json", "--store", store).stdout)
    return {"store": store, "folder": folder, "shown": shown, "printed": printed, "info": info}


def test_fewer_points_than_modes_is_one_caution(two_points, tmp_path):
    printed, info = two_points["printed"], two_points["info"]
    assert (len(info["modes"]), len(info["points"])) == (5, 2)
    auto = np.triu(np.array(info["auto_mac"]), 1)
    alike = int((auto > 0.5).sum())
    assert alike >= 2  # else there was no flood to make one line of
    one = [c for c in info["cautions"] if "cannot tell" in c]
    assert one == [
        f"2 points cannot tell 5 modes apart (auto-MAC above 0.5 for {alike} of the 10 pairs of modes, "
        f"up to {auto.max():.2f}): measure more points than there are modes, or name the modes wanted "
        "with --frequencies"
    ]
    assert not [c for c in info["cautions"] if "look alike" in c]
    assert printed.count("caution: 2 points cannot tell 5 modes apart") == 1
    assert "look alike" not in printed
    # The report holds the same line, once.
    daq_ok("test", "report", "two", "-o", str(tmp_path / "r"), "--store", two_points["store"])
    page = page_text(tmp_path / "r" / "index.html")
    assert page.count("2 points cannot tell 5 modes apart") == 1
    assert "look alike" not in page


def test_the_band_of_a_test_is_its_own_line_about_its_runs(two_points):
    lines = two_points["printed"].splitlines()
    assert lines[0].startswith("Test two: 5 modes from 2 points, synthesis error ")
    assert lines[1] == (
        "  band 1-3000 Hz: nothing in the test's runs limits it (no force spectrum, no coherence)"
    )
    assert "((" not in lines[0] + lines[1]
    assert "in the run " not in two_points["printed"]
    # The JSON says it in the same words (a new user found "nothing in the run limits it").
    assert lines[1].endswith(two_points["info"]["band_reason"])


def test_a_test_filled_from_files_goes_on_with_import(two_points):
    store, folder, shown = two_points["store"], two_points["folder"], two_points["shown"]
    assert shown[0].splitlines()[-1] == "next: daq import FILE --test two --point p2"
    assert shown[1].splitlines()[-1] == "next: daq import FILE --test two --point p3"
    # A test with a captured point too offers both; one with no run yet, the capture.
    daq_ok("test", "new", "mix", "--points", "q1=0.7,q2=0.5,q3=0.3", "--store", store)
    assert daq_ok("test", "show", "mix", "--store", store).stdout.splitlines()[-1] == (
        "next: daq capture --test mix --point q1"
    )
    daq_ok("import", str(folder / "P1.txt"), "--test", "mix", "--point", "q1", "--store", store)
    result = invoke_daq("capture", "--sim", "--yes", "--hits", "2", "--time-scale", "0", "--seed", "3",
                        "--test", "mix", "--point", "q2", "--store", store)  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert daq_ok("test", "show", "mix", "--store", store).stdout.splitlines()[-1] == (
        "next: daq capture --test mix --point q3, or daq import FILE --test mix --point q3"
    )


FRAME = """kind = "free"
[[nodes]]
name = "n1"
x_m = 0.0
y_m = 0.0
z_m = 0.0
direction = "+z"
[[nodes]]
name = "n2"
x_m = 0.3
y_m = 0.0
z_m = 0.0
direction = "+z"
"""


def test_a_free_structure_says_once_that_it_has_no_mac_and_has_no_report(two_points, tmp_path):
    folder = two_points["folder"]
    store = str(tmp_path / "runs")
    (tmp_path / "frame.toml").write_text(FRAME)
    daq_ok("test", "new", "fr", "--article", str(tmp_path / "frame.toml"), "--points", "a=n1,b=n2",
           "--sensor", "a", "--store", store)  # fmt: skip
    # Refused before any analysis: with no point measured the analysis would fail first.
    refused = invoke_daq("test", "report", "fr", "-o", str(tmp_path / "r"), "--store", store)
    assert_one_line_error(
        refused, "test fr: the report draws shapes along a beam", "its article is not a beam"
    )
    assert refused.returncode == 1
    for k, point in enumerate("ab", start=1):
        daq_ok("import", str(folder / f"P{k}.txt"), "--test", "fr", "--point", point, "--store", store)
    printed = daq_ok("test", "analyze", "fr", "--store", store).stdout
    assert printed.count("no MAC") == 1
    assert "\n  no MAC against a beam: the article is a free structure" in printed
    header = next(line for line in printed.splitlines() if line.startswith("  mode  frequency"))
    rows = [line for line in printed.splitlines() if re.match(r"\s+\d+\s+\d+(\.\d+)? ± ", line)]
    assert len(rows) == 5
    assert "MAC" not in header
    assert max(len(line) for line in [header, *rows]) <= 80
    assert not (tmp_path / "r").exists()


def test_a_beam_test_with_one_point_measured_is_refused_before_analysis(tmp_path):
    store = tmp_path / "runs"
    daq_ok("test", "new", "b2", "--points", "p1=0.7,p2=0.5", "--store", str(store))
    frf_table(tmp_path / "P1.txt", SHAPES[0])
    daq_ok("import", str(tmp_path / "P1.txt"), "--test", "b2", "--point", "p1", "--store", str(store))
    result = invoke_daq("test", "report", "b2", "-o", str(tmp_path / "r"), "--store", str(store))
    assert_one_line_error(
        result, "needs a beam article and two measured points or more", "only 1 of its 2 points is measured"
    )


def test_test_report_help_says_it_needs_a_beam():
    text = " ".join(daq_ok("test", "report", "--help").stdout.split())
    assert "for a test on a beam with two measured points or more" in text


def test_zones_of_one_order_say_it_once(tmp_path):
    """Twelve modes on 3001 lines make three zones of the least order: "LSCF order 30 in
    each", not "LSCF orders 30-30"."""
    modes = tuple((150.0 + 230.0 * k, 0.01) for k in range(12))
    frf_table(tmp_path / "twelve.txt", (1.0,) * 12, modes)
    store = str(tmp_path / "store")
    daq_ok("import", str(tmp_path / "twelve.txt"), "--frf-form", "receptance", "--store", store)
    printed = daq_ok("analyze", "latest", "--store", store).stdout
    assert re.search(r"\n  [2-9] frequency zones, LSCF order 30 in each\n", printed), printed
