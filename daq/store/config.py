"""The user's configuration file (TOML), read-only.

Location: $DAQ_CONFIG if set, else $XDG_CONFIG_HOME/cantilever-daq/config.toml, else
~/.config/cantilever-daq/config.toml. A missing file is an empty configuration.
Known keys (both optional): ``store = "path/to/runs"`` and ``resource = "GPIB0::11::INSTR"``.
Unknown keys are ignored so that newer versions can add settings.
"""

from __future__ import annotations

import os
import stat
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from daq.store.errors import ConfigError

APP_DIR = "cantilever-daq"
#: A config file holds two short keys: anything larger is not one.
MAX_CONFIG_BYTES = 64 * 1024


@dataclass(frozen=True)
class Config:
    """path: the file read (it may not exist). store: folder of runs, made absolute
    relative to the file's folder. resource: the instrument's VISA resource string."""

    path: Path
    store: Path | None = None
    resource: str | None = None


def config_path(env: Mapping[str, str] | None = None) -> Path:
    env = os.environ if env is None else env
    if env.get("DAQ_CONFIG"):
        return Path(env["DAQ_CONFIG"]).expanduser()
    base = Path(env["XDG_CONFIG_HOME"]) if env.get("XDG_CONFIG_HOME") else Path.home() / ".config"
    return base / APP_DIR / "config.toml"


def load_config(path: Path | None = None, env: Mapping[str, str] | None = None) -> Config:
    """The configuration at ``path`` (default: config_path()); ConfigError if unusable."""
    path = config_path(env) if path is None else Path(path)
    try:
        raw = _read_small_regular(path)
    except FileNotFoundError:
        return Config(path=path)
    except OSError as exc:
        raise ConfigError(f"config file {path}: cannot read it ({exc.__class__.__name__})") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ConfigError(f"config file {path}: cannot read it ({exc.__class__.__name__})") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"config file {path}: not valid TOML ({exc})") from None
    store = data.get("store")
    resource = data.get("resource")
    for key, value in (("store", store), ("resource", resource)):
        if value is not None and (not isinstance(value, str) or not value.strip()):
            raise ConfigError(f"config file {path}: {key} must be a non-empty string")
    store_path = None
    if store is not None:
        store_path = Path(store).expanduser()
        if not store_path.is_absolute():
            store_path = path.parent / store_path  # relative to the file, not to the cwd
    return Config(path=path, store=store_path, resource=resource)


def _read_small_regular(path: Path) -> bytes:
    """The bytes of ``path`` if it is a regular file of at most MAX_CONFIG_BYTES
    (a symlink to one is fine); ConfigError otherwise. Opened non-blocking and checked
    with fstat before any read: a FIFO would block every command for good, and
    /dev/zero would be read until memory runs out."""
    fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC | getattr(os, "O_NOCTTY", 0))
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            kind = "a directory" if stat.S_ISDIR(info.st_mode) else "a FIFO, device or socket"
            raise ConfigError(f"config file {path}: it is {kind}, not a regular file")
        if info.st_size > MAX_CONFIG_BYTES:
            raise ConfigError(
                f"config file {path}: {info.st_size} bytes, more than the {MAX_CONFIG_BYTES} "
                "a config file may have"
            )
        chunks, total = [], 0
        while chunk := os.read(fd, MAX_CONFIG_BYTES + 1 - total):
            chunks.append(chunk)
            total += len(chunk)
            if total > MAX_CONFIG_BYTES:  # it grew after the fstat
                raise ConfigError(f"config file {path}: more than {MAX_CONFIG_BYTES} bytes")
        return b"".join(chunks)
    finally:
        os.close(fd)
