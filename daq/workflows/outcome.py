"""What analysing or fitting one stored run came to: :class:`RunOutcome`.

A run either gives its summary (the JSON-able dict `daq analyze|fit --json` prints
and the result file stores), or fails with one line saying why, or is skipped (it
holds nothing to analyse, in a batch over every run). Outcomes are small, frozen and
picklable: they come back from worker processes and Dask workers as they are.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

Status = Literal["ok", "failed", "skipped"]


@dataclass(frozen=True)
class RunOutcome:
    """run_id : the run. status : "ok", "failed" or "skipped". summary : the result's
    summary when ok (with ``cached``), else None. error : the one-line reason when
    failed or skipped, else None."""

    run_id: str
    status: Status
    summary: dict[str, Any] | None = None
    error: str | None = None

    @classmethod
    def done(cls, run_id: str, summary: dict[str, Any]) -> RunOutcome:
        return cls(run_id, "ok", summary=summary)

    @classmethod
    def failed(cls, run_id: str, reason: str) -> RunOutcome:
        return cls(run_id, "failed", error=reason)

    @property
    def ok(self) -> bool:
        return self.status == "ok"


def failure_reason(exc: BaseException) -> str | None:
    """The one-line reason a run failed with ``exc``, as `daq analyze` and `daq fit`
    report it (wherever the run was computed); None when ``exc`` is no failure of the
    run but a bug, which the caller raises."""
    import numpy as np

    from daq.store import StoreError

    if isinstance(exc, (StoreError, ValueError)):
        return " ".join(str(exc).split())
    if isinstance(exc, (np.linalg.LinAlgError, FloatingPointError, ZeroDivisionError)):
        return f"numerical failure ({type(exc).__name__}: {' '.join(str(exc).split())})"
    return None
