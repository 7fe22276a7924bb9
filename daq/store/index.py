"""A cache of run summaries in SQLite, so listing 1,000 runs does not open 1,000 files.

The cache (``.index.sqlite`` in the store folder) is never the only copy of anything:
each row is keyed by file name, size and mtime_ns and used only while the file still
matches; rows of vanished files are dropped; a corrupt, foreign or locked database is
deleted and rebuilt, and if even that fails the listing reads the files directly.
WAL mode and a busy timeout let several processes list and seal at once.
"""

from __future__ import annotations

import contextlib
import sqlite3
from collections.abc import Callable
from dataclasses import fields
from pathlib import Path

from daq.store import layout
from daq.store.summary_model import RunSummary

# Bump when the table changes; an index of another version is rebuilt.
INDEX_VERSION = 2  # 2: summaries check links, declared sizes and file names
_COLUMNS = [f.name for f in fields(RunSummary)]
_BUSY_TIMEOUT_S = 5.0
_BUSY_CODES = {sqlite3.SQLITE_BUSY, sqlite3.SQLITE_LOCKED}

FileKey = tuple[str, int, int]  # (file name, size in bytes, mtime in ns)


def cached_summaries(
    store_dir: Path, files: list[FileKey], read: Callable[[Path], RunSummary]
) -> list[RunSummary]:
    """Summaries of ``files`` (in that order), from the cache where it is fresh."""
    path = store_dir / layout.INDEX_FILE
    for attempt in range(2):
        try:
            return _with_index(path, store_dir, files, read)
        except sqlite3.Error as exc:
            if getattr(exc, "sqlite_errorcode", None) in _BUSY_CODES:
                break  # another process holds it too long: use it next time, not now
            if attempt == 0:
                _remove(path)  # corrupt or foreign: start again from the run files
    # The folder may be read-only or the disk full: the files are the truth anyway.
    return [read(store_dir / name) for name, _, _ in files]


def _with_index(path: Path, store_dir: Path, files: list[FileKey], read: Callable[[Path], RunSummary]):
    db = sqlite3.connect(path, timeout=_BUSY_TIMEOUT_S, isolation_level=None)
    try:
        version = db.execute("PRAGMA user_version").fetchone()[0]
        if version != INDEX_VERSION:
            _create(db)
        query = f"SELECT size, mtime_ns, {', '.join(_COLUMNS)} FROM runs"
        keyed = {row[2]: row for row in db.execute(query)}
        out: list[RunSummary] = []
        fresh: list[tuple] = []
        for name, size, mtime_ns in files:
            row = keyed.get(name)
            if row is not None and row[0] == size and row[1] == mtime_ns:
                out.append(_summary(row[2:]))
                continue
            summary = read(store_dir / name)
            out.append(summary)
            fresh.append((size, mtime_ns, *(getattr(summary, c) for c in _COLUMNS)))
        vanished = set(keyed) - {name for name, _, _ in files}
        if fresh or vanished:
            db.execute("BEGIN IMMEDIATE")
            db.executemany(
                f"INSERT OR REPLACE INTO runs VALUES ({', '.join('?' * (len(_COLUMNS) + 2))})", fresh
            )
            db.executemany("DELETE FROM runs WHERE file_name = ?", [(n,) for n in vanished])
            db.execute("COMMIT")
        return out
    finally:
        db.close()


def _create(db: sqlite3.Connection) -> None:
    with contextlib.suppress(sqlite3.Error):
        db.execute("PRAGMA journal_mode=WAL")  # readers never block the one writer
    db.execute("BEGIN IMMEDIATE")
    db.execute("DROP TABLE IF EXISTS runs")
    db.execute(
        "CREATE TABLE runs (size INTEGER NOT NULL, mtime_ns INTEGER NOT NULL, "
        "file_name TEXT PRIMARY KEY, run_id TEXT, start_time TEXT, kind TEXT, complete INTEGER, "
        "n_hits INTEGER, n_accepted INTEGER, operator TEXT, note TEXT, size_bytes INTEGER, error TEXT)"
    )
    db.execute(f"PRAGMA user_version = {INDEX_VERSION}")
    db.execute("COMMIT")


def _summary(values: tuple) -> RunSummary:
    summary = RunSummary(*values)
    # Rows come from a file anyone can edit: a row with the wrong types is a cache
    # miss in disguise, so it is refused here and the run file is read instead.
    expected = (str, str, str, str, int, int, int, str, str, int)
    if not all(isinstance(v, t) for v, t in zip(values, expected, strict=False)) or not (
        summary.error is None or isinstance(summary.error, str)
    ):
        raise sqlite3.DatabaseError("index row has unexpected types")
    return RunSummary(**{**summary.__dict__, "complete": bool(summary.complete)})


def _remove(path: Path) -> None:
    for suffix in ("", "-wal", "-shm", "-journal"):
        with contextlib.suppress(OSError):
            Path(f"{path}{suffix}").unlink()
