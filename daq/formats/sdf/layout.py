"""SDF record layouts: one table per record type, every field in file order, per revision.

Big-endian, packed, no padding. Codes: h int16, i int32, f float32, d float64,
b signed char, Ns a NUL-terminated string of N bytes, ``unit`` an SDF_UNIT (22 bytes),
``window`` an SDF_WINDOW (24 bytes). Each field lists the revisions that hold it: where
revision 2 or 3 replaced a field, the old one keeps its place as ``...Old`` and the new
one is appended (e.g. DATA_HDR num_of_points: int16 at byte 30 up to revision 2, int32 at
byte 134 in revision 3). The second column names the attribute of daq.formats.sdf.model
that holds the value: "" for what the writer derives (record type, size, counts,
offsets), "<attr" for an old copy the writer fills from ``attr`` and the reader ignores.

Sources: HP SDF_comm.h / SDF_basi.h (SDF_REV 3) and the guide's tables B-2 to B-14
(P/N 5963-1715, appendix B); the sizes below are the guide's table B-1 and a test
(tests/formats/test_sdf_layout.py) checks every table adds up to them.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass
from functools import cache
from typing import Any

from daq.formats.sdf import codes
from daq.formats.sdf.model import Unit, Window

ALL, R1, R12, R23, R3 = (1, 2, 3), (1,), (1, 2), (2, 3), (3,)
REVISIONS = ALL

Field = tuple[str, str, str, tuple[int, ...]]  # (SDF name, model attribute, code, revisions)

UNIT_FIELDS = ("10s", "f", "b", "b", "b", "b", "b", "b", "b", "b")
WINDOW_FIELDS = ("h", "h", "f", "f", "f", "f", "f")
_HEAD: tuple[Field, ...] = (("recordType", "", "h", ALL), ("recordSize", "", "i", ALL))
_COUNTS = ("DATA_HDR", "VECTOR", "CHANNEL", "UNIQUE", "SCAN_STRUCT", "XDATA")

FILE_HDR: tuple[Field, ...] = (
    *_HEAD,
    ("revisionNum", "revision", "h", ALL),
    ("applic", "applic", "h", ALL),
    ("yearStamp", "year", "h", ALL),
    ("monthDayStamp", "month_day", "h", ALL),
    ("hourMinStamp", "hour_min", "h", ALL),
    ("applicVer", "applic_version", "8s", ALL),
    *((f"num_of_{n}_record", "", "h", ALL) for n in _COUNTS),
    *((f"offset_of_{n}_record", "", "i", ALL) for n in (*_COUNTS, "YDATA")),
    ("num_of_SCAN_BIG_record", "", "h", R3),
    ("num_of_COMMENT_record", "", "h", R3),
    ("offset_of_SCAN_BIG_record", "", "i", R3),
    ("offset_of_COMMENT_record", "", "i", R3),
    ("offset_of_next_SDF_FILE", "", "i", R3),
)

MEAS_HDR: tuple[Field, ...] = (
    *_HEAD,
    ("unique_record", "", "i", ALL),
    ("centerFreq", "center_freq", "f", R1),
    ("centerFreqOld", "<center_freq", "f", R23),
    ("spanFreq", "span_freq", "f", R1),
    ("spanFreqOld", "<span_freq", "f", R23),
    ("blockSize", "block_size", "i", ALL),
    ("zoomModeOn", "zoom", "h", ALL),
    ("startFreqIndex", "start_freq_index", "h", R12),
    ("startFreqIndexOld", "<start_freq_index", "h", R3),
    ("stopFreqIndex", "stop_freq_index", "h", R12),
    ("stopFreqIndexOld", "<stop_freq_index", "h", R3),
    ("averageType", "average_type", "h", ALL),
    ("averageNum", "average_num", "i", ALL),
    ("pctOverlap", "pct_overlap", "f", ALL),
    ("measTitle", "title", "60s", ALL),
    ("videoBandWidth", "video_bandwidth", "f", ALL),
    ("centerFreq", "center_freq", "d", R23),
    ("spanFreq", "span_freq", "d", R23),
    ("sweepFreq", "sweep_freq", "d", R23),
    ("measType", "meas_type", "h", R23),
    ("realTime", "real_time", "h", R23),
    ("detection", "detection", "h", R23),
    ("sweepTime", "sweep_time", "d", R23),
    ("startFreqIndex", "start_freq_index", "i", R3),
    ("stopFreqIndex", "stop_freq_index", "i", R3),
    ("expAverageNum", "exp_average_num", "d", R3),
)

DATA_HDR: tuple[Field, ...] = (
    *_HEAD,
    ("unique_record", "", "i", ALL),
    ("dataTitle", "title", "16s", ALL),
    ("domain", "domain", "h", ALL),
    ("dataType", "data_type", "h", ALL),
    ("num_of_points", "n_points", "h", R12),
    ("num_of_pointsOld", "<n_points", "h", R3),
    ("last_valid_index", "last_valid_index", "h", R12),
    ("last_valid_indexOld", "<last_valid_index", "h", R3),
    ("abscissa_firstX", "first_x", "f", R1),
    ("abscissa_firstXOld", "<first_x", "f", R23),
    ("abscissa_deltaX", "delta_x", "f", R1),
    ("abscissa_deltaXOld", "<delta_x", "f", R23),
    ("xResolution_type", "x_resolution", "h", ALL),
    ("xdata_type", "xdata_type", "h", ALL),
    ("xPerPoint", "x_per_point", "h", ALL),
    ("ydata_type", "ydata_type", "h", ALL),
    ("yPerPoint", "y_per_point", "h", ALL),
    ("yIsComplex", "y_is_complex", "h", ALL),
    ("yIsNormalized", "y_is_normalized", "h", ALL),
    ("yIsPowerData", "y_is_power", "h", ALL),
    ("yIsValid", "y_is_valid", "h", ALL),
    ("first_VECTOR_recordNum", "", "i", ALL),
    ("total_rows", "total_rows", "h", ALL),
    ("total_cols", "total_cols", "h", ALL),
    ("xUnit", "x_unit", "unit", ALL),
    ("yUnitValid", "y_unit_valid", "h", ALL),
    ("yUnit", "y_unit", "unit", ALL),
    ("abscissa_firstX", "first_x", "d", R23),
    ("abscissa_deltaX", "delta_x", "d", R23),
    ("scanData", "scan_data", "h", R23),
    ("windowApplied", "window_applied", "h", R23),
    ("num_of_points", "n_points", "i", R3),
    ("last_valid_index", "last_valid_index", "i", R3),
    ("overSampleFactor", "over_sample_factor", "h", R3),
    ("multiPassMode", "multi_pass_mode", "h", R3),
    ("multiPassDecimations", "multi_pass_decimations", "h", R3),
)

VECTOR_HDR: tuple[Field, ...] = (
    *_HEAD,
    ("unique_record", "", "i", ALL),
    ("the_CHANNEL_record[0]", "row_channel", "h", ALL),
    ("the_CHANNEL_record[1]", "col_channel", "h", ALL),
    ("pwrOfChan[0]", "row_power", "h", ALL),
    ("pwrOfChan[1]", "col_power", "h", ALL),
)

CHANNEL_HDR: tuple[Field, ...] = (
    *_HEAD,
    ("unique_record", "", "i", ALL),
    ("channelLabel", "label", "30s", ALL),
    ("moduleId", "module_id", "12s", ALL),
    ("serialNum", "serial", "12s", ALL),
    ("window", "window", "window", ALL),
    ("weight", "weight", "h", ALL),
    ("delay", "delay", "f", R12),
    ("delayOld", "<delay", "f", R3),
    ("range", "range_dbv", "f", ALL),
    ("direction", "direction", "h", ALL),
    ("pointNum", "point_num", "h", ALL),
    ("coupling", "coupling", "h", ALL),
    ("overloaded", "overloaded", "h", ALL),
    ("intLabel", "int_label", "10s", ALL),
    ("engUnit", "eng_unit", "unit", ALL),
    ("int2engrUnit", "int2engr", "f", ALL),
    ("inputImpedance", "input_impedance", "f", ALL),
    ("channelAttribute", "attribute", "h", R23),
    ("aliasProtected", "alias_protected", "h", R23),
    ("digital", "digital", "h", R23),
    ("channelScale", "scale", "d", R23),
    ("channelOffset", "offset", "d", R23),
    ("gateBegin", "gate_begin", "d", R23),
    ("gateEnd", "gate_end", "d", R23),
    ("userDelay", "user_delay", "d", R23),
    ("delay", "delay", "d", R3),
    ("carrierFreq", "carrier_freq", "d", R3),
    ("channelNumber", "channel_number", "h", R3),
    ("channelModule", "channel_module", "h", R3),
)

# Followed by num_of_scan scan values of scanVar_type (the record size covers them).
SCAN_STRUCT: tuple[Field, ...] = (
    *_HEAD,
    ("num_of_scan", "", "h", ALL),
    ("last_scan_index", "", "h", ALL),
    ("scan_type", "", "h", ALL),
    ("scanVar_type", "", "h", ALL),
    ("scanUnit", "", "unit", ALL),
)

SCAN_BIG: tuple[Field, ...] = (
    *_HEAD,
    ("unique_record", "", "i", R3),
    ("num_of_scan", "", "i", R3),
    ("last_scan_index", "", "i", R3),
    ("scan_type", "", "h", R3),
)

# Followed by the scan values (headerSize = 54 bytes of header).
SCAN_VAR: tuple[Field, ...] = (
    *_HEAD,
    ("unique_record", "", "i", R3),
    ("headerSize", "", "i", R3),
    ("scanBase_type", "base_type", "h", R3),
    ("scanOrder_type", "order_type", "h", R3),
    ("DATA_recordNum", "data_record", "h", R3),
    ("scan_ID", "name", "10s", R3),
    ("scanVar_type", "number_type", "h", R3),
    ("scanUnit", "unit", "unit", R3),
)

# Followed by the comment text (headerSize = 24 bytes of header).
COMMENT: tuple[Field, ...] = (
    *_HEAD,
    ("unique_record", "", "i", R3),
    ("headerSize", "", "i", R3),
    ("comment_bytes", "", "i", R3),
    ("comment_type", "comment_type", "h", R3),
    ("scope_type", "scope_type", "h", R3),
    ("scope_info", "scope_info", "h", R3),
)

# XDATA and YDATA: the 6-byte head, then the values.
DATA_BLOCK: tuple[Field, ...] = _HEAD

TABLES: dict[int, tuple[Field, ...]] = {
    codes.FILE_HDR: FILE_HDR,
    codes.MEAS_HDR: MEAS_HDR,
    codes.DATA_HDR: DATA_HDR,
    codes.VECTOR_HDR: VECTOR_HDR,
    codes.CHANNEL_HDR: CHANNEL_HDR,
    codes.SCAN_STRUCT: SCAN_STRUCT,
    codes.SCAN_BIG: SCAN_BIG,
    codes.SCAN_VAR: SCAN_VAR,
    codes.COMMENT: COMMENT,
    codes.XDATA: DATA_BLOCK,
    codes.YDATA: DATA_BLOCK,
}

#: The guide's table B-1: record size in bytes for revisions 1, 2, 3 (without values).
SIZES = {
    codes.FILE_HDR: (64, 64, 80),
    codes.MEAS_HDR: (102, 140, 156),
    codes.DATA_HDR: (114, 134, 148),
    codes.VECTOR_HDR: (18, 18, 18),
    codes.CHANNEL_HDR: (146, 192, 212),
    codes.SCAN_STRUCT: (36, 36, 36),
    codes.SCAN_BIG: (None, None, 20),
    codes.SCAN_VAR: (None, None, 54),
    codes.COMMENT: (None, None, 24),
}

_LIMITS = {"h": (-(2**15), 2**15 - 1), "i": (-(2**31), 2**31 - 1), "b": (-128, 127)}
_FLOAT32_MAX = 3.4028234663852886e38
SDF_MAX_FLOAT = 3.0e30  # what HP's CAST_IN_FLOAT writes for a double too large for a float


@dataclass(frozen=True)
class Layout:
    """One record type at one revision: its fields and their packed form."""

    record_type: int
    revision: int
    fields: tuple[Field, ...]
    packer: struct.Struct

    @property
    def size(self) -> int:
        return self.packer.size

    @property
    def name(self) -> str:
        return codes.RECORD_NAMES[self.record_type]

    def unpack(self, data: bytes | memoryview, offset: int) -> dict[str, Any]:
        """{SDF name: value}; strings decoded (latin-1, up to the first NUL), units and
        windows as model objects. The caller has checked that the bytes are there."""
        raw = iter(self.packer.unpack_from(data, offset))
        out: dict[str, Any] = {}
        for name, _attr, code, _revs in self.fields:
            if code == "unit":
                label, factor, *dims = (next(raw) for _ in UNIT_FIELDS)
                out[name] = Unit(_text(label), float(factor), tuple(dims))
            elif code == "window":
                out[name] = Window(*(next(raw) for _ in WINDOW_FIELDS))
            else:
                value = next(raw)
                out[name] = _text(value) if code.endswith("s") else value
        return out

    def pack(self, values: dict[str, Any]) -> bytes:
        """Bytes of the record head from {SDF name: value}. ValueError names a value that
        does not fit its field (an old copy is clipped to its field instead)."""
        flat: list[Any] = []
        for name, attr, code, _revs in self.fields:
            value = values[name]
            clip = attr.startswith("<")
            if code == "unit":
                flat += [_bytes(value.label, 10), *_fit("f", value.factor, name, clip)]
                flat += [v for d in value.dims for v in _fit("b", d, name, clip)]
            elif code == "window":
                w = value
                flat += [*_fit("h", w.type, name, clip), *_fit("h", w.corr_mode, name, clip)]
                for number in (w.bandwidth, w.time_const, w.trunc, w.wide_band_corr, w.narrow_band_corr):
                    flat += _fit("f", number, name, clip)
            elif code.endswith("s"):
                flat.append(_bytes(value, int(code[:-1])))
            else:
                flat += _fit(code, value, name, clip)
        return self.packer.pack(*flat)


@cache
def layout(record_type: int, revision: int) -> Layout:
    """The layout of ``record_type`` (codes.FILE_HDR...) at ``revision`` (1, 2 or 3)."""
    fields = tuple(f for f in TABLES[record_type] if revision in f[3])
    parts = []
    for _name, _attr, code, _revs in fields:
        parts += UNIT_FIELDS if code == "unit" else WINDOW_FIELDS if code == "window" else (code,)
    return Layout(record_type, revision, fields, struct.Struct(">" + "".join(parts)))


def _text(value: bytes) -> str:
    return value.split(b"\0", 1)[0].decode("latin-1")


def _bytes(text: str, size: int) -> bytes:
    """``text`` as at most size - 1 bytes (latin-1, others as "?"), NUL-padded."""
    return text.encode("latin-1", "replace")[: size - 1]


def _fit(code: str, value: Any, name: str, clip: bool) -> list[Any]:
    if code in _LIMITS:
        lo, hi = _LIMITS[code]
        number = int(value)
        if not lo <= number <= hi:
            if not clip:
                raise ValueError(f"{name} = {number} does not fit its {code!r} field ({lo}..{hi})")
            number = min(max(number, lo), hi)
        return [number]
    number = float(value)
    if code == "f" and math.isfinite(number) and abs(number) > _FLOAT32_MAX:
        if not clip:
            raise ValueError(f"{name} = {number!r} does not fit a float32 field")
        number = math.copysign(SDF_MAX_FLOAT, number)
    return [number]
