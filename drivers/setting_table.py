"""How an impact test's settings meet a dialect's commands: one row per setting.

Each dialect declares one table (drivers/commands.py ``SETTINGS``, drivers/scpi_commands.py
``SETTINGS``): a row maps one field of the settings, as the analyzer holds it
(``ImpactSettings.wire_fields``), to the command that sets it and the query that reads
it back, with its value map declared once (ours -> the instrument's; the inverse is
computed), PyMeasure's ``control(get, set, values=..., map_values=True)`` in spirit.
``write_steps`` and ``read_fields`` walk a table; ``configure`` and ``read_settings``
of every dialect are made of them (drivers/base.py). The vocabulary the settings
share with every table (windows, trigger sources and slopes) is here too, once.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any

log = logging.getLogger(__name__)


class Window(StrEnum):
    """The windows of a channel, as the HP mnemonic table spells them (WIN1/WIN2)."""

    UNIFORM = "UNIF"
    HANNING = "HANN"
    FLAT_TOP = "FLAT"
    FORCE = "FORC"
    EXPONENTIAL = "EXPO"


TRIGGER_SOURCES = ("CH1", "CH2", "FREE")
SLOPES = ("POS", "NEG")
CHANNELS = (1, 2)

#: ``Setting.fixed`` when the value comes from the settings.
FROM_SETTINGS: Any = object()


@dataclass(frozen=True)
class Setting:
    """One row: the field ``field`` and the command that sets it (``{ch}`` or ``<n>``
    stands for the channel in a channel row).

    values : ours -> the instrument's (the inverse reads it back); extra_replies: more
        replies the instrument may give, and what they mean.
    fixed : a value sent whatever the settings (None: the command is an action).
    query : what reads it back (default: the command's own read-back; a fixed row is not
        read unless it names one). write: False for a row that is only read.
    when_none : (command, value) sent instead when our value is None (autorange).
    unless : (field, reply, ours): when the row ``field`` read back ``reply``, this row's
        value is ``ours`` and its query is not asked (no range under autorange).
    each_channel : a setting of the measurement sent (and read) once per channel.
    """

    field: str
    command: str
    values: Mapping[Any, Any] | None = None
    extra_replies: Mapping[Any, Any] = field(default_factory=dict)
    fixed: Any = FROM_SETTINGS
    query: str | None = None
    write: bool = True
    when_none: tuple[str, Any] | None = None
    unless: tuple[str, Any, Any] | None = None
    each_channel: bool = False

    def __post_init__(self) -> None:
        if self.values is not None and len(set(self.values.values())) != len(self.values):
            raise ValueError(f"{self.field}: the value map of {self.command} is not one to one")

    @property
    def reads(self) -> bool:
        return self.query is not None or self.fixed is FROM_SETTINGS

    def to_wire(self, ours: Any) -> Any:
        return ours if self.values is None else self.values[ours]

    def to_ours(self, reply: Any) -> Any:
        if self.values is None:
            return reply
        inverse = {wire: ours for ours, wire in self.values.items()} | dict(self.extra_replies)
        return inverse[reply]


@dataclass(frozen=True)
class Channels:
    """Rows of each channel, sent (and read) channel after channel; ``read_order``
    names their fields in the order they are read back, where it differs."""

    rows: tuple[Setting, ...]
    read_order: tuple[str, ...] = ()


@dataclass(frozen=True)
class SettingsTable:
    """A dialect's rows in the order they are sent; the span row ends the first part
    (the analyzer rounds the span: what follows depends on the span it chose).
    ``read_order``: the fields (and CHANNEL_ROWS) in the order they are read back, where
    it differs from the order they are sent."""

    rows: tuple[Setting | Channels, ...]
    read_order: tuple[str, ...] = ()

    def row(self, name: str) -> Setting:
        for item in self.rows:
            for row in item.rows if isinstance(item, Channels) else (item,):
                if row.field == name:
                    return row
        raise KeyError(name)

    def split_at_span(self) -> tuple[SettingsTable, SettingsTable]:
        at = next(i for i, r in enumerate(self.rows) if isinstance(r, Setting) and r.field == "span_hz") + 1
        return SettingsTable(self.rows[:at]), SettingsTable(self.rows[at:])


#: In a ``read_order``: where the channels are read.
CHANNEL_ROWS = "channels"

#: A step: (command, value, channel or None): value None for an action.
Step = tuple[str, Any, int | None]


def write_steps(
    table: SettingsTable, fields: Mapping[str, Any], channels: Mapping[int, Mapping]
) -> Iterator[Step]:
    """The commands that set ``fields`` (and each channel's ``channels[ch]``), in order."""
    for item in table.rows:
        if isinstance(item, Channels):
            for ch in CHANNELS:
                for row in item.rows:
                    yield from _row_steps(row, channels[ch], ch)
        else:
            for ch in CHANNELS if item.each_channel else (None,):
                yield from _row_steps(item, fields, ch)


def _row_steps(row: Setting, fields: Mapping[str, Any], ch: int | None) -> Iterator[Step]:
    if not row.write:
        return
    if row.fixed is not FROM_SETTINGS:
        yield row.command, row.fixed[ch] if isinstance(row.fixed, Mapping) else row.fixed, ch
        return
    value = fields[row.field]
    if value is None and row.when_none is not None:
        yield row.when_none[0], row.when_none[1], ch
    else:
        yield row.command, row.to_wire(value), ch


Ask = Callable[[str, int | None], Any]


def read_fields(table: SettingsTable, ask: Ask) -> tuple[dict[str, Any], dict[int, dict[str, Any]]]:
    """Every field the table reads back, by ``ask(query, channel)`` (a typed reply):
    the measurement's fields and each channel's."""
    rows = {r.field: r for r in table.rows if isinstance(r, Setting)}
    group = next((r for r in table.rows if isinstance(r, Channels)), Channels(()))
    order = table.read_order or tuple(
        CHANNEL_ROWS if isinstance(r, Channels) else r.field for r in table.rows
    )
    fields: dict[str, Any] = {}
    channels: dict[int, dict[str, Any]] = {ch: {} for ch in CHANNELS}
    for name in order:
        if name == CHANNEL_ROWS:
            by_field = {r.field: r for r in group.rows}
            for ch in CHANNELS:
                for row_name in group.read_order or tuple(by_field):
                    _read_row(by_field[row_name], channels[ch], ask, ch)
        elif rows[name].each_channel:
            values = [_ask(rows[name], ask, ch) for ch in CHANNELS]
            if len(set(values)) > 1:  # configure sends them equal; channel 1's rules
                log.warning("%s differs by channel: %s", name, ", ".join(f"{v:g}" for v in values))
            fields[name] = values[0]
        else:
            _read_row(rows[name], fields, ask, None)
    return fields, channels


def _read_row(
    row: Setting, into: dict[str, Any], ask: Callable[[str, int | None], Any], ch: int | None
) -> None:
    if not row.reads:
        return
    if row.unless is not None and into.get(row.unless[0]) == row.unless[1]:
        into[row.field] = row.unless[2]
    else:
        into[row.field] = _ask(row, ask, ch)


def _ask(row: Setting, ask: Ask, ch: int | None) -> Any:
    return row.to_ours(ask(row.query or row.command, ch))
