"""The numeric codes of SDF fields and their names (HP's SDF_basi.h enums, guide appendix B).

Only codes the reader acts on or reports are named; ``name_of`` gives "code N" for the rest.
"""

from __future__ import annotations

import numpy as np

# Record types (recordType of every record).
FILE_HDR, MEAS_HDR, DATA_HDR, VECTOR_HDR, CHANNEL_HDR = 10, 11, 12, 13, 14
SCAN_STRUCT, XDATA, YDATA, SCAN_BIG, SCAN_VAR, COMMENT = 15, 16, 17, 18, 19, 20
RECORD_NAMES = {
    FILE_HDR: "FILE_HDR",
    MEAS_HDR: "MEAS_HDR",
    DATA_HDR: "DATA_HDR",
    VECTOR_HDR: "VECTOR_HDR",
    CHANNEL_HDR: "CHANNEL_HDR",
    SCAN_STRUCT: "SCAN_STRUCT",
    XDATA: "XDATA",
    YDATA: "YDATA",
    SCAN_BIG: "SCAN_BIG",
    SCAN_VAR: "SCAN_VAR",
    COMMENT: "COMMENT",
}
#: recordType range HP reserves for instrument-specific ("unique") records.
UNIQUE_TYPES = range(1000, 2001)

# Number_type: xdata_type, ydata_type, scanVar_type. Code -> (big-endian numpy dtype, name).
INT16, INT32, FLOAT32, FLOAT64 = 1, 2, 3, 4
NUMBER_TYPES: dict[int, tuple[np.dtype, str]] = {
    INT16: (np.dtype(">i2"), "int16"),
    INT32: (np.dtype(">i4"), "int32"),
    FLOAT32: (np.dtype(">f4"), "float32"),
    FLOAT64: (np.dtype(">f8"), "float64"),
}

TYPE_CODES = "1 (int16), 2 (int32), 3 (float32) or 4 (float64)"

# Domain.
FREQ_DOMAIN, TIME_DOMAIN, ORDER_DOMAIN = 0, 1, 4
DOMAINS = {-99: "unknown", 0: "frequency", 1: "time", 2: "amplitude", 3: "RPM", 4: "order", 5: "channel"}
DOMAINS[6] = "octave"

# Data_type (the ones a vibration lab meets; the full list is in SDF_basi.h).
TIME_DATA, LINEAR_SPC_DATA, AUTO_PWR_DATA, CROSS_PWR_DATA, FREQ_RESP_DATA = 0, 1, 2, 3, 4
ORD_COH_DATA = 8
DATA_TYPES = {
    -99: "unknown",
    0: "time",
    1: "linear spectrum",
    2: "auto-power spectrum",
    3: "cross-power spectrum",
    4: "frequency response",
    5: "auto-correlation",
    6: "cross-correlation",
    7: "impulse response",
    8: "ordinary coherence",
    9: "partial coherence",
    10: "multiple coherence",
    11: "full octave",
    12: "third octave",
    14: "histogram",
    44: "power spectral density",
    45: "decimated time",
    47: "compressed time",
}

# XResolution_type.
LINEAR_RES, LOG_RES, ARB_PER_FILE, ARB_PER_DATA_HDR, ARB_PER_VECTOR = 0, 1, 2, 3, 4
X_RESOLUTIONS = {0: "linear", 1: "logarithmic", 2: "XDATA, one per file", 3: "XDATA, one per data header"}
X_RESOLUTIONS[4] = "XDATA, one per trace"

# Window_type and Window_corr_mode.
UNIFORM_WINDOW, FORCE_WINDOW, EXPONENTIAL_WINDOW = 3, 4, 5
WINDOWS = {-99: "unknown", 0: "none", 1: "Hanning", 2: "flat top", 3: "uniform", 4: "force"}
WINDOWS.update({5: "exponential", 6: "user", 7: "Hamming", 8: "P301", 9: "P310", 10: "Kaiser-Bessel"})
WINDOWS.update({11: "Harris", 12: "Blackman", 13: "resolution filter", 16: "gated", 17: "P400"})
CORR_NOT_APPLIED, CORR_NARROW, CORR_WIDE, CORR_USER = 0, 1, 2, 3

# Scan_type, ScanBase_type, ScanOrder_type.
DEPTH, SCAN = 0, 1
SCAN_TYPES = {DEPTH: "depth", SCAN: "scan"}
SCAN_NUMBER = 1
INCREASING = 1

# Channel attribute bit meaning "reference channel" (Attrib_type).
REFERENCE_ATTRIB = 2

# Measure_type, Detect_type, Average_type codes this package writes.
FFT_MEAS, SAMPLE_DETECT, AVERAGE_OFF = 3, 0, 0
# Comment_type and Scope_type.
COMMENT_TEXT, SCOPE_FILE = 0, 0

# Applic: the instrument (or program) that wrote the file.
UNKNOWN_APPLIC = -99
APPLICATIONS = {
    -99: "unknown",
    -1: "HP 35630A",
    -2: "HP 35631A",
    -3: "HP 35660A",
    -4: "HP 3562A/3563A",
    -5: "HP 3588A",
    -6: "HP 3589A",
    1: "HP 3566A/3567A",
    2: "HP 35665A",
    3: "HP 3560A",
    4: "HP 89410A/89440A",
    5: "Paragon calibration",
    7: "HP 35635R",
    8: "HP 35654A-S1A",
    9: "HP 3569A",
    10: "HP 35670A",
    11: "HP 3587S",
    12: "HP E3200",
}


def name_of(table: dict[int, str], code: int) -> str:
    """The name of ``code`` in ``table``, or "code N" when the table does not know it."""
    return table.get(int(code), f"code {int(code)}")
