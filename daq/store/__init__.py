"""The run store: every impact test as one self-contained, checksummed HDF5 file.

Everything that reads or writes runs goes through this package:

- :class:`Run` and its parts (model.py) — the run in memory;
- :func:`seal` (writer.py) — write a run atomically, never overwriting;
- :func:`open_run` (reader.py) — read one back, read-only; :func:`open_run_bytes`
  — the same from a run file's bytes in memory; :func:`read_hits` — only its time
  records (what replay needs), checked as open_run checks the whole run;
- :func:`verify` (verify.py) — list what is wrong with a file;
- :class:`Store` (store.py) — a folder of runs: list, resolve by prefix, results;
- :func:`write_result` / :func:`read_result` (results.py) — analysis beside a run;
- :func:`create_test`, :func:`load_test`, :func:`list_tests`, :func:`join_run`,
  :func:`next_point` (modal_tests.py) — multi-point modal tests, one TOML file each.

docs/run-format.md documents the file layout.
"""

from __future__ import annotations

import importlib
import sys
import types
from typing import TYPE_CHECKING

# Each public name and the module that defines it, imported on first use (PEP 562):
# `import daq.store` costs next to nothing, and a listing served from the index never
# loads numpy or h5py. `from daq.store import Run` works exactly as before.
_LAZY = {
    "ConfigError": "errors",
    "NotARunError": "errors",
    "StoreError": "errors",
    "new_run_id": "ids",
    "validate_run_id": "ids",
    "SCHEMA_NAME": "layout",
    "SCHEMA_VERSION": "layout",
    "Hits": "model",
    "Instrument": "model",
    "MeasuredFrf": "model",
    "Point": "model",
    "Run": "model",
    "RunPoints": "model",
    "Sample": "model",
    "Spectra": "model",
    "JoinedRun": "modal_tests",
    "ModalTest": "modal_tests",
    "create_test": "modal_tests",
    "join_run": "modal_tests",
    "list_tests": "modal_tests",
    "load_test": "modal_tests",
    "next_point": "modal_tests",
    "RunSummary": "reader",
    "open_run": "reader",
    "open_run_bytes": "reader",
    "read_hits": "reader",
    "read_summary": "reader",
    "read_result": "results",
    "write_result": "results",
    "Store": "store",
    "resolve_store_dir": "store",
    "verify": "verify",
    "seal": "writer",
}

if TYPE_CHECKING:  # what type checkers and readers see; nothing of it runs
    from daq.store.errors import ConfigError, NotARunError, StoreError
    from daq.store.ids import new_run_id, validate_run_id
    from daq.store.layout import SCHEMA_NAME, SCHEMA_VERSION
    from daq.store.modal_tests import (
        JoinedRun,
        ModalTest,
        create_test,
        join_run,
        list_tests,
        load_test,
        next_point,
    )
    from daq.store.model import Hits, Instrument, MeasuredFrf, Point, Run, RunPoints, Sample, Spectra
    from daq.store.reader import RunSummary, open_run, open_run_bytes, read_hits, read_summary
    from daq.store.results import read_result, write_result
    from daq.store.store import Store, resolve_store_dir
    from daq.store.verify import verify
    from daq.store.writer import seal


def __getattr__(name: str) -> object:
    module = _LAZY.get(name)
    if module is not None:
        value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    elif name.startswith("__"):
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    else:
        # A submodule (daq.store.reader, ...): once all were imported with the package.
        try:
            value = importlib.import_module(f"{__name__}.{name}")
        except ModuleNotFoundError as exc:
            if exc.name != f"{__name__}.{name}":
                raise
            raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    # The public names, loaded or not, and the submodules loaded so far; not this
    # file's own helpers.
    helpers = {"annotations", "importlib", "sys", "types", "TYPE_CHECKING"}
    return sorted((set(globals()) - helpers) | set(_LAZY))


class _Package(types.ModuleType):
    """The package's module object. Importing a submodule sets it as an attribute of
    its package: for daq.store.verify that would hide the function verify (the name
    daq.store.verify has always meant) behind the module, so that one is not set."""

    def __setattr__(self, name: str, value: object) -> None:
        if name in _LAZY and isinstance(value, types.ModuleType):
            return
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package

__all__ = [
    "SCHEMA_NAME",
    "SCHEMA_VERSION",
    "ConfigError",
    "Hits",
    "Instrument",
    "JoinedRun",
    "MeasuredFrf",
    "ModalTest",
    "NotARunError",
    "Point",
    "Run",
    "RunPoints",
    "RunSummary",
    "Sample",
    "Spectra",
    "Store",
    "StoreError",
    "create_test",
    "join_run",
    "list_tests",
    "load_test",
    "new_run_id",
    "next_point",
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
