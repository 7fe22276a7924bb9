"""Where the store is: --store, then $DAQ_STORE, then the config file, then the
per-user data folder; a bad config file is one ConfigError naming it."""

from __future__ import annotations

from pathlib import Path

import pytest

from daq.store import ConfigError, StoreError, resolve_store_dir
from daq.store.config import config_path, load_config


def test_precedence(tmp_path):
    config = tmp_path / "config.toml"
    config.write_text('store = "/data/runs"\nresource = "GPIB0::11::INSTR"\n')
    env = {"DAQ_CONFIG": str(config), "DAQ_STORE": "/env/runs", "XDG_DATA_HOME": "/xdg/data"}
    assert resolve_store_dir("/opt/runs", env) == (Path("/opt/runs"), "--store option")
    assert resolve_store_dir(None, env) == (Path("/env/runs"), "$DAQ_STORE")
    env["DAQ_STORE"] = ""  # set but empty counts as unset
    assert resolve_store_dir(None, env) == (Path("/data/runs"), f"config file {config}")
    config.write_text('resource = "GPIB0::11::INSTR"\n')
    assert resolve_store_dir(None, env) == (
        Path("/xdg/data/cantilever-daq/runs"),
        "default per-user data folder",
    )
    del env["XDG_DATA_HOME"]
    folder, source = resolve_store_dir(None, env)
    assert folder == Path.home() / ".local/share/cantilever-daq/runs"
    assert source == "default per-user data folder"


def test_relative_paths(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert resolve_store_dir("runs", {}) == (tmp_path / "runs", "--store option")
    config = tmp_path / "etc" / "config.toml"
    config.parent.mkdir()
    config.write_text('store = "../lab/runs"\n')
    folder, _ = resolve_store_dir(None, {"DAQ_CONFIG": str(config)})
    assert folder == tmp_path / "etc" / ".." / "lab" / "runs"  # relative to the file


def test_config_file_location():
    assert config_path({"DAQ_CONFIG": "/a/b.toml"}) == Path("/a/b.toml")
    assert config_path({"XDG_CONFIG_HOME": "/x"}) == Path("/x/cantilever-daq/config.toml")
    assert config_path({}) == Path.home() / ".config/cantilever-daq/config.toml"


def test_missing_config_is_empty(tmp_path):
    config = load_config(tmp_path / "none.toml")
    assert (config.store, config.resource) == (None, None)


def test_config_values(tmp_path):
    path = tmp_path / "c.toml"
    path.write_text('store = "~/runs"\nresource = "TCPIP::lab-gpib::1234::SOCKET"\nfuture_key = 3\n')
    config = load_config(path)
    assert config.store == Path.home() / "runs"
    assert config.resource == "TCPIP::lab-gpib::1234::SOCKET"


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("store = /no/quotes\n", "not valid TOML"),
        ("store = 3\n", "store must be a non-empty string"),
        ('resource = ""\n', "resource must be a non-empty string"),
        (b"store = '\xff'\n", "cannot read"),
    ],
)
def test_bad_config_is_one_clear_error(tmp_path, text, message):
    path = tmp_path / "config.toml"
    path.write_bytes(text if isinstance(text, bytes) else text.encode())
    with pytest.raises(ConfigError, match=message) as caught:
        resolve_store_dir(None, {"DAQ_CONFIG": str(path)})
    assert isinstance(caught.value, StoreError)
    assert str(path) in str(caught.value)
    assert "\n" not in str(caught.value)
