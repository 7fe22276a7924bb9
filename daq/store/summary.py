"""The summary attribute: a run's listing line, written once at seal, read alone by listings.

``/@summary_json`` (layout.ATTR_SUMMARY) is one JSON object holding exactly what a
listing shows (RunSummary without the file name and the error):

    {"complete": true, "kind": "simulated", "n_accepted": 9, "n_hits": 10,
     "note": "...", "operator": "...", "run_id": "...", "size_bytes": 150528,
     "start_time": "..."}

``size_bytes`` is the size of the file as sealed, the summary attribute included:
a sealed run never changes, so a file of any other size was changed afterwards (an
edit through HDF5 allocates space) and its summary is not trusted. Nor is one that
is malformed in any way, too long, of the wrong type or naming another run: the
listing then reads the run's data as it did before the attribute existed, and
reports what it finds there. `daq runs verify` checks the summary against the data.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from daq.store import layout
from daq.store.h5io import MAX_HITS, compact_json
from daq.store.ids import is_run_id
from daq.store.model import RUN_KINDS, Run, check_iso_utc

#: The keys of the summary object, with the type of each value.
SUMMARY_TYPES: dict[str, type] = {
    "run_id": str,
    "start_time": str,
    "kind": str,
    "complete": bool,
    "n_hits": int,
    "n_accepted": int,
    "operator": str,
    "note": str,
    "size_bytes": int,
}
#: The longest summary read (bytes of JSON): a longer one is not trusted and the listing
#: reads the data instead (only a note of about a megabyte makes one this long).
MAX_SUMMARY_BYTES = 1024 * 1024
#: The size_bytes a summary is first written with: as many digits as any file size
#: (a petabyte), so that the real size later fits in the same attribute.
_SIZE_PLACEHOLDER = 10**15


def summary_of(run: Run, size_bytes: int) -> dict[str, Any]:
    """The summary object of ``run`` sealed into a file of ``size_bytes`` bytes."""
    hits = run.hits
    return {
        "run_id": run.run_id,
        "start_time": run.start_time,
        "kind": run.kind,
        "complete": bool(run.complete),
        "n_hits": 0 if hits is None else hits.n_hits,
        "n_accepted": 0 if hits is None else int(np.count_nonzero(hits.accepted)),
        "operator": run.operator,
        "note": run.note,
        "size_bytes": int(size_bytes),
    }


def write_summary(f: h5py.File, run: Run) -> None:
    """Add the summary attribute to the root of ``f`` (in memory) holding the file's final
    size: written first with room for any size, then rewritten in place, which leaves
    the file's layout and size unchanged."""
    width = len(compact_json(summary_of(run, _SIZE_PLACEHOLDER)).encode("utf-8"))
    dtype = h5py.string_dtype("utf-8", width)
    f.attrs.create(layout.ATTR_SUMMARY, np.array(b"", dtype=dtype))
    size = _image_size(f)
    for _ in range(3):
        text = compact_json(summary_of(run, size)).encode("utf-8")
        f.attrs.get_id(layout.ATTR_SUMMARY).write(np.array(text, dtype=dtype))
        now = _image_size(f)
        if now == size:
            return
        size = now
    raise RuntimeError("the file kept changing size while its summary was written")


def _image_size(f: h5py.File) -> int:
    f.flush()
    return len(f.id.get_file_image())


def summary_text(f: h5py.File) -> str | None:
    """The summary attribute's text, or None when it is absent or not a scalar
    fixed-length string of at most MAX_SUMMARY_BYTES (checked before it is read)."""
    if layout.ATTR_SUMMARY not in f.attrs:
        return None
    attr = f.attrs.get_id(layout.ATTR_SUMMARY)
    kind = attr.get_type()
    if (
        not isinstance(kind, h5py.h5t.TypeStringID)
        or kind.is_variable_str()
        or kind.get_size() > MAX_SUMMARY_BYTES
        or attr.shape != ()
    ):
        return None
    value = f.attrs[layout.ATTR_SUMMARY]
    if isinstance(value, np.ndarray) and value.shape == ():
        value = value[()]
    if isinstance(value, bytes):
        try:
            return value.decode("utf-8")
        except UnicodeDecodeError:
            return None
    return value if isinstance(value, str) else None


def read_root_summary(path: Path) -> str | None:
    """The summary text of the run file at ``path``, read from the root's attributes
    alone, or None when the file has none, is not a run of a schema version this code
    reads, or any attribute has an unexpected type. HDF5 errors (a damaged or
    truncated file) propagate.

    h5py's low-level interface: a listing does this for every run, and the
    high-level one spends three times as long around the same three reads."""
    fid = h5py.h5f.open(os.fsencode(path), h5py.h5f.ACC_RDONLY, fapl=_read_fapl())
    try:
        schema = _root_attribute(fid, layout.ATTR_SCHEMA, 256)
        version = _root_attribute(fid, layout.ATTR_SCHEMA_VERSION, 0)
        if (
            schema != layout.SCHEMA_NAME.encode()
            or not isinstance(version, int)
            or not 1 <= version <= layout.READ_SCHEMA_VERSION
        ):
            return None
        text = _root_attribute(fid, layout.ATTR_SUMMARY, MAX_SUMMARY_BYTES)
    finally:
        fid.close()
    if not isinstance(text, bytes):
        return None
    try:
        return text.decode("utf-8")
    except UnicodeDecodeError:
        return None


def _root_attribute(fid: h5py.h5f.FileID, name: str, max_text: int) -> bytes | int | None:
    """The scalar root attribute ``name``: bytes if it is a fixed-length string of at
    most ``max_text`` bytes, an int if it is an integer of at most 8 bytes, else None."""
    try:
        attr = h5py.h5a.open(fid, name.encode())
    except KeyError:  # no such attribute
        return None
    try:
        if attr.shape != ():
            return None
        kind = attr.get_type()
        if isinstance(kind, h5py.h5t.TypeStringID):
            if kind.is_variable_str() or kind.get_size() > max_text:
                return None
            text = np.empty((), dtype=f"S{kind.get_size()}")
            attr.read(text, mtype=kind)
            return bytes(text[()])
        if isinstance(kind, h5py.h5t.TypeIntegerID) and kind.get_size() <= 8:
            number = np.empty((), dtype=np.int64)
            attr.read(number)
            return int(number)
        return None
    finally:
        attr.close()


_FAPL: list[h5py.h5p.PropFAID] = []


def _read_fapl() -> h5py.h5p.PropFAID:
    """File access as the reader's h5py.File(..., locking=False): default driver, no lock."""
    if not _FAPL:
        fapl = h5py.h5p.create(h5py.h5p.FILE_ACCESS)
        fapl.set_file_locking(False, ignore_when_disabled=False)
        _FAPL.append(fapl)
    return _FAPL[0]


def parse_summary(text: str, run_id: str | None = None, size_bytes: int | None = None) -> dict[str, Any]:
    """The summary object in ``text``; ValueError (one line) unless it has exactly the
    keys of SUMMARY_TYPES with values of their types and of their ranges, names the run
    ``run_id`` and gives the size ``size_bytes`` (when these are given)."""
    try:
        value = json.loads(text, parse_constant=_no_constant)
    except (json.JSONDecodeError, RecursionError) as exc:
        raise ValueError(f"not JSON ({getattr(exc, 'msg', type(exc).__name__)})") from None
    if not isinstance(value, dict):
        raise ValueError(f"a JSON {type(value).__name__}, not an object")
    if set(value) != set(SUMMARY_TYPES):
        odd = sorted(set(value) ^ set(SUMMARY_TYPES))
        raise ValueError(f"keys missing or unknown: {', '.join(odd)}")
    for key, kind in SUMMARY_TYPES.items():
        # bool is an int in Python: JSON true must not pass for a count.
        if not isinstance(value[key], kind) or (kind is int and isinstance(value[key], bool)):
            raise ValueError(f"{key} is a {type(value[key]).__name__}, not a {kind.__name__}")
    if not is_run_id(value["run_id"]):
        raise ValueError(f"run_id {value['run_id']!r} is not a run id")
    if value["kind"] not in RUN_KINDS:
        raise ValueError(f"kind {value['kind']!r} is not one of {', '.join(RUN_KINDS)}")
    check_iso_utc(value["start_time"], "start_time")
    if not 0 <= value["n_accepted"] <= value["n_hits"] <= MAX_HITS:
        raise ValueError(f"counts out of range: {value['n_accepted']} of {value['n_hits']} hits accepted")
    if value["size_bytes"] <= 0:
        raise ValueError(f"size_bytes {value['size_bytes']} is not a file size")
    if run_id is not None and value["run_id"] != run_id:
        raise ValueError(f"it names run {value['run_id']!r}, the file is {run_id!r}")
    if size_bytes is not None and value["size_bytes"] != size_bytes:
        raise ValueError(f"it says the file has {value['size_bytes']} bytes, it has {size_bytes}")
    return value


def summary_problems(f: h5py.File, run: Run, size_bytes: int) -> list[str]:
    """What is wrong with the summary attribute of ``f``, whose data decode to ``run``
    and whose size is ``size_bytes`` (no attribute: nothing wrong, an older run)."""
    where = f"attribute /@{layout.ATTR_SUMMARY}"
    if layout.ATTR_SUMMARY not in f.attrs:
        return []
    text = summary_text(f)
    if text is None:
        return [f"{where} is not UTF-8 text of at most {MAX_SUMMARY_BYTES} bytes"]
    try:
        stored = parse_summary(text)
    except ValueError as exc:
        return [f"{where} is malformed: {exc}"]
    want = summary_of(run, size_bytes)
    wrong = [key for key in SUMMARY_TYPES if stored[key] != want[key]]
    if not wrong:
        return []
    shown = "; ".join(f"{key} {_short(stored[key])} there, {_short(want[key])} in the file" for key in wrong)
    return [f"{where} disagrees with the run: {shown}"]


def _short(value: object) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _no_constant(name: str) -> None:
    raise ValueError(f"{name} is not JSON")
