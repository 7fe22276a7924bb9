"""The lab's transducers: hammers and accelerometers with their calibration, one TOML
table in the store, ``<store>/transducers.toml`` (docs/setups.md).

A transducer has a plain id (``hammer-1``), a kind (hammer or accelerometer), a model,
a serial number, a sensitivity with its unit as the calibration sheet gives it
(``2.25 mV/N``, ``10 mV/g``) and the dates of its last calibration and of the next one
due. ``sensitivity_v_per_eu`` turns the sensitivity into what the analyzer is set to:
V/N for a hammer, V/(m/s^2) for an accelerometer.

Two built-ins are always there and not stored unless overwritten: ``hammer-default``
(2.25 mV/N) and ``accel-default`` (1.02 mV/(m/s^2), a nominal 10 mV/g part), without
dates: exactly the capture's default sensitivities (2.25e-3 V/N, 1.02e-3 V/(m/s^2)).

Writing follows the store's protocol (writer.write_atomically: temporary, fsync,
rename, folder fsync) under ``<store>/.transducers.lock`` (flock), so two processes
adding transducers at once both land. A table that does not check is refused whole
with a StoreError naming the file and the field.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from datetime import date
from pathlib import Path
from typing import Any

from daq.store.errors import StoreError
from daq.store.setups import SetupStore
from daq.store.text_files import file_lock, parse_toml, read_bounded, toml_string
from daq.store.writer import write_atomically

TRANSDUCERS_FILE = "transducers.toml"
KINDS = ("hammer", "accelerometer")
#: Standard gravity, m/s^2 (a "g" of an accelerometer's sheet); pound-force, N.
STANDARD_GRAVITY = 9.80665
POUND_FORCE_N = 4.4482216152605
#: Sensitivity units: (kind, what divides the number to give V/N or V/(m/s^2)).
UNITS: dict[str, tuple[str, float]] = {
    "mV/N": ("hammer", 1e3),
    "V/N": ("hammer", 1.0),
    "mV/lbf": ("hammer", 1e3 * POUND_FORCE_N),
    "mV/g": ("accelerometer", 1e3 * STANDARD_GRAVITY),
    "V/g": ("accelerometer", STANDARD_GRAVITY),
    "mV/(m/s^2)": ("accelerometer", 1e3),
    "V/(m/s^2)": ("accelerometer", 1.0),
}
#: The engineering unit of each kind.
EU = {"hammer": "N", "accelerometer": "m/s^2"}
ID_PATTERN = re.compile(r"[A-Za-z0-9._-]{1,64}")
FIELDS = ("id", "kind", "model", "serial", "sensitivity", "sensitivity_unit", "calibrated", "due")
#: A table larger than this is refused unread (a real one is a few kB).
MAX_FILE_BYTES = 4 * 2**20


def check_id(value: object, what: str = "id") -> str:
    """``value`` if it is a plain transducer id, else StoreError naming ``what``."""
    if not isinstance(value, str) or not ID_PATTERN.fullmatch(value) or value.startswith("."):
        raise StoreError(f"{what}: {value!r} is not a plain name (letters, digits, . _ -, 1 to 64)")
    return value


def _date(value: object, where: str, key: str) -> str:
    if isinstance(value, date):  # TOML reads a bare 2026-01-10 as a date
        value = value.isoformat()
    if not isinstance(value, str):
        raise StoreError(f"{where}: {key}: not a date YYYY-MM-DD")
    if value == "":
        return ""
    try:
        if len(value) != 10:
            raise ValueError
        date.fromisoformat(value)
    except ValueError:
        raise StoreError(f"{where}: {key}: not a date YYYY-MM-DD ({value!r})") from None
    return value


def _a(kind: str) -> str:
    """ "a hammer", "an accelerometer"."""
    return f"an {kind}" if kind[0] in "aeiou" else f"a {kind}"


def _text(value: object, where: str, key: str) -> str:
    if not isinstance(value, str) or len(value) > 200 or re.search(r"[\x00-\x1f\x7f]", value):
        raise StoreError(f"{where}: {key}: must be one line of text (up to 200 characters)")
    return value


@dataclass(frozen=True)
class Transducer:
    """A hammer or an accelerometer.

    id : plain name ([A-Za-z0-9._-]{1,64}). kind : "hammer" or "accelerometer".
    model, serial : as on its label. sensitivity : the number of its calibration sheet,
    in ``sensitivity_unit`` (one of UNITS: "mV/N", "V/N", "mV/lbf", "mV/g", "V/g",
    "mV/(m/s^2)", "V/(m/s^2)"). calibrated, due : ISO dates YYYY-MM-DD, or "".
    """

    id: str
    kind: str
    model: str
    serial: str
    sensitivity: float
    sensitivity_unit: str
    calibrated: str = ""
    due: str = ""

    def __post_init__(self) -> None:
        checked = self.from_dict(self._fields(), f"transducer {self.id}")  # StoreError naming the field
        for name in FIELDS:  # e.g. a date given as a date, a sensitivity as an int
            object.__setattr__(self, name, getattr(checked, name))

    def _fields(self) -> dict[str, Any]:
        return {name: getattr(self, name) for name in FIELDS}

    @property
    def sensitivity_v_per_eu(self) -> float:
        """V/N for a hammer, V/(m/s^2) for an accelerometer."""
        return self.sensitivity / UNITS[self.sensitivity_unit][1]

    @property
    def eu(self) -> str:
        """The engineering unit: N or m/s^2."""
        return EU[self.kind]

    def overdue(self, today: date) -> bool:
        """True when its calibration was due before ``today`` (never without a due date)."""
        return bool(self.due) and date.fromisoformat(self.due) < today

    def to_dict(self, today: date | None = None) -> dict[str, Any]:
        """Its fields plus ``sensitivity_v_per_eu`` and ``overdue`` (against ``today``,
        default the local date)."""
        return {
            **self._fields(),
            "sensitivity_v_per_eu": self.sensitivity_v_per_eu,
            "overdue": self.overdue(today or date.today()),
        }

    @classmethod
    def from_dict(cls, d: object, where: str = "transducer") -> Transducer:
        """A Transducer from ``d`` (its fields; ``sensitivity_v_per_eu`` and ``overdue``
        are ignored, being derived); StoreError "<where>: <field>: ..." otherwise."""
        if not isinstance(d, dict):
            raise StoreError(f"{where}: must be a table")
        unknown = sorted(set(d) - set(FIELDS) - {"sensitivity_v_per_eu", "overdue"})
        if unknown:
            raise StoreError(f"{where}: {unknown[0]}: unknown field; known: {', '.join(FIELDS)}")
        for key in ("id", "kind", "sensitivity", "sensitivity_unit"):
            if key not in d:
                raise StoreError(f"{where}: {key}: missing")
        ident = d["id"]
        if not isinstance(ident, str) or not ID_PATTERN.fullmatch(ident) or ident.startswith("."):
            raise StoreError(f"{where}: id: {ident!r} is not a plain name (letters, digits, . _ -, 1 to 64)")
        kind = d["kind"]
        if kind not in KINDS:
            raise StoreError(f"{where}: kind: must be hammer or accelerometer, got {kind!r}")
        unit = d["sensitivity_unit"]
        if unit not in UNITS:
            raise StoreError(f"{where}: sensitivity_unit: must be one of {', '.join(UNITS)}, got {unit!r}")
        if UNITS[unit][0] != kind:
            raise StoreError(f"{where}: sensitivity_unit: {unit} is not a unit of {_a(kind)}")
        value = d["sensitivity"]
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0 < value < float("inf"):
            raise StoreError(f"{where}: sensitivity: must be a positive number, got {value!r}")
        calibrated = _date(d.get("calibrated", ""), where, "calibrated")
        due = _date(d.get("due", ""), where, "due")
        if calibrated and due and due < calibrated:
            raise StoreError(f"{where}: due: {due} is before the calibration {calibrated}")
        values = (
            ident, kind, _text(d.get("model", ""), where, "model"),
            _text(d.get("serial", ""), where, "serial"), float(value), unit, calibrated, due,
        )  # fmt: skip
        obj = object.__new__(cls)
        for name, v in zip(FIELDS, values, strict=True):
            object.__setattr__(obj, name, v)
        return obj


#: The built-ins, always present (a stored transducer of the same id replaces one).
BUILTINS: dict[str, Transducer] = {
    "hammer-default": Transducer("hammer-default", "hammer", "PCB 086C03 (default)", "", 2.25, "mV/N"),
    # A nominal 10 mV/g part, declared as the capture's default sensitivity is made
    # (drivers/settings.py: 1.02 mV/(m/s^2) = 10.003 mV/g), so that a capture with the
    # built-in setup and one without any setup measure the same number.
    "accel-default": Transducer(
        "accel-default", "accelerometer", "nominal 10 mV/g accelerometer (default)", "", 1.02, "mV/(m/s^2)"
    ),
}


class TransducerTable:
    """The transducers of store ``store_dir`` (``<store>/transducers.toml``) and the built-ins."""

    def __init__(self, store_dir: Path | str) -> None:
        self.store_dir = Path(store_dir)
        self.path = self.store_dir / TRANSDUCERS_FILE

    def _stored(self) -> dict[str, Transducer]:
        try:
            doc = parse_toml(read_bounded(self.path, MAX_FILE_BYTES, str(self.path)), str(self.path))
        except FileNotFoundError:
            return {}
        unknown = sorted(set(doc) - {"transducer"})
        if unknown:
            raise StoreError(f"{self.path}: {unknown[0]}: unknown key; the file holds [[transducer]] tables")
        entries = doc.get("transducer", [])
        if not isinstance(entries, list):
            raise StoreError(f"{self.path}: transducer: must be an array of tables [[transducer]]")
        found: dict[str, Transducer] = {}
        for i, entry in enumerate(entries):
            name = entry.get("id") if isinstance(entry, dict) else None
            label = f"transducer {name}" if isinstance(name, str) else f"transducer[{i}]"
            t = Transducer.from_dict(entry, f"{self.path}: {label}")
            if t.id in found:
                raise StoreError(f"{self.path}: {label}: id: listed twice")
            found[t.id] = t
        return found

    def all(self) -> list[Transducer]:
        """Every transducer, the built-ins included (a stored one replaces a built-in), by id."""
        merged = {**BUILTINS, **self._stored()}
        return [merged[k] for k in sorted(merged)]

    def get(self, ident: str) -> Transducer:
        """The transducer ``ident``; StoreError "no transducer 'x' (known: a, b)"."""
        for t in self.all():
            if t.id == ident:
                return t
        known = ", ".join(t.id for t in self.all())
        raise StoreError(f"no transducer {ident!r} (known: {known})")

    def put(self, transducer: Transducer, today: date | None = None) -> Transducer:
        """Add ``transducer`` or replace the one of its id (atomic write under a lock).

        StoreError "transducer <id>: <field>: ..." (nothing written) when its calibration
        date is after ``today`` (default: the local date), or when it changes the kind
        of a transducer that a setup's current version names on the other channel (the
        setup would no longer resolve): "transducer a-7: kind: a-7 is the accelerometer
        of setup beam; ...".
        """
        if not isinstance(transducer, Transducer):
            raise StoreError(f"put takes a Transducer, not a {type(transducer).__name__}")
        where = f"transducer {transducer.id}"
        today = today or date.today()
        if transducer.calibrated and date.fromisoformat(transducer.calibrated) > today:
            raise StoreError(f"{where}: calibrated: {transducer.calibrated} is in the future")
        with file_lock(self.store_dir, ".transducers.lock", "the transducer table"):
            stored = self._stored()
            previous = {**BUILTINS, **stored}.get(transducer.id)
            if previous is not None and previous.kind != transducer.kind:
                users = setups_naming(self.store_dir, transducer.id)
                named = sorted(name for name, channel in users if channel != transducer.kind)
                if named:
                    which = f"setup {named[0]}" if len(named) == 1 else f"setups {', '.join(named)}"
                    raise StoreError(
                        f"{where}: kind: {transducer.id} is the {previous.kind} of {which}; "
                        f"it cannot become {_a(transducer.kind)} (give the {transducer.kind} another "
                        f"id, or name another {previous.kind} in the setup first)"
                    )
            stored[transducer.id] = transducer
            text = dump_transducers(stored.values())
            write_atomically(
                self.store_dir, self.path, text.encode("utf-8"), what="the transducer table", overwrite=True
            )
        return transducer


def setups_naming(store_dir: Path | str, ident: str) -> list[tuple[str, str]]:
    """(setup name, channel) of each setup whose current version names transducer
    ``ident`` on a channel (the built-in ``default`` included); a setup whose file does
    not read is skipped (it resolves to nothing anyway)."""
    setups = SetupStore(store_dir)
    found = []
    for name in setups.names():
        try:
            data = setups.get(name).data
        except StoreError:
            continue
        for channel in KINDS:
            table = data.get(channel)
            if isinstance(table, dict) and table.get("transducer") == ident:
                found.append((name, channel))
    return found


def dump_transducers(transducers: Any) -> str:
    """The TOML text of the table holding ``transducers``."""
    lines = [
        "# The lab's transducers (cantilever-daq, docs/setups.md). Written by `daq transducer add`",
        "# and the service: edit with care, a table that does not check is refused whole.",
        "",
    ]
    for t in sorted(transducers, key=lambda t: t.id):
        lines.append("[[transducer]]")
        for name in FIELDS:
            value = getattr(t, name)
            lines.append(f"{name} = {repr(float(value)) if name == 'sensitivity' else toml_string(value)}")
        lines.append("")
    return "\n".join(lines)
