"""Named, versioned capture setups: ``<store>/setups/NAME.toml`` (docs/setups.md).

A setup is the setup file of ``daq capture --setup`` (daq/workflows/setup_codec.py
checks its keys) with, in each channel's table, an optional ``transducer = "<id>"``
naming a transducer of the store (daq/store/transducers.py) whose sensitivity then
replaces ``sensitivity_v_per_eu``. The store keeps the setup's text and a small
``[saved]`` table (name, version, saved_utc) at its end; the store does not judge
the settings themselves (the workflows do, daq/workflows/setups.py), only that the
file is a table of TOML values and tables.

Every save writes version n + 1 and keeps the text of version n as
``<store>/setups/.history/NAME.v<n>.toml``. A save may name the version it was made
from (``expected_version``; 0: the setup must be new): a different current version
is a :class:`VersionConflict` and nothing is written. Writing follows the runs'
protocol (writer.write_atomically: temporary, fsync, rename, folder fsync) under
``<store>/setups/.NAME.lock`` (flock).

The built-in setup ``default`` (version 0) is always listed: the capture's defaults
with the built-in transducers ``hammer-default`` and ``accel-default``. Saving a setup
named ``default`` stores it like any other (version 1).
"""

from __future__ import annotations

import contextlib
import errno
import math
import os
import re
from dataclasses import dataclass, field
from datetime import date, datetime
from pathlib import Path
from typing import Any

from daq.store.errors import StoreError
from daq.store.text_files import file_lock, now_utc, parse_toml, read_bounded, toml_string
from daq.store.writer import write_atomically

SETUPS_FOLDER = "setups"
HISTORY_FOLDER = ".history"
SETUP_SUFFIX = ".toml"
#: The table at the end of a stored setup that is the store's, not the settings'.
SAVED_TABLE = "saved"
DEFAULT_NAME = "default"
#: The built-in default: the capture's defaults (keys left out) with the built-in transducers.
DEFAULT_DATA: dict[str, Any] = {
    "hammer": {"transducer": "hammer-default"},
    "accelerometer": {"transducer": "accel-default"},
}
NAME_PATTERN = re.compile(r"[A-Za-z0-9._-]{1,64}")
#: A setup file larger than this is refused unread (a real one is under 1 kB).
MAX_FILE_BYTES = 2**20


class VersionConflict(StoreError):
    """A save made from another version than the current one (someone saved in between)."""

    def __init__(self, message: str, current: int = 0) -> None:
        super().__init__(message)
        self.current = current


@dataclass(frozen=True)
class StoredSetup:
    """One version of a named setup.

    name : the setup's name (also its file name). version : 1, 2, ... (0: the built-in
    default). saved_utc : ISO 8601 UTC time of the save ("" for the built-in).
    data : the setup-file dict (setup_codec keys, channels' optional "transducer").
    """

    name: str
    version: int
    saved_utc: str
    data: dict[str, Any] = field(default_factory=dict)

    def summary(self) -> dict[str, Any]:
        return {"name": self.name, "version": self.version, "saved_utc": self.saved_utc}


def check_setup_name(name: object) -> str:
    """``name`` if it is a plain setup name ([A-Za-z0-9._-]{1,64}, not starting with a
    dot), else StoreError."""
    if not isinstance(name, str) or not NAME_PATTERN.fullmatch(name) or name.startswith("."):
        raise StoreError(f"setup name {name!r}: not a plain name (letters, digits, . _ -, 1 to 64)")
    if name.endswith(SETUP_SUFFIX):
        raise StoreError(f"setup name {name!r}: give the name without {SETUP_SUFFIX}")
    return name


class SetupStore:
    """The named setups of store ``store_dir``."""

    def __init__(self, store_dir: Path | str) -> None:
        self.store_dir = Path(store_dir)
        self.folder = self.store_dir / SETUPS_FOLDER
        self.history_folder = self.folder / HISTORY_FOLDER

    def path(self, name: str) -> Path:
        return self.folder / f"{check_setup_name(name)}{SETUP_SUFFIX}"

    def names(self) -> list[str]:
        """Every setup's name, sorted; "default" always among them."""
        names = {DEFAULT_NAME}
        try:
            entries = os.listdir(self.folder)
        except FileNotFoundError:
            entries = []
        except OSError as exc:
            raise StoreError(f"cannot list {self.folder}: {os.strerror(exc.errno or 0)}") from None
        for entry in entries:
            if not entry.endswith(SETUP_SUFFIX):
                continue
            stem = entry[: -len(SETUP_SUFFIX)]
            with contextlib.suppress(StoreError):
                names.add(check_setup_name(stem))
        return sorted(names)

    def list(self) -> list[StoredSetup]:
        """The current version of every setup, by name (a damaged file: StoreError)."""
        return [self.get(name) for name in self.names()]

    def get(self, name: str, version: int | None = None) -> StoredSetup:
        """Setup ``name`` as it is now, or its ``version`` from the history; StoreError
        (one line, naming the file) if there is none or its file does not check."""
        path = self.path(name)
        if not path.is_file() and name == DEFAULT_NAME:
            if version not in (None, 0):
                raise StoreError(f"setup {name} has no version {version} (the built-in is version 0)")
            return StoredSetup(DEFAULT_NAME, 0, "", _copy(DEFAULT_DATA))
        if not path.is_file():
            known = ", ".join(self.names())
            raise StoreError(f"no setup {name!r} in {self.store_dir} (known: {known})")
        current = _read(path, name)
        if version is None or version == current.version:
            return current
        old = self.history_folder / f"{name}.v{version}{SETUP_SUFFIX}"
        if isinstance(version, bool) or not isinstance(version, int) or not old.is_file():
            raise StoreError(f"setup {name} has no version {version!r} (current: {current.version})")
        return _read(old, name)

    def history(self, name: str) -> list[StoredSetup]:
        """Every version of setup ``name`` kept, oldest first, the current one last."""
        current = self.get(name)
        found = []
        for n in range(1, current.version):
            old = self.history_folder / f"{name}.v{n}{SETUP_SUFFIX}"
            if old.is_file():
                found.append(_read(old, name))
        return [*found, current]

    def put(self, name: str, data: dict[str, Any], expected_version: int | None = None) -> StoredSetup:
        """Save ``data`` as the next version of setup ``name``; the StoredSetup written.

        expected_version : the version the change was made from (0: the setup must be
        new); VersionConflict when the current one differs. None: no check.
        StoreError (nothing written) for a bad name or data that is not a table of
        TOML values (the settings themselves are the workflows' to check).
        """
        path = self.path(name)
        if expected_version is not None and (
            isinstance(expected_version, bool)
            or not isinstance(expected_version, int)
            or expected_version < 0
        ):
            raise StoreError(f"version: must be a whole number >= 0, got {expected_version!r}")
        body = dump_data(data, f"setup {name}")
        with file_lock(self.folder, f".{name}.lock", f"setup {name}"):
            old_text = None
            current = 0
            if path.is_file():
                current = _read(path, name).version
                with open(path, "rb") as fh:
                    old_text = fh.read()
            if expected_version is not None and expected_version != current:
                if current == 0:
                    text = f"setup {name}: version {expected_version} was changed, but it does not exist yet"
                elif expected_version == 0:
                    text = f"setup {name} exists already (version {current}); choose another name"
                else:
                    text = (
                        f"setup {name}: version {expected_version} was changed, but it is at version "
                        f"{current} now (someone saved it meanwhile)"
                    )
                raise VersionConflict(text, current)
            saved = StoredSetup(name, current + 1, now_utc(), _copy(data))
            text = body + _saved_table(saved)
            if old_text is not None:
                write_atomically(
                    self.history_folder,
                    self.history_folder / f"{name}.v{current}{SETUP_SUFFIX}",
                    old_text,
                    what=f"setup {name} version {current}",
                    overwrite=True,
                )
            write_atomically(self.folder, path, text.encode("utf-8"), what=f"setup {name}", overwrite=True)
        return saved

    def text(self, name: str) -> str:
        """The TOML text of setup ``name`` as stored (the built-in's as it would be)."""
        path = self.path(name)
        if path.is_file():
            return path.read_text(encoding="utf-8")
        stored = self.get(name)
        return dump_data(stored.data, f"setup {name}") + _saved_table(stored)


def strip_saved(doc: dict[str, Any]) -> dict[str, Any]:
    """A setup file's dict without the store's ``[saved]`` table (a stored setup's file
    passed as ``--setup FILE.toml`` reads as its settings)."""
    return {k: v for k, v in doc.items() if k != SAVED_TABLE}


def _read(path: Path, name: str) -> StoredSetup:
    try:
        doc = parse_toml(read_bounded(path, MAX_FILE_BYTES, str(path)), str(path))
    except FileNotFoundError:
        raise StoreError(f"cannot read {path}: {os.strerror(errno.ENOENT)}") from None
    saved = doc.get(SAVED_TABLE)
    if not isinstance(saved, dict):
        raise StoreError(f"{path}: [{SAVED_TABLE}]: missing (the store's name, version, saved_utc)")
    version = saved.get("version")
    if isinstance(version, bool) or not isinstance(version, int) or version < 1:
        raise StoreError(f"{path}: saved.version: must be a whole number >= 1, got {version!r}")
    if saved.get("name") != name:
        raise StoreError(f"{path}: saved.name: names setup {saved.get('name')!r}, not {name!r}")
    saved_utc = saved.get("saved_utc")
    if not isinstance(saved_utc, str):
        raise StoreError(f"{path}: saved.saved_utc: must be an ISO 8601 UTC text")
    data = strip_saved(doc)
    for key, value in data.items():
        if isinstance(value, dict):
            for sub, v in value.items():
                if isinstance(v, (dict, list, date, datetime)):
                    raise StoreError(f"{path}: {key}.{sub}: must be a number, text or true/false")
        elif isinstance(value, (list, date, datetime)):
            raise StoreError(f"{path}: {key}: must be a number, text, true/false or a table")
    return StoredSetup(name, version, saved_utc, data)


def dump_data(data: object, what: str) -> str:
    """The TOML text of setup ``data``: its values, then each table; StoreError for
    anything a setup cannot hold (nested tables, lists, non-finite numbers)."""
    if not isinstance(data, dict):
        raise StoreError(f"{what}: the setup must be a table of settings")
    if SAVED_TABLE in data:
        raise StoreError(f"{what}: {SAVED_TABLE}: a name the store keeps for itself")
    lines = ["# A capture setup of cantilever-daq (docs/setups.md, docs/capture.md)."]
    tables = []
    for key, value in data.items():
        _check_key(key, what)
        if isinstance(value, dict):
            tables.append((key, value))
        else:
            lines.append(f"{key} = {_value(value, what, key)}")
    for key, table in tables:
        lines += ["", f"[{key}]"]
        for sub, value in table.items():
            _check_key(sub, what)
            if isinstance(value, dict):
                raise StoreError(f"{what}: {key}.{sub}: must be a number, text or true/false")
            lines.append(f"{sub} = {_value(value, what, f'{key}.{sub}')}")
    return "\n".join(lines) + "\n"


def _saved_table(saved: StoredSetup) -> str:
    return (
        f"\n[{SAVED_TABLE}]  # the store's: which setup and version this is\n"
        f"name = {toml_string(saved.name)}\nversion = {saved.version}\n"
        f"saved_utc = {toml_string(saved.saved_utc)}\n"
    )


def _check_key(key: object, what: str) -> None:
    if not isinstance(key, str) or not re.fullmatch(r"[A-Za-z0-9_-]{1,64}", key):
        raise StoreError(f"{what}: {key!r}: not a setting's name")


def _value(value: object, what: str, key: str) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if not math.isfinite(value):
            raise StoreError(f"{what}: {key}: must be a finite number")
        return repr(value)
    if isinstance(value, str):
        return toml_string(value)
    raise StoreError(f"{what}: {key}: must be a number, text or true/false, got {type(value).__name__}")


def _copy(data: dict[str, Any]) -> dict[str, Any]:
    return {k: dict(v) if isinstance(v, dict) else v for k, v in data.items()}
