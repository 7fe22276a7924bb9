"""The settings codec (daq/workflows/setup_codec.py): dict and setup file (TOML) round
trips, every bad key refused by name, and a key table that is the dataclasses' fields."""

from __future__ import annotations

import json
import tomllib
from dataclasses import fields

import pytest

from daq.workflows.errors import WorkflowError
from daq.workflows.setup_codec import (
    CHANNELS,
    NOT_IN_FILE,
    STORED,
    channel_keys,
    read_setup_file,
    settings_from_dict,
    settings_from_stored,
    settings_to_dict,
    settings_to_toml,
    top_keys,
)
from drivers.settings import ChannelSetup, ImpactSettings, Window

#: Settings other than the defaults in every key a setup file shows uncommented.
CHANGED = ImpactSettings(
    span_hz=400.0,
    center_hz=1000.0,
    hammer=ChannelSetup(Window.HANNING, 1.5e-3, range_v=None, ac_coupled=True),
    accelerometer=ChannelSetup(Window.UNIFORM, 2e-3, range_v=0.5),
    trigger_source="CH2",
    trigger_level_eu=2.5,
    trigger_slope="NEG",
    averages=7,
)
#: ... and in the keys only a stored run's settings carry (or a file comments out).
STORED_CHANGED = ImpactSettings(
    span_hz=100.0,
    hammer=ChannelSetup(Window.FORCE, 2e-3, force_width_s=0.2, exp_decay_s=0.5),
    pre_trigger_s=0.05,
    preview=False,
    lines=800,
)


def _settings_field_names(cls: type) -> set[str]:
    return {f.name for f in fields(cls) if f.compare}


def test_the_key_tables_are_the_dataclass_fields():
    """A field added to the settings is a key of the codec (or is named as left out)."""
    top = _settings_field_names(ImpactSettings)
    assert set(top_keys()) | set(CHANNELS) | NOT_IN_FILE == top
    assert not set(top_keys()) & (set(CHANNELS) | NOT_IN_FILE)
    assert set(top_keys(stored=True)) | set(CHANNELS) == top
    for stored in (False, True):
        assert set(channel_keys(stored)) == _settings_field_names(ChannelSetup)
    written = settings_to_dict(ImpactSettings())
    assert set(written) == top
    assert all(set(written[name]) == _settings_field_names(ChannelSetup) for name in CHANNELS)


@pytest.mark.parametrize(
    "settings", [ImpactSettings(), CHANGED, STORED_CHANGED], ids=["default", "changed", "stored"]
)
def test_dict_round_trip(settings):
    data = settings_to_dict(settings)
    again = json.loads(json.dumps(data))
    assert again == data
    assert settings_from_stored(again) == settings
    assert json.dumps(settings_to_dict(settings_from_stored(again))) == json.dumps(data)


@pytest.mark.parametrize("settings", [ImpactSettings(), CHANGED], ids=["default", "changed"])
def test_toml_round_trip(settings, tmp_path):
    text = settings_to_toml(settings)
    assert settings_from_dict(tomllib.loads(text), "setup file x") == settings
    path = tmp_path / "setup.toml"
    path.write_text(text, encoding="utf-8")
    assert read_setup_file(path) == settings
    assert settings_to_toml(read_setup_file(path)) == text


def test_toml_spells_none_and_comments_the_record_sized():
    text = settings_to_toml(CHANGED)
    assert 'range_v = "auto"' in text
    assert "center_hz = 1000.0" in text
    assert "center_hz = 0.0  # 0 = baseband" in settings_to_toml(ImpactSettings())
    for key in ("pre_trigger_s", "force_width_s", "exp_decay_s", "lines"):
        assert f"\n# {key} = " in text
    assert "preview" not in text
    assert settings_from_dict({"center_hz": 0}, "w").center_hz is None


@pytest.mark.parametrize("key", list(top_keys()))
def test_an_ill_typed_top_key_is_refused_by_name(key):
    with pytest.raises(WorkflowError, match=rf"^setup file x: {key}: must be "):
        settings_from_dict({key: [1]}, "setup file x")


@pytest.mark.parametrize("channel", CHANNELS)
@pytest.mark.parametrize("key", list(channel_keys()))
def test_an_ill_typed_channel_key_is_refused_by_name(channel, key):
    with pytest.raises(WorkflowError, match=rf"^setup file x: {channel}\.{key}: must be "):
        settings_from_dict({channel: {key: [1]}}, "setup file x")


@pytest.mark.parametrize(
    ("data", "message"),
    [
        ({"span": 1}, "w: span: unknown key; known: span_hz, center_hz, averages, trigger_source, "
         "trigger_level_eu, trigger_slope, pre_trigger_s, lines, [hammer], [accelerometer]"),
        ({"preview": False}, "w: preview: unknown key; known: "),
        ({"hammer": {"foo": 1}}, "w: hammer.foo: unknown key; known: window, sensitivity_v_per_eu, "
         "range_v, force_width_s, exp_decay_s, ac_coupled"),
        ({"accelerometer": 3}, "w: accelerometer: must be a table"),
        ({"span_hz": "wide"}, "w: span_hz: must be a number, got 'wide'"),
        ({"span_hz": float("inf")}, "w: span_hz: must be finite"),
        ({"span_hz": -5.0}, "w: span_hz: must be a positive number, got -5.0"),
        ({"averages": 5.0}, "w: averages: must be int, got 5.0"),
        ({"averages": True}, "w: averages: must be int, got True"),
        ({"hammer": {"range_v": "big"}}, 'w: hammer.range_v: must be a number or "auto", got \'big\''),
        ({"hammer": {"range_v": True}}, "w: hammer.range_v: must be a number or str, got True"),
        ({"hammer": {"window": "BOX"}},
         "w: hammer.window: 'BOX' is not a window; one of UNIF, HANN, FLAT, FORC, EXPO"),
        ({"hammer": {"ac_coupled": 1}}, "w: hammer.ac_coupled: must be bool, got 1"),
    ],
)  # fmt: skip
def test_setup_errors_keep_their_words(data, message):
    with pytest.raises(WorkflowError) as caught:
        settings_from_dict(data, "w")
    assert str(caught.value).startswith(message)


@pytest.mark.parametrize(
    "data",
    [{"foo": 1}, {"span_hz": "x"}, {"hammer": {"window": "BOX"}}, {"preview": 1}, {"span_hz": -1.0}],
)
def test_stored_settings_errors_say_so(data):
    with pytest.raises(WorkflowError, match=rf"^{STORED}: "):
        settings_from_stored(data)


def test_stored_settings_take_none_and_preview():
    data = settings_to_dict(ImpactSettings())
    assert data["center_hz"] is None
    assert data["lines"] is None
    assert settings_from_stored({**data, "preview": False}).preview is False


def test_read_setup_file_errors(tmp_path):
    missing = tmp_path / "none.toml"
    with pytest.raises(WorkflowError, match=rf"^setup file {missing}: cannot read it"):
        read_setup_file(missing)
    bad = tmp_path / "bad.toml"
    bad.write_text("span_hz = \n", encoding="utf-8")
    with pytest.raises(WorkflowError, match=rf"^setup file {bad}: not valid TOML"):
        read_setup_file(bad)
    binary = tmp_path / "bin.toml"
    binary.write_bytes(b"\xff\xfe")
    with pytest.raises(WorkflowError, match=rf"^setup file {binary}: not UTF-8 text"):
        read_setup_file(binary)
