"""x axes of SDF traces: linear and logarithmic from the DATA_HDR, or read from XDATA.

xResolution_type 0 (linear): x_n = abscissa_firstX + n * abscissa_deltaX.
xResolution_type 1 (log):    x_n = abscissa_firstX * abscissa_deltaX ** n.
2, 3, 4: values in the XDATA record, xdata_type each, x_per_point per point. Their
order in XDATA is not spelled out by the guide; we read (and write) it as: the one
vector shared by every type-2 data header first (once), then, data header by data
header, one vector for each type-3 header and one per trace for each type-4 header.
A file with a single data header, the common case, is the same under any reading.
"""

from __future__ import annotations

import numpy as np

from daq.formats.sdf import codes
from daq.formats.sdf.model import DataHeader

ARBITRARY = (codes.ARB_PER_FILE, codes.ARB_PER_DATA_HDR, codes.ARB_PER_VECTOR)


def linear_axis(first: float, delta: float, n: int) -> np.ndarray:
    """(n,) float64 first + delta * k. The writer checks an axis against exactly this
    expression before it stores it as linear, so that it reads back bit for bit."""
    with np.errstate(all="ignore"):
        return float(first) + float(delta) * np.arange(n, dtype=np.float64)


def log_axis(first: float, ratio: float, n: int) -> np.ndarray:
    """(n,) float64 first * ratio ** k."""
    with np.errstate(all="ignore"):
        return float(first) * np.power(float(ratio), np.arange(n, dtype=np.float64))


def x_count(dh: DataHeader) -> int:
    """Number of x values one x vector of ``dh`` holds."""
    return dh.n_points * max(1, dh.x_per_point)


def xdata_plan(data: list[DataHeader]) -> list[tuple[int, int, int]]:
    """For every data header (start byte in the XDATA values, n vectors, item size),
    (-1, 0, 0) for headers without XDATA; the last entry is (total bytes, 0, 0).
    ValueError when type-2 headers disagree on their shared vector."""
    plan: list[tuple[int, int, int]] = []
    shared = [dh for dh in data if dh.x_resolution == codes.ARB_PER_FILE]
    position = 0
    shared_at = 0
    if shared:
        first = shared[0]
        for dh in shared[1:]:
            if (x_count(dh), dh.xdata_type) != (x_count(first), first.xdata_type):
                raise ValueError("data headers sharing the file's x vector differ in its length or type")
        position = x_count(first) * codes.NUMBER_TYPES[first.xdata_type][0].itemsize
    for dh in data:
        if dh.x_resolution not in ARBITRARY:
            plan.append((-1, 0, 0))
            continue
        item = codes.NUMBER_TYPES[dh.xdata_type][0].itemsize
        if dh.x_resolution == codes.ARB_PER_FILE:
            plan.append((shared_at, 1, item))
            continue
        n_vectors = 1 if dh.x_resolution == codes.ARB_PER_DATA_HDR else len(dh.vectors)
        plan.append((position, n_vectors, item))
        position += n_vectors * x_count(dh) * item
    plan.append((position, 0, 0))
    return plan


def read_x(dh: DataHeader, payload: memoryview, start: int, n_vectors: int) -> np.ndarray:
    """x values of ``dh`` from the XDATA values (bounds checked by the caller)."""
    dtype = codes.NUMBER_TYPES[dh.xdata_type][0]
    per = x_count(dh)
    with np.errstate(all="ignore"):
        values = np.frombuffer(payload, dtype=dtype, count=n_vectors * per, offset=start).astype(np.float64)
    shape: tuple[int, ...] = (dh.n_points,) if dh.x_per_point <= 1 else (dh.n_points, dh.x_per_point)
    if dh.x_resolution == codes.ARB_PER_VECTOR:
        shape = (n_vectors, *shape)
    return values.reshape(shape)


def computed_x(dh: DataHeader) -> np.ndarray:
    """x of a linear or logarithmic data header."""
    if dh.x_resolution == codes.LOG_RES:
        return log_axis(dh.first_x, dh.delta_x, dh.n_points)
    return linear_axis(dh.first_x, dh.delta_x, dh.n_points)
