"""`daq setup`, `daq transducer`, and `daq capture --setup NAME --auto-range N` as a
user runs them: saved versions, JSON, cautions on stderr, one-line errors."""

from __future__ import annotations

import json

import pytest

from daq.store import Store, open_run
from tests.cli_helpers import assert_one_line_error, invoke_daq

SETUP = 'span_hz = 200.0\naverages = 2\n[hammer]\ntransducer = "h-12"\n'


@pytest.fixture
def store(tmp_path):
    folder = tmp_path / "runs"
    added = invoke_daq(
        "transducer", "add", "h-12", "--kind", "hammer", "--model", "PCB 086C03", "--serial", "4711",
        "--sensitivity", "2.31 mV/N", "--calibrated", "2025-01-10", "--due", "2026-01-10",
        "--store", str(folder),
    )  # fmt: skip
    assert added.returncode == 0, added.stderr
    assert "2.31 mV/N = 0.00231 V/N" in added.stdout
    return folder


def _save(store, tmp_path, text=SETUP, *extra):
    path = tmp_path / "beam.toml"
    path.write_text(text)
    return invoke_daq("setup", "save", "beam", "--from", str(path), "--store", str(store), *extra)


def test_transducer_list_json_and_text(store):
    listed = invoke_daq("transducer", "list", "--json", "--store", str(store))
    assert listed.returncode == 0, listed.stderr
    ids = {t["id"]: t for t in json.loads(listed.stdout)["transducers"]}
    assert set(ids) == {"accel-default", "h-12", "hammer-default"}
    assert ids["h-12"]["sensitivity_v_per_eu"] == pytest.approx(2.31e-3)
    text = invoke_daq("transducer", "list", "--store", str(store)).stdout
    assert "OVERDUE" in next(line for line in text.splitlines() if line.startswith("h-12"))


def test_setup_save_list_show_and_versions(store, tmp_path):
    saved = _save(store, tmp_path)
    assert saved.returncode == 0, saved.stderr
    assert saved.stdout == "Saved setup beam version 1\n"
    assert saved.stderr == "caution: hammer transducer h-12 calibration was due 2026-01-10\n"
    assert _save(store, tmp_path, SETUP.replace("200.0", "400.0"), "--expect-version", "1").returncode == 0
    listed = json.loads(invoke_daq("setup", "list", "--json", "--store", str(store)).stdout)
    assert [(s["name"], s["version"]) for s in listed["setups"]] == [("beam", 2), ("default", 0)]
    shown = json.loads(invoke_daq("setup", "show", "beam", "--json", "--store", str(store)).stdout)
    assert shown["settings"]["span_hz"] == 400.0
    assert shown["settings"]["hammer"]["sensitivity_v_per_eu"] == pytest.approx(2.31e-3)
    assert shown["transducers"]["hammer"]["serial"] == "4711"
    assert shown["cautions"] == ["hammer transducer h-12 calibration was due 2026-01-10"]
    old = invoke_daq("setup", "show", "beam", "--version", "1", "--store", str(store))
    assert "span_hz = 200.0" in old.stdout
    history = json.loads(invoke_daq("setup", "history", "beam", "--json", "--store", str(store)).stdout)
    assert [v["version"] for v in history["versions"]] == [1, 2]


@pytest.mark.parametrize(
    ("args", "fragments"),
    [
        (("setup", "show", "nope"), ("no setup 'nope'", "known: default")),
        (("transducer", "add", "h-1", "--kind", "hammer", "--sensitivity", "2.25"), ("--sensitivity",)),
        (
            ("transducer", "add", "h-1", "--kind", "hammer", "--sensitivity", "2.25 mV/N", "--due", "soon"),
            ("transducer h-1: due: not a date YYYY-MM-DD",),
        ),
        (
            ("transducer", "add", "h-1", "--kind", "hammer", "--sensitivity", "10 mV/g"),
            ("sensitivity_unit: mV/g is not a unit of a hammer",),
        ),
    ],
)
def test_bad_input_is_one_line(store, args, fragments):
    assert_one_line_error(invoke_daq(*args, "--store", str(store)), *fragments)


def test_setup_save_refuses_bad_files_and_old_versions_in_one_line(store, tmp_path):
    assert_one_line_error(_save(store, tmp_path, "span_hz = -5.0\n"), "span_hz: must be a positive number")
    assert_one_line_error(
        _save(store, tmp_path, '[hammer]\ntransducer = "zz"\n'), "hammer.transducer: no transducer 'zz'"
    )
    assert _save(store, tmp_path).returncode == 0
    assert_one_line_error(_save(store, tmp_path, SETUP, "--expect-version", "0"), "setup beam exists already")


def test_capture_with_a_named_setup_and_auto_range_on_the_simulator(store, tmp_path):
    assert _save(store, tmp_path).returncode == 0
    result = invoke_daq(
        "capture", "--sim", "--yes", "--seed", "3", "--scenario", "realistic", "--time-scale", "0",
        "--setup", "beam", "--auto-range", "2", "--store", str(store),
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert "caution: hammer transducer h-12 calibration was due 2026-01-10" in result.stderr
    assert result.stdout.count("(not kept)") == 2
    assert "Auto-range: hammer range" in result.stdout
    (summary,) = Store(store).list()
    run = open_run(store / summary.file_name)
    assert run.provenance["setup"] == {"name": "beam", "version": 1}
    assert run.provenance["cautions"] == ["hammer transducer h-12 calibration was due 2026-01-10"]
    assert run.instrument.settings["hammer"]["transducer"]["id"] == "h-12"
    assert not run.hits.overload.any()
    assert run.hits.accepted.sum() == 2
    ranged = run.provenance["auto_range"]
    assert ranged["practice_hits"] == 2
    assert len(ranged["peaks_force_n"]) == 2
    held = run.instrument.settings  # as the analyzer holds them: rounded
    assert ranged["hammer_range_v"] == pytest.approx(held["hammer"]["range_v"], rel=1e-6)
    assert ranged["accelerometer_range_v"] == pytest.approx(held["accelerometer"]["range_v"], rel=1e-6)
    assert ranged["trigger_level_eu"] == pytest.approx(held["trigger_level_eu"], rel=1e-3)
    assert ranged["setup"] == {"hammer_range_v": 0.02, "accelerometer_range_v": 1.0, "trigger_level_eu": 1.0}
    shown = invoke_daq("runs", "show", summary.run_id, "--store", str(store))
    line = next(line for line in shown.stdout.splitlines() if line.startswith("auto-range"))
    assert line.startswith("auto-range    2 practice hits: hammer range ")
    assert "; the setup's own values were hammer range 0.02 V, accelerometer range 1 V, trigger 1 N" in line


def test_an_impossible_setup_is_refused_before_any_hit(store, tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text("trigger_level_eu = 1000.0\n")
    result = invoke_daq(
        "capture", "--sim", "--yes", "--time-scale", "0", "--setup", str(path), "--store", str(store)
    )
    assert_one_line_error(result, "trigger_level_eu: 1000 N is above the hammer's range (8.89 N")
    assert Store(store).list() == []
    lines = tmp_path / "lines.toml"
    lines.write_text("lines = 800\n")
    result = invoke_daq(
        "capture", "--sim", "--yes", "--time-scale", "0", "--setup", str(lines), "--store", str(store)
    )
    assert_one_line_error(result, "lines: the 35660A offers 400 lines only")


def test_capture_with_an_unknown_setup_name_is_one_line(store):
    result = invoke_daq("capture", "--sim", "--yes", "--setup", "nope", "--store", str(store))
    assert_one_line_error(result, "no setup 'nope'")


def test_serve_refuses_a_setup_that_does_not_resolve_before_it_starts(store, tmp_path):
    env = {"DAQ_TOKEN_FILE": str(tmp_path / "token")}
    result = invoke_daq("serve", "--sim", "--port", "0", "--setup", "nope", "--store", str(store), env=env)
    assert_one_line_error(result, "no setup 'nope'")
    bad = tmp_path / "bad.toml"
    bad.write_text("span_hz = -1.0\n")
    result = invoke_daq("serve", "--sim", "--port", "0", "--setup", str(bad), "--store", str(store), env=env)
    assert_one_line_error(result, "span_hz: must be a positive number")


def test_serve_passes_the_setup_to_the_service(store, tmp_path, monkeypatch):
    from daq.cli.commands import serve as serve_command

    seen = {}
    monkeypatch.setattr(serve_command, "run_service", lambda *a, **k: seen.update(k))
    assert _save(store, tmp_path).returncode == 0
    env = {"DAQ_TOKEN_FILE": str(tmp_path / "token")}
    result = invoke_daq("serve", "--sim", "--port", "0", "--setup", "beam", "--store", str(store), env=env)
    assert result.returncode == 0, result.stderr
    assert seen["setup"] == "beam"
    assert "caution: hammer transducer h-12" in result.stderr
    (tmp_path / "mine.toml").write_text("span_hz = 400.0\n")
    monkeypatch.chdir(tmp_path)
    invoke_daq("serve", "--sim", "--port", "0", "--setup", "mine.toml", "--store", str(store), env=env)
    assert seen["setup"] == str(tmp_path / "mine.toml")


def test_transducer_add_says_it_replaced_and_refuses_a_kind_change_a_setup_depends_on(store, tmp_path):
    add = ("transducer", "add", "a-7", "--kind", "accelerometer", "--sensitivity", "10 mV/g")
    first = invoke_daq(*add, "--store", str(store))
    assert first.stdout.startswith("Transducer a-7: accelerometer, 10 mV/g = 0.00101972 V/(m/s^2)"), first
    again = invoke_daq(*add, "--store", str(store))
    assert again.stdout.startswith("Transducer a-7 replaced: accelerometer"), again
    assert _save(store, tmp_path, '[accelerometer]\ntransducer = "a-7"\n').returncode == 0
    hammer = ("transducer", "add", "a-7", "--kind", "hammer", "--sensitivity", "2.25 mV/N")
    assert_one_line_error(
        invoke_daq(*hammer, "--store", str(store)), "kind: a-7 is the accelerometer of setup beam;"
    )
    assert invoke_daq("setup", "show", "beam", "--store", str(store)).returncode == 0


@pytest.mark.parametrize(
    ("text", "fragment"),
    [
        ("trigger_level_eu = 1000.0\n", "trigger_level_eu: 1000 N is above the hammer's range (8.89 N"),
        ("lines = 800\n", "lines: the 35660A offers 400 lines only, not 800"),
    ],
)
def test_auto_range_checks_the_setup_before_the_practice_hits(store, tmp_path, text, fragment):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    result = invoke_daq(
        "capture", "--sim", "--yes", "--time-scale", "0", "--setup", str(path), "--auto-range", "2",
        "--store", str(store),
    )  # fmt: skip
    assert_one_line_error(result, fragment)
    assert "Auto-range" not in result.stdout
    assert "practice hit" not in result.stdout


def test_setup_save_and_capture_word_a_bad_file_alike(store, tmp_path):
    for text, words in (
        ("span_hz = -5.0\n", "span_hz: must be a positive number, got -5.0"),
        (
            '[hammer]\nwindow = "BOX"\n',
            "hammer.window: 'BOX' is not a window; one of UNIF, HANN, FLAT, FORC, EXPO",
        ),
    ):
        path = tmp_path / "bad.toml"
        path.write_text(text)
        saved = invoke_daq("setup", "save", "beam", "--from", str(path), "--store", str(store))
        captured = invoke_daq("capture", "--sim", "--yes", "--setup", str(path), "--store", str(store))
        for result in (saved, captured):
            assert_one_line_error(result, f"{path}: {words}")


@pytest.mark.parametrize(
    ("text", "fragment"),
    [
        ("lines = 3\n", "lines: no analyzer offers 3 lines; one of 100, 200, 400, 800, 1600"),
        ("trigger_level_eu = 1000.0\n", "trigger_level_eu: 1000 N is above the hammer's range (8.89 N"),
        ("trigger_level_eu = -1000.0\n", "trigger_level_eu: -1000 N is beyond the hammer's range"),
    ],
)
def test_setup_save_refuses_a_setup_no_analyzer_could_run(store, tmp_path, text, fragment):
    assert_one_line_error(_save(store, tmp_path, text), fragment)


def test_transducer_list_keeps_its_columns_without_a_model(store):
    added = invoke_daq(
        "transducer", "add", "h-x", "--kind", "hammer", "--sensitivity", "2 mV/N", "--store", str(store)
    )
    assert added.returncode == 0, added.stderr
    lines = invoke_daq("transducer", "list", "--store", str(store)).stdout.splitlines()
    due_column = {line.index("  (due ") if "(due " in line else line.index("  (no due") for line in lines}
    assert len(due_column) == 1, lines  # the due dates line up
    assert next(line for line in lines if line.startswith("h-x")).split()[4] == "-"


def test_setup_save_blames_a_bad_name_not_the_file(store, tmp_path):
    path = tmp_path / "f.toml"
    path.write_text("span_hz = 200.0\n")
    result = invoke_daq("setup", "save", "bad name", "--from", str(path), "--store", str(store))
    assert_one_line_error(result, "setup name 'bad name': not a plain name")
    assert str(path) not in result.stderr


def test_expect_version_0_does_not_save_over_the_built_in_default(store, tmp_path):
    path = tmp_path / "f.toml"
    path.write_text("span_hz = 400.0\n")
    args = ("setup", "save", "default", "--from", str(path), "--store", str(store))
    assert_one_line_error(
        invoke_daq(*args, "--expect-version", "0"), "setup default exists (version 0, built in)"
    )
    assert invoke_daq(*args).returncode == 0  # without it, the built-in is replaced
    assert_one_line_error(
        invoke_daq(*args, "--expect-version", "0"), "setup default exists already (version 1)"
    )
