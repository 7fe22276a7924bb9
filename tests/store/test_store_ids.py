"""Run ids: sortable by time, unique across processes, and strictly validated."""

from __future__ import annotations

import subprocess
import sys

import pytest

from daq.store import StoreError, new_run_id, validate_run_id
from daq.store.ids import RUN_ID_LENGTH, run_id_time, validate_run_id_prefix

CHILD = "from daq.store import new_run_id\nprint('\\n'.join(new_run_id() for _ in range(1000)))"


def test_ids_from_four_processes_are_unique_and_each_sorted():
    children = [
        subprocess.Popen([sys.executable, "-c", CHILD], stdout=subprocess.PIPE, text=True) for _ in range(4)
    ]
    per_process = []
    for child in children:
        out, _ = child.communicate(timeout=60)
        assert child.returncode == 0
        per_process.append(out.split())
    everything = [i for ids in per_process for i in ids]
    assert len(everything) == 4000
    assert len(set(everything)) == 4000
    for ids in per_process:
        assert ids == sorted(ids)  # one process's ids increase strictly...
        assert len(set(ids)) == len(ids)
        for run_id in ids:
            assert validate_run_id(run_id) == run_id


def test_ids_sort_by_creation_time():
    times = [1_700_000_000.0, 1_700_000_000.001, 1_700_000_059.999, 1_800_000_000.5, 4_102_444_799.0]
    ids = [new_run_id(now_s=t) for t in (times[3], times[0], times[4], times[2], times[1])]
    assert [run_id_time(i).timestamp() for i in sorted(ids)] == pytest.approx(times, abs=1e-6)
    assert sorted(ids)[0].startswith("20231114T221320.000Z-")  # 1.7e9 s after the epoch, by hand
    assert sorted(ids)[1].startswith("20231114T221320.001Z-")
    assert run_id_time(sorted(ids)[-1]).isoformat() == "2099-12-31T23:59:59+00:00"


def test_example_id_is_valid():
    assert validate_run_id("20261123T101503.123Z-3f9c1a2b") == "20261123T101503.123Z-3f9c1a2b"
    assert len("20261123T101503.123Z-3f9c1a2b") == RUN_ID_LENGTH


@pytest.mark.parametrize(
    "bad",
    [
        "../x",
        "a/b",
        "..",
        ".",
        "",
        "20261123T101503.123Z-3f9c1a2b/../../etc/passwd",
        "../20261123T101503.123Z-3f9c1a2",
        "20261123T101503.123Z-3f9c1a2b\x00",
        "20261123T101503.123Z-3f9c1a2b\n",
        " 20261123T101503.123Z-3f9c1a2b",
        "20261123T101503.123Z-3F9C1A2B",  # upper-case hex: a second spelling of an id
        "２0261123T101503.123Z-3f9c1a2b",  # full-width digit
        "٢0261123T101503.123Z-3f9c1a2b",  # Arabic-Indic digit, which \\d would accept
        "20261123T101503.123Z-3f9c1a2bé",
        "20261123T101503.123Z-3f9c1a2b" * 10,
        "x" * 10_000,
        "20261123T101503.123Z-3f9c1a2",
        "20261123T101503Z-3f9c1a2b",
    ],
)
def test_validator_refuses(bad):
    with pytest.raises(StoreError) as caught:
        validate_run_id(bad)
    message = str(caught.value)
    assert "\n" not in message
    assert len(message) < 200


@pytest.mark.parametrize("bad", [None, 20261123, b"20261123T101503.123Z-3f9c1a2b"])
def test_validator_refuses_non_text(bad):
    with pytest.raises(StoreError, match="text"):
        validate_run_id(bad)


@pytest.mark.parametrize("bad", ["", "../", "a/b", "2026*", "x" * 30, "2026 11"])
def test_prefix_validator_refuses(bad):
    with pytest.raises(StoreError):
        validate_run_id_prefix(bad)


def test_prefix_validator_accepts_prefixes():
    for n in (1, 8, 15, 20, 29):
        assert validate_run_id_prefix("20261123T101503.123Z-3f9c1a2b"[:n])
