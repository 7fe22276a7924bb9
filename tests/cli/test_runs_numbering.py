"""One numbering (issue 24): people read hits from 1 (`daq runs show`, the report, the
UFF export's titles); the JSON and the files keep their 0-based index and say so. A hit
accepted although one of its checks failed is marked in `runs show` and its JSON."""

from __future__ import annotations

import json
from dataclasses import replace

import pytest
import pyuff

from daq.cli import app as cli
from daq.cli.commands import runs as runs_command
from daq.store import Store, seal
from daq.workflows.run_views import accepted_against_checks
from tests.cli.run_files import make_run
from tests.cli_helpers import invoke_daq

runs_command.register(cli.app)

RUN_ID = "20261123T101503.123Z-0000aaaa"


def _check(passed: bool, detail: str) -> dict:
    return {"passed": passed, "detail": detail, "value": None}


def _checks(double: bool = True, rolloff: bool = True) -> dict:
    return {
        "overload": _check(True, "no overload"),
        "double impact": _check(double, "single pulse" if double else "second pulse at 34 % of the peak"),
        "force roll-off": _check(rolloff, "falls 3 dB" if rolloff else "falls 14 dB"),
        "too weak": _check(True, "peak 40 N"),
    }


@pytest.fixture
def env(tmp_path) -> dict[str, str | None]:
    return {
        "DAQ_STORE": None,
        "DAQ_RESOURCE": None,
        "DAQ_CONFIG": str(tmp_path / "absent-config.toml"),
        "XDG_DATA_HOME": str(tmp_path / "xdg-data"),
    }


@pytest.fixture
def store(tmp_path):
    """Four hits: 1 clean, 2 accepted against the double-impact check, 3 accepted against
    two checks, 4 rejected (its double-impact check failed)."""
    run = make_run(RUN_ID, n_hits=4)
    checks = [_checks(), _checks(double=False), _checks(double=False, rolloff=False), _checks(double=False)]
    hits = replace(run.hits, checks=checks)
    run = replace(
        run,
        hits=hits,
        provenance={
            "setup": {"name": "beam-A", "version": 3},
            "cautions": ["caution: hammer transducer h-12 calibration was due 2026-01-01"],
        },
    )
    folder = tmp_path / "store"
    seal(run, folder)
    return folder


def test_accepted_against_checks_is_derived_from_the_stored_verdicts(store):
    run = Store(store).open(RUN_ID)
    assert accepted_against_checks(run) == [1, 2]  # 0-based indices: hits 2 and 3
    # Check dicts without a "passed" flag (older runs' flags) are not checks that failed.
    assert accepted_against_checks(make_run(RUN_ID, n_hits=3)) == []


def test_runs_show_json_keeps_the_index_declares_its_base_and_adds_the_number(store, env):
    result = invoke_daq("runs", "show", RUN_ID, "--store", str(store), "--json", env=env)
    assert result.returncode == 0, result.stderr
    shown = json.loads(result.stdout)
    assert shown["hit_index_base"] == 0
    hits = shown["hits"]["hits"]
    assert [(h["index"], h["number"]) for h in hits] == [(0, 1), (1, 2), (2, 3), (3, 4)]
    assert [h["accepted_against_checks"] for h in hits] == [False, True, True, False]
    assert hits[2]["failed_checks"] == ["double impact", "force roll-off"]
    assert shown["hits"]["n_accepted_against_checks"] == 2


def test_runs_show_text_counts_from_1_and_names_the_overridden_checks(store, env):
    result = invoke_daq("runs", "show", RUN_ID, "--store", str(store), env=env)
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    hit_lines = [line.strip() for line in lines if line.strip().startswith("hit ")]
    assert [line.split()[1] for line in hit_lines] == ["1", "2", "3", "4"]
    assert hit_lines[0].endswith("  accepted")
    assert hit_lines[1].endswith("accepted although the double impact check failed")
    assert hit_lines[2].endswith("accepted although the double impact and force roll-off checks failed")
    assert "rejected: double hit" in hit_lines[3]
    assert "numbered from 1" in result.stdout
    cautions = [line[14:] for line in lines if line.startswith("caution")]
    assert cautions == [
        "hammer transducer h-12 calibration was due 2026-01-01",
        "hit 2: accepted although the double impact check failed",
        "hit 3: accepted although the double impact and force roll-off checks failed",
    ]
    assert "setup         beam-A version 3" in lines


def test_the_uff_export_titles_count_hits_from_1_and_say_so(store, env, tmp_path):
    out = tmp_path / "run.uff"
    result = invoke_daq("export", RUN_ID, "--format", "uff", "-o", str(out), "--store", str(store), env=env)
    assert result.returncode == 0, result.stderr
    records = [r for r in pyuff.UFF(str(out)).read_sets() if r["func_type"] == 1]
    titles = [r["id1"] for r in records]
    assert titles[:2] == [f"{RUN_ID} hit 1 force", f"{RUN_ID} hit 1 response"]
    assert titles[-2].startswith(f"{RUN_ID} hit 4 force rejected: double hit")
    assert all(r["id3"].endswith("hit numbers count from 1") for r in records)
    # The file reads back with every verdict (the reader keys on the order, not the number).
    back = tmp_path / "back"
    result = invoke_daq("import", str(out), "--store", str(back), env=env)
    assert result.returncode == 0, result.stderr
    (summary,) = Store(back).list()
    assert (summary.n_hits, summary.n_accepted) == (4, 3)
