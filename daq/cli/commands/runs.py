"""`daq runs list`, `daq runs show`, `daq runs verify`: what the run store holds.

The store folder comes from --store, $DAQ_STORE, the config file or the per-user
data folder, in that order (daq.store.resolve_store_dir). `list` names the store and
where its location came from on stderr, so that its stdout stays clean for --json.
"""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path
from typing import Annotated, Any

import typer

from daq.cli.errors import UserError
from daq.cli.options import JsonOption, StoreOption
from daq.report.numbers import span
from daq.workflows.run_views import run_dict, summary_dict

runs_app = typer.Typer(
    help="List, show and check the runs in the run store.\n\n"
    "Each impact test is one HDF5 file in the store folder, named by its run id. "
    "The folder is --store, else $DAQ_STORE, else the config file's store, else the "
    "per-user data folder (see `daq config`).",
    invoke_without_command=True,
)


def register(app: typer.Typer) -> None:
    """Add `daq runs` to ``app`` (once: a second call does nothing)."""
    if any(group.name == "runs" for group in app.registered_groups):
        return
    app.add_typer(runs_app, name="runs")


@runs_app.callback()
def _runs(ctx: typer.Context) -> None:
    if ctx.invoked_subcommand is None:
        # A bare `daq runs`: the help is the answer, not an error.
        typer.echo(ctx.get_help())
        raise typer.Exit()


def _store(option: str | None):
    from daq.store import Store, resolve_store_dir

    path, source = resolve_store_dir(option)
    return Store(path), source


def _note(text: str) -> None:
    sys.stderr.write(" ".join(text.split()) + "\n")
    sys.stderr.flush()


def _dumps(data: Any) -> str:
    # JSON escapes C0 controls (ESC is \u001b); C1 ones (U+009B is a CSI to many
    # terminals) only with ensure_ascii, which would escape every accent too.
    text = json.dumps(data, indent=2, ensure_ascii=False, default=_json_default)
    return _C1.sub(lambda m: f"\\u{ord(m.group()):04x}", text)


#: Control characters: C0 (ESC, BEL, CR...), DEL and C1 (U+0080..U+009F, CSI among them).
_CONTROLS = re.compile(r"[\x00-\x1f\x7f-\x9f]")
_C1 = re.compile(r"[\x7f-\x9f]")


def shown(value: Any) -> str:
    """``value`` as text safe to print: every control character written as a Python
    escape (ESC as \\x1b, a line break as \\n), so that text from a run file, which
    may come from anywhere, never drives the terminal that lists it."""
    text = value if isinstance(value, str) else str(value)
    return _CONTROLS.sub(lambda m: m.group().encode("unicode_escape").decode("ascii"), text)


def _json_default(value: Any) -> Any:
    # numpy scalars and arrays that reach a JSON dump (settings, sample constants).
    if hasattr(value, "tolist"):
        return value.tolist()
    if isinstance(value, Path):
        return str(value)
    raise TypeError(f"{type(value).__name__} is not JSON serialisable")


# ----------------------------------------------------------------------- list
@runs_app.command(name="list")
def list_runs(store: StoreOption = None, as_json: JsonOption = False) -> None:
    """List the runs of the store, oldest first.

    Damaged files are listed too, marked DAMAGED, with what is wrong with them.
    The first line on stderr names the store and where its location came from.
    """
    the_store, source = _store(store)
    summaries = the_store.list() if the_store.path.exists() else []
    # Only now, when nothing can fail any more: an error stays the one line on stderr.
    _note(f"store {the_store.path} (from {source})")
    if not summaries:
        why = "no runs yet" if the_store.path.is_dir() else "the folder does not exist yet"
        _note(f"no runs in this store: {why}")
    if as_json:
        print(_dumps([summary_dict(s) for s in summaries]))
        return
    if summaries:
        _print_table(summaries, the_store.path)


def _print_table(summaries, store_dir: Path) -> None:
    from rich.console import Console
    from rich.markup import escape
    from rich.table import Table

    table = Table(box=None, header_style="bold", pad_edge=False)
    # The id is what a user copies into every other command: never cut it (nor the
    # date, kind and counts); operator and note take what width is left.
    id_width = max(len(s.run_id) for s in summaries)
    table.add_column("run id", no_wrap=True, min_width=id_width)
    table.add_column("started (UTC)", no_wrap=True, min_width=19)
    table.add_column("kind", no_wrap=True, min_width=9)
    table.add_column("status", no_wrap=True, min_width=10)
    table.add_column("hits", justify="right", no_wrap=True)
    table.add_column("accepted", justify="right", no_wrap=True)
    table.add_column("operator", overflow="fold")
    table.add_column("note", overflow="fold")
    for s in summaries:
        if s.error is not None:
            table.add_row(escape(shown(s.run_id)), "", "", "[red]DAMAGED[/]", "", "", "", "see below")
            continue
        table.add_row(
            escape(shown(s.run_id)),
            escape(shown(s.start_time[:19].replace("T", " "))),
            escape(shown(s.kind)),
            "complete" if s.complete else "[yellow]incomplete[/]",
            str(s.n_hits),
            str(s.n_accepted),
            escape(shown(s.operator)),
            escape(shown(" ".join(s.note.split()))),
        )
    console = Console()
    if not console.is_terminal:
        # Piped into grep or a file: no terminal width to respect, so cut nothing.
        console = Console(width=1000)
    console.print(table)
    damaged = [s for s in summaries if s.error is not None]
    for s in damaged:
        # Plain print: a long error must not be wrapped or cut by the table.
        error = s.error.removeprefix(f"{store_dir / s.file_name}: ")
        print(f"DAMAGED {shown(s.file_name)}: {shown(error)}")
    if damaged:
        print("('daq runs verify' lists every problem of a file)")


# ----------------------------------------------------------------------- show
@runs_app.command()
def show(
    run: Annotated[
        str,
        typer.Argument(
            metavar="RUN", help="A run id, any unique start of one (e.g. 20261123T1015), or latest."
        ),
    ],
    store: StoreOption = None,
    as_json: JsonOption = False,
) -> None:
    """Show what one run holds: metadata, hits, FRFs, spectra."""
    from daq.store import open_run

    the_store, source = _store(store)
    path = the_store.resolve(run)
    data = run_dict(open_run(path), path)
    if as_json:
        print(_dumps(data))
        return
    _print_run(data, f"{the_store.path} (from {source})")


def _one_line(value: Any) -> str:
    text = value if isinstance(value, str) else json.dumps(value, ensure_ascii=False, default=_json_default)
    return " ".join(text.split())


#: Shown in place of a hit's time for a run read from a file, which records none (the
#: store keeps the file's modification time there).
HIT_TIME_UNKNOWN = "time not recorded".ljust(24)


def _failed_text(names: list[str]) -> str:
    """The failed checks in words: "the double impact check failed", "the a and b checks failed"."""
    names = [_one_line(n) for n in names]
    if not names:
        return "a check failed"
    if len(names) == 1:
        return f"the {names[0]} check failed"
    return f"the {', '.join(names[:-1])} and {names[-1]} checks failed"


def _print_run(d: dict[str, Any], store: str) -> None:
    from daq.store.model import FRF_FORM_UNITS

    def field(name: str, value: Any) -> None:
        print(f"{name:<14}{shown(value)}")  # every value may come from a foreign file

    field("run", d["run_id"])
    field("file", f"{d['file']} ({d['size_bytes']} bytes)")
    field("store", store)
    field("kind", d["kind"])
    field("status", "complete" if d["complete"] else "incomplete (sealed after an interruption)")
    field("started", d["start_time"])
    field("ended", d["end_time"])
    field("operator", _one_line(d["operator"]) or "-")
    field("note", _one_line(d["note"]) or "-")
    field("software", d["software"])
    field("provenance", _one_line(d["provenance"]) if d["provenance"] else "-")
    prov = d["provenance"] if isinstance(d["provenance"], dict) else {}
    setup = prov.get("setup")
    if isinstance(setup, dict) and setup.get("name"):
        version = f" version {setup['version']}" if setup.get("version") is not None else ""
        field("setup", f"{_one_line(setup['name'])}{version}")
    if "auto_range" in prov:
        from daq.workflows.run_views import auto_range_text

        source = ((d["instrument"] or {}).get("settings") or {}).get("trigger_source")
        field("auto-range", auto_range_text(prov["auto_range"], source) or _one_line(prov["auto_range"]))
    cautions = prov.get("cautions")
    for text in cautions if isinstance(cautions, list) else []:
        field("caution", _one_line(text).removeprefix("caution: "))
    inst = d["instrument"]
    if inst is None:
        field("instrument", "-")
    else:
        field(
            "instrument",
            f"{inst['model']} at {inst['resource']} via {inst['transport']}, dialect {inst['dialect']}",
        )
        field("", f"identification: {_one_line(inst['identification'])}")
        if inst.get("settings"):
            field("", f"settings: {_one_line(inst['settings'])}")
    sample = d["sample"]
    if sample is None:
        field("sample", "-")
    else:
        field("sample", ", ".join(f"{k} {v:g}" for k, v in sample.items() if v is not None))
    points = d.get("points")
    if points:

        def where(p: dict) -> str:
            place = f"{p['position_m']:g} m" if p.get("position_m") is not None else f"node {p.get('node')}"
            return f"{p['name']} ({place}, {p['direction']})"

        test = f"test {points['test']}, " if points.get("test") else ""
        said = "" if points.get("recorded") else " (not recorded: the seed's beam at the tip assumed)"
        responses = ", ".join(where(p) for p in points["response_points"])
        if not points.get("recorded") and d.get("kind") == "imported":
            field("points", "not recorded (the imported file says nothing of the structure)")
        else:
            field("points", f"{test}force at {where(points['force_point'])}, response at {responses}{said}")
    hits = d["hits"]
    if hits is None:
        field("hits", "none")
    else:
        band = f"zoom around {hits['center_hz']:g} Hz" if hits["zoom"] else "baseband"
        field(
            "hits",
            f"{hits['n_hits']}: {hits['n_accepted']} accepted, {hits['n_rejected']} rejected; "
            f"{hits['n_samples']} samples at {hits['sample_rate_hz']:g} Hz from "
            f"{hits['start_s']:g} s, {band}; numbered from 1",
        )
        for h in hits["hits"]:
            overload = [
                c for c, on in (("force", h["overload_force"]), ("response", h["overload_response"])) if on
            ]
            verdict = "accepted" if h["accepted"] else f"rejected: {_one_line(h['reject_reason'])}"
            if h.get("accepted_against_checks"):
                verdict = f"accepted although {_failed_text(h['failed_checks'])}"
            extra = f", OVERLOAD {'+'.join(overload)}" if overload else ""
            when = h["timestamp_utc"] if h.get("time_recorded", True) else HIT_TIME_UNKNOWN
            field("", f"hit {h['number']:>3}  {when}  peak {h['peak_force_n']:.4g} N{extra}  {verdict}")
        against = [h for h in hits["hits"] if h.get("accepted_against_checks")]
        for h in against:
            field("caution", f"hit {h['number']}: accepted although {_failed_text(h['failed_checks'])}")
    for name, key in (("analyzer", "analyzer"), ("measured FRF", "measured_frf")):
        frf = d[key]
        if frf is None:
            field(name, "none")
            continue
        coherence = "with coherence" if frf["coherence"] else "no coherence"
        field(
            name,
            f"{frf['n_frf']} FRF(s) x {frf['n_lines']} points, "
            f"{span(frf['f_min_hz'], frf['f_max_hz'], 'g')}, "
            f"{frf['form']} ({FRF_FORM_UNITS[frf['form']]}), {coherence}; "
            f"labels: {', '.join(_one_line(x) for x in frf['labels'])}",
        )
    spectra = d["spectra"]
    if spectra is None:
        field("spectra", "none")
        return
    traces = [
        f"{_one_line(label)} ({kind}, {_one_line(unit) or 'dimensionless'})"
        for label, kind, unit in zip(spectra["labels"], spectra["kinds"], spectra["units"], strict=True)
    ]
    field(
        "spectra",
        f"{spectra['n_traces']} x {spectra['n_lines']} points, "
        f"{span(spectra['f_min_hz'], spectra['f_max_hz'], 'g')}: {', '.join(traces)}",
    )


# --------------------------------------------------------------------- verify
@runs_app.command()
def verify(
    runs: Annotated[
        list[str] | None,
        typer.Argument(
            metavar="RUN",
            show_default=False,
            help="Run ids or unique starts of them; default: every run of the store.",
        ),
    ] = None,
    store: StoreOption = None,
    as_json: JsonOption = False,
    repair: Annotated[
        bool,
        typer.Option(
            "--repair", help="Remove the temporaries crashed writes left (untouched for an hour or more)."
        ),
    ] = False,
) -> None:
    """Check run files end to end; exit 1 if any has a problem.

    Every dataset is read in full, so every checksum is checked, and every run is
    decoded. Prints OK or the problems of each run, and the temporaries crashed writes
    left behind (--repair removes them).
    """
    from daq.store import verify as verify_file
    from daq.store.verify import leftover_temporaries, remove_temporaries

    the_store, source = _store(store)
    if repair:
        for path in remove_temporaries(the_store.path):
            _note(f"removed {shown(path.name)}: a temporary a crashed write left")
    for path in leftover_temporaries(the_store.path):
        _note(f"leftover {shown(path.name)}: a temporary a crashed write left; --repair removes it")
    if runs:
        paths = list(dict.fromkeys(the_store.resolve(name) for name in runs))
    else:
        summaries = the_store.list() if the_store.path.exists() else []
        paths = [the_store.path / s.file_name for s in summaries]
    results = [(path, verify_file(path)) for path in paths]
    bad = [path for path, problems in results if problems]
    if as_json:
        print(
            _dumps(
                [
                    {
                        "run_id": path.name.removesuffix(".h5"),
                        "file": str(path),
                        "ok": not problems,
                        "problems": problems,
                    }
                    for path, problems in results
                ]
            )
        )
    else:
        print(f"store {the_store.path} (from {source})")
        for path, problems in results:
            run_id = path.name.removesuffix(".h5")
            if not problems:
                print(f"OK       {run_id}")
                continue
            print(f"PROBLEM  {shown(run_id)}: {shown(' '.join(problems[0].split()))}")
            for problem in problems[1:]:
                print(f"         {shown(run_id)}: {shown(' '.join(problem.split()))}")
        if results:
            print(f"{len(results)} run(s) checked: {len(results) - len(bad)} OK, {len(bad)} with problems")
    if not results:
        _note(f"no runs in store {the_store.path}: nothing to verify")
    if bad:
        names = ", ".join(path.name.removesuffix(".h5") for path in bad[:3]) + (
            ", ..." if len(bad) > 3 else ""
        )
        raise UserError(f"{len(bad)} of {len(results)} run(s) have problems: {names}")
