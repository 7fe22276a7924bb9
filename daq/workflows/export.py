"""Writing a stored run in another program's format: CSV (time records), UFF 58 (time
records and FRFs) or HP SDF (and spectra). One dispatch, which `daq export` and the
service's export endpoint both call."""

from __future__ import annotations

from pathlib import Path

from daq.workflows.errors import WorkflowError

#: The formats a run can be written as, with the file suffix of each.
SUFFIX = {"csv": ".csv", "uff": ".uff", "sdf": ".sdf"}


def write_run(run, target: Path, fmt: str) -> None:
    """Write ``run`` (daq.store.Run) to ``target`` as ``fmt`` (a key of SUFFIX).

    WorkflowError (one line, the format's own words) when the run cannot be written in
    that format; OSError when the file cannot be written."""
    from daq.formats import FormatError

    try:
        _write(run, target, fmt)
    except FormatError as exc:
        raise WorkflowError(str(exc)) from None


def _write(run, target: Path, fmt: str) -> None:
    if fmt == "csv":
        from daq.formats.csv_text import write_csv

        write_csv(run, target)
    elif fmt == "sdf":
        from daq.formats.sdf.run_export import write_sdf_run

        write_sdf_run(run, target)
    elif fmt == "uff":
        from daq.formats.uff58_export import write_uff

        write_uff(run, target)
    else:
        raise ValueError(f"unknown export format {fmt!r}: one of {', '.join(SUFFIX)}")
