"""The store's lock: one lab service per store folder.

A file in the store folder itself (hidden, never taken for a run), locked with flock
through the driver's ResourceLock, so that every process using the folder (any
environment, any user, any machine sharing it through a filesystem with working
flock) finds the same one. Instrument locks, by contrast, live in the user's lock
directory (drivers/locking.py): they belong to the link, this one to the store.
"""

from __future__ import annotations

import os
from pathlib import Path

from drivers.locking import ResourceLock

#: The store lock's file, in the store folder.
STORE_LOCK_NAME = ".daq-serve.lock"


def store_lock(store_dir: Path | str, holder: str = "") -> ResourceLock:
    """The lock of one service per store ``store_dir``; ``holder`` says who holds it in
    the message another process gets (e.g. "daq serve at http://127.0.0.1:8000")."""
    where = os.path.realpath(store_dir)
    return ResourceLock(f"STORE::{where}", f"store {where}", holder, path=Path(where) / STORE_LOCK_NAME)
