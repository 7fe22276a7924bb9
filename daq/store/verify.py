"""Checking a run file end to end, reporting every problem instead of stopping at the first.

verify() reads every dataset completely, which makes HDF5 check each chunk's
fletcher32 sum, and every attribute, whose object headers carry their own HDF5
metadata checksums; then it decodes the run, which checks the schema, the required
groups and attributes, dtypes and the shapes against each other; last, that the
summary attribute listings read (daq/store/summary.py), if the run has one, agrees
with the data and with the file's size.
"""

from __future__ import annotations

import contextlib
import os
import stat
import time
from pathlib import Path

import h5py

from daq.store import layout
from daq.store.decode import check_schema, decode_run, nonfinite_problems
from daq.store.errors import StoreError
from daq.store.h5io import refuse_outside_references
from daq.store.reader import misnamed
from daq.store.summary import summary_problems

_EXPECTED_FILTERS = "gzip + shuffle + fletcher32"


def verify(path: Path | str) -> list[str]:
    """The problems found in the run file at ``path``; an empty list means it is sound.

    Never raises for a damaged or foreign file: damage is what it reports.
    """
    path = Path(path)
    if not path.is_file():
        return [f"{path}: no such file"]
    try:
        f = h5py.File(path, "r", locking=False)
    except Exception as exc:
        return [f"cannot open as HDF5 (truncated or damaged): {_short(exc)}"]
    problems: list[str] = []
    try:
        with f:
            _check(f, problems, path)
    except Exception as exc:  # closing a damaged file can fail too
        problems.append(f"unreadable: {_short(exc)}")
    return problems


def _check(f: h5py.File, problems: list[str], path: Path) -> None:
    try:
        refuse_outside_references(f)
    except StoreError as exc:
        problems.append(str(exc))
        return  # never read through a link to another file
    except Exception as exc:
        problems.append(f"metadata damaged (cannot walk the groups): {_short(exc)}")
        return
    try:
        check_schema(f)
    except Exception as exc:
        problems.append(_short(exc))
        return
    _read_everything(f, problems)
    if problems:
        return  # decoding damaged data would only repeat the same faults less clearly
    try:
        run = decode_run(f)
    except Exception as exc:
        problems.append(_short(exc))
        return
    problems.extend(nonfinite_problems(run))
    wrong = misnamed(path, run.run_id)
    if wrong is not None:
        problems.append(wrong)
    try:
        problems.extend(summary_problems(f, run, path.stat().st_size))
    except Exception as exc:
        problems.append(f"attribute /@{layout.ATTR_SUMMARY} unreadable: {_short(exc)}")


def _read_everything(f: h5py.File, problems: list[str]) -> None:
    objects: list[tuple[str, h5py.HLObject]] = [("/", f)]
    try:
        f.visititems(lambda name, obj: objects.append(("/" + name, obj)))
    except Exception as exc:
        problems.append(f"cannot list all objects: {_short(exc)}")
    for name, obj in objects:
        try:
            for key in obj.attrs:
                obj.attrs[key]
        except Exception as exc:
            problems.append(f"attributes of {name} unreadable (metadata damaged): {_short(exc)}")
        if not isinstance(obj, h5py.Dataset):
            continue
        if not (obj.compression == "gzip" and obj.shuffle and obj.fletcher32):
            problems.append(f"dataset {name} lacks {_EXPECTED_FILTERS} (has {_filters(obj)})")
        try:
            obj[()]
        except Exception as exc:
            problems.append(f"dataset {name} unreadable (checksum mismatch or damaged chunk): {_short(exc)}")


#: A temporary untouched this long is a crashed write's (a seal keeps its own fresh).
STALE_TEMPORARY_S = 3600.0


def _is_temporary(name: str) -> bool:
    # Seals write ".<run_id>.h5.tmp-<pid>-<hex>", exports and imports ".<name>.<random>.tmp".
    return name.startswith(layout.TMP_PREFIX) and (layout.TMP_MARKER in name or name.endswith(".tmp"))


def leftover_temporaries(store_dir: Path | str, older_than_s: float = STALE_TEMPORARY_S) -> list[Path]:
    """Hidden temporaries of crashed writes in the store folder (regular files untouched
    for ``older_than_s`` seconds), for `daq runs verify` to report. Never raises."""
    store_dir = Path(store_dir)
    now = time.time()
    found = []
    try:
        entries = list(os.scandir(store_dir))
    except OSError:
        return []
    for entry in entries:
        if not _is_temporary(entry.name):
            continue
        try:
            info = entry.stat(follow_symlinks=False)
        except OSError:
            continue
        if stat.S_ISREG(info.st_mode) and now - info.st_mtime >= older_than_s:
            found.append(store_dir / entry.name)
    return sorted(found)


def remove_temporaries(store_dir: Path | str, older_than_s: float = STALE_TEMPORARY_S) -> list[Path]:
    """`daq runs verify --repair`: delete leftover_temporaries(); the paths removed."""
    removed = []
    for path in leftover_temporaries(store_dir, older_than_s):
        with contextlib.suppress(FileNotFoundError):
            path.unlink()
            removed.append(path)
    return removed


def _filters(dset: h5py.Dataset) -> str:
    found = [
        n
        for n, on in (
            ("gzip", dset.compression == "gzip"),
            ("shuffle", dset.shuffle),
            ("fletcher32", dset.fletcher32),
        )
        if on
    ]
    return " + ".join(found) or "no filters"


def _short(exc: BaseException) -> str:
    text = " ".join(str(exc).split()) or type(exc).__name__
    return text if len(text) <= 200 else text[:197] + "..."
