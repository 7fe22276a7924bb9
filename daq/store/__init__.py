"""The run store: every impact test as one self-contained, checksummed HDF5 file.

Everything that reads or writes runs goes through this package:

- :class:`Run` and its parts (model.py) — the run in memory;
- :func:`seal` (writer.py) — write a run atomically, never overwriting;
- :func:`open_run` (reader.py) — read one back, read-only; :func:`open_run_bytes`
  — the same from a run file's bytes in memory; :func:`read_hits` — only its time
  records (what replay needs), checked as open_run checks the whole run;
- :func:`verify` (verify.py) — list what is wrong with a file;
- :class:`Store` (store.py) — a folder of runs: list, resolve by prefix, results;
- :func:`write_result` / :func:`read_result` (results.py) — analysis beside a run.

docs/run-format.md documents the file layout.
"""

from daq.store.errors import ConfigError, NotARunError, StoreError
from daq.store.ids import new_run_id, validate_run_id
from daq.store.layout import SCHEMA_NAME, SCHEMA_VERSION
from daq.store.model import Hits, Instrument, MeasuredFrf, Run, Sample, Spectra
from daq.store.reader import RunSummary, open_run, open_run_bytes, read_hits, read_summary
from daq.store.results import read_result, write_result
from daq.store.store import Store, resolve_store_dir
from daq.store.verify import verify
from daq.store.writer import seal

__all__ = [
    "SCHEMA_NAME",
    "SCHEMA_VERSION",
    "ConfigError",
    "Hits",
    "Instrument",
    "MeasuredFrf",
    "NotARunError",
    "Run",
    "RunSummary",
    "Sample",
    "Spectra",
    "Store",
    "StoreError",
    "new_run_id",
    "open_run",
    "open_run_bytes",
    "read_hits",
    "read_result",
    "read_summary",
    "resolve_store_dir",
    "seal",
    "validate_run_id",
    "verify",
    "write_result",
]
