"""An SDF file in memory: what :func:`daq.formats.sdf.read_sdf` returns and
:func:`daq.formats.sdf.write_sdf` writes.

Field names are the SDF names in snake case (docs/sdf.md maps every one). Defaults
are HP's (SDF_basi.h ``DEF_*``) where the guide gives one. Record counts, sizes and
byte offsets are not stored: the writer derives them, the reader checks them.

Arrays hold values in ENGINEERING UNITS: the reader has already applied each
channel's int2engrUnit, the window correction and, for integer data, channelScale
and channelOffset (docs/sdf.md, "From stored numbers to engineering units").
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from daq.formats.sdf import codes

# Doubled SI exponents (mass, length, time, current, temperature, luminous intensity,
# mole, plane angle), as SDF_UNIT stores them.
FORCE_DIMS = (2, 2, -4, 0, 0, 0, 0, 0)
ACCELERATION_DIMS = (0, 2, -4, 0, 0, 0, 0, 0)
NO_DIMS = (0,) * 8


@dataclass(frozen=True)
class Unit:
    """SDF_UNIT: a label, the factor to its SI equivalent, and 2 x the SI exponents.

    Example: g is ("g", 9.80665, length 2, time -4): 1 g = 9.80665 m s^-2.
    """

    label: str = ""
    factor: float = 1.0
    dims: tuple[int, ...] = NO_DIMS


SECOND = Unit("s", 1.0, (0, 0, 2, 0, 0, 0, 0, 0))
HERTZ = Unit("Hz", float(np.float32(2 * np.pi)), (0, 0, -2, 0, 0, 0, 0, 2))  # as HP codes it: rad/s
NEWTON = Unit("N", 1.0, FORCE_DIMS)
METRE_PER_S2 = Unit("m/s^2", 1.0, ACCELERATION_DIMS)
COUNT = Unit("count", 1.0, NO_DIMS)


@dataclass(frozen=True)
class Window:
    """SDF_WINDOW of a channel. corr_mode: 0 no correction applied to the stored data,
    1 narrow-band applied, 2 wide-band applied, 3 user correction applied.
    bandwidth in bins; time_const and trunc in s (force and exponential windows)."""

    type: int = codes.UNIFORM_WINDOW
    corr_mode: int = codes.CORR_NOT_APPLIED
    bandwidth: float = 1.0
    time_const: float = 0.0
    trunc: float = 0.0
    wide_band_corr: float = 1.0
    narrow_band_corr: float = 1.0


@dataclass
class FileHeader:
    """FILE_HDR: revision 1..3, the writing instrument (``applic``, codes.APPLICATIONS),
    the measurement's start as the instrument's local clock gave it."""

    revision: int = 3
    applic: int = codes.UNKNOWN_APPLIC
    year: int = 0
    month_day: int = 0  # month * 100 + day
    hour_min: int = 0  # hour * 100 + minute
    applic_version: str = ""

    @property
    def instrument(self) -> str:
        return codes.name_of(codes.APPLICATIONS, self.applic)

    @property
    def stamp(self) -> str:
        """ "YYYY-MM-DD HH:MM" as stored (local time of the instrument, unchecked)."""
        month, day = divmod(self.month_day, 100)
        hour, minute = divmod(self.hour_min, 100)
        return f"{self.year:04d}-{month:02d}-{day:02d} {hour:02d}:{minute:02d}"


@dataclass
class MeasHeader:
    """MEAS_HDR: frequencies in Hz, times in s. start/stop_freq_index: the alias-protected
    lines of frequency-domain data (what the analyzer's screen shows)."""

    center_freq: float = 0.0
    span_freq: float = 0.0
    block_size: int = 0
    zoom: int = 0
    start_freq_index: int = 0
    stop_freq_index: int = 0
    average_type: int = codes.AVERAGE_OFF
    average_num: int = 1
    pct_overlap: float = 0.0
    title: str = ""
    video_bandwidth: float = 0.0
    sweep_freq: float = 0.0
    meas_type: int = -99
    real_time: int = 0
    detection: int = -99
    sweep_time: float = 0.0
    exp_average_num: float = 0.0


@dataclass
class Vector:
    """VECTOR_HDR: the channels (indexes into SdfFile.channels, -1 = none) that made one
    trace, and each one's power times 48 (PWR_OF_CHAN): an FRF is (response, 48),
    (force, -48); an auto-power spectrum (channel, 96), (-1, 0)."""

    row_channel: int = 0
    col_channel: int = -1
    row_power: int = 48
    col_power: int = 0

    @property
    def channels(self) -> tuple[tuple[int, int], tuple[int, int]]:
        return ((self.row_channel, self.row_power), (self.col_channel, self.col_power))


@dataclass
class Channel:
    """CHANNEL_HDR. range in dBV; delay, gate_*, user_delay in s; carrier_freq in Hz.
    int2engr: internal unit / engineering unit (divide to get EU). scale, offset: volts =
    offset + scale * stored integer (integer y data only)."""

    label: str = ""
    module_id: str = ""
    serial: str = ""
    window: Window = field(default_factory=Window)
    weight: int = 0
    delay: float = 0.0
    range_dbv: float = 0.0
    direction: int = 0
    point_num: int = 0
    coupling: int = 0
    overloaded: int = 0
    int_label: str = "V"
    eng_unit: Unit = field(default_factory=Unit)
    int2engr: float = 1.0
    input_impedance: float = 1.0e6
    attribute: int = 0
    alias_protected: int = 1
    digital: int = 0
    scale: float = 1.0
    offset: float = 0.0
    gate_begin: float = 0.0
    gate_end: float = 0.0
    user_delay: float = 0.0
    carrier_freq: float = 0.0
    channel_number: int = 0
    channel_module: int = 0


@dataclass
class DataHeader:
    """DATA_HDR with its vectors and values.

    x: (n_points,) when one x vector serves every trace (linear, logarithmic, XDATA per
        file or per data header); (n_vectors, n_points) for XDATA per trace; a trailing
        axis of x_per_point when that is > 1. Units of x_unit.
    y: (n_scans, n_vectors, n_points), float64 or complex128 (y_is_complex), a trailing
        axis of y_per_point when that is > 1; engineering units. n_scans is 1 for data
        that is not scanned.
    """

    title: str = ""
    domain: int = codes.FREQ_DOMAIN
    data_type: int = codes.FREQ_RESP_DATA
    n_points: int = 0
    last_valid_index: int = 0
    x_resolution: int = codes.LINEAR_RES
    xdata_type: int = codes.FLOAT32
    x_per_point: int = 1
    ydata_type: int = codes.FLOAT32
    y_per_point: int = 1
    y_is_complex: int = 0
    y_is_normalized: int = 0
    y_is_power: int = 0
    y_is_valid: int = 1
    total_rows: int = 1
    total_cols: int = 1
    x_unit: Unit = field(default_factory=Unit)
    y_unit_valid: int = 0
    y_unit: Unit = field(default_factory=Unit)
    first_x: float = 0.0
    delta_x: float = 1.0
    scan_data: int = 0
    window_applied: int = 1
    over_sample_factor: int = 1
    multi_pass_mode: int = 0
    multi_pass_decimations: int = 0
    vectors: list[Vector] = field(default_factory=list)
    x: np.ndarray = field(default_factory=lambda: np.zeros(0))
    y: np.ndarray = field(default_factory=lambda: np.zeros((1, 0, 0)))

    def trace(self, scan: int, vector: int) -> np.ndarray:
        """(n_points,) values of one trace (or (n_points, y_per_point))."""
        return self.y[scan, vector]

    def x_of(self, vector: int) -> np.ndarray:
        """(n_points,) x values of one trace."""
        return self.x[vector] if self.x_resolution == codes.ARB_PER_VECTOR else self.x


@dataclass
class ScanVariable:
    """The value of one scan variable at each scan (n_scans,), float64, in ``unit``.
    The first comes from SCAN_STRUCT (no name), the others from SCAN_VAR records."""

    values: np.ndarray
    number_type: int = codes.FLOAT32
    unit: Unit = COUNT
    name: str = ""
    base_type: int = 0
    order_type: int = 0
    data_record: int = -1


@dataclass
class Scans:
    """The scan structure: n_scans sets of vectors for every DATA_HDR with scan_data = 1,
    organised per scan_type (codes.DEPTH or codes.SCAN, docs/sdf.md)."""

    n_scans: int
    last_scan_index: int
    scan_type: int = codes.DEPTH
    variables: list[ScanVariable] = field(default_factory=list)


@dataclass
class Comment:
    """COMMENT record (revision 3): text, and the header it belongs to (scope_type,
    scope_info: codes.SCOPE_FILE and -1 for the whole file)."""

    text: str
    comment_type: int = codes.COMMENT_TEXT
    scope_type: int = codes.SCOPE_FILE
    scope_info: int = -1


@dataclass
class SdfFile:
    """One logical SDF file. unique: (recordType, recordSize) of the instrument-specific
    records, which are skipped. next_file: the next logical file in the same physical
    file (revision 3 offset_of_next_SDF_FILE), or None."""

    file: FileHeader = field(default_factory=FileHeader)
    meas: MeasHeader = field(default_factory=MeasHeader)
    data: list[DataHeader] = field(default_factory=list)
    channels: list[Channel] = field(default_factory=list)
    scans: Scans | None = None
    comments: list[Comment] = field(default_factory=list)
    unique: list[tuple[int, int]] = field(default_factory=list)
    next_file: SdfFile | None = None
