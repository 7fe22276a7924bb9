"""`daq runs list/show/verify` and `daq config` against real run files in tmp_path."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from daq.cli import app as cli
from daq.cli.commands import config as config_command
from daq.cli.commands import runs as runs_command
from daq.store import seal
from tests.cli.run_files import NOTE, make_run
from tests.cli_helpers import assert_one_line_error, invoke_daq

# Until daq/cli/app.py registers them itself; register() does nothing the second time.
runs_command.register(cli.app)
config_command.register(cli.app)

IDS = [
    "20261123T101503.123Z-0000aaaa",
    "20261123T101503.456Z-1111bbbb",
    "20261124T090000.000Z-2222cccc",
]


@pytest.fixture
def env(tmp_path) -> dict[str, str | None]:
    """No store or config from the machine running the tests."""
    return {
        "DAQ_STORE": None,
        "DAQ_RESOURCE": None,
        "DAQ_CONFIG": str(tmp_path / "absent-config.toml"),
        "XDG_DATA_HOME": str(tmp_path / "xdg-data"),
    }


@pytest.fixture
def store(tmp_path) -> Path:
    folder = tmp_path / "store"
    # Sealed out of order: the listing must sort by id, not by creation.
    for run_id, n_hits in ((IDS[2], 2), (IDS[0], 3), (IDS[1], 5)):
        seal(make_run(run_id, n_hits, complete=run_id != IDS[1]), folder)
    return folder


def runs(*args: str, env: dict[str, str | None]):
    return invoke_daq("runs", *args, env=env)


def damage(path: Path, keep_fraction: float | None = None, flip_at: float | None = None) -> None:
    data = bytearray(path.read_bytes())
    if keep_fraction is not None:
        data = data[: int(len(data) * keep_fraction)]
    if flip_at is not None:
        i = int(len(data) * flip_at)
        data[i] ^= 0xFF
    path.chmod(0o644)
    path.write_bytes(bytes(data))


# ----------------------------------------------------------------------- list
def test_list_json_fields_sorted_by_id(store, env):
    result = runs("list", "--store", str(store), "--json", env=env)
    assert result.returncode == 0, result.stderr
    listed = json.loads(result.stdout)  # stdout is nothing but the JSON
    assert [r["run_id"] for r in listed] == IDS
    first, second, third = listed
    assert first["start_time"] == "2026-11-23T10:15:03.123Z"
    assert first["kind"] == "simulated"
    assert (first["complete"], second["complete"], third["complete"]) == (True, False, True)
    assert [(r["n_hits"], r["n_accepted"]) for r in listed] == [(3, 2), (5, 4), (2, 1)]
    assert first["operator"] == "Ada Lovelace"
    assert first["note"] == NOTE
    assert all(r["error"] is None for r in listed)
    lines = result.stderr.splitlines()
    assert lines[0] == f"store {store.absolute()} (from --store option)"


def test_list_table(store, env):
    result = runs("list", "--store", str(store), env=env)
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert "run id" in lines[0]
    assert "note" in lines[0]
    rows = [line for line in lines if line.startswith("2026")]
    assert [row.split()[0] for row in rows] == IDS
    assert "incomplete" in rows[1]
    assert "incomplete" not in rows[0]
    assert rows[0].split()[1:7] == ["2026-11-23", "10:15:03", "simulated", "complete", "3", "2"]
    assert "Ada Lovelace" in rows[0]
    assert "bolt re-torqued" in rows[0]
    assert result.stderr.startswith(f"store {store.absolute()} (from --store option)\n")


@pytest.mark.parametrize("as_json", [False, True])
def test_empty_and_missing_store(tmp_path, env, as_json):
    empty = tmp_path / "empty"
    empty.mkdir()
    for folder in (empty, tmp_path / "never-made"):
        result = runs("list", "--store", str(folder), *(["--json"] if as_json else []), env=env)
        assert result.returncode == 0, result.stderr
        if as_json:
            assert json.loads(result.stdout) == []
        else:
            assert result.stdout == ""
        lines = result.stderr.splitlines()
        assert lines[0] == f"store {folder} (from --store option)"
        assert "no runs" in lines[1]
    assert not (tmp_path / "never-made").exists()  # listing creates nothing


def test_damaged_run_is_listed_and_verify_fails(store, env):
    damage(store / f"{IDS[1]}.h5", flip_at=0.0)  # the HDF5 signature
    listed = runs("list", "--store", str(store), "--json", env=env)
    assert listed.returncode == 0, listed.stderr
    rows = {r["run_id"]: r for r in json.loads(listed.stdout)}
    assert list(rows) == IDS
    assert rows[IDS[1]]["error"]
    assert "damaged" in rows[IDS[1]]["error"]
    assert rows[IDS[0]]["error"] is None
    table = runs("list", "--store", str(store), env=env)
    assert table.returncode == 0
    assert f"DAMAGED {IDS[1]}.h5: damaged" in table.stdout

    checked = runs("verify", "--store", str(store), env=env)
    assert_one_line_error(checked, "1 of 3", IDS[1])
    assert checked.returncode == 1
    assert f"OK       {IDS[0]}" in checked.stdout
    assert f"PROBLEM  {IDS[1]}: cannot open as HDF5" in checked.stdout
    assert f"OK       {IDS[2]}" in checked.stdout

    as_json = runs("verify", "--store", str(store), "--json", env=env)
    assert as_json.returncode == 1
    report = {r["run_id"]: r for r in json.loads(as_json.stdout)}
    assert report[IDS[0]] == {
        "run_id": IDS[0],
        "file": str(store.absolute() / f"{IDS[0]}.h5"),
        "ok": True,
        "problems": [],
    }
    assert report[IDS[1]]["ok"] is False
    assert report[IDS[1]]["problems"]


def test_truncated_run(store, env):
    damage(store / f"{IDS[2]}.h5", keep_fraction=0.6)
    listed = json.loads(runs("list", "--store", str(store), "--json", env=env).stdout)
    assert listed[2]["run_id"] == IDS[2]
    assert listed[2]["error"]
    checked = runs("verify", IDS[2], "--store", str(store), env=env)
    assert_one_line_error(checked, "1 of 1", IDS[2])
    assert "truncated" in checked.stdout
    # The sound runs alone still pass.
    good = runs("verify", IDS[0], IDS[1], "--store", str(store), env=env)
    assert good.returncode == 0, good.stderr
    shown = runs("show", IDS[2], "--store", str(store), env=env)
    assert_one_line_error(shown, IDS[2])


def test_verify_good_store(store, env):
    result = runs("verify", "--store", str(store), env=env)
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""
    assert [line.split()[:2] for line in result.stdout.splitlines()[1:4]] == [["OK", i] for i in IDS]
    assert "3 run(s) checked: 3 OK, 0 with problems" in result.stdout


def test_verify_names_leftover_temporaries_and_repair_removes_them(store, env):
    import os
    import time

    old = store / f".{IDS[0]}.h5.abc123.tmp"  # what a write killed before its rename leaves
    fresh = store / f".{IDS[1]}.h5.def456.tmp"  # a write maybe still under way: left alone
    old.write_bytes(b"half a run")
    fresh.write_bytes(b"being written")
    two_hours_ago = time.time() - 7200
    os.utime(old, (two_hours_ago, two_hours_ago))
    result = runs("verify", "--store", str(store), env=env)
    assert result.returncode == 0, result.stderr
    assert f"leftover {old.name}" in result.stderr
    assert fresh.name not in result.stderr
    assert old.exists()
    result = runs("verify", "--repair", "--store", str(store), env=env)
    assert result.returncode == 0, result.stderr
    assert f"removed {old.name}" in result.stderr
    assert not old.exists()
    assert fresh.exists()


def test_verify_empty_store_is_fine(tmp_path, env):
    result = runs("verify", "--store", str(tmp_path / "none"), "--json", env=env)
    assert result.returncode == 0
    assert json.loads(result.stdout) == []
    assert "nothing to verify" in result.stderr


# ----------------------------------------------------------------------- show
def test_show_by_unique_prefix(store, env):
    result = runs("show", "20261124", "--store", str(store), "--json", env=env)
    assert result.returncode == 0, result.stderr
    shown = json.loads(result.stdout)
    assert shown["run_id"] == IDS[2]
    assert shown["kind"] == "simulated"
    assert shown["complete"] is True
    assert shown["start_time"] == "2026-11-23T10:15:03.123Z"
    assert shown["end_time"] == "2026-11-23T10:17:45.000Z"
    assert shown["operator"] == "Ada Lovelace"
    assert shown["note"] == NOTE
    assert shown["software"].startswith("cantilever-daq ")
    assert shown["provenance"] == {"scenario": "seed", "seed": 7}
    assert shown["instrument"]["model"] == "HP 35660A"
    assert shown["sample"]["length_m"] == 0.3
    assert (shown["n_hits"], shown["n_accepted"]) == (2, 1)
    hits = shown["hits"]
    assert (hits["n_rejected"], hits["n_samples"], hits["sample_rate_hz"]) == (1, 64, 2560.0)
    assert [(h["accepted"], h["reject_reason"]) for h in hits["hits"]] == [(True, ""), (False, "double hit")]
    assert hits["hits"][0]["overload_response"] is True
    assert shown["analyzer"]["n_lines"] == 33
    assert shown["analyzer"]["labels"] == ["H21"]
    assert shown["measured_frf"] is None


def test_show_text(store, env):
    result = runs("show", IDS[1], "--store", str(store), env=env)
    assert result.returncode == 0, result.stderr
    text = result.stdout
    assert f"run           {IDS[1]}" in text
    assert "incomplete" in text
    assert NOTE in text
    assert "5: 4 accepted, 1 rejected" in text
    assert "rejected: double hit" in text
    assert "analyzer      1 FRF(s) x 33 points" in text


@pytest.mark.parametrize(
    ("prefix", "fragments"),
    [
        ("20261123T", ["matches 2 runs", IDS[0], IDS[1]]),
        ("2025", ["no run matches '2025'"]),
        ("not/an/id", ["invalid run id or prefix"]),
    ],
)
def test_show_ambiguous_unknown_or_bad_prefix(store, env, prefix, fragments):
    result = runs("show", prefix, "--store", str(store), env=env)
    assert_one_line_error(result, *fragments)
    assert result.returncode == 1
    assert result.stdout == ""


# ---------------------------------------------------------- store location
def test_store_precedence(tmp_path, store, env):
    other = tmp_path / "other"
    seal(make_run("20261201T000000.000Z-3333dddd"), other)
    config = tmp_path / "config.toml"
    config.write_text('store = "other"\n', encoding="utf-8")  # relative to the file

    def listed(*args: str, **changes: str | None):
        result = runs("list", "--json", *args, env={**env, **changes})
        assert result.returncode == 0, result.stderr
        return [r["run_id"] for r in json.loads(result.stdout)], result.stderr.splitlines()[0]

    ids, line = listed(DAQ_CONFIG=str(config))
    assert ids == ["20261201T000000.000Z-3333dddd"]
    assert line == f"store {other} (from config file {config})"
    ids, line = listed(DAQ_CONFIG=str(config), DAQ_STORE=str(store))
    assert ids == IDS
    assert line == f"store {store} (from $DAQ_STORE)"
    ids, line = listed("--store", str(other), DAQ_STORE=str(store))
    assert ids == ["20261201T000000.000Z-3333dddd"]
    assert line == f"store {other} (from --store option)"
    ids, line = listed()
    assert ids == []
    assert (
        line
        == f"store {tmp_path / 'xdg-data' / 'cantilever-daq' / 'runs'} (from default per-user data folder)"
    )


# --------------------------------------------------------------------- config
def test_config_with_a_file(tmp_path, env):
    config = tmp_path / "config.toml"
    config.write_text('store = "runs"\nresource = "GPIB0::11::INSTR"\n', encoding="utf-8")
    result = invoke_daq("config", "--json", env={**env, "DAQ_CONFIG": str(config)})
    assert result.returncode == 0, result.stderr
    report = json.loads(result.stdout)
    assert report["config_file"] == {
        "path": str(config),
        "source": "$DAQ_CONFIG",
        "exists": True,
        "store": str(tmp_path / "runs"),
        "resource": "GPIB0::11::INSTR",
    }
    assert report["store"]["path"] == str(tmp_path / "runs")
    assert report["store"]["source"] == f"config file {config}"
    assert report["resource"] == {"value": "GPIB0::11::INSTR", "source": f"config file {config}"}

    text = invoke_daq(
        "config",
        env={**env, "DAQ_CONFIG": str(config), "DAQ_STORE": str(tmp_path / "s"), "DAQ_RESOURCE": "sim"},
    )
    assert text.returncode == 0, text.stderr
    assert f"config file  {config} (from $DAQ_CONFIG; exists)" in text.stdout
    assert "  resource   GPIB0::11::INSTR" in text.stdout
    assert f"store        {tmp_path / 's'} (from $DAQ_STORE" in text.stdout
    assert "resource     sim (from $DAQ_RESOURCE)" in text.stdout


def test_config_without_a_file(tmp_path, env):
    result = invoke_daq("config", "--json", env=env)
    assert result.returncode == 0, result.stderr
    report = json.loads(result.stdout)
    assert report["config_file"]["exists"] is False
    assert report["store"]["source"] == "default per-user data folder"
    assert report["resource"]["value"] is None


def test_malformed_config_is_one_line(tmp_path, env):
    config = tmp_path / "config.toml"
    config.write_text('store = "unterminated\n', encoding="utf-8")
    bad = {**env, "DAQ_CONFIG": str(config)}
    for args in (("config",), ("runs", "list"), ("runs", "verify")):
        result = invoke_daq(*args, env=bad)
        assert_one_line_error(result, str(config), "not valid TOML")
        assert result.returncode == 1
    # --store does not need the config file.
    fine = invoke_daq("runs", "list", "--store", str(tmp_path / "s"), env=bad)
    assert fine.returncode == 0, fine.stderr


def test_help_texts(env):
    for words in (("runs",), ("runs", "list"), ("runs", "show"), ("runs", "verify"), ("config",)):
        result = invoke_daq(*words, "--help", env=env)
        assert result.returncode == 0, result.stderr
        summary = result.stdout.splitlines()[2].strip()
        assert summary.endswith(".")
        assert len(summary) <= 60, summary
        assert "<bool>" not in result.stdout
    assert "--store <dir>" in invoke_daq("runs", "list", "--help", env=env).stdout
    bare = invoke_daq("runs", env=env)
    assert bare.returncode == 0
    assert "verify" in bare.stdout
