"""Small text files of the store beside its runs (tests, setups, transducers): the lock
held while one is read, changed and written again, the bounded TOML read their readers
share, and the TOML their writers share.

The store's own lock (daq/store/lock.py) is held by `daq serve` for its whole life, so
each of these files has a lock of its own: an flock on a file beside it, which the
kernel frees when its holder dies.
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import os
import time
import tomllib
from collections.abc import Iterator
from datetime import UTC, datetime
from pathlib import Path

from daq.store.errors import StoreError

#: Seconds a change waits for another process's change of the same file.
LOCK_TIMEOUT_S = 30.0


@contextlib.contextmanager
def file_lock(folder: Path, lock_name: str, what: str, timeout_s: float = LOCK_TIMEOUT_S) -> Iterator[None]:
    """Hold ``folder/lock_name`` (flock, exclusive) for a read-modify-write of ``what``;
    wait up to ``timeout_s`` for another process's. The kernel frees it when its holder
    dies. (The same lock as a modal test's, daq/store/modal_tests.py; not the store's
    lock, which ``daq serve`` holds for its whole life.)"""
    try:
        folder.mkdir(parents=True, exist_ok=True)
        fd = os.open(folder / lock_name, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_CLOEXEC, 0o644)
    except OSError as exc:
        reason = "it is a symlink" if exc.errno == errno.ELOOP else os.strerror(exc.errno or 0)
        raise StoreError(f"cannot lock {what} in {folder}: {reason}") from None
    try:
        deadline = time.monotonic() + timeout_s
        while True:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                break
            except BlockingIOError:
                if time.monotonic() > deadline:
                    raise StoreError(
                        f"{what} is being changed by another process for over {timeout_s:g} s; try again"
                    ) from None
                time.sleep(0.01)
        yield
    finally:
        os.close(fd)


def read_bounded(path: Path, max_bytes: int, what: str) -> bytes:
    """The bytes of the file at ``path`` (``what`` names it in messages); StoreError (one
    line) when it cannot be read or holds more than ``max_bytes``: a TOML file that large
    is no file of ours, and reading it whole could exhaust the memory. FileNotFoundError
    passes through, for the caller to say what is missing."""
    try:
        with open(path, "rb") as fh:
            data = fh.read(max_bytes + 1)
    except FileNotFoundError:
        raise
    except OSError as exc:
        raise StoreError(f"cannot read {what}: {os.strerror(exc.errno or 0)}") from None
    if len(data) > max_bytes:
        raise StoreError(f"{what}: larger than {max_bytes} bytes; refused")
    return data


def parse_toml(data: bytes, what: str) -> dict:
    """The TOML document in ``data`` as a dict; StoreError (one line naming ``what``) when
    it is not UTF-8 text or not valid TOML."""
    try:
        return tomllib.loads(data.decode("utf-8"))
    except UnicodeDecodeError:
        raise StoreError(f"{what}: not UTF-8 text") from None
    except tomllib.TOMLDecodeError as exc:
        raise StoreError(f"{what}: not valid TOML ({exc})") from None


def toml_string(text: str) -> str:
    """A TOML basic string: quote, backslash and the control characters escaped."""
    out = ['"']
    for char in text:
        code = ord(char)
        if char == '"':
            out.append('\\"')
        elif char == "\\":
            out.append("\\\\")
        elif code < 0x20 or code == 0x7F:
            out.append({"\n": "\\n", "\t": "\\t", "\r": "\\r"}.get(char, f"\\u{code:04X}"))
        elif 0xD800 <= code <= 0xDFFF:
            raise StoreError("text that is not valid Unicode (a lone surrogate) cannot be stored")
        else:
            out.append(char)
    out.append('"')
    return "".join(out)


def now_utc() -> str:
    now = datetime.now(UTC)
    return f"{now:%Y-%m-%dT%H:%M:%S}.{now.microsecond // 1000:03d}Z"
