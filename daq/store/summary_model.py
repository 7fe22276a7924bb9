"""RunSummary, the listing line of one run file, on its own: no numpy, no h5py.

A listing served from the index (daq/store/index.py) builds these from SQLite rows
alone, so this module imports nothing heavy; daq/store/reader.py, which reads them
from run files, hands the same class on under the same name.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class RunSummary:
    """What a listing shows about one run file, read without loading the records.

    n_hits and n_accepted are 0 for runs without hits. error is None for a readable
    run; otherwise it says what is wrong, and the other fields may be empty.
    """

    file_name: str
    run_id: str
    start_time: str
    kind: str
    complete: bool
    n_hits: int
    n_accepted: int
    operator: str
    note: str
    size_bytes: int
    error: str | None = None
