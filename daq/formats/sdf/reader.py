"""Read an SDF file (HP Standard Data Format, revisions 1 to 3) into daq.formats.sdf.model.

Everything is checked before anything is allocated: each record must be where the
FILE_HDR says, of the type expected there, at least as long as its revision's layout and
inside the file; counts and sizes are Python integers compared with the bytes the file
really holds, so a damaged header cannot ask for more memory than a few times the file's
size. Any problem is one FormatError line naming the file (docs/sdf.md lists them).
"""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np

from daq.formats.imported import MAX_IMPORT_BYTES, open_checked, show_path
from daq.formats.sdf import axes, codes, ydata
from daq.formats.sdf.convert import WINDOW_POLICIES, integer_scaling, used_channels, vector_factor
from daq.formats.sdf.layout import layout
from daq.formats.sdf.model import (
    Channel,
    Comment,
    DataHeader,
    FileHeader,
    MeasHeader,
    Scans,
    ScanVariable,
    SdfFile,
    Vector,
)
from daq.formats.sdf.source import HEAD_SIZE, Source

SIGNATURE = b"B\0"


def read_sdf(path: Path | str, *, window: str = "narrow", max_bytes: int = MAX_IMPORT_BYTES) -> SdfFile:
    """Read every logical file of the SDF file at ``path``; FormatError (one line) if it
    is not a readable SDF file. window: "narrow" (default), "wide" or "none", the window
    correction applied where windowCorrMode says none has been (daq/formats/sdf/convert.py)."""
    name = show_path(path)
    with open_checked(Path(path), max_bytes) as (handle, _info):
        try:
            data = handle.read(max_bytes + 1)
        except OSError as exc:
            raise Source(b"", name).fail(f"cannot read it ({exc.strerror or exc})") from None
    if len(data) > max_bytes:
        Source(b"", name).fail(f"grew beyond the import limit of {max_bytes} bytes while being read")
    return parse_sdf(data, name, window=window)


def parse_sdf(data: bytes, name: str, *, window: str = "narrow") -> SdfFile:
    """The SDF file held in ``data`` (its name for messages)."""
    if window not in WINDOW_POLICIES:
        raise ValueError(f"window must be one of {WINDOW_POLICIES}, got {window!r}")
    files: list[SdfFile] = []
    base = 0
    while True:
        sdf, next_offset = _logical_file(Source(data, name, base), window)
        files.append(sdf)
        if next_offset <= 0:
            break
        # Offsets must move forward, so a damaged chain cannot loop.
        if base + next_offset >= len(data):
            Source(data, name).fail(f"the next logical SDF file would start at byte {base + next_offset}, "
                                    f"past the end of the file ({len(data)} bytes)")  # fmt: skip
        base += next_offset
    for earlier, later in itertools.pairwise(files):
        earlier.next_file = later
    return files[0]


def _logical_file(src: Source, window: str) -> tuple[SdfFile, int]:
    where = "" if src.base == 0 else f"the logical SDF file at byte {src.base}: "
    src.need(src.at(0), 2, f"{where}the format mark B\\0")
    mark = src.data[src.at(0) : src.at(2)]
    if mark != SIGNATURE:
        shown = mark.decode("latin-1") if mark.isascii() and mark.decode("latin-1").isprintable() else ""
        src.fail(
            f"{where}not an SDF file: its first two bytes are {mark.hex(' ').upper()}"
            + (f" ({shown!r})" if shown else "")
            + ", not SDF's 42 00 ('B' and NUL)"
        )
    src.need(src.at(2), HEAD_SIZE + 2, "the FILE_HDR record")
    revision = int.from_bytes(src.data[src.at(8) : src.at(10)], "big", signed=True)
    if revision not in (0, 1, 2, 3):
        src.fail(f"FILE_HDR says SDF revision {revision}; this reader knows revisions 1, 2 and 3")
    revision = max(revision, 1)  # the guide's own example file of revision 1 says 0
    head = layout(codes.FILE_HDR, revision)
    start, size = src.record(2, codes.FILE_HDR, "the FILE_HDR record", head.size)
    index = src.unpack(head, start, "the FILE_HDR record")
    file = FileHeader(**_attrs(head, index))
    file.revision = revision

    meas_layout = layout(codes.MEAS_HDR, revision)
    start, _ = src.record(2 + size, codes.MEAS_HDR, "the MEAS_HDR record", meas_layout.size)
    meas = MeasHeader(**_attrs(meas_layout, src.unpack(meas_layout, start, "the MEAS_HDR record")))

    raw_data = _records(src, index, "DATA_HDR", codes.DATA_HDR, revision, minimum=1)
    vectors = [Vector(**_attrs(layout(codes.VECTOR_HDR, revision), r)) for r in
               _records(src, index, "VECTOR", codes.VECTOR_HDR, revision)]  # fmt: skip
    channels = [Channel(**_attrs(layout(codes.CHANNEL_HDR, revision), r)) for r in
                _records(src, index, "CHANNEL", codes.CHANNEL_HDR, revision)]  # fmt: skip
    unique = _unique(src, index)
    scans, comments = _scans_and_comments(src, index, revision)
    data = [_data_header(src, k, raw, vectors, revision) for k, raw in enumerate(raw_data)]
    sdf = SdfFile(file, meas, data, channels, scans, comments, unique)
    places, payload = _locate_y(src, index, sdf)  # checks sizes before anything is allocated
    _read_x(src, index, data)
    _read_y(src, sdf, window, places, payload)
    return sdf, int(index.get("offset_of_next_SDF_FILE", -1))


def _attrs(table, raw: dict) -> dict:
    return {attr: raw[name] for name, attr, _code, _revs in table.fields if attr and attr[0] != "<"}


def _count(src: Source, index: dict, key: str, minimum: int = 0) -> int:
    count = int(index[key])
    if count < minimum:
        src.fail(f"FILE_HDR {key} is {count}; it must be at least {minimum}")
    return count


def _records(src, index, key, record_type, revision, minimum=0) -> list[dict]:
    """The raw fields of the ``num_of_<key>_record`` consecutive records of one type."""
    table = layout(record_type, revision)
    count = _count(src, index, f"num_of_{key}_record", minimum)
    offset = int(index[f"offset_of_{key}_record"])
    out = []
    for k in range(count):
        start, size = src.record(offset, record_type, f"{table.name} #{k}", table.size)
        out.append(src.unpack(table, start, f"{table.name} #{k}"))
        offset += size
    return out


def _unique(src: Source, index: dict) -> list[tuple[int, int]]:
    offset = int(index["offset_of_UNIQUE_record"])
    found = []
    for k in range(_count(src, index, "num_of_UNIQUE_record")):
        what = f"instrument-specific record #{k}"
        start, size = src.record(offset, codes.UNIQUE_TYPES.start, what, HEAD_SIZE)
        found.append((int.from_bytes(src.data[start : start + 2], "big", signed=True), size))
        offset += size
    return found


def _values(src: Source, start: int, end: int, count: int, number_type: int, what: str) -> np.ndarray:
    """(count,) float64 values of ``number_type`` from bytes [start, end); NaN where the
    record ends before ``count`` values."""
    if number_type not in codes.NUMBER_TYPES:
        src.fail(f"{what} has data type code {number_type}; SDF knows {codes.TYPE_CODES}")
    dtype = codes.NUMBER_TYPES[number_type][0]
    have = max(0, min(count, (end - start) // dtype.itemsize))
    values = np.full(count, np.nan)
    with np.errstate(all="ignore"):
        values[:have] = np.frombuffer(src.view, dtype=dtype, count=have, offset=start)
    return values


def _scans_and_comments(src: Source, index: dict, revision: int) -> tuple[Scans | None, list[Comment]]:
    struct_raw = big = None
    if _count(src, index, "num_of_SCAN_STRUCT_record") > 0:
        table = layout(codes.SCAN_STRUCT, revision)
        offset = int(index["offset_of_SCAN_STRUCT_record"])
        start, size = src.record(offset, codes.SCAN_STRUCT, "SCAN_STRUCT", table.size)
        struct_raw = (src.unpack(table, start, "SCAN_STRUCT"), start, size)
    var_raws = []
    comments = []
    if revision >= 3:
        offset = int(index["offset_of_SCAN_BIG_record"])
        for k in range(_count(src, index, "num_of_SCAN_BIG_record")):
            kind = codes.SCAN_BIG
            if offset >= 0 and 0 <= src.at(offset) <= len(src.data) - 2:
                found = int.from_bytes(src.data[src.at(offset) : src.at(offset) + 2], "big", signed=True)
                kind = found if found == codes.SCAN_VAR else kind
            table = layout(kind, 3)
            start, size = src.record(offset, kind, f"{table.name} #{k}", table.size)
            raw = src.unpack(table, start, f"{table.name} #{k}")
            if kind == codes.SCAN_BIG:
                big = raw
            else:
                var_raws.append((raw, start, size))
            offset += size
        offset = int(index["offset_of_COMMENT_record"])
        for k in range(_count(src, index, "num_of_COMMENT_record")):
            start, size = src.record(offset, codes.COMMENT, f"COMMENT #{k}", 24)
            raw = src.unpack(layout(codes.COMMENT, 3), start, f"COMMENT #{k}")
            text_start = start + min(max(24, int(raw["headerSize"])), size)
            length = size - (text_start - start)
            if 0 <= int(raw["comment_bytes"]) < length:
                length = int(raw["comment_bytes"])
            text = src.data[text_start : text_start + length].split(b"\0", 1)[0].decode("latin-1")
            comments.append(Comment(text, raw["comment_type"], raw["scope_type"], raw["scope_info"]))
            offset += size
    if struct_raw is None and big is None:
        if var_raws:
            src.fail("SCAN_VAR records without a SCAN_STRUCT or SCAN_BIG record")
        return None, comments
    main = big if big is not None else struct_raw[0]
    n_scans, last, scan_type = int(main["num_of_scan"]), int(main["last_scan_index"]), int(main["scan_type"])
    if n_scans > len(src.data):
        src.fail(f"num_of_scan {n_scans} is more scans than a file of {len(src.data)} bytes can hold")
    if n_scans < 1:
        src.fail(f"{'SCAN_BIG' if big is not None else 'SCAN_STRUCT'} says num_of_scan = {n_scans}")
    if scan_type not in codes.SCAN_TYPES:
        src.fail(f"scan_type {scan_type} is neither 0 (depth) nor 1 (scan)")
    variables = []
    if struct_raw is not None:
        raw, start, size = struct_raw
        values = _values(src, start + 36, start + size, n_scans, raw["scanVar_type"], "SCAN_STRUCT")
        variables.append(ScanVariable(values, raw["scanVar_type"], raw["scanUnit"]))
    for raw, start, size in var_raws:
        header = min(max(54, int(raw["headerSize"])), size)
        values = _values(src, start + header, start + size, n_scans, raw["scanVar_type"], "SCAN_VAR")
        fields = {attr: raw[name] for name, attr, _c, _r in layout(codes.SCAN_VAR, 3).fields if attr}
        variables.append(ScanVariable(values, **fields))
    return Scans(n_scans, last, scan_type, variables), comments


def _data_header(src: Source, k: int, raw: dict, vectors: list[Vector], revision: int) -> DataHeader:
    table = layout(codes.DATA_HDR, revision)
    dh = DataHeader(**_attrs(table, raw))
    what = f"DATA_HDR #{k}"
    n_vectors = int(dh.total_rows) * int(dh.total_cols)
    first = int(raw["first_VECTOR_recordNum"])
    if dh.total_rows < 1 or dh.total_cols < 1:
        src.fail(f"{what} has {dh.total_rows} rows and {dh.total_cols} columns of traces; each must be >= 1")
    if first < 0 or first + n_vectors > len(vectors):
        src.fail(f"{what} uses VECTOR_HDR #{first}..#{first + n_vectors - 1}; the file has {len(vectors)}")
    dh.vectors = vectors[first : first + n_vectors]
    if dh.ydata_type not in codes.NUMBER_TYPES:
        src.fail(f"{what} has ydata_type {dh.ydata_type}; SDF knows {codes.TYPE_CODES}")
    if dh.n_points < 1 or dh.y_per_point < 1:
        src.fail(f"{what} has {dh.n_points} points of {dh.y_per_point} values each; both must be >= 1")
    if dh.x_resolution not in codes.X_RESOLUTIONS:
        src.fail(f"{what} has xResolution_type {dh.x_resolution}; SDF knows 0 to 4")
    if dh.x_resolution in axes.ARBITRARY and dh.xdata_type not in codes.NUMBER_TYPES:
        src.fail(f"{what} has xdata_type {dh.xdata_type}; SDF knows {codes.TYPE_CODES}")
    dh.x_per_point = max(1, int(dh.x_per_point))
    dh.y_is_complex = int(dh.y_is_complex != 0)
    if revision == 1:
        dh.scan_data = 1  # revision 1 has no scanData: with a scan structure, all data is scanned
    return dh


def _read_x(src: Source, index: dict, data: list[DataHeader]) -> None:
    try:
        plan = axes.xdata_plan(data)
    except ValueError as exc:
        src.fail(str(exc))
    total = plan[-1][0]
    payload = memoryview(b"")
    if any(dh.x_resolution in axes.ARBITRARY for dh in data):
        if _count(src, index, "num_of_XDATA_record") < 1:
            src.fail("its data headers take x values from XDATA, but num_of_XDATA_record is 0")
        offset = int(index["offset_of_XDATA_record"])
        start, size = src.record(offset, codes.XDATA, "the XDATA record", HEAD_SIZE)
        if size - HEAD_SIZE < total:
            src.fail(f"the XDATA record holds {size - HEAD_SIZE} bytes of x values; the headers need {total}")
        payload = src.view[start + HEAD_SIZE : start + size]
    for dh, (start, n_vectors, _item) in zip(data, plan, strict=False):
        dh.x = axes.read_x(dh, payload, start, n_vectors) if start >= 0 else axes.computed_x(dh)


def _locate_y(src: Source, index: dict, sdf: SdfFile) -> tuple[list[ydata.Place], memoryview]:
    """Where every data header's values are, checked against the YDATA record's size."""
    scans = sdf.scans
    n_scans = scans.n_scans if scans else 1
    scanned = [scans is not None and dh.scan_data != 0 for dh in sdf.data]
    try:
        places = ydata.plan(sdf.data, scanned, n_scans, scans.scan_type if scans else codes.DEPTH)
    except ValueError as exc:
        src.fail(str(exc))
    total = max((p.end for p in places), default=0)
    offset = int(index["offset_of_YDATA_record"])
    start, size = src.record(offset, codes.YDATA, "the YDATA record", HEAD_SIZE)
    if size - HEAD_SIZE < total:
        src.fail(f"the YDATA record holds {size - HEAD_SIZE} bytes of y values; the headers need {total}")
    return places, src.view[start + HEAD_SIZE : start + size]


def _read_y(src: Source, sdf: SdfFile, window: str, places: list[ydata.Place], payload: memoryview) -> None:
    for k, (dh, place) in enumerate(zip(sdf.data, places, strict=True)):
        try:
            for v in dh.vectors:
                used_channels(v, len(sdf.channels))
            factors = np.array([vector_factor(dh, v, sdf.channels, window) for v in dh.vectors])
            scaling = None
            if dh.ydata_type in (codes.INT16, codes.INT32):
                scaling = np.array([integer_scaling(v, sdf.channels) for v in dh.vectors]).reshape(-1, 2)
        except ValueError as exc:
            src.fail(f"DATA_HDR #{k}: a trace {exc}")
        dh.y = ydata.read_values(dh, place, payload, factors, scaling)
