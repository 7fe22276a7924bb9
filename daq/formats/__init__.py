"""Readers and writers for foreign file formats: CSV / text time records and UFF 58.

Pure functions, no CLI and no store access. Readers return :class:`ImportedData` in SI
units (N, m/s^2, (m/s^2)/N) and raise only one-line :class:`daq.formats.errors.FormatError`.
"""

from daq.formats.csv_text import read_csv, write_csv
from daq.formats.errors import FormatError
from daq.formats.imported import MAX_IMPORT_BYTES, ImportedData
from daq.formats.uff58 import read_uff
from daq.formats.uff58_export import write_uff
from daq.formats.units import parse_unit, to_si

__all__ = [
    "MAX_IMPORT_BYTES",
    "FormatError",
    "ImportedData",
    "parse_unit",
    "read_csv",
    "read_uff",
    "to_si",
    "write_csv",
    "write_uff",
]
