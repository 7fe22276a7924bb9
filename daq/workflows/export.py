"""Writing a stored run in another program's format: CSV (time records), UFF 58 (time
records and FRFs) or HP SDF (and spectra). One dispatch, which `daq export` and the
service's export endpoint both call.

UFF is what other modal tools read, and they know nothing of our windows: a run with
accepted hits is written with the H1 FRF of those hits recomputed with the run's force
window and NO response window (uff_frfs), so that a tool fitting poles to the file gets
the structure's damping, not the damping plus the exponential window's decay
(docs/import-export.md, "What the UFF's FRF is"). A run without hits is written with
its stored FRFs, their window stated in ID line 4."""

from __future__ import annotations

from pathlib import Path

import numpy as np

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

        write_uff(run, target, uff_frfs(run))
    else:
        raise ValueError(f"unknown export format {fmt!r}: one of {', '.join(SUFFIX)}")


def uff_frfs(run):
    """The FRF ``daq export --format uff`` writes for ``run`` (an ExportFrfs), or None
    when the run has no accepted hit (its stored FRFs are written then).

    H1 over the accepted hits with the run's force window and a uniform response window:
    the exponential window the analyzer puts on the response adds its decay to every
    pole (analysis/damping/windowed_frf.py); without it the FRF holds the structure's
    poles. A response still ringing at the record's end is cut there: at the DFT's lines
    that cut scales each mode's residue and leaves its pole (docs/import-export.md).
    Lines where H1 is not finite (no force there) are left out."""
    from analysis.spectra import frf_estimate, linear_spectra
    from analysis.windows import WindowSpec
    from daq.formats.uff58_export import ExportFrfs
    from daq.store.model import MeasuredFrf
    from daq.workflows.analysis import window_specs

    hits = run.hits
    if hits is None or not hits.accepted.any():
        return None
    force_window, _, _ = window_specs(run)
    accepted = hits.accepted
    spectra = linear_spectra(
        hits.force_n[accepted], hits.response_m_s2[accepted], hits.sample_rate_hz,
        force_window, WindowSpec("uniform"), hits.center_hz,
    )  # fmt: skip
    estimate = frf_estimate(spectra)
    keep = np.isfinite(estimate.h1) & np.isfinite(estimate.coherence)
    if keep.sum() < 2:
        return None
    n = int(accepted.sum())
    label = f"H1 of {n} accepted hit{'s' if n != 1 else ''}, response unwindowed"
    frfs = MeasuredFrf(
        estimate.frequency_hz[keep], estimate.h1[keep][None], estimate.coherence[keep][None], [label]
    )
    words = ["response_window=uniform", f"force_window={force_window.kind}"]
    for key in ("force_width_s", "taper_s", "exp_decay_s"):
        value = getattr(force_window, key)
        if value:
            words.append(f"{key.replace('exp_', 'force_exp_')}={float(value)!r}")
    # Whole words only: ID line 4 is one 80-character record.
    windows = " ".join(words)
    while len(windows) > 80:
        words.pop()
        windows = " ".join(words)
    return ExportFrfs(frfs, windows, "h1")
