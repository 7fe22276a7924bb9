"""HP's Standard Data Format (SDF, revisions 1 to 3): read any file, write revision 3.

read_sdf / parse_sdf give an :class:`SdfFile` (model.py) with every header and the
values in engineering units; write_sdf / encode_sdf write one. read_sdf_run and
write_sdf_run turn files into runs and back (run_import.py, run_export.py). The format
in our own words, with its sources: docs/sdf.md.
"""

from daq.formats.sdf.model import (
    Channel,
    Comment,
    DataHeader,
    FileHeader,
    MeasHeader,
    Scans,
    ScanVariable,
    SdfFile,
    Unit,
    Vector,
    Window,
)
from daq.formats.sdf.reader import parse_sdf, read_sdf
from daq.formats.sdf.run_export import sdf_of_run, write_sdf_run
from daq.formats.sdf.run_import import read_sdf_run
from daq.formats.sdf.writer import encode_sdf, write_sdf

__all__ = [
    "Channel",
    "Comment",
    "DataHeader",
    "FileHeader",
    "MeasHeader",
    "ScanVariable",
    "Scans",
    "SdfFile",
    "Unit",
    "Vector",
    "Window",
    "encode_sdf",
    "parse_sdf",
    "read_sdf",
    "read_sdf_run",
    "sdf_of_run",
    "write_sdf",
    "write_sdf_run",
]
