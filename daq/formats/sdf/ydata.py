"""Where each trace's y values sit in the YDATA record, and reading them.

A vector (one trace) is n_points * yPerPoint values of ydata_type, each value a
(real, imaginary) pair when yIsComplex. Without scans the vectors follow the VECTOR_HDR
order. With a scan structure, a data header with scanData = 1 (every data header in
revision 1, which has no such field) repeats its vectors n_scans times:

- scan_type DEPTH (0): data header by data header, all scans of its vectors together;
- scan_type SCAN (1): scan by scan, the vectors of every scanned data header; the
  scanned headers must then be consecutive (SDF_comm.h), and headers without scans sit
  before or after that block in their own order.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from daq.formats.sdf import codes
from daq.formats.sdf.model import DataHeader


@dataclass(frozen=True)
class Place:
    """Where one data header's values are: scan s, vector v starts at byte
    start + s * scan_stride + v * vector_bytes of the YDATA values."""

    start: int
    n_scans: int
    scan_stride: int
    vector_bytes: int
    n_vectors: int

    @property
    def scan_bytes(self) -> int:
        return self.vector_bytes * self.n_vectors

    @property
    def end(self) -> int:
        return self.start + (self.n_scans - 1) * self.scan_stride + self.scan_bytes


def vector_bytes(dh: DataHeader) -> int:
    item = codes.NUMBER_TYPES[dh.ydata_type][0].itemsize
    return dh.n_points * dh.y_per_point * item * (2 if dh.y_is_complex else 1)


def plan(data: list[DataHeader], scanned: list[bool], n_scans: int, scan_type: int) -> list[Place]:
    """The Place of every data header. ValueError when scan-ordered data headers are not
    consecutive. Sizes are Python ints: nothing here allocates."""
    places: list[Place | None] = [None] * len(data)
    group = [k for k, s in enumerate(scanned) if s]
    position = 0
    for k, dh in enumerate(data):
        size = vector_bytes(dh)
        n = len(dh.vectors)
        if scanned[k] and scan_type == codes.SCAN:
            if k != group[0]:
                continue
            if group != list(range(group[0], group[-1] + 1)):
                raise ValueError("its scan-ordered (scanData = 1) data headers are not consecutive")
            stride = sum(vector_bytes(data[g]) * len(data[g].vectors) for g in group)
            inner = position
            for g in group:
                g_size = vector_bytes(data[g])
                places[g] = Place(inner, n_scans, stride, g_size, len(data[g].vectors))
                inner += g_size * len(data[g].vectors)
            position += stride * n_scans
        else:
            scans = n_scans if scanned[k] else 1
            places[k] = Place(position, scans, size * n, size, n)
            position += size * n * scans
    return [p for p in places if p is not None]


def read_values(
    dh: DataHeader, place: Place, payload: memoryview, factors: np.ndarray, scaling: np.ndarray | None
) -> np.ndarray:
    """EU values of ``dh``: (n_scans, n_vectors, n_points[, y_per_point]), float64 or
    complex128. factors: (n_vectors,) EU factors; scaling: (n_vectors, 2) integer
    (scale, offset) or None for float data. The caller has checked the bytes exist."""
    dtype = codes.NUMBER_TYPES[dh.ydata_type][0]
    parts = 2 if dh.y_is_complex else 1
    shape = (place.n_scans, place.n_vectors, dh.n_points, dh.y_per_point, parts)
    if place.n_scans == 1 or place.scan_stride == place.scan_bytes:
        count = place.n_scans * place.scan_bytes // dtype.itemsize
        raw = np.frombuffer(payload, dtype=dtype, count=count, offset=place.start)
    else:
        block = np.ndarray(
            (place.n_scans, place.scan_bytes), np.uint8, payload, place.start, (place.scan_stride, 1)
        )
        raw = np.ascontiguousarray(block).view(dtype)
    per_vector = (1, place.n_vectors, 1, 1, 1)
    with np.errstate(all="ignore"):  # a signalling NaN or an overflow stays a value, not a warning
        values = raw.reshape(shape).astype(np.float64)
        if scaling is not None:
            scale, offset = scaling[:, 0], scaling[:, 1]
            if np.any(scale != 1.0):
                values *= scale.reshape(per_vector)
            if np.any(offset != 0.0):
                values += offset.reshape(per_vector)
        if np.any(factors != 1.0):
            values *= factors.reshape(per_vector)
    if parts == 2:
        values = values.view(np.complex128)
    values = values.reshape(shape[:4])
    return values[..., 0] if dh.y_per_point == 1 else values
