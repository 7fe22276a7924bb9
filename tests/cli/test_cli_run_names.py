"""Run names from the command line can never reach outside the store: every command
that takes a run id or prefix refuses traversal, separators, wildcards and control
characters with one line, and reads or writes nothing outside the store folder."""

from __future__ import annotations

import pytest

from daq.store import seal
from tests.cli_helpers import assert_one_line_error, invoke_daq
from tests.store.store_helpers import make_run

BAD_NAMES = [
    "../etc/passwd",
    "..",
    "20261123T101503.123Z-3f9c1a2b/../../x",
    "2026*",
    "2026?",
    "a\nb",
    "20261123\x00",
    "~",
    "$HOME",
    "-",
]
COMMANDS = {
    "runs show": ("runs", "show"),
    "runs verify": ("runs", "verify"),
    "export": ("export", "--format", "csv"),
}


@pytest.mark.parametrize("command", list(COMMANDS))
@pytest.mark.parametrize("name", BAD_NAMES)
def test_a_bad_run_name_is_refused_with_one_line(tmp_path, command, name):
    store = tmp_path / "store"
    run = make_run()
    seal(run, store)
    # A decoy beside the store that a traversal would reach.
    (tmp_path / "x.h5").write_bytes((store / f"{run.run_id}.h5").read_bytes())
    before = sorted(p.name for p in tmp_path.rglob("*"))
    args = COMMANDS[command]
    result = (
        invoke_daq(*args, "--store", str(store), "-o", str(tmp_path / "out.csv"), "--", name)
        if (command == "export")
        else invoke_daq(*args, "--store", str(store), "--", name)
    )
    assert_one_line_error(result)
    assert "\n" not in result.stderr.rstrip("\n")
    assert sorted(p.name for p in tmp_path.rglob("*")) == before


def test_a_prefix_that_matches_two_runs_names_both(tmp_path):
    a = make_run(run_id="20261123T101503.123Z-3f9c1a2b")
    b = make_run(run_id="20261123T101503.123Z-3f9c1a2c")
    seal(a, tmp_path)
    seal(b, tmp_path)
    result = invoke_daq("export", "20261123T1015", "-f", "csv", "--store", str(tmp_path))
    assert_one_line_error(result, "matches 2 runs")


def test_latest_names_the_newest_run(tmp_path):
    older = make_run(run_id="20261123T101503.123Z-3f9c1a2b")
    newer = make_run(run_id="20261124T090000.000Z-00000000")
    seal(newer, tmp_path)
    seal(older, tmp_path)  # sealed last, yet not the newest by id (= by start)
    out = tmp_path / "x.csv"
    result = invoke_daq("export", "latest", "-f", "csv", "-o", str(out), "--store", str(tmp_path))
    assert result.returncode == 0, result.stderr
    assert newer.run_id in result.stdout
    assert_one_line_error(
        invoke_daq("export", "latest", "-f", "csv", "--store", str(tmp_path / "empty")), "no runs"
    )
