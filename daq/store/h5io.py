"""Low-level HDF5 helpers shared by the writer, reader and verifier.

Strings are stored as fixed-length UTF-8, never as variable-length strings:
variable-length strings live in HDF5's global heap, which carries no checksum, so a
flipped byte there would go unnoticed. Fixed-length strings sit inside checksummed
object headers (attributes) or fletcher32-checked chunks (datasets).
"""

from __future__ import annotations

import json
from typing import Any

import h5py
import numpy as np

from daq.store import layout
from daq.store.errors import StoreError

# --- writing ------------------------------------------------------------------------


def set_text(obj: h5py.HLObject, name: str, text: str) -> None:
    """Attribute ``name`` = ``text`` as a fixed-length UTF-8 string."""
    data = text.encode("utf-8")
    # Length 0 is not a valid HDF5 string type; "" is stored as one NUL of padding.
    obj.attrs.create(name, np.array(data, dtype=h5py.string_dtype("utf-8", max(len(data), 1))))


def compact_json(value: Any) -> str:
    """JSON text with sorted keys and no spaces (NaN refused: it is not JSON)."""
    return json.dumps(value, sort_keys=True, allow_nan=False, separators=(",", ":"))


def set_json(obj: h5py.HLObject, name: str, value: Any) -> None:
    set_text(obj, name, compact_json(value))


def set_number(obj: h5py.HLObject, name: str, value: float | int | bool) -> None:
    if isinstance(value, bool):
        obj.attrs.create(name, np.bool_(value))
    elif isinstance(value, int):
        obj.attrs.create(name, np.int64(value))
    else:
        obj.attrs.create(name, np.float64(value))


def nx_group(parent: h5py.Group, name: str, nx_class: str) -> h5py.Group:
    group = parent.create_group(name)
    set_text(group, layout.ATTR_NX_CLASS, nx_class)
    return group


def text_array(strings: np.ndarray | list[str]) -> np.ndarray:
    """(n,) str -> (n,) fixed-length UTF-8 bytes array for a dataset."""
    encoded = [str(s).encode("utf-8") for s in strings]
    width = max([len(e) for e in encoded] + [1])
    return np.array(encoded, dtype=h5py.string_dtype("utf-8", width))


def add_dataset(
    group: h5py.Group, name: str, data: np.ndarray, units: str | None = None, long_name: str | None = None
) -> h5py.Dataset:
    """A dataset with gzip + shuffle + fletcher32 (chunked, as fletcher32 requires)."""
    data = np.asarray(data)
    if data.size == 0:
        raise StoreError(f"internal: refusing to write empty dataset {name} (chunked datasets need data)")
    dset = group.create_dataset(
        name,
        data=data,
        chunks=_chunks(data),
        compression="gzip",
        compression_opts=layout.GZIP_LEVEL,
        shuffle=True,
        fletcher32=True,
        track_times=False,  # no wall-clock in object headers: identical runs give identical files
    )
    if units is not None:
        set_text(dset, layout.ATTR_UNITS, units)
    if long_name is not None:
        set_text(dset, layout.ATTR_LONG_NAME, long_name)
    return dset


def _chunks(data: np.ndarray) -> tuple[int, ...]:
    # One row of records per chunk keeps a single hit readable without inflating
    # the others; small arrays are one chunk. Chunks stay below ~1 MiB.
    if data.ndim >= 2 and data.nbytes > 256 * 1024:
        return (1, *data.shape[1:])
    if data.ndim == 1 and data.nbytes > 1024 * 1024:
        return (max(1, (1024 * 1024) // data.itemsize),)
    return data.shape


# --- reading ------------------------------------------------------------------------


def get_text(obj: h5py.HLObject, name: str) -> str:
    value = _attr(obj, name)
    if isinstance(value, bytes):
        return value.decode("utf-8")
    if isinstance(value, str):
        return value
    raise StoreError(f"attribute {obj.name}@{name} should be text, found {type(value).__name__}")


def get_json(obj: h5py.HLObject, name: str) -> Any:
    try:
        return json.loads(get_text(obj, name))
    except json.JSONDecodeError as exc:
        raise StoreError(f"attribute {obj.name}@{name} is not valid JSON ({exc.msg})") from None


def get_float(obj: h5py.HLObject, name: str) -> float:
    value = _attr(obj, name)
    if not isinstance(value, (np.floating, np.integer, float, int)) or isinstance(value, (bool, np.bool_)):
        raise StoreError(f"attribute {obj.name}@{name} should be a number, found {type(value).__name__}")
    return float(value)


def get_bool(obj: h5py.HLObject, name: str) -> bool:
    value = _attr(obj, name)
    if not isinstance(value, (bool, np.bool_)):
        raise StoreError(f"attribute {obj.name}@{name} should be a bool, found {type(value).__name__}")
    return bool(value)


def get_int(obj: h5py.HLObject, name: str) -> int:
    value = _attr(obj, name)
    if not isinstance(value, (int, np.integer)) or isinstance(value, (bool, np.bool_)):
        raise StoreError(f"attribute {obj.name}@{name} should be an integer, found {type(value).__name__}")
    return int(value)


def _attr(obj: h5py.HLObject, name: str) -> Any:
    if name not in obj.attrs:
        raise StoreError(f"attribute {obj.name}@{name} is missing")
    value = obj.attrs[name]
    if isinstance(value, np.ndarray) and value.shape == ():
        value = value[()]
    return value


def get_group(parent: h5py.Group, path: str, required: bool = True) -> h5py.Group | None:
    """The group at ``path`` below ``parent``, reached through hard links only
    (so that even a partial read never follows a link into another file)."""
    node = parent
    for part in path.split("/"):
        link = node.get(part, getlink=True) if isinstance(node, h5py.Group) else None
        if link is None:
            if not required:
                return None
            raise StoreError(f"group /{path} is missing")
        if not isinstance(link, h5py.HardLink):
            raise StoreError(f"/{path} goes through a {type(link).__name__}; refused")
        node = node[part]
    if not isinstance(node, h5py.Group):
        raise StoreError(f"/{path} should be a group")
    return node


def dataset(group: h5py.Group, name: str, required: bool = True) -> h5py.Dataset | None:
    """The dataset ``group/name`` (nothing read), None if absent and optional; StoreError
    if it is missing or is not a dataset."""
    node = group.get(name)
    if node is None and not required:
        return None
    if not isinstance(node, h5py.Dataset):
        where = f"{group.name}/{name}"
        raise StoreError(f"dataset {where} is missing" if node is None else f"{where} should be a dataset")
    return node


def get_array(
    group: h5py.Group, name: str, kinds: str, ndim: int, required: bool = True
) -> np.ndarray | None:
    """The whole dataset ``group/name`` (HDF5 checks its fletcher32 sums on this read)."""
    node = dataset(group, name, required)
    if node is None:
        return None
    if not node.fletcher32:
        raise StoreError(f"dataset {node.name} has no fletcher32 checksum; refused as not written by us")
    if node.dtype.kind not in kinds or node.ndim != ndim:
        raise StoreError(
            f"dataset {node.name} has dtype {node.dtype} and {node.ndim} dimensions, "
            f"expected kind {kinds!r} and {ndim} dimensions"
        )
    check_declared_size(node)  # before the read: memory follows the declared shape
    return node[()]


def get_text_array(group: h5py.Group, name: str, required: bool = True) -> list[str] | None:
    raw = get_array(group, name, "S", 1, required)
    if raw is None:
        return None
    try:
        return [item.decode("utf-8") for item in raw]
    except UnicodeDecodeError:
        raise StoreError(f"dataset {group.name}/{name} holds text that is not UTF-8") from None


_MAX_DEPTH = 8

#: The most the datasets of one file may declare, each and all together, counted as
#: their size once read (shape x item size: decompressed, fill values included). A real
#: run is far below: 100 hits x 65,536 complex samples on two channels is 200 MiB.
MAX_FILE_BYTES = 512 * 2**20
#: The most one chunk may declare (our writer's chunks are one record row, <= a few MiB).
MAX_CHUNK_BYTES = 64 * 2**20
#: Hits in one run: far above any impact test, low enough to list without reading data.
MAX_HITS = 100_000
#: Objects (groups and datasets) in one file: ours hold a few dozen.
MAX_OBJECTS = 10_000

# --- safety -------------------------------------------------------------------------


def declared_bytes(dset: h5py.Dataset) -> int:
    """What reading ``dset`` whole costs in memory: shape x item size (Python ints, no overflow)."""
    total = int(dset.dtype.itemsize)
    for extent in dset.shape or ():
        total *= int(extent)
    return total


def check_declared_size(dset: h5py.Dataset, limit: int = MAX_FILE_BYTES) -> int:
    """StoreError unless ``dset`` and its chunks declare at most ``limit`` / MAX_CHUNK_BYTES
    bytes; its declared size. Only metadata is read: nothing is allocated for the data."""
    size = declared_bytes(dset)
    if size > limit:
        raise StoreError(
            f"dataset {dset.name} declares {size} bytes ({tuple(dset.shape or ())} x "
            f"{dset.dtype.itemsize}), more than the limit of {limit} bytes; refused"
        )
    chunk = int(dset.dtype.itemsize)
    for extent in dset.chunks or ():
        chunk *= int(extent)
    if chunk > MAX_CHUNK_BYTES:
        raise StoreError(
            f"dataset {dset.name} declares chunks of {chunk} bytes, more than the limit of "
            f"{MAX_CHUNK_BYTES} bytes; refused"
        )
    return size


def refuse_outside_references(root: h5py.Group) -> int:
    """StoreError if any object links or maps to data outside this file, has more than
    one name, or if the datasets declare more than MAX_FILE_BYTES; the bytes declared.

    External links, soft links (which could loop or dangle), virtual datasets and
    datasets with external raw storage are all refused: a run file must be
    self-contained, and reading one must never open another file. An object with
    several names (hard links: our writer never makes them) is refused too, and each
    object is visited once, by its address: otherwise a few groups linking 30 times
    to the next would make 30**7 paths to walk. Only metadata is read.
    """
    pending = [(root, 0)]
    seen: set[tuple[int, int]] = set()
    total = 0
    while pending:
        group, depth = pending.pop()
        if depth > _MAX_DEPTH:
            raise StoreError(f"{group.name} is nested more than {_MAX_DEPTH} groups deep; refused")
        for name in group:
            link = group.get(name, getlink=True)
            where = f"{group.name.rstrip('/')}/{name}"
            if isinstance(link, h5py.ExternalLink):
                target = f"{link.filename}:{link.path}"
                raise StoreError(f"{where} is an external link (linked to {target}); refused")
            if isinstance(link, h5py.SoftLink):
                raise StoreError(f"{where} is a soft link to {link.path}; refused")
            node = group[name]  # not .get(): a damaged object must raise, not read as None
            info = h5py.h5o.get_info(node.id)
            if info.rc != 1:
                raise StoreError(f"{where} has {info.rc} names (hard links); refused")
            key = (int(info.fileno), int(info.addr))
            if key in seen:  # unreachable with rc == 1, kept so the walk ends whatever HDF5 says
                raise StoreError(f"{where} is reached twice; refused")
            seen.add(key)
            if len(seen) > MAX_OBJECTS:
                raise StoreError(f"more than {MAX_OBJECTS} objects in the file; refused")
            if isinstance(node, h5py.Group):
                pending.append((node, depth + 1))
            elif isinstance(node, h5py.Dataset):
                if node.is_virtual:
                    raise StoreError(f"{where} is a virtual dataset (maps data from other files); refused")
                if node.external:
                    raise StoreError(f"{where} stores its data in external raw files; refused")
                total += check_declared_size(node)
                if total > MAX_FILE_BYTES:
                    raise StoreError(
                        f"the datasets declare more than {MAX_FILE_BYTES} bytes together "
                        f"(at {where}); refused"
                    )
            else:
                raise StoreError(f"{where} is a {type(node).__name__}, not a group or dataset; refused")
    return total
