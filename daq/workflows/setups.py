"""Setups for a capture: a named setup of the store or a setup file, its transducers,
and whether the analyzer at hand can measure it (docs/setups.md).

* :func:`resolve_setup` turns a name (``<store>/setups/NAME.toml``, or the built-in
  ``default``) or a path ending in ``.toml`` into :class:`ResolvedSetup`: the settings,
  with the sensitivity of each transducer a channel names, the transducers and the
  cautions (a calibration past due).
* :func:`check_setup_data` checks a setup's dict (what the service receives), each
  error naming the field first ("span_hz: must be a positive number, got -5.0").
* :func:`validate_for_model` refuses settings the analyzer cannot measure, before any
  hit: lines, span, input ranges, a trigger level above the hammer's range;
  :func:`validate_for_family` those no model could (a setup being saved).
* :func:`transducer_record` is what a run stores of its transducers.

Cautions are plain sentences; whoever shows them adds "caution: " (as the report and
the command line do for every caution).
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field, replace
from datetime import date
from pathlib import Path
from typing import Any

from daq.store.errors import StoreError
from daq.store.setups import SetupStore, strip_saved
from daq.store.transducers import EU, Transducer, TransducerTable, check_id
from daq.workflows.errors import WorkflowError
from daq.workflows.setup_codec import CHANNELS, settings_from_dict
from drivers.dialects import DIALECTS, SCPI_MODEL_LINES
from drivers.scpi_commands import MAX_RANGE_V as SCPI_MAX_RANGE_V
from drivers.settings import ImpactSettings

#: The analyzer's input ranges, V peak, ascending, per model: the one place the
#: workflows know them (the drivers declare only the SCPI models' top, the mnemonic
#: table takes any number up to 100 V).
#: - 35660A and 3562A/3563A: 1 dB steps from -51 dBV to +27 dBV (3.5 mV to 22.4 V
#:   peak), as docs/simulator.md states them ("proj": not confirmed on a 35660A);
#: - 35665A and 35670A: 2 dB steps of dBVrms from -51 to +27 (3.99 mV to 31.7 V peak),
#:   docs/instrument-scpi.md (SENS:VOLT:RANG), drivers/scpi_commands.py MAX_RANGE_V.
_HP_RANGES_V = tuple(10.0 ** (db / 20.0) for db in range(-51, 28))
_SCPI_RANGES_V = tuple(10.0 ** (db / 20.0) * math.sqrt(2.0) for db in range(-51, 28, 2))
ANALYZER_RANGES_V: dict[str, tuple[float, ...]] = {
    "35660A": _HP_RANGES_V,
    "3562A": _HP_RANGES_V,
    "35665A": _SCPI_RANGES_V,
    "35670A": _SCPI_RANGES_V,
}
assert math.isclose(_SCPI_RANGES_V[-1], SCPI_MAX_RANGE_V)
#: Model names a run or the driver may give, and the model they stand for.
_ALIASES = {"3563A": "3562A"}


@dataclass(frozen=True)
class ResolvedSetup:
    """A setup ready for a capture.

    name : the setup's name, or the file's path as given. version : its version in the
    store (0: the built-in default, or a file). settings : the settings, each channel
    that names a transducer with that transducer's sensitivity. transducers : by
    channel ("hammer", "accelerometer"), those the setup names. cautions : plain
    sentences (a calibration past due), shown as "caution: ...". data : the setup's dict.
    """

    name: str
    version: int
    settings: ImpactSettings
    transducers: dict[str, Transducer] = field(default_factory=dict)
    cautions: list[str] = field(default_factory=list)
    data: dict[str, Any] = field(default_factory=dict)

    def provenance(self) -> dict[str, Any]:
        """What a run records of it: {"name", "version"}."""
        return {"name": self.name, "version": self.version}


def is_setup_path(name_or_path: str | Path) -> bool:
    """True when ``name_or_path`` names a setup file (it ends in .toml), not a stored setup."""
    return isinstance(name_or_path, Path) or str(name_or_path).lower().endswith(".toml")


def resolve_setup(
    store_dir: Path | str, name_or_path: str | Path, today: date | None = None
) -> ResolvedSetup:
    """The setup ``name_or_path``: a file when it ends in .toml, else the named setup of
    ``store_dir``. WorkflowError (one line) naming the setup and the field when it does
    not check; an unknown name or transducer lists the known ones. ``today`` (default:
    the local date) decides which calibrations are past due."""
    if is_setup_path(name_or_path):
        path = Path(name_or_path)
        where = f"setup file {path}"
        try:
            doc = tomllib.loads(path.read_text(encoding="utf-8"))
        except OSError as exc:
            raise WorkflowError(f"{where}: cannot read it ({exc.strerror or exc})") from None
        except UnicodeDecodeError:
            raise WorkflowError(f"{where}: not UTF-8 text") from None
        except tomllib.TOMLDecodeError as exc:
            raise WorkflowError(f"{where}: not valid TOML ({exc})") from None
        name, version, data = str(path), 0, strip_saved(doc)
        settings = check_setup_data(data, where)  # "setup file x.toml: span_hz: must be ..."
    else:
        try:
            stored = SetupStore(store_dir).get(str(name_or_path))
        except StoreError as exc:
            raise WorkflowError(str(exc)) from None
        name, version, data = stored.name, stored.version, stored.data
        where = f"setup {name}"
        try:
            settings = check_setup_data(data)
        except WorkflowError as exc:
            raise WorkflowError(f"{where}: {exc}") from None
    transducers = _named_transducers(store_dir, data, where)
    settings = with_transducers(settings, transducers)
    return ResolvedSetup(name, version, settings, transducers, calibration_cautions(transducers, today), data)


def _named_transducers(store_dir: Path | str, data: dict[str, Any], where: str) -> dict[str, Transducer]:
    table = TransducerTable(store_dir)
    where = f"{where}: " if where else ""
    found = {}
    for channel, ident in named_transducer_ids(data).items():
        try:
            transducer = table.get(ident)
        except StoreError as exc:
            raise WorkflowError(f"{where}{channel}.transducer: {exc}") from None
        if transducer.kind != channel:
            raise WorkflowError(
                f"{where}{channel}.transducer: {ident} is {_a(transducer.kind)}, not {_a(channel)}"
            )
        found[channel] = transducer
    return found


def _a(kind: str) -> str:
    return f"an {kind}" if kind[0] in "aeiou" else f"a {kind}"


def named_transducer_ids(data: dict[str, Any]) -> dict[str, str]:
    """{channel: transducer id} of the channels of setup ``data`` that name one;
    WorkflowError "hammer.transducer: ..." for a name that is not a plain id."""
    found = {}
    for channel in CHANNELS:
        table = data.get(channel) if isinstance(data, dict) else None
        if isinstance(table, dict) and "transducer" in table:
            try:
                found[channel] = check_id(table["transducer"], f"{channel}.transducer")
            except StoreError as exc:
                raise WorkflowError(str(exc)) from None
    return found


def with_transducers(settings: ImpactSettings, transducers: dict[str, Transducer]) -> ImpactSettings:
    """``settings`` with each channel's sensitivity that of its transducer (engineering
    units follow: the analyzer is set to V/N or V/(m/s^2) of the transducer)."""
    for channel, transducer in transducers.items():
        setup = getattr(settings, channel)
        settings = replace(
            settings, **{channel: replace(setup, sensitivity_v_per_eu=transducer.sensitivity_v_per_eu)}
        )
    return settings


def calibration_cautions(transducers: dict[str, Transducer], today: date | None = None) -> list[str]:
    """A sentence for each transducer whose calibration is past due."""
    today = today or date.today()
    return [
        f"{channel} transducer {t.id} calibration was due {t.due}"
        for channel, t in transducers.items()
        if t.overdue(today)
    ]


_WHERE = "\x00setup"


def check_setup_data(data: dict[str, Any], where: str | None = None) -> ImpactSettings:
    """The settings of setup ``data`` (a setup file's dict; channels may name a
    ``transducer``, a ``[saved]`` table is ignored); WorkflowError naming the field
    first, e.g. "span_hz: must be a positive number, got -5.0", after "<where>: " when
    ``where`` is given (a setup file's: the same words). Transducer sensitivities are
    not applied here (resolve_setup does, knowing the store)."""
    if not isinstance(data, dict):
        raise WorkflowError(
            f"{where}: must be a table of settings" if where else "setup: must be a table of settings"
        )
    try:
        named_transducer_ids(data)
    except WorkflowError as exc:
        raise WorkflowError(f"{where}: {exc}" if where else str(exc)) from None
    plain = {
        k: (
            {ck: cv for ck, cv in v.items() if ck != "transducer"}
            if k in CHANNELS and isinstance(v, dict)
            else v
        )
        for k, v in strip_saved(data).items()
    }
    if where is not None:
        return settings_from_dict(plain, where)
    try:
        return settings_from_dict(plain, _WHERE)
    except WorkflowError as exc:
        text = str(exc)
        raise WorkflowError(text[len(_WHERE) + 2 :] if text.startswith(_WHERE + ": ") else text) from None


def model_name(model: str) -> str:
    """The model a name stands for (``HP 35670A`` -> ``35670A``, ``3563A`` -> ``3562A``);
    WorkflowError naming the known ones."""
    key = str(model).strip().upper().removeprefix("HP").strip()
    key = _ALIASES.get(key, key)
    if key not in ANALYZER_RANGES_V:
        raise WorkflowError(f"model: unknown analyzer {model!r}; known: {', '.join(ANALYZER_RANGES_V)}")
    return key


def analyzer_ranges_v(model: str) -> tuple[float, ...]:
    """The input ranges of ``model``, V peak, ascending."""
    return ANALYZER_RANGES_V[model_name(model)]


def max_span_hz(model: str) -> float:
    """The widest span of ``model``, Hz."""
    model = model_name(model)
    return DIALECTS["SCPI"].max_span_hz if model in SCPI_MODEL_LINES else DIALECTS[model].max_span_hz


def _lines_offered(model: str) -> tuple[int, ...]:
    return SCPI_MODEL_LINES[model] if model in SCPI_MODEL_LINES else DIALECTS[model].line_choices


def _hz(value: float) -> str:
    return f"{value / 1000:g} kHz" if value >= 1000 else f"{value:g} Hz"


def validate_for_model(settings: ImpactSettings, model: str) -> None:
    """WorkflowError naming the field when ``model`` (35660A, 3562A, 35665A, 35670A, or
    "HP 35670A" as a run records it) cannot measure ``settings``: a resolution it does not
    offer, a span or zoom band above its widest, an input range above its largest, a
    trigger level the trigger channel's range cannot reach."""
    model = model_name(model)
    offered = _lines_offered(model)
    if settings.lines is not None and settings.lines not in offered:
        if len(offered) == 1:
            raise WorkflowError(f"lines: the {model} offers {offered[0]} lines only, not {settings.lines}")
        choices = ", ".join(str(n) for n in offered)
        raise WorkflowError(f"lines: the {model} offers {choices} lines, not {settings.lines}")
    top = max_span_hz(model)
    if settings.span_hz > top * (1 + 1e-9):
        raise WorkflowError(f"span_hz: {settings.span_hz:g} Hz is above the {model}'s {_hz(top)}")
    if settings.center_hz and settings.center_hz + settings.span_hz / 2 > top * (1 + 1e-9):
        raise WorkflowError(
            f"center_hz: a {settings.span_hz:g} Hz band around {settings.center_hz:g} Hz reaches above "
            f"the {model}'s {_hz(top)}"
        )
    largest = ANALYZER_RANGES_V[model][-1]
    for channel in CHANNELS:
        range_v = getattr(settings, channel).range_v
        if range_v is not None and range_v > largest * (1 + 1e-9):
            raise WorkflowError(
                f"{channel}.range_v: {range_v:g} V is above the analyzer's largest range "
                f"({largest:.3g} V on the {model})"
            )
    check_trigger_level(settings)


def check_trigger_level(settings: ImpactSettings) -> None:
    """WorkflowError "trigger_level_eu: ..." when the trigger level is beyond what the
    trigger channel's range reaches (a fixed range only; either sign, the message keeps
    it): no hit could ever trigger."""
    trigger_channel = {"CH1": "hammer", "CH2": "accelerometer"}.get(settings.trigger_source)
    if trigger_channel is None:
        return
    setup = getattr(settings, trigger_channel)
    if setup.range_v is None:
        return
    reach = setup.range_v / setup.sensitivity_v_per_eu
    level = settings.trigger_level_eu
    if abs(level) > reach * (1 + 1e-9):
        unit = EU[trigger_channel]
        sens = setup.sensitivity_v_per_eu * 1e3
        per = f"mV/{'N' if unit == 'N' else '(m/s^2)'}"
        where = "above" if level > 0 else "beyond"
        sign = "" if level > 0 else "±"
        raise WorkflowError(
            f"trigger_level_eu: {level:g} {unit} is {where} the {trigger_channel}'s range "
            f"({sign}{reach:.3g} {unit} = {setup.range_v:g} V / {sens:g} {per})"
        )


#: What some model of the family offers: every resolution, the widest span, the
#: largest input range (a setup no model can measure is refused when it is saved).
FAMILY_LINES = tuple(sorted({n for model in ANALYZER_RANGES_V for n in _lines_offered(model)}))


def validate_for_family(settings: ImpactSettings) -> None:
    """WorkflowError naming the field when no model of the family (35660A, 3562A,
    35665A, 35670A) could measure ``settings``: what needs no analyzer at hand. A
    resolution none offers, a span or zoom band above the widest model's, an input
    range above the largest, a trigger level the trigger channel's fixed range cannot
    reach (validate_for_model checks the rest against the model connected)."""
    if settings.lines is not None and settings.lines not in FAMILY_LINES:
        choices = ", ".join(str(n) for n in FAMILY_LINES)
        raise WorkflowError(f"lines: no analyzer offers {settings.lines} lines; one of {choices}")
    widest = max(ANALYZER_RANGES_V, key=max_span_hz)
    top = max_span_hz(widest)
    if settings.span_hz > top * (1 + 1e-9):
        raise WorkflowError(
            f"span_hz: {settings.span_hz:g} Hz is above the widest span of any analyzer "
            f"({_hz(top)} on the {widest})"
        )
    if settings.center_hz and settings.center_hz + settings.span_hz / 2 > top * (1 + 1e-9):
        raise WorkflowError(
            f"center_hz: a {settings.span_hz:g} Hz band around {settings.center_hz:g} Hz reaches above "
            f"the widest span of any analyzer ({_hz(top)} on the {widest})"
        )
    biggest = max(ANALYZER_RANGES_V, key=lambda m: ANALYZER_RANGES_V[m][-1])
    largest = ANALYZER_RANGES_V[biggest][-1]
    for channel in CHANNELS:
        range_v = getattr(settings, channel).range_v
        if range_v is not None and range_v > largest * (1 + 1e-9):
            raise WorkflowError(
                f"{channel}.range_v: {range_v:g} V is above the largest range of any analyzer "
                f"({largest:.3g} V on the {biggest})"
            )
    check_trigger_level(settings)


def transducer_record(transducers: dict[str, Transducer], today: date | None = None) -> dict[str, dict]:
    """{channel: what the run stores in its settings[channel]["transducer"]}: the
    transducer's fields (Transducer.to_dict) and, for the report, "calibration_date" and
    "due_date"."""
    record = {}
    for channel, t in transducers.items():
        d = t.to_dict(today)
        d["calibration_date"], d["due_date"] = t.calibrated, t.due
        record[channel] = d
    return record


def save_setup(
    store_dir: Path | str,
    name: str,
    data: dict[str, Any],
    expected_version: int | None = None,
    model: str | None = None,
) -> ResolvedSetup:
    """Check setup ``data`` (its settings, the transducers it names, that some model of
    the family can measure it, and, with ``model``, that this analyzer can) and save it
    as the next version of setup ``name``; the setup as resolved after the save.
    WorkflowError naming the field (nothing is written); VersionConflict (a StoreError)
    when ``expected_version`` is not the current one (0: the setup must be new)."""
    settings = check_setup_data(data)
    transducers = _named_transducers(store_dir, data, "")
    settings = with_transducers(settings, transducers)
    validate_for_family(settings)
    if model is not None:
        validate_for_model(settings, model)
    try:
        SetupStore(store_dir).put(name, data, expected_version)
    except StoreError as exc:
        if type(exc) is StoreError:  # a bad name or value; a VersionConflict stays one
            raise WorkflowError(str(exc)) from None
        raise
    return resolve_setup(store_dir, name)


def setup_view(store_dir: Path | str, name: str, today: date | None = None) -> dict[str, Any]:
    """What ``daq setup show --json`` and GET /api/setups/{name} answer: name, version,
    saved_utc, the setup's data ("setup"), the resolved settings (setup_codec's
    settings_to_dict), the transducers by channel (Transducer.to_dict) and the cautions."""
    from daq.workflows.setup_codec import settings_to_dict

    try:
        stored = SetupStore(store_dir).get(name)
    except StoreError as exc:
        raise WorkflowError(str(exc)) from None
    resolved = resolve_setup(store_dir, name, today)
    return {
        "name": stored.name,
        "version": stored.version,
        "saved_utc": stored.saved_utc,
        "setup": stored.data,
        "settings": settings_to_dict(resolved.settings),
        "transducers": {ch: t.to_dict(today) for ch, t in resolved.transducers.items()},
        "cautions": resolved.cautions,
    }
