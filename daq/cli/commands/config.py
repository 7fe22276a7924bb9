"""`daq config`: which configuration file is used, what it holds, and what is in effect.

The file is $DAQ_CONFIG, else $XDG_CONFIG_HOME/cantilever-daq/config.toml, else
~/.config/cantilever-daq/config.toml (daq.store.config). A missing file is fine: it
is an empty configuration. A file that is not valid TOML is one error line.
"""

from __future__ import annotations

import json
import os
from typing import Annotated, Any

import typer


def register(app: typer.Typer) -> None:
    """Add `daq config` to ``app`` (once: a second call does nothing)."""
    if any(command.name == "config" for command in app.registered_commands):
        return
    app.command(name="config")(config)


def _config_source(env) -> str:
    if env.get("DAQ_CONFIG"):
        return "$DAQ_CONFIG"
    if env.get("XDG_CONFIG_HOME"):
        return "$XDG_CONFIG_HOME"
    return "default location"


def _report() -> dict[str, Any]:
    from daq.store import resolve_store_dir
    from daq.store.config import load_config

    env = os.environ
    cfg = load_config(env=env)  # ConfigError (one line, exit 1) if unusable
    store_path, store_source = resolve_store_dir(None, env=env)
    if env.get("DAQ_RESOURCE"):
        resource, resource_source = env["DAQ_RESOURCE"], "$DAQ_RESOURCE"
    elif cfg.resource is not None:
        resource, resource_source = cfg.resource, f"config file {cfg.path}"
    else:
        resource, resource_source = None, "not set (give --resource or set $DAQ_RESOURCE)"
    return {
        "config_file": {
            "path": str(cfg.path),
            "source": _config_source(env),
            "exists": cfg.path.is_file(),
            "store": None if cfg.store is None else str(cfg.store),
            "resource": cfg.resource,
        },
        "store": {"path": str(store_path), "source": store_source, "exists": store_path.is_dir()},
        "resource": {"value": resource, "source": resource_source},
    }


def config(
    as_json: Annotated[bool, typer.Option("--json", help="Print JSON instead of text.")] = False,
) -> None:
    """Show the config file and the settings in effect.

    The config file is $DAQ_CONFIG if set, else cantilever-daq/config.toml in
    $XDG_CONFIG_HOME (default ~/.config). It may hold
    store = "<dir>" (relative to the file's folder) and resource = "<resource>".
    The store in effect is --store, else $DAQ_STORE, else the file's store, else
    the per-user data folder.
    """
    report = _report()
    if as_json:
        print(json.dumps(report, indent=2, ensure_ascii=False))
        return
    f, store, resource = report["config_file"], report["store"], report["resource"]
    state = "exists" if f["exists"] else "not found: nothing configured, defaults apply"
    print(f"config file  {f['path']} (from {f['source']}; {state})")
    if f["exists"]:
        print(f"  store      {f['store'] or '(not set)'}")
        print(f"  resource   {f['resource'] or '(not set)'}")
    folder = "" if store["exists"] else "; the folder does not exist yet"
    print(f"store        {store['path']} (from {store['source']}{folder})")
    if resource["value"] is None:
        print(f"resource     {resource['source']}")
    else:
        print(f"resource     {resource['value']} (from {resource['source']})")
