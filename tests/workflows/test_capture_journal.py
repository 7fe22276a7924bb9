"""The hit journal (daq/store/journal.py) and the checks made before the first hit.

The journal on its own: a torn last record is dropped, a journal whose owner still
holds its lock is left alone, one whose owner is gone is sealed as an incomplete run
by the next listing, undecided hits are kept rejected. The command line: a note that
is not UTF-8, control characters, and no analyzer configured are refused before the
first hit, with nothing stored.
"""

from __future__ import annotations

import fcntl
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from daq.store import Store, new_run_id, open_run, verify
from daq.store.journal import Journal, is_journal_name, read_journal, recover
from daq.workflows.capture import check_plain_text, table1_sample, utc_now
from tests.cli_helpers import DAQ, ENV, invoke_daq

N = 64


def _meta(run_id: str) -> dict:
    from dataclasses import asdict

    return {
        "run_id": run_id, "kind": "simulated", "start_time": utc_now(), "operator": "kim", "note": "bolt",
        "provenance": {"hits_wanted": 3}, "sample": asdict(table1_sample()),
        "instrument": {"model": "35660A", "identification": "HP35660A", "resource": "x", "transport": "t",
                       "dialect": "35660A", "settings": {"span_hz": 200.0}},
    }  # fmt: skip


def _hit(journal: Journal, index: int, verdict: tuple[bool, str] | None) -> None:
    rng = np.random.default_rng(index)
    info = {
        "overload": [False, False], "peak_force_n": 1.0 + index, "timestamp_utc": utc_now(),
        "checks": {"overload": {"passed": True, "detail": "", "value": None}},
        "sample_rate_hz": 512.0, "start_s": -0.0625, "center_hz": 0.0,
    }  # fmt: skip
    journal.add_hit(index, info, rng.normal(size=N), rng.normal(size=N))
    if verdict is not None:
        journal.add_verdict(index, *verdict)


def _journal_in(store, verdicts) -> tuple[str, Journal]:
    run_id = new_run_id()
    journal = Journal.create(store, run_id, _meta(run_id))
    for i, verdict in enumerate(verdicts):
        _hit(journal, i, verdict)
    return run_id, journal


def test_a_released_journal_is_sealed_as_an_incomplete_run_by_the_next_listing(tmp_path, capsys):
    store = tmp_path / "runs"
    run_id, journal = _journal_in(store, [(True, ""), (False, "double impact"), None])
    assert is_journal_name(journal.path.name)
    assert Store(store).list() == []  # its owner lives: left alone
    assert journal.path.exists()
    journal.release()  # as the owner's death does
    (summary,) = Store(store).list()
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1
    assert f"3 hits (1 accepted) sealed as incomplete run {run_id}" in err[0]
    assert summary.run_id == run_id
    assert not summary.complete
    assert not journal.path.exists()
    assert verify(store / f"{run_id}.h5") == []
    run = open_run(store / f"{run_id}.h5")
    assert run.hits.accepted.tolist() == [True, False, False]
    assert list(run.hits.reject_reason) == ["", "double impact", "interrupted before a decision"]
    assert run.operator == "kim"
    assert run.provenance["recovered_from_journal"] == journal.path.name
    assert np.array_equal(run.hits.force_n[1], np.random.default_rng(1).normal(size=N))
    assert Store(store).list()[0].run_id == run_id  # and only once
    assert capsys.readouterr().err == ""


def test_a_lock_held_by_another_process_keeps_the_journal_alive(tmp_path):
    store = tmp_path / "runs"
    _, journal = _journal_in(store, [(True, "")])
    journal.release()
    holder = subprocess.Popen(
        [sys.executable, "-c", textwrap.dedent(f"""
            import fcntl, os, sys, time
            fd = os.open({str(journal.path)!r}, os.O_RDONLY)
            fcntl.flock(fd, fcntl.LOCK_EX)
            print("held", flush=True)
            time.sleep(30)
        """)],
        stdout=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        assert holder.stdout.readline().strip() == "held"
        assert recover(store) == []
        assert journal.path.exists()
    finally:
        holder.kill()
        holder.wait()
        holder.stdout.close()
    assert len(recover(store)) == 1
    assert not journal.path.exists()


def test_a_torn_last_record_is_dropped_and_the_rest_kept(tmp_path):
    store = tmp_path / "runs"
    _, journal = _journal_in(store, [(True, ""), (True, "")])
    journal.release()
    data = journal.path.read_bytes()
    for cut in (1, 7, 30):  # into the last verdict
        contents = read_journal(data[:-cut])
        assert contents.torn
        assert len(contents.hits) == 2
        assert contents.hits[1]["verdict"] is None  # the verdict record was cut
    contents = read_journal(data[:-200])  # into the second hit
    assert contents.torn
    assert len(contents.hits) == 1
    with open(journal.path, "r+b") as f:
        f.truncate(len(data) - 3)
    (line,) = recover(store)
    assert "2 hits (1 accepted)" in line
    assert "cut short" in line


def test_a_journal_of_a_run_already_sealed_is_simply_removed(tmp_path):
    store = tmp_path / "runs"
    run_id, journal = _journal_in(store, [(True, "")])
    journal.release()
    recover(store)  # sealed ...
    journal2 = Journal.create(store, run_id, _meta(run_id))  # ... and its journal back, as after a kill
    _hit(journal2, 0, (True, ""))
    journal2.release()
    assert recover(store) == []
    assert not journal2.path.exists()
    assert len(Store(store).list()) == 1


def test_a_journal_with_no_hit_is_removed_and_said(tmp_path):
    store = tmp_path / "runs"
    _, journal = _journal_in(store, [])
    journal.release()
    (line,) = recover(store)
    assert "no hits were taken" in line
    assert list(store.iterdir()) == []


def test_no_room_for_the_whole_run_is_refused_before_the_journal_exists(tmp_path):
    from daq.store import StoreError

    with pytest.raises(StoreError, match="free, the run needs about"):
        Journal.create(tmp_path, new_run_id(), _meta(new_run_id()), need_bytes=1 << 62)
    assert list(tmp_path.iterdir()) == []


def test_a_forked_child_does_not_keep_the_journal_locked(tmp_path):
    _, journal = _journal_in(tmp_path, [(True, "")])
    pid = os.fork()
    if pid == 0:  # the child: its copy of the journal's descriptor was closed at fork
        try:
            fd = os.open(journal.path, os.O_RDONLY)
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            os._exit(1)  # the parent holds it: the child must not get it
        except OSError:
            os._exit(0)
    _, status = os.waitpid(pid, 0)
    assert os.waitstatus_to_exitcode(status) == 0
    journal.release()
    assert len(recover(tmp_path)) == 1


@pytest.mark.parametrize(
    ("value", "one_line", "ok"),
    [("kim", True, True), ("bolt\ttorqued\nagain", False, True), ("a\tb", True, False),
     ("bolt \udce9", False, False), ("esc \x1b[31m", False, False), ("nul \x00", False, False),
     ("Zoë ✓", True, True)],
)  # fmt: skip
def test_plain_text_rule(value, one_line, ok):
    if ok:
        assert check_plain_text(value, "--note", one_line) == value
    else:
        with pytest.raises(ValueError, match="--note"):
            check_plain_text(value, "--note", one_line)


def _env(tmp_path) -> dict[str, str]:
    env = {**os.environ, **ENV, "DAQ_LOCK_DIR": str(tmp_path / "locks"), "DAQ_CONFIG": str(tmp_path / "none")}
    for name in ("DAQ_DEBUG", "DAQ_RESOURCE", "DAQ_STORE"):
        env.pop(name, None)
    return env


def test_a_note_that_is_not_utf8_is_refused_before_the_first_hit(tmp_path):
    """The shell's $'bolt \\xe9' reaches Python as a lone surrogate: one line, exit 2, no
    simulator started, nothing stored."""
    store = tmp_path / "runs"
    command = [DAQ, b"capture", b"--sim", b"--yes", b"--hits", b"2", b"--store", os.fsencode(store)]
    result = subprocess.run(
        [*command, b"--note", b"bolt \xe9"], capture_output=True, env=_env(tmp_path), timeout=60
    )
    err = result.stderr.decode("utf-8", "replace").splitlines()
    assert result.returncode == 2, err
    assert err == ["daq: error: --note is not valid UTF-8 text (check the terminal's encoding)"]
    assert result.stdout == b""  # not even the simulator's line
    assert not store.exists() or list(store.iterdir()) == []


def test_control_characters_in_the_operator_are_refused(tmp_path):
    store = tmp_path / "runs"
    result = invoke_daq(
        "capture", "--sim", "--yes", "--store", str(store), "--operator", "kim\x1b[2J",
        env={"DAQ_CONFIG": str(tmp_path / "none")},
    )  # fmt: skip
    assert result.returncode == 2
    assert "--operator: control characters are not allowed" in result.stderr
    assert not store.exists()


def test_import_checks_the_note_before_reading_the_file(tmp_path):
    store = tmp_path / "runs"
    result = invoke_daq(
        "import", str(tmp_path / "does-not-exist.csv"), "--note", "x\x07", "--store", str(store),
        env={"DAQ_CONFIG": str(tmp_path / "none")},
    )  # fmt: skip
    assert result.returncode == 2, result.stderr
    assert "--note: control characters are not allowed" in result.stderr
    assert not store.exists()


def test_capture_without_an_analyzer_configured_is_refused(tmp_path):
    store = tmp_path / "runs"
    result = invoke_daq(
        "capture", "--yes", "--hits", "2", "--store", str(store),
        env={"DAQ_CONFIG": str(tmp_path / "none"), "DAQ_RESOURCE": None},
    )  # fmt: skip
    assert result.returncode == 2
    lines = result.stderr.splitlines()
    assert len(lines) == 1
    assert "no analyzer configured" in lines[0]
    assert "--resource" in lines[0]
    assert "--sim" in lines[0]
    assert result.stdout == ""
    assert not store.exists()
