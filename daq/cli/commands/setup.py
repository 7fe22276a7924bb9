"""`daq setup`: the named capture setups of the store (list, show, save, history), and
`daq transducer`: the lab's transducers (list, add).

A setup is a setup file (``daq capture --print-setup``) kept in the store under a name,
versioned; a channel may name a transducer (``transducer = "h-12"``) whose sensitivity
then sets the channel's. The files: daq/store/setups.py, daq/store/transducers.py; the
checks: daq/workflows/setups.py. docs/setups.md describes both.
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Annotated

import typer

from daq.cli.errors import UserError
from daq.cli.options import JsonOption, StoreOption

setup_app = typer.Typer(
    help="Named capture setups in the store: list, show, save (versioned), history.",
    no_args_is_help=True,
    rich_markup_mode=None,
)
transducer_app = typer.Typer(
    help="The lab's transducers (hammers, accelerometers) and their calibration: list, add.",
    no_args_is_help=True,
    rich_markup_mode=None,
)


def register(app: typer.Typer) -> None:
    app.add_typer(setup_app, name="setup")
    app.add_typer(transducer_app, name="transducer")


def _store_dir(store: str | None) -> Path:
    from daq.store import resolve_store_dir

    return resolve_store_dir(store)[0]


def print_cautions(cautions: list[str]) -> None:
    """Each caution as a line "caution: ..." on stderr (stdout stays the command's answer)."""
    for text in cautions:
        typer.echo(f"caution: {text}", err=True)


@setup_app.command("list")
def setup_list(store: StoreOption = None, as_json: JsonOption = False) -> None:
    """List the setups: name, version, when saved ("default" is built in)."""
    from daq.store.setups import SetupStore

    setups = [s.summary() for s in SetupStore(_store_dir(store)).list()]
    if as_json:
        print(json.dumps({"setups": setups}, indent=2, ensure_ascii=False))
        return
    width = max(len(s["name"]) for s in setups)
    for s in setups:
        saved = s["saved_utc"] or "(built in)"
        print(f"{s['name']:<{width}}  v{s['version']}  {saved}")


@setup_app.command("show")
def setup_show(
    name: Annotated[str, typer.Argument(metavar="NAME", help="The setup's name.")],
    version: Annotated[
        int | None, typer.Option(metavar="<n>", help="An earlier version [default: the current one].")
    ] = None,
    store: StoreOption = None,
    as_json: JsonOption = False,
) -> None:
    """Show a setup: its file as stored, or with --json its data, the settings it
    resolves to, its transducers and cautions."""
    from daq.store.setups import SetupStore, dump_data
    from daq.workflows.setups import setup_view

    store_dir = _store_dir(store)
    if as_json:
        if version is not None:
            raise UserError("--version goes without --json (the JSON is the current version's)", exit_code=2)
        view = setup_view(store_dir, name)
        print(json.dumps(view, indent=2, ensure_ascii=False))
        print_cautions(view["cautions"])
        return
    setups = SetupStore(store_dir)
    if version is None:
        text = setups.text(name)
    else:
        stored = setups.get(name, version)
        text = dump_data(stored.data, f"setup {name}")
        text += f"\n# version {stored.version}, saved {stored.saved_utc or '(built in)'}\n"
    print(text, end="")
    from daq.workflows.setups import resolve_setup

    resolved = resolve_setup(store_dir, name)
    # The file may still hold a sensitivity the named transducer overrides: say which counts.
    data = setups.get(name, version).data
    for channel, transducer in sorted(resolved.transducers.items()):
        table = data.get(channel)
        if transducer is None or not isinstance(table, dict) or not table.get("transducer"):
            continue
        unused = "; sensitivity_v_per_eu above is not used" if "sensitivity_v_per_eu" in table else ""
        print(
            f"# {channel}: transducer {transducer.id} sets the sensitivity to "
            f"{transducer.sensitivity:g} {transducer.sensitivity_unit} "
            f"({transducer.sensitivity_v_per_eu:.6g} V per EU){unused}"
        )
    print_cautions(resolved.cautions)


@setup_app.command("history")
def setup_history(
    name: Annotated[str, typer.Argument(metavar="NAME", help="The setup's name.")],
    store: StoreOption = None,
    as_json: JsonOption = False,
) -> None:
    """List every version of a setup kept, oldest first."""
    from daq.store.setups import SetupStore

    versions = [s.summary() for s in SetupStore(_store_dir(store)).history(name)]
    if as_json:
        print(json.dumps({"versions": versions}, indent=2, ensure_ascii=False))
        return
    for s in versions:
        print(f"v{s['version']}  {s['saved_utc'] or '(built in)'}")


@setup_app.command("save")
def setup_save(
    name: Annotated[str, typer.Argument(metavar="NAME", help="The setup's name.")],
    from_file: Annotated[
        Path,
        typer.Option("--from", metavar="<file.toml>", help="The setup file (see daq capture --print-setup)."),
    ],
    expect_version: Annotated[
        int | None,
        typer.Option(
            metavar="<n>",
            help="Refuse unless the setup is at this version now (0: it must be new).",
        ),
    ] = None,
    store: StoreOption = None,
) -> None:
    """Save a setup file under NAME as its next version (the previous one is kept)."""
    import tomllib

    from daq.store.errors import StoreError
    from daq.store.setups import DEFAULT_NAME, SetupStore, check_setup_name, strip_saved
    from daq.workflows.setups import save_setup

    try:
        check_setup_name(name)  # the name's fault, before the file is read
    except StoreError as exc:
        raise UserError(str(exc), exit_code=2) from None
    store_dir = _store_dir(store)
    if expect_version == 0 and name == DEFAULT_NAME and not SetupStore(store_dir).path(name).is_file():
        # The built-in is version 0 too, but --expect-version 0 means "a new setup".
        raise UserError(
            f"setup {name} exists (version 0, built in); --expect-version 0 saves only a new setup: "
            "leave --expect-version out to replace the built-in",
        )

    try:
        data = tomllib.loads(from_file.read_text(encoding="utf-8"))
    except OSError as exc:
        raise UserError(f"--from {from_file}: cannot read it ({exc.strerror or exc})") from None
    except UnicodeDecodeError:
        raise UserError(f"--from {from_file}: not UTF-8 text") from None
    except tomllib.TOMLDecodeError as exc:
        raise UserError(f"--from {from_file}: not valid TOML ({exc})") from None
    from daq.workflows.errors import WorkflowError

    try:
        resolved = save_setup(store_dir, name, strip_saved(data), expect_version)
    except WorkflowError as exc:
        raise UserError(f"{from_file}: {exc}") from None
    print(f"Saved setup {resolved.name} version {resolved.version}")
    print_cautions(resolved.cautions)


@transducer_app.command("list")
def transducer_list(store: StoreOption = None, as_json: JsonOption = False) -> None:
    """List the transducers, the built-ins included; overdue calibrations are marked."""
    from daq.store.transducers import TransducerTable

    items = [t.to_dict() for t in TransducerTable(_store_dir(store)).all()]
    if as_json:
        print(json.dumps({"transducers": items}, indent=2, ensure_ascii=False))
        return
    width = max(len(t["id"]) for t in items)
    labels = [f"{t['model']} {t['serial']}".strip() or "-" for t in items]  # "-": none given
    label_width = max(len(label) for label in labels)
    for t, label in zip(items, labels, strict=True):
        due = f"due {t['due']}" if t["due"] else "no due date"
        mark = "  OVERDUE" if t["overdue"] else ""
        sens = f"{t['sensitivity']:g} {t['sensitivity_unit']}"
        print(f"{t['id']:<{width}}  {t['kind']:<13}  {sens:<16}  {label:<{label_width}}  ({due}){mark}")


_SENSITIVITY = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*([A-Za-z]\S*)\s*$")


def parse_sensitivity(text: str) -> tuple[float, str]:
    """("2.25 mV/N") -> (2.25, "mV/N"); UserError (exit 2) otherwise."""
    from daq.store.transducers import UNITS

    match = _SENSITIVITY.match(text)
    units = ", ".join(UNITS)
    if match is None:
        raise UserError(f"--sensitivity: give a number and a unit, e.g. '2.25 mV/N' ({units})", exit_code=2)
    try:
        value = float(match.group(1))
    except ValueError:
        raise UserError(f"--sensitivity: {match.group(1)!r} is not a number", exit_code=2) from None
    return value, match.group(2)


@transducer_app.command("add")
def transducer_add(
    ident: Annotated[str, typer.Argument(metavar="ID", help="A plain name, e.g. hammer-1.")],
    kind: Annotated[str, typer.Option(metavar="<hammer|accelerometer>", help="What it is.")],
    sensitivity: Annotated[
        str,
        typer.Option(
            metavar="<value unit>",
            help="As the calibration sheet gives it: '2.25 mV/N', '10 mV/g', '1.02 mV/(m/s^2)'.",
        ),
    ],
    model: Annotated[str, typer.Option(metavar="<text>", help="Its model.")] = "",
    serial: Annotated[str, typer.Option(metavar="<text>", help="Its serial number.")] = "",
    calibrated: Annotated[
        str, typer.Option(metavar="<YYYY-MM-DD>", help="Date of its last calibration.")
    ] = "",
    due: Annotated[str, typer.Option(metavar="<YYYY-MM-DD>", help="Date the next calibration is due.")] = "",
    store: StoreOption = None,
) -> None:
    """Add a transducer, or replace the one of that ID."""
    from daq.store.errors import StoreError
    from daq.store.transducers import Transducer, TransducerTable

    value, unit = parse_sensitivity(sensitivity)
    fields = {
        "id": ident, "kind": kind, "model": model, "serial": serial, "sensitivity": value,
        "sensitivity_unit": unit, "calibrated": calibrated, "due": due,
    }  # fmt: skip
    try:
        transducer = Transducer.from_dict(fields, f"transducer {ident}")
    except StoreError as exc:
        raise UserError(str(exc), exit_code=2) from None
    table = TransducerTable(_store_dir(store))
    replaced = transducer.id in {t.id for t in table.all()}
    table.put(transducer)
    print(
        f"Transducer {transducer.id}{' replaced' if replaced else ''}: {transducer.kind}, "
        f"{transducer.sensitivity:g} "
        f"{transducer.sensitivity_unit} = {transducer.sensitivity_v_per_eu:.6g} "
        f"V/{'N' if transducer.eu == 'N' else f'({transducer.eu})'}"
    )
    from datetime import date

    if transducer.overdue(date.today()):
        print_cautions([f"transducer {transducer.id} calibration was due {transducer.due}"])
