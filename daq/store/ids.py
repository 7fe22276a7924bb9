"""Run ids: sortable by time, unique across processes and machines, safe as file names.

An id looks like ``20261123T101503.123Z-3f9c1a2b``: the UTC time of creation to the
millisecond, then 32 random bits from :mod:`secrets`. Sorting ids as text sorts runs
by creation time. Two machines would need to create a run in the same millisecond
AND draw the same 32 bits to collide (about 1 in 4 billion per such pair); sealing
refuses to overwrite anyway, so a collision is an error, never lost data.
"""

from __future__ import annotations

import re
import secrets
import threading
import time
from datetime import UTC, datetime

from daq.store.errors import StoreError

RUN_ID_LENGTH = 29
# [0-9] rather than \d: \d also matches non-ASCII digits such as Arabic-Indic ones.
RUN_ID_PATTERN = re.compile(r"[0-9]{8}T[0-9]{6}\.[0-9]{3}Z-[0-9a-f]{8}")
# A prefix typed by a user to pick a run: the same characters, nothing else.
_PREFIX_PATTERN = re.compile(r"[0-9TZ.a-f-]{1,29}")

_lock = threading.Lock()
_last_ms = 0


def new_run_id(now_s: float | None = None) -> str:
    """A fresh run id for a run created at ``now_s`` (Unix time, s; default: now).

    Within one process successive ids strictly increase even when created in the
    same millisecond: the time part is nudged forward by 1 ms when needed.
    """
    global _last_ms
    ms = round((time.time() if now_s is None else now_s) * 1000)
    with _lock:
        if now_s is None:
            ms = max(ms, _last_ms + 1)
            _last_ms = ms
    stamp = datetime.fromtimestamp(ms / 1000, tz=UTC)
    return f"{stamp:%Y%m%dT%H%M%S}.{ms % 1000:03d}Z-{secrets.token_hex(4)}"


def is_run_id(text: object) -> bool:
    """Whether ``text`` is a well-formed run id (no exception)."""
    return isinstance(text, str) and RUN_ID_PATTERN.fullmatch(text) is not None


def validate_run_id(text: object) -> str:
    """``text`` if it is a well-formed run id, else StoreError.

    Use on every id that comes from outside (command line, web request, file
    contents): the pattern admits no slash, dot-dot, NUL, space or non-ASCII, so a
    valid id is always a plain file name inside the store folder.
    """
    if not isinstance(text, str):
        raise StoreError(f"run id must be text, not {type(text).__name__}")
    if RUN_ID_PATTERN.fullmatch(text) is None:
        raise StoreError(f"invalid run id {_show(text)}: expected e.g. 20261123T101503.123Z-3f9c1a2b")
    return text


def validate_run_id_prefix(text: object) -> str:
    """``text`` if it could be the start of a run id (for picking a run by prefix)."""
    if not isinstance(text, str) or _PREFIX_PATTERN.fullmatch(text) is None:
        shown = _show(text) if isinstance(text, str) else type(text).__name__
        raise StoreError(f"invalid run id or prefix {shown}: expected e.g. 20261123T1015, or latest")
    return text


def run_id_time(run_id: str) -> datetime:
    """The UTC creation time encoded in a valid run id."""
    validate_run_id(run_id)
    try:
        return datetime.strptime(run_id[:19] + "000", "%Y%m%dT%H%M%S.%f").replace(tzinfo=UTC)
    except ValueError as exc:  # e.g. month 13: matches the pattern, is no date
        raise StoreError(f"invalid run id {run_id!r}: no such date") from exc


def _show(text: str) -> str:
    # repr() escapes NUL, newlines and odd characters; long input is cut so the
    # message stays one readable line.
    return repr(text if len(text) <= 40 else text[:40] + "...")
