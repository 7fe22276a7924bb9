"""The work the executor runs: one typed task per stored run, and its outcome.

A task says everything a worker needs and nothing more (the store folder, the run,
the options, whether to recompute an up-to-date result), is frozen and picklable,
and runs anywhere: in this process, in a worker process (:func:`run_task`), or on a
Dask cluster (daq/batch/dask_backend.py, which reads the run here and sends its
bytes). Its outcome is a :class:`daq.workflows.outcome.RunOutcome`.

Light at import: the options' classes are only named for the type checker.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, ClassVar

from daq.workflows.outcome import RunOutcome

if TYPE_CHECKING:
    from analysis.run_analysis import AnalysisOptions
    from daq.workflows.fit import FitOptions


@dataclass(frozen=True)
class AnalyseTask:
    """Analyse run ``run_id`` of the store at ``store_dir`` with ``options``;
    ``recompute``: even if an up-to-date result is stored (`--recompute`)."""

    store_dir: Path
    run_id: str
    options: AnalysisOptions
    recompute: bool = False

    #: The command's name, as its lines on stderr say it (``daq analyze: run ...``).
    command: ClassVar[str] = "analyze"

    @classmethod
    def default(cls, store_dir: Path, run_id: str) -> AnalyseTask:
        """The analysis with the default options (the service's, a fit's)."""
        from analysis.run_analysis import AnalysisOptions

        return cls(store_dir, run_id, AnalysisOptions())

    def run(self) -> RunOutcome:
        from daq.workflows.analysis import analyze_one

        return analyze_one(self.store_dir, self.run_id, self.options, self.recompute)


@dataclass(frozen=True)
class FitTask:
    """Fit the damping matrix of run ``run_id`` of the store at ``store_dir`` with
    ``options`` (analysing the run first if its analysis is missing or stale);
    ``recompute``: even if an up-to-date fit is stored."""

    store_dir: Path
    run_id: str
    options: FitOptions
    recompute: bool = False

    command: ClassVar[str] = "fit"

    @classmethod
    def default(cls, store_dir: Path, run_id: str) -> FitTask:
        """The default fit (least squares, R = L L^T: the service's)."""
        from daq.workflows.fit import FitOptions

        return cls(store_dir, run_id, FitOptions())

    def run(self) -> RunOutcome:
        from daq.workflows.fit import fit_one

        return fit_one(self.store_dir, self.run_id, self.options, self.recompute)


Task = AnalyseTask | FitTask


def run_task(task: Task) -> RunOutcome:
    """``task.run()``: the function a worker process is handed (module level, so that
    it pickles by name)."""
    return task.run()


__all__ = ["AnalyseTask", "FitTask", "RunOutcome", "Task", "run_task"]
