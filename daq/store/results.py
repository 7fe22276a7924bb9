"""Results computed from a run (analysis, fits), each in a file of its own beside the run.

``<store>/<run_id>.<name>.h5`` is written with the same atomic protocol as a run
(writer.write_atomically). The run file itself is never touched. A payload is a
dict: numpy arrays become datasets (gzip + shuffle + fletcher32), every other value
must be JSON-able and is kept together as one JSON text dataset, so that it is
checksummed as well.
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from daq.store import layout
from daq.store.errors import StoreError
from daq.store.h5io import (
    add_dataset,
    compact_json,
    get_array,
    get_group,
    get_int,
    get_text,
    set_number,
    set_text,
)
from daq.store.ids import validate_run_id
from daq.store.model import SOFTWARE
from daq.store.reader import open_h5
from daq.store.writer import build_image, run_path, write_atomically

# No dots: "<run_id>.<name>.h5" must never look like a run file "<run_id>.h5".
RESULT_NAME_PATTERN = re.compile(r"[a-z0-9][a-z0-9_-]{0,63}")
_KEY_PATTERN = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_-]{0,63}")


def result_path(store_dir: Path | str, run_id: str, name: str) -> Path:
    validate_run_id(run_id)
    if not isinstance(name, str) or RESULT_NAME_PATTERN.fullmatch(name) is None:
        raise StoreError(f"invalid result name {name!r}: use lower-case letters, digits, _ and - (max 64)")
    return Path(store_dir) / f"{run_id}.{name}{layout.RUN_SUFFIX}"


def write_result(
    store_dir: Path | str, run_id: str, name: str, payload: dict[str, Any], overwrite: bool = False
) -> Path:
    """Store ``payload`` as result ``name`` of run ``run_id``; return the file's path.

    payload: {key: numpy array (numbers or bools, non-empty) | JSON-able value}.
    overwrite: replace an existing result of that name (atomically) instead of refusing.
    """
    store_dir = Path(store_dir)
    final = result_path(store_dir, run_id, name)
    if not run_path(store_dir, run_id).is_file():
        raise StoreError(f"no run {run_id} in {store_dir}: a result needs its run")
    arrays, values = _split(payload)

    def fill(f: h5py.File) -> None:
        set_text(f, layout.ATTR_SCHEMA, layout.RESULT_SCHEMA_NAME)
        set_number(f, layout.ATTR_SCHEMA_VERSION, layout.RESULT_SCHEMA_VERSION)
        set_text(f, layout.ATTR_CREATOR, SOFTWARE)
        set_text(f, "run_id", run_id)
        set_text(f, "name", name)
        group = f.create_group(layout.RESULT_GROUP)
        set_text(group, layout.ATTR_NX_CLASS, "NXcollection")
        for key, array in arrays.items():
            add_dataset(group, key, array)
        add_dataset(group, layout.D_RESULT_JSON, np.array(compact_json(values).encode("utf-8")).reshape(1))

    what = f"result {name} of run {run_id}"
    return write_atomically(store_dir, final, build_image(fill, what), what, overwrite=overwrite)


def read_result(store_dir: Path | str, run_id: str, name: str) -> dict[str, Any]:
    """The payload stored by write_result (arrays bit-exact, other values from JSON)."""
    path = result_path(store_dir, run_id, name)
    if not path.is_file():
        raise StoreError(f"run {run_id} has no result {name!r} in {store_dir}")
    with open_h5(path) as f:
        if get_text(f, layout.ATTR_SCHEMA) != layout.RESULT_SCHEMA_NAME:
            raise StoreError("not a result file")
        if get_int(f, layout.ATTR_SCHEMA_VERSION) > layout.RESULT_SCHEMA_VERSION:
            raise StoreError("result schema version is newer than this software reads")
        if get_text(f, "run_id") != run_id or get_text(f, "name") != name:
            raise StoreError("result file names a different run or result than its file name")
        group = get_group(f, layout.RESULT_GROUP)
        raw = get_array(group, layout.D_RESULT_JSON, "S", 1)
        try:
            payload: dict[str, Any] = json.loads(raw[0].decode("utf-8"))
        except (ValueError, IndexError):
            raise StoreError(f"{layout.RESULT_GROUP}/{layout.D_RESULT_JSON} is not JSON text") from None
        for key in group:
            if key != layout.D_RESULT_JSON:
                node = group[key]
                payload[key] = get_array(group, key, "biufc", node.ndim)
        return payload


def _split(payload: object) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    if not isinstance(payload, dict):
        raise StoreError(f"a result payload must be a dict, got {type(payload).__name__}")
    arrays: dict[str, np.ndarray] = {}
    values: dict[str, Any] = {}
    for key, value in payload.items():
        if not isinstance(key, str) or _KEY_PATTERN.fullmatch(key) is None or key == layout.D_RESULT_JSON:
            raise StoreError(f"invalid result key {key!r}: letters, digits, _ and - only")
        if isinstance(value, np.ndarray):
            if value.dtype.kind not in "biufc" or value.size == 0:
                raise StoreError(
                    f"result array {key!r} must be non-empty numbers or bools, got {value.dtype}"
                )
            arrays[key] = value
        else:
            values[key] = value
    try:
        compact_json(values)
    except (TypeError, ValueError) as exc:
        raise StoreError(f"result values are not JSON-able (use numpy arrays for arrays): {exc}") from None
    return arrays, values
