"""Named setups and transducers as the lab service reads and writes them (the test
station's ``/api/setups`` and ``/api/transducers``): the JSON views, a save checked
against the connected analyzer, and a setup resolved and checked for a capture.

The files are the store's (daq/store/setups.py, daq/store/transducers.py); checking and
resolving a setup is daq/workflows/setups.py's. Errors are one line naming the field:
WorkflowError for a setup or transducer that does not check (HTTP 422), StoreError's
VersionConflict for a save from a stale version (409), StoreError for an unknown name.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from daq.store import StoreError
from daq.store.setups import SetupStore
from daq.store.transducers import Transducer, TransducerTable
from daq.workflows.errors import WorkflowError
from daq.workflows.setups import ResolvedSetup, resolve_setup, validate_for_model
from drivers.settings import ImpactSettings


class UnknownName(Exception):
    """No setup or transducer of that name (HTTP 404); one line."""


def connected_model(dialect: str | None, identification: str | None) -> str | None:
    """The analyzer's model (``HP 35660A``...) from its dialect's name and its reply to
    the identification query, as a run records it; None when not known yet."""
    if not dialect or not identification:
        return None
    from drivers.dialects import DIALECTS, model_of

    found = DIALECTS.get(dialect)
    return None if found is None else model_of(found, identification)


def setups_listing(store_dir: Path) -> dict[str, Any]:
    """``{"setups": [{"name", "version", "saved_utc"}]}``, by name ("default" always)."""
    return {"setups": [s.summary() for s in SetupStore(store_dir).list()]}


def setup_view(store_dir: Path, name: str, version: int | None = None) -> dict[str, Any]:
    """GET /api/setups/{name} (daq/workflows/setups.py ``setup_view``): ``{"name",
    "version", "saved_utc", "setup": data, "settings": the resolved settings
    (transducers' sensitivities applied), "transducers", "cautions"}``; ``version``: that
    version of it, from the history (None: the current one). UnknownName when the store
    has no such setup or version; WorkflowError when it does not check."""
    from daq.workflows.setups import setup_view as view

    _known(store_dir, name)
    if version is None:
        return view(store_dir, name)
    try:
        stored = SetupStore(store_dir).get(name, version)
    except StoreError:
        raise UnknownName(f"setup {name} has no version {version}") from None
    if stored.version != version:
        raise UnknownName(f"setup {name} has no version {version}")
    current = view(store_dir, name)
    if current["version"] == version:
        return current
    return _stored_view(store_dir, stored)


def _stored_view(store_dir: Path, stored: Any) -> dict[str, Any]:
    """setup_view's answer for one stored version (an older one): its settings with the
    transducers it names as they are now."""
    from datetime import date

    from daq.workflows.setup_codec import settings_to_dict
    from daq.workflows.setups import (
        calibration_cautions,
        check_setup_data,
        named_transducer_ids,
        with_transducers,
    )

    where = f"setup {stored.name} version {stored.version}"
    try:
        settings = check_setup_data(stored.data)
    except WorkflowError as exc:
        raise WorkflowError(f"{where}: {exc}") from None
    table = TransducerTable(store_dir)
    transducers = {}
    for channel, ident in named_transducer_ids(stored.data).items():
        try:
            transducers[channel] = table.get(ident)
        except StoreError as exc:
            raise WorkflowError(f"{where}: {channel}.transducer: {exc}") from None
    today = date.today()
    return {
        "name": stored.name,
        "version": stored.version,
        "saved_utc": stored.saved_utc,
        "setup": stored.data,
        "settings": settings_to_dict(with_transducers(settings, transducers)),
        "transducers": {ch: t.to_dict(today) for ch, t in transducers.items()},
        "cautions": calibration_cautions(transducers, today),
    }


def _known(store_dir: Path, name: str) -> None:
    store = SetupStore(store_dir)
    try:
        names = store.names()
        store.path(name)
    except StoreError as exc:
        raise UnknownName(str(exc)) from None
    if name not in names:
        raise UnknownName(f"no setup {name!r} (known: {', '.join(names)})")


def save_setup(
    store_dir: Path, name: str, data: dict[str, Any], version: int, model: str | None
) -> dict[str, Any]:
    """Save ``data`` as setup ``name`` from ``version`` (0: a new setup); its view.
    WorkflowError naming the field when it does not check, or when the connected
    ``model`` (None: not known) cannot measure it; VersionConflict when someone saved a
    version in between (daq/workflows/setups.py ``save_setup``)."""
    from daq.store.setups import VersionConflict
    from daq.workflows.setups import save_setup as save

    try:
        SetupStore(store_dir).path(name)
    except StoreError as exc:
        raise WorkflowError(f"name: {exc}") from None
    try:
        save(store_dir, name, data, version, model)
    except VersionConflict as exc:
        raise VersionConflict(stale_version_text(name, version, exc.current), exc.current) from None
    return setup_view(store_dir, name)


def stale_version_text(name: str, given: int, current: int, field: str = "") -> str:
    """What to say of a save or capture from ``given`` when setup ``name`` is at
    ``current`` (0: it does not exist), field first (``field``: the request's, when it
    is not ``version``)."""
    where = f"{field}: " if field else ""
    if current == 0 and given != 0:
        return f"{where}version {given}: setup {name} does not exist yet (version 0 saves it new)"
    if given == 0:
        return (
            f"{where}version 0: setup {name} exists already (version {current}); "
            "load it or choose another name"
        )
    return f"{where}version {given} is not the current one ({current}): load the setup again"


def _strip_where(text: str, name: str) -> str:
    """A resolve error names the setup first ("setup x: span_hz: ..."): the field first."""
    prefix = f"setup {name}: "
    return text[len(prefix) :] if text.startswith(prefix) else text


def setup_for_capture(store_dir: Path, name: str, version: int | None = None) -> ResolvedSetup:
    """Setup ``name`` resolved for a capture. UnknownName when there is none;
    WorkflowError (field first) when it does not check; VersionConflict when
    ``version`` is given and the setup is at another one."""
    from daq.workflows.setups import is_setup_path

    store = SetupStore(store_dir)
    try:
        if not is_setup_path(name) and name not in store.names():
            raise UnknownName(f"setup: no setup {name!r} (known: {', '.join(store.names())})")
    except StoreError as exc:
        raise WorkflowError(f"setup: {exc}") from None
    try:
        resolved = resolve_setup(store_dir, name)
    except WorkflowError as exc:
        raise WorkflowError(_strip_where(str(exc), name)) from None
    if version is not None and resolved.version != version:
        from daq.store.setups import VersionConflict

        raise VersionConflict(
            stale_version_text(name, version, resolved.version, "setup_version"), resolved.version
        )
    return resolved


def check_for_model(settings: ImpactSettings, model: str | None) -> None:
    """WorkflowError naming the field when ``model`` cannot measure ``settings``."""
    if model is not None:
        validate_for_model(settings, model)


def transducers_listing(store_dir: Path) -> dict[str, Any]:
    """``{"transducers": [Transducer.to_dict() ...]}`` (built-ins included)."""
    return {"transducers": [t.to_dict() for t in TransducerTable(store_dir).all()]}


def transducer_view(store_dir: Path, ident: str) -> dict[str, Any]:
    """One transducer's dict; UnknownName when there is none."""
    try:
        return TransducerTable(store_dir).get(ident).to_dict()
    except StoreError as exc:
        raise UnknownName(str(exc)) from None


def save_transducer(store_dir: Path, ident: str, fields: dict[str, Any]) -> dict[str, Any]:
    """Save transducer ``ident`` from its fields (``id`` may be left out; if given it must
    be ``ident``); its dict. WorkflowError naming the field when they do not check."""
    given = {k: v for k, v in fields.items() if k not in ("sensitivity_v_per_eu", "overdue")}
    if "id" in given and given["id"] != ident:
        raise WorkflowError(f"id: {given['id']!r} is not the transducer of this address ({ident!r})")
    given["id"] = ident
    given.setdefault("calibrated", "")
    given.setdefault("due", "")
    try:
        transducer = Transducer.from_dict(given, where=f"transducer {ident}")
        TransducerTable(store_dir).put(transducer)
    except StoreError as exc:
        text = str(exc)
        prefix = f"transducer {ident}: "
        raise WorkflowError(text[len(prefix) :] if text.startswith(prefix) else text) from None
    return transducer.to_dict()
