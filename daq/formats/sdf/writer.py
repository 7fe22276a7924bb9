"""Write an :class:`SdfFile` as SDF bytes (revision 3 by default; 1 and 2 for old readers).

The records go in the order of SDF_comm.h's "General SDF File": FILE_HDR, MEAS_HDR,
DATA_HDRs, VECTOR_HDRs, CHANNEL_HDRs, SCAN_STRUCT, SCAN_BIG and SCAN_VARs, COMMENTs,
XDATA (only when a data header needs it), YDATA; counts and offsets are derived here.
Values are turned back from engineering units into stored units with the same factors
the reader applies (daq/formats/sdf/convert.py); with factors of 1 and float64 storage,
what is read back is bit for bit what was written.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from daq.formats.errors import FormatError
from daq.formats.imported import atomic_temp, commit_temp, discard_temp, one_line, show_path
from daq.formats.sdf import axes, codes, ydata
from daq.formats.sdf.convert import integer_scaling, vector_factor
from daq.formats.sdf.layout import layout
from daq.formats.sdf.model import COUNT, Comment, DataHeader, Scans, SdfFile
from daq.formats.sdf.reader import SIGNATURE
from daq.formats.sdf.source import HEAD_SIZE

_INT_RANGE = {codes.INT16: (-(2**15), 2**15 - 1), codes.INT32: (-(2**31), 2**31 - 1)}


def write_sdf(sdf: SdfFile, path: Path | str, *, revision: int = 3, window: str = "narrow") -> None:
    """Write ``sdf`` to ``path`` atomically (temporary file, fsync, rename); FormatError
    (one line) if it cannot be written as it is."""
    path = Path(path)
    try:
        data = encode_sdf(sdf, revision=revision, window=window)
    except ValueError as exc:
        raise FormatError(f"cannot write {show_path(path)}: {one_line(str(exc))}") from None
    temp = atomic_temp(path)
    try:
        try:
            temp.write_bytes(data)
        except OSError as exc:
            raise FormatError(f"cannot write {show_path(path)}: {exc.strerror or exc}") from None
        commit_temp(temp, path)
    except BaseException:
        discard_temp(temp)
        raise


def encode_sdf(sdf: SdfFile, *, revision: int = 3, window: str = "narrow") -> bytes:
    """The bytes of ``sdf`` as an SDF file of ``revision``. ValueError (one line) for
    what the format or the revision cannot hold."""
    if revision not in (1, 2, 3):
        raise ValueError(f"SDF revision {revision} does not exist (1, 2 or 3)")
    if not sdf.data:
        raise ValueError("an SDF file needs at least one data header")
    if revision < 3 and sdf.comments:
        raise ValueError(f"revision {revision} has no COMMENT records; write revision 3")
    scans = sdf.scans
    if revision < 3 and scans is not None and (scans.n_scans > 2**15 - 1 or len(scans.variables) > 1):
        raise ValueError(f"revision {revision} holds at most 32767 scans and one scan variable")
    for k, dh in enumerate(sdf.data):
        _check(dh, k, sdf, revision)
    head = {t: layout(t, revision) for t in (codes.FILE_HDR, codes.MEAS_HDR, codes.DATA_HDR)}
    head.update({t: layout(t, revision) for t in (codes.VECTOR_HDR, codes.CHANNEL_HDR, codes.SCAN_STRUCT)})

    scan_parts = _scan_records(scans, revision, len(sdf.data))
    comment_parts = [_comment(c) for c in sdf.comments]
    x_plan = axes.xdata_plan(sdf.data)
    x_block = _xdata(sdf.data, x_plan) if any(p[0] >= 0 for p in x_plan[:-1]) else None
    y_block = _ydata(sdf, window, revision)

    vectors = [v for dh in sdf.data for v in dh.vectors]
    index: dict[str, int] = {}
    position = len(SIGNATURE) + head[codes.FILE_HDR].size + head[codes.MEAS_HDR].size
    parts: list[bytes] = []

    def area(key: str, records: list[bytes]) -> None:
        nonlocal position
        index[f"num_of_{key}_record"] = len(records)
        index[f"offset_of_{key}_record"] = position if records else -1
        parts.extend(records)
        position += sum(len(r) for r in records)

    first = 0
    data_records = []
    for dh in sdf.data:
        data_records.append(_record(head[codes.DATA_HDR], dh, first_VECTOR_recordNum=first))
        first += len(dh.vectors)
    area("DATA_HDR", data_records)
    area("VECTOR", [_record(head[codes.VECTOR_HDR], v) for v in vectors])
    area("CHANNEL", [_record(head[codes.CHANNEL_HDR], c) for c in sdf.channels])
    area("UNIQUE", [])
    area("SCAN_STRUCT", scan_parts[:1])
    if revision >= 3:
        area("SCAN_BIG", scan_parts[1:])
        area("COMMENT", comment_parts)
        index["offset_of_next_SDF_FILE"] = -1
    area("XDATA", [x_block] if x_block is not None else [])
    index["offset_of_YDATA_record"] = position
    parts.append(y_block)
    file_record = _record(head[codes.FILE_HDR], sdf.file, **index, revisionNum=revision)
    meas_record = _record(head[codes.MEAS_HDR], sdf.meas)
    return b"".join([SIGNATURE, file_record, meas_record, *parts])


def _record(table, obj, **extra) -> bytes:
    """One header record from a model object; extra: {SDF name: value} the model lacks."""
    values = {"recordType": table.record_type, "recordSize": table.size, "unique_record": -1, **extra}
    for name, attr, _code, _revs in table.fields:
        if name not in values and attr:
            values[name] = getattr(obj, attr.lstrip("<"))
    return table.pack(values)


def _check(dh: DataHeader, k: int, sdf: SdfFile, revision: int) -> None:
    what = f"data header #{k} ({dh.title!r})"
    n_vectors = len(dh.vectors)
    if n_vectors == 0 or dh.total_rows * dh.total_cols != n_vectors:
        raise ValueError(f"{what}: {n_vectors} vectors for {dh.total_rows} x {dh.total_cols} traces")
    if dh.ydata_type not in codes.NUMBER_TYPES or (
        dh.x_resolution in axes.ARBITRARY and dh.xdata_type not in codes.NUMBER_TYPES
    ):
        raise ValueError(f"{what}: data types must be 1 to 4 (int16, int32, float32, float64)")
    if dh.n_points < 1 or (revision < 3 and dh.n_points > 2**15 - 1):
        raise ValueError(f"{what}: {dh.n_points} points do not fit revision {revision}")
    scaled = any(integer_scaling(v, sdf.channels) != (1.0, 0.0) for v in dh.vectors)
    if revision == 1 and dh.ydata_type in _INT_RANGE and scaled:
        raise ValueError(f"{what}: revision 1 has no channelScale or channelOffset for integer data")
    n_scans = sdf.scans.n_scans if sdf.scans is not None and (dh.scan_data or revision == 1) else 1
    shape = (n_scans, n_vectors, dh.n_points) + ((dh.y_per_point,) if dh.y_per_point > 1 else ())
    if dh.y.shape != shape or dh.y.dtype != (np.complex128 if dh.y_is_complex else np.float64):
        kind = "complex128" if dh.y_is_complex else "float64"
        raise ValueError(f"{what}: y must be {kind} of shape {shape}, got {dh.y.dtype} {dh.y.shape}")
    if dh.x_resolution in axes.ARBITRARY:
        per = (dh.n_points,) if dh.x_per_point <= 1 else (dh.n_points, dh.x_per_point)
        want = (n_vectors, *per) if dh.x_resolution == codes.ARB_PER_VECTOR else per
        if np.shape(dh.x) != want:
            raise ValueError(f"{what}: x must have shape {want}, got {np.shape(dh.x)}")


def _numbers(values: np.ndarray, number_type: int, what: str) -> np.ndarray:
    """``values`` (float64) as the big-endian array of ``number_type``; ValueError when
    an integer type cannot hold them."""
    dtype = codes.NUMBER_TYPES[number_type][0]
    if number_type in _INT_RANGE:
        lo, hi = _INT_RANGE[number_type]
        with np.errstate(all="ignore"):
            rounded = np.rint(values)
        if not np.all(np.isfinite(rounded)) or np.any(rounded < lo) or np.any(rounded > hi):
            raise ValueError(f"{what}: values outside the range of {codes.NUMBER_TYPES[number_type][1]}")
        return rounded.astype(dtype)
    with np.errstate(all="ignore"):
        return values.astype(dtype)


def _ydata(sdf: SdfFile, window: str, revision: int) -> bytes:
    scans = sdf.scans
    n_scans = scans.n_scans if scans is not None else 1
    # Revision 1 has no scanData field: with a scan structure, every data header is scanned.
    scanned = [scans is not None and (dh.scan_data != 0 or revision == 1) for dh in sdf.data]
    places = ydata.plan(sdf.data, scanned, n_scans, scans.scan_type if scans else codes.DEPTH)
    total = max(p.end for p in places)
    block = np.zeros(total, dtype=np.uint8)
    for k, (dh, place) in enumerate(zip(sdf.data, places, strict=True)):
        stored = _stored(dh, sdf, window, f"data header #{k}")
        raw = np.frombuffer(stored.tobytes(), dtype=np.uint8).reshape(place.n_scans, place.scan_bytes)
        shape = (place.n_scans, place.scan_bytes)
        target = np.ndarray(shape, np.uint8, block, place.start, (place.scan_stride, 1))
        target[...] = raw
    return _block(codes.YDATA, block.tobytes())


def _stored(dh: DataHeader, sdf: SdfFile, window: str, what: str) -> np.ndarray:
    """The stored numbers of ``dh``: EU values divided by each trace's factor, and for
    integer types less the channel offset over its scale, rounded."""
    values = np.ascontiguousarray(dh.y)
    if dh.y_is_complex:
        values = values.view(np.float64).reshape(*values.shape, 2)
    else:
        values = values.reshape(*values.shape, 1)
    if dh.y_per_point == 1:
        values = values.reshape((*values.shape[:3], 1, values.shape[-1]))
    per_vector = (1, len(dh.vectors), 1, 1, 1)
    factors = np.array([vector_factor(dh, v, sdf.channels, window) for v in dh.vectors])
    with np.errstate(all="ignore"):
        if np.any(factors != 1.0):
            values = values / factors.reshape(per_vector)
        if dh.ydata_type in _INT_RANGE:
            scaling = np.array([integer_scaling(v, sdf.channels) for v in dh.vectors]).reshape(-1, 2)
            values = (values - scaling[:, 1].reshape(per_vector)) / scaling[:, 0].reshape(per_vector)
    return _numbers(values, dh.ydata_type, what)


def _xdata(data: list[DataHeader], plan: list[tuple[int, int, int]]) -> bytes:
    shared = [np.asarray(dh.x, dtype=np.float64) for dh in data if dh.x_resolution == codes.ARB_PER_FILE]
    if any(not np.array_equal(x, shared[0]) for x in shared[1:]):
        raise ValueError("data headers with the file's one x vector (xResolution_type 2) have different x")
    block = np.zeros(plan[-1][0], dtype=np.uint8)
    for dh, (start, _n, _item) in zip(data, plan, strict=False):
        if start < 0:
            continue
        numbers = _numbers(np.asarray(dh.x, dtype=np.float64).ravel(), dh.xdata_type, f"x of {dh.title!r}")
        block[start : start + numbers.nbytes] = np.frombuffer(numbers.tobytes(), dtype=np.uint8)
    return _block(codes.XDATA, block.tobytes())


def _block(record_type: int, payload: bytes) -> bytes:
    size = HEAD_SIZE + len(payload)
    if size > 2**31 - 1:
        raise ValueError("more than 2 GiB of values: too large for an SDF record")
    return int(record_type).to_bytes(2, "big") + size.to_bytes(4, "big") + payload


def _scan_records(scans: Scans | None, revision: int, n_data: int) -> list[bytes]:
    """[SCAN_STRUCT, SCAN_BIG, SCAN_VAR...] (revision 3), [SCAN_STRUCT] before, [] without scans."""
    if scans is None:
        return []
    if scans.n_scans < 1 or scans.scan_type not in codes.SCAN_TYPES:
        raise ValueError(f"{scans.n_scans} scans of scan_type {scans.scan_type}")
    variables = scans.variables or []
    first = variables[0] if variables else None
    values = first.values if first is not None else np.arange(1, scans.n_scans + 1, dtype=np.float64)
    number_type = first.number_type if first is not None else codes.INT32
    unit = first.unit if first is not None else COUNT
    for var in variables:
        if np.shape(var.values) != (scans.n_scans,):
            count = np.size(var.values)
            raise ValueError(f"scan variable {var.name!r}: {count} values for {scans.n_scans} scans")
    head = layout(codes.SCAN_STRUCT, revision)
    numbers = _numbers(np.asarray(values, dtype=np.float64), number_type, "scan values").tobytes()
    record = head.pack({
        "recordType": codes.SCAN_STRUCT, "recordSize": head.size + len(numbers),
        "num_of_scan": min(scans.n_scans, 2**15 - 1),
        "last_scan_index": min(scans.last_scan_index, 2**15 - 1),
        "scan_type": scans.scan_type, "scanVar_type": number_type, "scanUnit": unit,
    })  # fmt: skip
    out = [record + numbers]
    if revision < 3:
        return out
    big = layout(codes.SCAN_BIG, 3)
    out.append(big.pack({
        "recordType": codes.SCAN_BIG, "recordSize": big.size, "unique_record": -1,
        "num_of_scan": scans.n_scans, "last_scan_index": scans.last_scan_index, "scan_type": scans.scan_type,
    }))  # fmt: skip
    var_layout = layout(codes.SCAN_VAR, 3)
    for var in variables[1:]:
        if not -1 <= var.data_record < n_data:
            raise ValueError(f"scan variable {var.name!r} refers to data header {var.data_record}")
        numbers = _numbers(np.asarray(var.values, dtype=np.float64), var.number_type, "scan values").tobytes()
        extra = {"recordSize": var_layout.size + len(numbers), "headerSize": var_layout.size}
        out.append(_record(var_layout, var, **extra) + numbers)
    return out


def _comment(comment: Comment) -> bytes:
    text = comment.text.encode("latin-1", "replace")
    table = layout(codes.COMMENT, 3)
    extra = {"recordSize": table.size + len(text), "headerSize": table.size, "comment_bytes": len(text)}
    return _record(table, comment, **extra) + text
