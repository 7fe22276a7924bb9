"""Picking traces and lines out of an SDF file for a run: shared by the import of FRFs
and time records (run_import.py) and of spectra (spectra.py)."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from daq.formats.sdf.model import DataHeader, SdfFile


def traces(sdf: SdfFile, wanted: Callable[[DataHeader], bool]) -> list[tuple[DataHeader, list[int]]]:
    """(data header, the scans to use) for the data headers ``wanted(dh)`` accepts; the
    scans are 0..last_scan_index of scanned data."""
    out = []
    for dh in sdf.data:
        if not wanted(dh):
            continue
        n_scans = dh.y.shape[0]
        if n_scans > 1 and sdf.scans is not None and 0 <= sdf.scans.last_scan_index < n_scans:
            n_scans = sdf.scans.last_scan_index + 1
        out.append((dh, list(range(n_scans))))
    return out


def alias_free_lines(sdf: SdfFile, dh: DataHeader) -> slice:
    """The lines of a frequency-domain data header to import: the measurement's alias-
    protected range when it lies inside the data, else 0..last_valid_index."""
    lo, hi = sdf.meas.start_freq_index, sdf.meas.stop_freq_index
    if 0 <= lo <= hi < dh.n_points:
        return slice(lo, hi + 1)
    return slice(0, dh.last_valid_index + 1 if 0 <= dh.last_valid_index < dh.n_points else dh.n_points)


def scaled(values: np.ndarray, factor: float) -> np.ndarray:
    """values * factor without touching values when factor is 1 (complex * 1.0 in numpy
    can flip the sign of a zero part)."""
    if factor == 1.0:
        return values
    with np.errstate(all="ignore"):  # an overflow shows as inf, refused by the caller
        if values.dtype.kind == "c":
            return (values.view(np.float64) * factor).view(np.complex128)
        return values * factor
