"""The service's access token: made at first start, kept where only the user reads it.

The token is 32 random bytes as hex, in ``$DAQ_TOKEN_FILE``, else
``service-token`` beside the config file (``$XDG_CONFIG_HOME/cantilever-daq/``).
The file is created 0600 without following symlinks, and an existing file that
others may read, or that is not a regular file of ours, is refused rather than
trusted: whoever reads the token can drive the analyzer.

Requests carry it as ``Authorization: Bearer <token>``; GET requests may give it
as ``?token=`` (a browser's EventSource and download links cannot set headers).
"""

from __future__ import annotations

import hmac
import os
import secrets
import stat
from collections.abc import Mapping
from pathlib import Path

from daq.store.config import config_path

TOKEN_BYTES = 32
#: A token file larger than this is refused (a token is 64 hex digits and a newline).
MAX_TOKEN_FILE_BYTES = 4096


class TokenError(Exception):
    """The token file cannot be made or is not safe to use; one line for the user."""


def token_path(env: Mapping[str, str] | None = None) -> Path:
    env = os.environ if env is None else env
    if env.get("DAQ_TOKEN_FILE"):
        return Path(env["DAQ_TOKEN_FILE"])
    return config_path(env).parent / "service-token"


def load_or_create_token(path: Path) -> tuple[str, bool]:
    """(the token, whether it was created now)."""
    try:
        return _read(path), False
    except FileNotFoundError:
        pass
    token = secrets.token_hex(TOKEN_BYTES)
    try:
        path.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW | os.O_CLOEXEC, 0o600)
    except FileExistsError:  # another service started at the same moment: use its token
        return _read(path), False
    except OSError as exc:
        raise TokenError(f"cannot create the token file {path}: {exc.strerror or exc}") from None
    with os.fdopen(fd, "w", encoding="ascii") as handle:
        handle.write(token + "\n")
    return token, True


def _read(path: Path) -> str:
    try:
        # O_NONBLOCK: a FIFO put in its place must not hang the open (no effect on files).
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_CLOEXEC | os.O_NONBLOCK)
    except FileNotFoundError:
        raise
    except OSError as exc:
        raise TokenError(f"cannot read the token file {path}: {exc.strerror or exc}") from None
    info = os.fstat(fd)  # before fdopen, which refuses a directory with IsADirectoryError
    if not stat.S_ISREG(info.st_mode) or info.st_uid != os.getuid():
        os.close(fd)
        raise TokenError(f"token file {path} is not a regular file of ours: refused")
    if info.st_size > MAX_TOKEN_FILE_BYTES:
        os.close(fd)
        raise TokenError(
            f"token file {path} is {info.st_size} bytes, too large to hold a token: refused; "
            f"delete it for a new one"
        )
    with os.fdopen(fd, "r", encoding="ascii", errors="replace") as handle:
        if info.st_mode & (stat.S_IRWXG | stat.S_IRWXO):
            raise TokenError(
                f"token file {path} is readable by others (mode {stat.S_IMODE(info.st_mode):04o}): "
                f"refused; chmod 600 {path}, or delete it for a new token"
            )
        token = handle.read(MAX_TOKEN_FILE_BYTES + 1).strip()  # it may have grown since
    if not 32 <= len(token) <= MAX_TOKEN_FILE_BYTES or not all(c in "0123456789abcdef" for c in token):
        raise TokenError(f"token file {path} does not hold a token; delete it for a new one")
    return token


def token_matches(given: str | None, token: str) -> bool:
    """Constant-time comparison (a timing difference must not reveal the token)."""
    return given is not None and hmac.compare_digest(given.encode(), token.encode())


def is_loopback(host: str) -> bool:
    """True for addresses only this machine can reach."""
    import ipaddress

    if host in ("localhost", "localhost.localdomain"):
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False
