"""daq/batch/executor.py: the rules of --jobs and --scheduler, the backend each batch
gets, outcomes (ok, failed, skipped) as the runs end; and --recompute, with --force
its hidden alias for one release."""

from __future__ import annotations

import pickle
from pathlib import Path

import pytest

from analysis.run_analysis import AnalysisOptions
from daq.batch.executor import (
    BackendChoice,
    DaskCluster,
    InProcess,
    ProcessPool,
    choose_backend,
    execute,
)
from daq.batch.tasks import AnalyseTask, FitTask, run_task
from daq.workflows.analysis import NOTHING_TO_IDENTIFY
from daq.workflows.errors import WorkflowError
from daq.workflows.fit import FitOptions
from daq.workflows.outcome import RunOutcome
from tests.cli_helpers import capture_sim, invoke_daq

ADDRESS = "tcp://10.0.0.9:8786"


def test_the_jobs_and_scheduler_rules():
    assert choose_backend(None, None, {}) == BackendChoice(None, None)
    assert choose_backend(None, None, {"DAQ_SCHEDULER": ADDRESS}) == BackendChoice(None, ADDRESS)
    assert choose_backend(None, ADDRESS, {}) == BackendChoice(None, ADDRESS)
    # An explicit --jobs is the local pool, whatever $DAQ_SCHEDULER says.
    assert choose_backend(3, None, {"DAQ_SCHEDULER": ADDRESS}) == BackendChoice(3, None)
    with pytest.raises(WorkflowError, match="--jobs must be at least 1") as info:
        choose_backend(0, None, {})
    assert info.value.exit_code == 2
    with pytest.raises(WorkflowError, match="not both") as info:
        choose_backend(2, ADDRESS, {})
    assert info.value.exit_code == 2
    with pytest.raises(WorkflowError, match="tcp://HOST:PORT") as info:
        choose_backend(None, "nowhere", {})
    assert info.value.exit_code == 2


def test_the_backend_each_batch_gets():
    assert BackendChoice(None, ADDRESS).backend(1) == DaskCluster(ADDRESS)
    assert isinstance(BackendChoice(4).backend(1), InProcess)  # one run: no pool
    assert isinstance(BackendChoice(1).backend(10), InProcess)
    assert BackendChoice(4).backend(10) == ProcessPool(4)
    assert BackendChoice(8).backend(3) == ProcessPool(3)  # never more workers than runs


class Scripted:
    """A backend that ends the tasks in reverse order with the outcomes given."""

    def __init__(self, outcomes: dict[str, RunOutcome]) -> None:
        self.outcomes = outcomes

    def run(self, tasks, on_done) -> None:
        for task in reversed(tasks):
            on_done(task, self.outcomes[task.run_id])


def test_outcomes_as_they_end_skips_and_failures(tmp_path):
    tasks = [AnalyseTask(tmp_path, rid, AnalysisOptions()) for rid in ("a", "b", "c", "d")]
    spectra = f"the run holds spectra but no time records or FRF: {NOTHING_TO_IDENTIFY}"
    outcomes = {
        "a": RunOutcome.done("a", {"run_id": "a"}),
        "b": RunOutcome.failed("b", "damaged"),
        "c": RunOutcome.failed("c", spectra),
        "d": RunOutcome.done("d", {"run_id": "d"}),
    }
    seen = []
    report = execute(tasks, Scripted(outcomes), skip_empty=True, on_outcome=lambda t, o: seen.append(o))
    assert [(o.run_id, o.status) for o in seen] == [
        ("d", "ok"), ("c", "skipped"), ("b", "failed"), ("a", "ok"),
    ]  # fmt: skip
    assert [o.run_id for o in report.failures] == ["b"]
    assert report.summaries(["a", "b", "c", "d"]) == [{"run_id": "a"}, {"run_id": "d"}]  # in the ids' order
    # Without skip_empty (named runs), a run of spectra alone fails.
    report = execute(tasks, Scripted(outcomes))
    assert [o.run_id for o in report.failures] == ["c", "b"]
    assert report.outcomes["c"].error == spectra


def test_tasks_pickle_and_say_their_command(tmp_path):
    for task in (AnalyseTask.default(tmp_path, "x"), FitTask(tmp_path, "x", FitOptions(method="de"), True)):
        assert pickle.loads(pickle.dumps(task)) == task
    assert (AnalyseTask.command, FitTask.command) == ("analyze", "fit")
    assert FitTask.default(tmp_path, "x").options == FitOptions()


def test_a_missing_run_is_a_failed_outcome(tmp_path):
    outcome = run_task(AnalyseTask.default(tmp_path, "20260101T000000.000Z-00000000"))
    assert outcome.status == "failed"
    assert "\n" not in (outcome.error or "")


def test_in_process_runs_the_tasks_in_order(tmp_path):
    store = tmp_path / "store"
    ids = [capture_sim(store, "realistic", seed=s, hits=2) for s in (1, 2)]
    seen = []
    tasks = [AnalyseTask.default(store, i) for i in ids]
    report = execute(tasks, InProcess(), on_outcome=lambda t, o: seen.append(t))
    assert [t.run_id for t in seen] == ids
    assert [s["run_id"] for s in report.summaries(ids)] == ids
    assert not any(s["cached"] for s in report.summaries(ids))
    again = execute([AnalyseTask.default(store, i) for i in ids], ProcessPool(2))
    assert all(s["cached"] for s in again.summaries(ids))


@pytest.mark.parametrize("command", ["analyze", "fit"])
def test_recompute_and_its_old_name(tmp_path: Path, command):
    store = tmp_path / "store"
    run_id = capture_sim(store, "realistic", seed=3, hits=2)
    first = invoke_daq(command, run_id, "--store", str(store))
    assert first.returncode == 0, first.stderr
    again = invoke_daq(command, run_id, "--recompute", "--json", "--store", str(store))
    assert again.returncode == 0
    assert again.stderr == ""
    assert '"cached": false' in again.stdout
    old = invoke_daq(command, run_id, "--force", "--json", "--store", str(store))
    assert old.returncode == 0
    assert old.stderr == "daq: note: --force is now --recompute; --force will go in the next release\n"
    assert '"cached": false' in old.stdout
    helped = invoke_daq(command, "--help")
    assert "--recompute" in helped.stdout
    assert "--force" not in helped.stdout
