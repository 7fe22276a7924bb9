"""The one codec of an impact test's settings: to and from a dict, a setup file (TOML).

Its keys and their types come from the fields of ImpactSettings and ChannelSetup
(drivers/settings.py), so a field added there is a key here. Kept explicit only what
the fields cannot say, all in the layout below:

* the setup file's order and its per-key comments;
* which keys the file leaves commented out: those sized to the record when left out
  (pre-trigger, force window, exponential decay) and the resolution (lines);
* how the file spells None: range_v "auto" (autorange), center_hz 0 (baseband);
  a key that is left out keeps its default;
* ``preview``, a field the setup file does not take (the command line decides it).

Two readings of a dict: a setup file's (``settings_from_dict(data, where)``, each
error "<where>: <key>: ..." naming the bad key first, "setup file x.toml: span_hz: must
be a positive number, got -5.0") and a stored run's (``stored=True``: the
dict ``settings_to_dict`` wrote, None where a field allows it, ``preview`` included;
a channel's ``transducer`` record is skipped).
"""

from __future__ import annotations

import copy
import math
import re
import types
import typing
from dataclasses import dataclass, fields, is_dataclass
from enum import Enum
from pathlib import Path
from typing import Any

from daq.workflows.errors import WorkflowError
from drivers.settings import ChannelSetup, ImpactSettings, Window

__all__ = [
    "STORED",
    "channel_keys",
    "read_setup_file",
    "settings_from_dict",
    "settings_from_stored",
    "settings_to_dict",
    "settings_to_toml",
    "top_keys",
]

#: The ``where`` of a stored run's settings: the start of every error about them.
STORED = "stored settings do not describe an impact test"

#: A stored run's channel may carry its transducer's record under this key
#: (daq/workflows/setups.py, transducer_record); reading the settings skips it.
TRANSDUCER_KEY = "transducer"
#: The built-in transducer of each channel (daq/store/transducers.py), named in the
#: setup file's comment.
DEFAULT_TRANSDUCERS = {"hammer": "hammer-default", "accelerometer": "accel-default"}

#: The windows a channel takes, as the setup file spells them.
WINDOWS = tuple(str(w.value) for w in Window)

#: The fields that hold a channel, and the header line of the setup file.
CHANNELS = ("hammer", "accelerometer")
HEADER = "# daq capture setup (SI units; EU = N for the hammer, m/s^2 for the accelerometer)"


@dataclass(frozen=True)
class Line:
    """One key of the setup file: its comment, and how the file shows it.

    record_sized : the fraction of the record it defaults to; the line is commented out
        with the value it has now ("uncomment to fix it").
    fixed : the whole line, printed as it is whatever the value (a key the file names
        without showing its value).
    none_as : how the file spells None (e.g. "auto"); None: it has no spelling.
    """

    key: str
    comment: str = ""
    record_sized: str = ""
    fixed: str = ""
    none_as: object = None


#: The setup file, in order: the top level, then each channel's table.
TOP_LAYOUT = (
    Line("span_hz", "the analyzer rounds up (35660A: to 102.4 kHz / 2^n)"),
    Line(
        "lines",
        fixed="# lines = 400  # default: the analyzer's own (35660A 400, 3562A 800); "
        "a 35670A takes 100 to 1600",
    ),
    Line("center_hz", "0 = baseband, else a zoom around it", none_as=0.0),
    Line("averages", "accepted hits wanted (--hits overrides)"),
    Line("trigger_source"),
    Line("trigger_level_eu", "N on CH1"),
    Line("trigger_slope"),
    Line("pre_trigger_s", record_sized="1/32"),
)
CHANNEL_LAYOUT = (
    Line("window", "UNIF, HANN, FLAT, FORC or EXPO"),
    Line("sensitivity_v_per_eu"),
    Line("range_v", 'full scale, V, or "auto"', none_as="auto"),
    Line("force_width_s", record_sized="1/16"),
    Line("exp_decay_s", record_sized="1/6"),
    Line("ac_coupled"),
)
#: Fields of the settings a setup file does not take.
NOT_IN_FILE = frozenset({"preview"})


def _settings_fields(cls: type) -> dict[str, Any]:
    """The fields of ``cls`` that make the settings, by name: their type hints (fields
    with compare=False, such as ``defaulted``, record how the settings were made)."""
    hints = typing.get_type_hints(cls)
    return {f.name: hints[f.name] for f in fields(cls) if f.compare}


def _kinds(hint: Any) -> tuple[tuple[type, ...], bool]:
    """(the Python types a value of ``hint`` takes in a dict, whether None is allowed).
    An Enum travels as its value's type (a window as its mnemonic)."""
    args = (
        typing.get_args(hint)
        if isinstance(hint, types.UnionType) or typing.get_origin(hint) is typing.Union
        else (hint,)
    )
    optional = type(None) in args
    kinds = []
    for arg in args:
        if arg is type(None):
            continue
        if isinstance(arg, type) and issubclass(arg, Enum):
            arg = type(next(iter(arg)).value)
        kinds.append(arg)
    return tuple(kinds), optional


def _layout(layout: tuple[Line, ...], field_names: set[str]) -> dict[str, Line]:
    by_key = {line.key: line for line in layout}
    # The layout names exactly the fields (tests/workflows/test_setup_codec.py too).
    assert set(by_key) == field_names, sorted(set(by_key) ^ field_names)
    return by_key


_TOP_FIELDS = _settings_fields(ImpactSettings)
_CHANNEL_FIELDS = _settings_fields(ChannelSetup)
_TOP_LINES = _layout(TOP_LAYOUT, set(_TOP_FIELDS) - set(CHANNELS) - NOT_IN_FILE)
_CHANNEL_LINES = _layout(CHANNEL_LAYOUT, set(_CHANNEL_FIELDS))


def _known(layout: tuple[Line, ...]) -> list[str]:
    """The keys of a layout as errors list them: those the file shows a value for, in
    its order, then those it only names."""
    return [line.key for line in layout if not line.fixed] + [line.key for line in layout if line.fixed]


def top_keys(stored: bool = False) -> dict[str, tuple[tuple[type, ...], bool]]:
    """The top-level keys besides the channels: name -> (types, None allowed).
    A setup file's (in the order its errors list them) or a stored run's (every field)."""
    if stored:
        return {k: _kinds(h) for k, h in _TOP_FIELDS.items() if k not in CHANNELS}
    return {k: _kinds(_TOP_FIELDS[k]) for k in _known(TOP_LAYOUT)}


def channel_keys(stored: bool = False) -> dict[str, tuple[tuple[type, ...], bool]]:
    """The keys of a channel's table: name -> (types, None allowed)."""
    if stored:
        return {k: _kinds(h) for k, h in _CHANNEL_FIELDS.items()}
    return {k: _kinds(_CHANNEL_FIELDS[k]) for k in _known(CHANNEL_LAYOUT)}


def _plain(value: Any) -> Any:
    if is_dataclass(value) and not isinstance(value, type):
        return {f.name: _plain(getattr(value, f.name)) for f in fields(value) if f.compare}
    if isinstance(value, Enum):
        return str(value.value)
    return copy.deepcopy(value)


def settings_to_dict(settings: ImpactSettings) -> dict[str, Any]:
    """JSON- and TOML-friendly dict of ``settings`` (windows as their mnemonics), as a
    run stores them."""
    return _plain(settings)


def _toml_value(v: object) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return f'"{v}"'
    return repr(float(v)) if isinstance(v, float) else str(v)


def _toml_line(line: Line, v: object) -> str:
    if line.fixed:
        return line.fixed
    if v is None and line.none_as is not None:
        v = line.none_as
    if isinstance(v, Enum):
        v = v.value
    if line.record_sized:
        default = f"default: {line.record_sized} of the record, uncomment to fix it"
        return f"# {line.key} = {_toml_value(v)}  # {default}"
    return f"{line.key} = {_toml_value(v)}" + (f"  # {line.comment}" if line.comment else "")


def settings_to_toml(settings: ImpactSettings) -> str:
    """``settings`` as a setup file; record-sized values appear as comments."""
    out = [HEADER, *(_toml_line(line, getattr(settings, line.key)) for line in TOP_LAYOUT)]
    for name in CHANNELS:
        channel = getattr(settings, name)
        out += ["", f"[{name}]", *(_toml_line(line, getattr(channel, line.key)) for line in CHANNEL_LAYOUT)]
        # Not a setting of the analyzer, so not in the layout: named setups take it
        # (daq/workflows/setups.py), and the file says so where a technician looks.
        out.append(
            f'# {TRANSDUCER_KEY} = "{DEFAULT_TRANSDUCERS[name]}"  # an id of `daq transducer list`: '
            "its sensitivity replaces sensitivity_v_per_eu, and the run records it"
        )
    return "\n".join(out) + "\n"


def _typed(where: str, key: str, raw: object, kinds: tuple[type, ...]) -> object:
    if float in kinds and isinstance(raw, int) and not isinstance(raw, bool):
        raw = float(raw)
    if not isinstance(raw, kinds) or (isinstance(raw, bool) and bool not in kinds):
        names = " or ".join("a number" if k is float else k.__name__ for k in kinds)
        raise WorkflowError(f"{where}: {key}: must be {names}, got {raw!r}")
    if isinstance(raw, float) and not math.isfinite(raw):
        raise WorkflowError(f"{where}: {key}: must be finite")
    return raw


def _value(
    where: str, key: str, raw: object, kinds: tuple[type, ...], optional: bool, line: Line | None
) -> object:
    """``raw`` checked against its field's types; None as the field or the file spells it."""
    if line is None:  # a stored run's: None as JSON holds it
        return None if raw is None and optional else _typed(where, key, raw, kinds)
    spelled = line.none_as
    if isinstance(spelled, str):
        v = _typed(where, key, raw, (*kinds, str))
        if isinstance(v, str):
            if v != spelled:
                names = " or ".join("a number" if k is float else k.__name__ for k in kinds)
                raise WorkflowError(f'{where}: {key}: must be {names} or "{spelled}", got {v!r}')
            v = None
        return v
    v = _typed(where, key, raw, kinds)
    return None if spelled is not None and v == spelled else v


def settings_from_dict(data: dict[str, Any], where: str = STORED, *, stored: bool = False) -> ImpactSettings:
    """ImpactSettings from a parsed setup file (``where`` starts each error, e.g.
    "setup file x.toml"), or with ``stored`` from a stored run's settings (the inverse
    of ``settings_to_dict``). WorkflowError names the bad key; keys left out keep their
    defaults."""
    top, channel_table = top_keys(stored), channel_keys(stored)
    kwargs: dict[str, Any] = {}
    if not isinstance(data, dict):
        raise WorkflowError(f"{where}: not a table of settings")
    for key, raw in data.items():
        if key in CHANNELS:
            if not isinstance(raw, dict):
                raise WorkflowError(f"{where}: {key}: must be a table")
            channel: dict[str, Any] = {}
            defaults = ImpactSettings.__dataclass_fields__[key].default_factory()  # type: ignore[misc]
            for ckey, craw in raw.items():
                if stored and ckey == TRANSDUCER_KEY:
                    continue  # a record of the transducer beside the settings, not a setting
                if ckey not in channel_table:
                    known = ", ".join(channel_table)
                    raise WorkflowError(f"{where}: {key}.{ckey}: unknown key; known: {known}")
                line = None if stored else _CHANNEL_LINES[ckey]
                channel[ckey] = _value(where, f"{key}.{ckey}", craw, *channel_table[ckey], line)
                if ckey == "window" and channel[ckey] not in WINDOWS:
                    raise WorkflowError(
                        f"{where}: {key}.window: {channel[ckey]!r} is not a window; "
                        f"one of {', '.join(WINDOWS)}"
                    )
            base = {name: getattr(defaults, name) for name in _CHANNEL_FIELDS}
            try:
                kwargs[key] = ChannelSetup(**{**base, **channel})
            except ValueError as exc:
                raise WorkflowError(f"{where}: {_field_first(str(exc), key)}") from None
        elif key in top:
            line = None if stored else _TOP_LINES[key]
            kwargs[key] = _value(where, key, raw, *top[key], line)
        else:
            known = ", ".join([*top, *(f"[{name}]" for name in CHANNELS)])
            raise WorkflowError(f"{where}: {key}: unknown key; known: {known}")
    try:
        return ImpactSettings(**kwargs)
    except ValueError as exc:
        raise WorkflowError(f"{where}: {_field_first(str(exc))}") from None


def _field_first(text: str, table: str = "") -> str:
    """A settings class's ValueError ("span_hz must be a positive number, got -5.0"), the
    field first as every error here names it: "span_hz: must be ...", in a channel's
    ``table`` "hammer.range_v: must be ..."."""
    prefix = f"{table}." if table else ""
    match = re.match(r"^(\w+) (must .*)$", text)
    if match is None:
        return f"{table}: {text}" if table else text
    return f"{prefix}{match.group(1)}: {match.group(2)}"


def settings_from_stored(data: dict[str, Any]) -> ImpactSettings:
    """A stored run's settings (``settings_to_dict``'s dict); WorkflowError "stored
    settings do not describe an impact test: ..." if they do not."""
    return settings_from_dict(data, STORED, stored=True)


def read_setup_file(path: Path) -> ImpactSettings:
    """The settings of the setup file at ``path``; WorkflowError "setup file <path>: ..."
    if it cannot be read or does not describe an impact test."""
    import tomllib

    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise WorkflowError(f"setup file {path}: cannot read it ({exc.strerror or exc})") from None
    except UnicodeDecodeError:
        raise WorkflowError(f"setup file {path}: not UTF-8 text") from None
    except tomllib.TOMLDecodeError as exc:
        raise WorkflowError(f"setup file {path}: not valid TOML ({exc})") from None
    return settings_from_dict(data, f"setup file {path}")
