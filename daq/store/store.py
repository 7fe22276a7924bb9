"""A folder of runs: where it is, what is in it, and picking a run by id or prefix.

Only files named exactly ``<run_id>.h5`` are runs. Hidden temporaries
(``.<run_id>.h5.tmp-...``), hit journals (``.journal-...``), result files
(``<run_id>.<name>.h5``) and the index cache are never listed.

Listing the store (``list``) and getting it ready for writing (``ensure_writable``)
first seal every hit journal left by a capture that died (daq/store/journal.py) as an
incomplete run, saying so in one line on stderr.
"""

from __future__ import annotations

import contextlib
import os
import sys
import time
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from daq.store import layout
from daq.store.config import APP_DIR, load_config
from daq.store.errors import StoreError
from daq.store.ids import RUN_ID_PATTERN, validate_run_id_prefix
from daq.store.index import cached_summaries
from daq.store.journal import recover
from daq.store.summary_model import RunSummary

if TYPE_CHECKING:
    from daq.store.model import Run

# What reads or writes HDF5 (numpy, h5py) is imported where it is used, not here: a
# listing served from the index needs neither, and `daq runs list` starts faster.

#: The name of the newest run in every command that takes a run.
LATEST = "latest"


def resolve_store_dir(option: str | None, env: Mapping[str, str] | None = None) -> tuple[Path, str]:
    """The store folder and where that choice came from, in order of precedence:

    the --store option, $DAQ_STORE, the config file's ``store`` key, and finally the
    per-user data folder ($XDG_DATA_HOME or ~/.local/share)/cantilever-daq/runs.
    """
    env = os.environ if env is None else env
    if option:
        return Path(option).expanduser().absolute(), "--store option"
    if env.get("DAQ_STORE"):
        return Path(env["DAQ_STORE"]).expanduser().absolute(), "$DAQ_STORE"
    config = load_config(env=env)
    if config.store is not None:
        return config.store.absolute(), f"config file {config.path}"
    base = Path(env["XDG_DATA_HOME"]) if env.get("XDG_DATA_HOME") else Path.home() / ".local" / "share"
    return (base / APP_DIR / "runs").absolute(), "default per-user data folder"


def is_run_file_name(name: str) -> bool:
    return (
        name.endswith(layout.RUN_SUFFIX)
        and RUN_ID_PATTERN.fullmatch(name[: -len(layout.RUN_SUFFIX)]) is not None
    )


def is_temporary_name(name: str) -> bool:
    return name.startswith(layout.TMP_PREFIX) and layout.TMP_MARKER in name


class Store:
    """The runs in folder ``path`` (which need not exist until the first seal)."""

    def __init__(self, path: Path | str) -> None:
        self.path = Path(path)

    def __repr__(self) -> str:
        return f"Store({str(self.path)!r})"

    def ensure_writable(self) -> None:
        """Create the folder if need be and check that runs can be sealed into it, so
        that a capture fails before the first hit rather than after the last."""
        if self.path.exists() and not self.path.is_dir():
            raise StoreError(f"store {self.path} is a file, not a folder; give --store a folder")
        try:
            self.path.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise StoreError(f"cannot create store folder {self.path}: {exc.strerror or exc}") from None
        if not os.access(self.path, os.W_OK | os.X_OK):
            raise StoreError(f"store folder {self.path} is not writable by this user")
        self.recover_journals()

    def recover_journals(self) -> list[str]:
        """Seal the hit journals of captures that died as incomplete runs (each said in
        one line on stderr); the lines."""
        lines = recover(self.path)
        for line in lines:
            with contextlib.suppress(OSError, ValueError):
                sys.stderr.write(f"daq: {line}\n")
                sys.stderr.flush()
        return lines

    def seal(self, run: Run) -> Path:
        """Write ``run`` atomically into the store (never overwriting); its path."""
        from daq.store.writer import seal

        return seal(run, self.path)

    def list(self) -> list[RunSummary]:
        """One summary per run file, sorted by run id (that is, by creation time).

        Damaged files are listed too, with ``error`` saying what is wrong. Hit journals
        of dead captures are sealed first (``recover_journals``).
        """
        self.recover_journals()
        files = [(entry.name, st.st_size, st.st_mtime_ns) for entry, st in self._entries(is_run_file_name)]
        files.sort()
        return cached_summaries(self.path, files, _summary_or_error)

    def resolve(self, name: str) -> Path:
        """The file of the run whose id is ``name`` or starts with ``name``.

        Accepts ``<id>.h5`` too, and ``latest`` for the newest run (ids sort by time,
        and a run id never starts with a letter). StoreError if no run or several match.
        """
        if isinstance(name, str) and name.endswith(layout.RUN_SUFFIX):
            name = name[: -len(layout.RUN_SUFFIX)]
        ids = sorted(e.name[: -len(layout.RUN_SUFFIX)] for e, _ in self._entries(is_run_file_name))
        if name == LATEST:
            if not ids:
                raise StoreError(f"no runs in {self.path}")
            return self.path / f"{ids[-1]}{layout.RUN_SUFFIX}"
        prefix = validate_run_id_prefix(name)
        if prefix in ids:
            return self.path / f"{prefix}{layout.RUN_SUFFIX}"
        matches = [run_id for run_id in ids if run_id.startswith(prefix)]
        if not matches:
            raise StoreError(f"no run matches {prefix!r} in {self.path}")
        if len(matches) > 1:
            shown = ", ".join(matches[:3]) + (", ..." if len(matches) > 3 else "")
            raise StoreError(
                f"{prefix!r} matches {len(matches)} runs in {self.path} ({shown}); type more of the id"
            )
        return self.path / f"{matches[0]}{layout.RUN_SUFFIX}"

    def open(self, name: str) -> Run:
        """The run picked by id or unique prefix."""
        from daq.store.reader import open_run

        return open_run(self.resolve(name))

    def verify(self, name: str) -> list[str]:
        """verify() of the run picked by id or unique prefix."""
        from daq.store.verify import verify

        return verify(self.resolve(name))

    def write_result(self, run_id: str, name: str, payload: dict[str, Any], overwrite: bool = False) -> Path:
        from daq.store.results import write_result

        return write_result(self.path, run_id, name, payload, overwrite=overwrite)

    def read_result(self, run_id: str, name: str) -> dict[str, Any]:
        from daq.store.results import read_result

        return read_result(self.path, run_id, name)

    def temporaries(self) -> list[Path]:
        """Hidden temporary files left by interrupted seals (or seals in progress)."""
        return sorted(self.path / e.name for e, _ in self._entries(is_temporary_name))

    def clean_temporaries(self, older_than_s: float = 3600.0) -> list[Path]:
        """Delete temporaries not modified for ``older_than_s`` seconds; the paths deleted.

        A seal in progress keeps its temporary's mtime fresh, so a threshold well above
        the time one seal takes (milliseconds to seconds) never removes live work.
        """
        removed = []
        now_ns = time.time_ns()
        for entry, st in self._entries(is_temporary_name):
            if now_ns - st.st_mtime_ns >= older_than_s * 1e9:
                with contextlib.suppress(FileNotFoundError):
                    (self.path / entry.name).unlink()
                    removed.append(self.path / entry.name)
        return sorted(removed)

    def _entries(self, wanted) -> list[tuple[os.DirEntry, os.stat_result]]:
        try:
            scan = list(os.scandir(self.path))
        except FileNotFoundError:
            return []  # a store nothing was sealed into yet is an empty store
        except OSError as exc:
            raise StoreError(f"cannot read store folder {self.path}: {os.strerror(exc.errno or 0)}") from None
        out = []
        for entry in scan:
            if not wanted(entry.name):
                continue
            try:
                st = entry.stat(follow_symlinks=False)
            except FileNotFoundError:
                continue  # removed while we looked
            out.append((entry, st))
        return out


def _summary_or_error(path: Path) -> RunSummary:
    from daq.store.reader import read_summary

    try:
        return read_summary(path)
    except StoreError as exc:
        size = path.stat().st_size if path.exists() else 0
        return RunSummary(
            path.name, path.name[: -len(layout.RUN_SUFFIX)], "", "", False, 0, 0, "", "", size, str(exc)
        )
