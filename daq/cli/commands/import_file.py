"""`daq import FILE`: time records, FRFs or spectra from another system become a run.

Formats: CSV / whitespace text (daq/formats/csv_text.py), UFF dataset 58
(daq/formats/uff58.py), HP's Standard Data Format (daq/formats/sdf/) and a run file of
another store (``run``: checked as every stored run is, then sealed here as a new run).
The file is read and checked whole before anything is written: a file that is not what
it claims leaves the store untouched. The new run is marked ``imported`` with the
source's name, size and SHA-256, so it can always be traced back to the bytes it came from.
"""

from __future__ import annotations

import contextlib
import enum
import math
import os
from collections.abc import Iterator
from pathlib import Path
from typing import Annotated, Any

import typer

from daq.cli.errors import UserError
from daq.cli.options import NextPointOption, PointOption, StoreOption, TestOption

HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"
SDF_SUFFIXES = (".sdf",)
TEXT_SUFFIXES = (".csv", ".txt", ".tsv", ".dat", ".asc")
UFF_SUFFIXES = (".uff", ".unv", ".uf")
#: The formats of time records as text, which take --columns, the units and --sample-rate.
TIME_TEXT = ("csv", "lvm")


class FrfForm(enum.StrEnum):
    receptance = "receptance"
    mobility = "mobility"
    accelerance = "accelerance"


class ImportFormat(enum.StrEnum):
    auto = "auto"
    csv = "csv"
    lvm = "lvm"
    frf_text = "frf-text"
    uff = "uff"
    sdf = "sdf"
    run = "run"


def register(app: typer.Typer) -> None:
    app.command(name="import")(import_file)


def import_file(
    file: Annotated[Path, typer.Argument(metavar="FILE", show_default=False, help="The file to import.")],
    format: Annotated[
        ImportFormat,
        typer.Option(
            "--format",
            "-f",
            help="csv (time records as text), lvm (LabVIEW Measurement, a hit per segment), "
            "frf-text (a table of frequency and Re/Im or "
            "magnitude/phase per FRF), uff (dataset 58), sdf (HP Standard Data Format), "
            "run (a run file of another store); auto decides from the content and the name, and says why.",
        ),
    ] = ImportFormat.auto,
    columns: Annotated[
        str | None,
        typer.Option(
            metavar="<t,F,a>",
            help="CSV: the time, force and response columns, by header name or 0-based index "
            "[default: by the header's names or units where they say which is the force and which the "
            "response, else the first three].",
        ),
    ] = None,
    force_unit: Annotated[
        str | None,
        typer.Option(
            metavar="<unit>",
            help="CSV: N, kN, lbf, or volts with a sensitivity: mV@2.25mV/N; wins over the header's "
            "unit [default: the header's, else N].",
        ),
    ] = None,
    response_unit: Annotated[
        str | None,
        typer.Option(
            metavar="<unit>",
            help="CSV: m/s^2, g, mm/s^2, or volts with a sensitivity: mV@10mV/g; wins over the "
            "header's unit [default: the header's, else m/s^2].",
        ),
    ] = None,
    sample_rate: Annotated[
        float | None,
        typer.Option(
            "--sample-rate",
            metavar="<Hz>",
            show_default=False,
            help="CSV: the sample rate to store instead of the one fitted to the time column; refused "
            "if the printed times do not allow it. A file of force and response alone (no time column) "
            "takes its times from it, k / rate [default: the fitted rate, or a preamble's].",
        ),
    ] = None,
    frf_form: Annotated[
        FrfForm | None,
        typer.Option(
            help="frf-text: what the values are (displacement, velocity or acceleration over force, "
            "in SI units); wins over the header's unit [default: the header's, else accelerance].",
        ),
    ] = None,
    operator: Annotated[str, typer.Option(metavar="<name>", help="Stored with the run.")] = "",
    note: Annotated[str, typer.Option(metavar="<text>", help="Stored with the run.")] = "",
    test: TestOption = None,
    point: PointOption = None,
    next_point: NextPointOption = False,
    as_test: Annotated[
        str | None,
        typer.Option(
            "--as-test",
            metavar="<name>",
            help="UFF holding the FRFs of several points (58 with node numbers, 15 geometry): import it as "
            "a whole new test of this name, one run per FRF.",
        ),
    ] = None,
    article: Annotated[
        str | None,
        typer.Option(
            metavar="<seed-beam|file.toml>",
            show_default=False,
            help="With --as-test: the test article; on a beam the nodes' X coordinates are the positions "
            "[default: the file's nodes as a free structure].",
        ),
    ] = None,
    force_at: Annotated[
        float | None,
        typer.Option(
            "--force-at",
            metavar="<metres>",
            show_default=False,
            help="Without --test: where the hammer struck the seed's beam, m from the clamp "
            "[default: the tip].",
        ),
    ] = None,
    sensor_at: Annotated[
        float | None,
        typer.Option(
            "--sensor-at",
            metavar="<metres>",
            show_default=False,
            help="Without --test: where the accelerometer sat on the seed's beam, m from the clamp "
            "[default: the tip].",
        ),
    ] = None,
    store: StoreOption = None,
) -> None:
    """Import a CSV, FRF table, UFF 58, SDF or run file into the store as a new run (kind "imported").

    CSV: columns time (s), force, response; one hit, or several (a `hit` column, or
    time starting over); units from the header (`Force [N]`) unless given. FRF table
    (frf-text): frequency, then Re/Im or magnitude/phase per FRF, stored as measured FRFs
    in their form (receptance, mobility, accelerance). UFF: dataset 58 time records (force
    and acceleration) and/or FRFs with coherence. SDF (HP analyzers, revisions 1-3): time
    records of a force and a response channel, FRFs with coherence, and spectra (power,
    linear, cross, coherence alone), kept as the run's spectra, not FRFs. Nothing is
    written unless the whole file reads cleanly.
    """
    from daq.cli.commands.capture import check_operator_and_note
    from daq.formats.errors import FormatError
    from daq.formats.imported import show_path
    from daq.store import Run, Store, StoreError, new_run_id, resolve_store_dir
    from daq.workflows.capture import utc_now

    check_operator_and_note(operator, note)  # before the file is even read
    if as_test is not None or article is not None:
        import_as_test(file, as_test, article, format, operator, note, store,
                       test is not None or point is not None or next_point or force_at is not None
                       or sensor_at is not None)  # fmt: skip
        return
    where, points = import_points(store, test, point, next_point, force_at, sensor_at)
    if format is ImportFormat.auto:
        chosen, why = detect_format(file)
        how = f"detected: {why}"
    else:
        chosen, how = format.value, "given by --format"
    if chosen not in TIME_TEXT and (
        columns is not None or force_unit is not None or response_unit is not None
    ):
        raise UserError(
            "--columns, --force-unit and --response-unit apply to CSV and LVM files only", exit_code=2
        )
    if sample_rate is not None and chosen not in TIME_TEXT:
        raise UserError(
            f"--sample-rate applies to CSV and LVM time records only, not {chosen} files"
            + (" (an FRF table has no sample rate)" if chosen == "frf-text" else ""),
            exit_code=2,
        )
    if sample_rate is not None and not (math.isfinite(sample_rate) and sample_rate > 0):
        raise UserError(f"--sample-rate {sample_rate:g}: give a rate above 0 Hz", exit_code=2)
    if chosen != "frf-text" and frf_form is not None:
        raise UserError("--frf-form applies to frf-text files only", exit_code=2)
    started = utc_now()
    store_dir, _ = resolve_store_dir(store)
    with _no_empty_store_left(store_dir):
        try:
            Store(store_dir).ensure_writable()
        except StoreError as exc:
            raise UserError(str(exc)) from None
        if format is not ImportFormat.auto and chosen in ("csv", "frf-text"):
            check_forced_format(file, chosen)
        digest, size = sha256_of(file)
        if chosen == "run":
            parts = _from_run_file(file)
        else:
            try:
                data = _read(file, chosen, columns, force_unit, response_unit, frf_form, sample_rate)
                check_read(file, chosen, format is not ImportFormat.auto, data)
            except MemoryError:
                # A well-formed file can still decode to more than this machine holds (int16
                # samples become float64 records four times their size).
                raise UserError(
                    f"{file}: its data do not fit in this machine's memory once decoded; nothing imported"
                ) from None
            except (FormatError, UserError) as exc:
                if format is not ImportFormat.auto:
                    raise
                # The "format ... detected" line is printed only on success: say here which
                # reader refused the file, and why it was chosen.
                raise UserError(f"{exc} (read as {chosen}: {how})", getattr(exc, "exit_code", 1)) from None
            parts = {
                "hits": data.hits,
                "measured_frfs": data.measured_frfs,
                "spectra": data.spectra,
                "details": data.details,
            }
        earlier = earlier_imports(store_dir, digest)
        provenance: dict[str, Any] = {
            "imported_from": {
                "file": file.name,
                "sha256": digest,
                "size_bytes": size,
                "format": chosen,
                "format_from": how,
                **parts.pop("details"),
            }
        }
        if points is not None:
            from daq.workflows.article import sample_for

            parts["sample"] = sample_for(points)
            parts["points"] = points
        try:
            run = Run(
                run_id=new_run_id(), kind="imported", complete=True, start_time=started, end_time=utc_now(),
                operator=operator, note=note, provenance=provenance, **parts,
            )  # fmt: skip
        except ValueError as exc:
            raise UserError(f"{file}: cannot make a run of it: {exc}") from None
        try:
            path = Store(store_dir).seal(run)
        except StoreError as exc:
            raise UserError(str(exc)) from None
    joined = ""
    if where is not None:
        # Joined before anything is printed: a closed pipe on stdout (| head) must not
        # leave a sealed run outside the test it was imported for.
        from daq.cli.commands.capture import join_run

        joined = join_run(store_dir, where, run.run_id)
    what = []
    if run.hits is not None:
        what.append(
            f"{counted(run.hits.n_hits, 'hit')} of {run.hits.n_samples} samples "
            f"at {run.hits.sample_rate_hz:g} Hz"
        )
    for frfs in (run.analyzer, run.measured_frfs):
        if frfs is not None:
            what.append(f"{counted(frfs.n_frf, 'FRF')} of {frfs.n_lines} points, {frfs.form}")
    if run.spectra is not None:
        what.append(f"{run.spectra.n_traces} spectra of {run.spectra.n_lines} points")
    typer.echo(f"Imported {show_path(file.name)} ({chosen}: {', '.join(what)}) as run {run.run_id}: {path}")
    if format is ImportFormat.auto:  # a given --format is named in the line above
        typer.echo(f"format {chosen}: {how}")
    for line in said_units(provenance["imported_from"]):
        typer.echo(line)
    for line in provenance["imported_from"].get("notes") or []:
        typer.echo(f"note: {line}")  # what the file holds that the run leaves out
    if short := short_note(run):
        typer.echo(f"note: {short}")
    for line in failed_hit_checks(run):
        typer.echo(f"note: {line}")
    for line in left_out_hits(run):
        typer.echo(f"note: {line}")
    if earlier:
        more = f" (and {counted(len(earlier) - 1, 'earlier run')})" if len(earlier) > 1 else ""
        typer.echo(
            f"note: the same file (SHA-256 {digest[:12]}...) was imported before as run {earlier[0]}{more}; "
            "this is another run of the same data"
        )
    for warning in unit_warnings(provenance["imported_from"]):
        typer.echo(f"warning: {warning}", err=True)
    if joined:
        typer.echo(joined)


@contextlib.contextmanager
def _no_empty_store_left(store_dir: Path) -> Iterator[None]:
    """The store folder, made before the file is read so that an unwritable store fails
    first, is removed again when the import is refused and the folder was made for it
    and is still empty: a refused import leaves nothing behind."""
    made = [d for d in (store_dir, *store_dir.parents) if not d.exists()]
    try:
        yield
    except BaseException:
        with contextlib.suppress(OSError):
            for folder in made:  # the store first, then the parents made for it
                folder.rmdir()  # refuses a folder that holds anything
        raise


def import_as_test(file: Path, name, article, format, operator, note, store, point_options: bool) -> None:
    """`daq import FILE --as-test NAME`: a multi-point UFF file as a new test, one run per FRF."""
    from daq.store import resolve_store_dir
    from daq.workflows.test_import import import_uff_test

    if name is None:
        raise UserError("--article goes with --as-test NAME", exit_code=2)
    if point_options:
        raise UserError(
            "--as-test makes a new test of the whole file: no --test, --point, --next, --force-at", 2
        )
    if format is not ImportFormat.auto and format.value != "uff":
        raise UserError("--as-test reads UFF files only", exit_code=2)
    if not file.is_file():
        raise UserError(f"{file}: no such file")
    store_dir, _ = resolve_store_dir(store)
    test, runs, notes = import_uff_test(store_dir, file, name, article, operator, note)
    typer.echo(
        f"Imported {file.name} as test {test.name}: {len(runs)} FRFs at {len(test.points)} points, roving "
        f"{test.roving}, fixed at {test.fixed_point.name}; daq test analyze {test.name}"
    )
    for line in notes:
        typer.echo(f"note: {line}")


def import_points(store, test, point, next_point, force_at, sensor_at):
    """(the test's point or None, the run's points or None) from --test/--point/--next or
    --force-at/--sensor-at; UserError (exit 2) on a bad combination."""
    from daq.cli.commands.capture import moved_points, test_point

    if test is None and (point is not None or next_point):
        raise UserError("--point and --next need --test NAME", exit_code=2)
    if test is not None:
        if force_at is not None or sensor_at is not None:
            raise UserError("--force-at and --sensor-at come from the test's point with --test", exit_code=2)
        where = test_point(store, test, point, next_point)
        return where, where.points
    if force_at is None and sensor_at is None:
        return None, None
    from daq.store.model import article_length_m

    length = article_length_m({"kind": "seed-beam"})
    try:
        return None, moved_points(
            length if force_at is None else force_at, length if sensor_at is None else sensor_at
        )
    except ValueError as exc:
        raise UserError(f"--force-at/--sensor-at: {exc}", exit_code=2) from None


def counted(n: int, one: str, many: str | None = None) -> str:
    """ "1 hit", "3 hits"; with ``many``, its plural instead of ``one`` + "s"."""
    return f"{n} {one if n == 1 else (many or one + 's')}"


def unit_warnings(details: dict[str, Any]) -> list[str]:
    """What an importer kept in units it could not convert to SI (e.g. an SDF channel in
    volts, the analyzer's engineering units being off), so that the technician hears of it
    and not only the provenance: the run's datasets are labelled N, m/s^2, (m/s^2)/N."""
    notes = [v for v in (details.get("time_units") or {}).values() if isinstance(v, str)]
    notes += [v for v in details.get("frf_units") or [] if isinstance(v, str)]
    return [f"{note} (stored under the SI label)" for note in notes if "values kept" in note]


def said_units(details: dict[str, Any]) -> list[str]:
    """One line saying which units (and FRF form) the import used, and where each came from."""
    if "units_from" in details:
        origin = details["units_from"]
        return [
            f"units: time {details.get('time_unit', 's') or 's (made from the sample rate)'}, "
            f"force {details['force_unit']} "
            f"({origin['force']}), response {details['response_unit']} ({origin['response']})"
        ]
    if "form_from" in details:
        return [f"form: {details['form']} ({details['form_from']})"]
    forms = details.get("frf_forms")
    if forms:
        return [f"form: {', '.join(forms)} (from the UFF records' data types and units)"]
    return []


def left_out_hits(run) -> list[str]:
    """One line per hit stored as rejected at import, counted from 1, with why: the file
    rejects it, its force or response is zero throughout, or it copies an earlier hit."""
    from daq.workflows.run_views import failed_check_names

    if run.hits is None:
        return []
    # A hit with a failed check is already said, with its fate, by failed_hit_checks.
    return [
        f"hit {i + 1} is kept but left out of the average: {run.hits.reject_reason[i]}"
        for i in range(int(run.hits.n_hits))
        if not run.hits.accepted[i] and not failed_check_names(run.hits.checks[i])
    ]


def failed_hit_checks(run) -> list[str]:
    """One line per hit whose checks failed (double impact, clipped), counted from 1:
    kept and accepted, and `daq analyze` cautions about them, unless the file rejects
    the hit (then it says so)."""
    from analysis.hit_checks import RESPONSE_TIMING
    from daq.workflows.run_views import failed_check_names, skewed_channels, swapped_columns

    if run.hits is None:
        return []
    out = []
    swapped = swapped_columns(run)
    if swapped is not None:  # one line for the file; the hits' other checks read the wrong channel
        out.append(swapped[1])
    skewed = skewed_channels(run) if swapped is None else None
    if skewed is not None:  # one line for the file: the recorder's skew, not a hit's
        out.append(skewed[1])
    for i, checks in enumerate(run.hits.checks):
        if swapped is not None and i in swapped[0]:
            continue
        # A hit the file itself rejects (a '# rejected hit K' line) is already left out.
        kept = bool(run.hits.accepted[i])
        fate = (
            "it is kept and averaged, and daq analyze cautions about it"
            if kept
            else "the file rejects it, so it is left out of the average"
        )
        for name in failed_check_names(checks):
            if name == RESPONSE_TIMING and skewed is not None:
                continue
            out.append(f"hit {i + 1} failed the {name} check ({checks[name].get('detail', '')}); {fate}")
    return out


def guess_format(path: Path) -> str:
    """csv, frf-text, uff, sdf or run (see detect_format); UserError if unsure."""
    return detect_format(path)[0]


def detect_format(path: Path) -> tuple[str, str]:
    """(format, why) from the file's first bytes and its name; UserError if unsure.

    The content decides first (HDF5 signature: run; "B\\0" and a plausible SDF FILE_HDR:
    sdf; a UFF "-1" line: uff), then the name (.sdf, UFF and text suffixes); a text file
    whose header's first column is a frequency is an FRF table (frf-text), else csv."""
    from daq.formats.imported import check_regular_file, show_path

    check_regular_file(path)
    try:
        with open(path, "rb") as handle:
            head = handle.read(16384)
    except OSError as exc:
        raise UserError(f"{show_path(path)}: cannot read it ({exc.strerror or exc})") from None
    if head.startswith(HDF5_SIGNATURE):
        return "run", "the HDF5 signature of a run file"
    if said := hp_ascii_export(path, head):
        raise UserError(said)
    if looks_like_sdf(head):
        return "sdf", "an SDF FILE_HDR record at the start"
    suffix = path.suffix.lower()
    if looks_like_uff(head):
        return "uff", "it starts with a UFF -1 delimiter line"
    if suffix in UFF_SUFFIXES:
        return "uff", f"the name ends in {suffix}"
    if suffix in SDF_SUFFIXES:
        return "sdf", f"the name ends in {suffix}"
    from daq.formats.lvm import looks_like_lvm

    if looks_like_lvm(head):
        return "lvm", "it starts with LabVIEW's 'LabVIEW Measurement' line"
    if suffix == ".lvm":
        return "lvm", "the name ends in .lvm"
    if head.startswith(b"B\0"):
        # A NUL in the first two bytes is no text file: a damaged SDF file (HP analyzers
        # name theirs .DAT) gets the SDF reader's reason, not a CSV parse error.
        return "sdf", "it starts with SDF's B and NUL"
    if refusal := not_readable(path, head):
        raise UserError(refusal)
    preamble, names = frf_table_head(head)
    if names and preamble:
        return "frf-text", (
            f"{preamble} preamble line{'s' if preamble > 1 else ''}, then the column names "
            f"{', '.join(repr(n) for n in names[:4])}{', ...' if len(names) > 4 else ''}, a frequency first"
        )
    header = text_header(head)
    if header and is_frequency_header(header[0]):
        return "frf-text", f"the header's first column {header[0]!r} is a frequency"
    if header and f_then_frf_columns(header):
        more = ", ..." if len(header) > 3 else ""
        return (
            "frf-text",
            f"the header names {header[0]!r}, then FRF columns ({', '.join(header[1:3])}{more})",
        )
    if not header and (why := headerless_frf_table(head)):
        check_not_time_in_ms(path, head, why)
        return "frf-text", why
    if not header:
        check_not_slow_time(path, head)
    if suffix in TEXT_SUFFIXES:
        why = f"the name ends in {suffix}"
        return "csv", f"{why}, and the header's first column {header[0]!r} is no frequency" if header else why
    raise UserError(
        f"{show_path(path)}: cannot tell its format from its name or content; "
        "give --format csv, lvm, frf-text, uff, sdf or run"
    )


#: The header file of an HP analyzer's ASCII export (SDF_FILE_HDR ... as text); its data
#: lie beside it in files of one number per line (.X the axis, .TXT or .Y/.Z the values).
HP_ASCII_HEADER = b"SDF_FILE_HDR"
HP_ASCII_SUFFIXES = (".hdr", ".x", ".txt", ".y", ".z")


def hp_ascii_export(path: Path, head: bytes) -> str:
    """The refusal of a file of an HP analyzer's ASCII export (its SDF_FILE_HDR text header,
    or a column of numbers beside one), else "". Its header and numbers are in several
    files and the binary SDF file the analyzer saves holds them all: that one is read."""
    from daq.formats.imported import show_path

    header = path
    if HP_ASCII_HEADER not in head[:4096]:
        if path.suffix.lower() not in HP_ASCII_SUFFIXES:
            return ""
        beside = [p for p in path.parent.glob(f"{glob_escape(path.stem)}.*") if p.suffix.lower() == ".hdr"]
        try:
            header = next(p for p in beside if HP_ASCII_HEADER in p.read_bytes()[:4096])
        except (StopIteration, OSError):
            return ""
    return (
        f"{show_path(path)}: part of an HP analyzer's ASCII export (header {show_path(header.name)}, "
        "one number per line in the files beside it); import the SDF file the analyzer saved "
        "(its binary .DAT or .SDF file) instead: it holds the header and the data together"
    )


def glob_escape(text: str) -> str:
    return "".join(f"[{c}]" if c in "*?[" else c for c in text)


def looks_like_uff(head: bytes) -> bool:
    """``head`` (a file's first bytes) starts, after any blank lines, with UFF's "-1"
    delimiter line ("    -1", right-aligned in 6 columns)."""
    for line in head.splitlines():
        if line.strip():
            return line.strip() == b"-1" and len(line.rstrip()) <= 6
    return False


def check_forced_format(path: Path, chosen: str) -> None:
    """A file of another format (UFF, LabVIEW, an FRF table after a preamble) given to a
    text reader with --format gets one line saying what it is, not a column count."""
    from daq.formats.imported import check_regular_file, show_path

    check_regular_file(path)
    try:
        with open(path, "rb") as handle:
            head = handle.read(512)
    except OSError as exc:
        raise UserError(f"{show_path(path)}: cannot read it ({exc.strerror or exc})") from None
    if looks_like_uff(head):
        raise UserError(
            f"{show_path(path)}: looks like a UFF file (it starts with a UFF -1 delimiter line), "
            f"not {chosen}; import it with --format uff"
        )
    from daq.formats.lvm import looks_like_lvm

    if looks_like_lvm(head):
        raise UserError(
            f"{show_path(path)}: a LabVIEW measurement file (it starts with 'LabVIEW Measurement'), "
            f"not {chosen}; import it with --format lvm"
        )
    if chosen == "csv":
        preamble, names = frf_table_head(head)
        if names and preamble:
            lines = f"{preamble} preamble line{'s' if preamble > 1 else ''}"
            raise UserError(
                f"{show_path(path)}: an FRF table ({lines}, then the column names "
                f"{', '.join(repr(n) for n in names[:3])}, a frequency first), not time records; "
                "import it with --format frf-text"
            )
    if refusal := not_readable(path, head):
        raise UserError(refusal)


def not_readable(path: Path, head: bytes) -> str:
    """The one-line refusal of a file in a format daq does not read, told by ``head`` (its
    first bytes) or its name, saying what to export instead; "" for anything else. A
    binary file is never sent to the text readers, whose messages ("not UTF-8", "not a
    number") would not say what it is."""
    from daq.formats.imported import show_path

    name, suffix = show_path(path), path.suffix.lower()
    zipped = head.startswith(b"PK\x03\x04")
    binary = b"\0" in head
    if head.startswith(b"\x93NUMPY") or (suffix in (".npy", ".npz") and (zipped or binary)):
        kind = ".npz" if zipped or suffix == ".npz" else ".npy"
        return (
            f"{name}: a binary NumPy file ({kind}), which daq does not read; write the arrays as "
            "text, e.g. numpy.savetxt with columns time, force, response (or frequency, then Re, Im "
            "per FRF), and import that"
        )
    if head.startswith(b"RIFF") and head[8:12] == b"WAVE":
        return (
            f"{name}: a WAV audio file, which daq does not read (its samples carry no force or acceleration "
            "units); export the force and response channels as a CSV with a header row (time, force, "
            "response, with their units) and import that"
        )
    if zipped:
        from daq.formats.zip_contents import is_excel_workbook, member_names

        # Unpacked, a workbook gives XML parts, no table: it must be saved as CSV instead.
        if is_excel_workbook(member_names(path, head)):
            return (
                f"{name}: an Excel workbook (.xlsx), which daq does not read; save the sheet as CSV "
                "(or text) from the spreadsheet and import that"
            )
        return f"{name}: a ZIP archive; unpack it and import the files inside"
    if head.startswith((b"\xff\xfe", b"\xfe\xff")):
        return f"{name}: text in UTF-16, which daq does not read; save it as UTF-8 and import it again"
    if _utf16_without_bom(head):
        return (
            f"{name}: text in UTF-16 (no byte-order mark), which daq does not read; save it as UTF-8 and "
            "import it again"
        )
    if binary:
        return (
            f"{name}: binary content (NUL bytes), and none of the binary formats daq reads (a run file, "
            "HP SDF, UFF 58); export the data as text (CSV time records or an FRF table) and import that"
        )
    return ""


def _utf16_without_bom(head: bytes) -> bool:
    """Whether ``head`` reads as UTF-16 text with no byte-order mark. The text an export
    writes is mostly ASCII, whose UTF-16 form has a NUL as the high byte of every
    character (the second byte in little-endian, the first in big-endian) and a
    printable character or line end as the low byte; binary data have NULs at random
    places. Up to a tenth of the characters may lie beyond Latin-1 (a unit's Greek
    letter)."""
    pairs = len(head) // 2
    if pairs < 2:
        return False
    even, odd = head[0 : 2 * pairs : 2], head[1 : 2 * pairs : 2]
    for low, high in ((even, odd), (odd, even)):
        text = sum(32 <= b < 127 or b >= 160 or b in b"\t\r\n" for b in low)
        if 0 not in low and high.count(0) >= 0.9 * pairs and text >= 0.9 * pairs:
            return True
    return False


def frf_table_head(head: bytes) -> tuple[int, list[str]]:
    """(preamble lines, column names) of an FRF table in ``head`` whose column-name row
    comes after a preamble of metadata lines (daq/formats/frf_text.py, scan_layout);
    (0, []) when there is none."""
    from daq.formats.frf_text import decode_line, scan_layout

    if b"\0" in head:
        return 0, []
    raw_lines = head.splitlines(keepends=True)
    if raw_lines and not raw_lines[-1].endswith((b"\n", b"\r")):
        raw_lines = raw_lines[:-1]  # cut by the read: not a whole line
    layout = scan_layout([decode_line(raw, k == 0) for k, raw in enumerate(raw_lines)])
    if layout.header is None:
        return 0, []
    return len(layout.preamble), layout.header_cells


def text_header(head: bytes) -> list[str]:
    """The cells of a text file's header row (its first line that is neither empty nor a
    comment nor in a preamble of metadata lines, when it is not all numbers), or [] when
    there is none or it is no text."""
    from daq.formats.csv_text import COMMENT_MARKS, looks_complex, preamble_lines, split_cells

    if b"\0" in head:
        return []
    lines = head.decode("utf-8-sig", errors="replace").splitlines()
    preamble = {index for index, _ in preamble_lines(lines)}  # "Sample rate: 4000 Hz" is no header
    for index, line in enumerate(lines):
        stripped = line.strip()
        if not stripped or stripped.startswith(COMMENT_MARKS) or index in preamble:
            continue
        cells = [c.strip("\"'") for c in split_cells(stripped)[0]]
        while cells and not cells[-1]:
            cells.pop()  # "0,1,2,", "f,Re,Im,": a delimiter at the end of the line makes no cell
        filled = [c for c in cells if c]  # nor does an empty cell make a row of numbers a header
        numeric = 0
        for cell in filled:
            try:
                float(cell.replace(",", "."))
                numeric += 1
            except ValueError:
                numeric += looks_complex(cell)  # numbers too: the reader says what they are
        return cells if numeric < len(filled) else []
    return []


#: A text table (csv, frf-text) whose records or FRFs give fewer frequency lines above 0 Hz
#: than this is refused: no analysis can read it (`daq analyze`: "no line above 0 Hz"), a
#: time table of 2 rows, say. Shorter than an analysis needs (MIN_ANALYSIS_LINES, 8) but
#: not that short, an import goes ahead with a note (short_note).
REFUSED_BELOW_LINES = 1
#: A first column stepping by at least this many units is no time axis a vibration record
#: has (1/step samples per second, 10 or fewer): it is a frequency axis.
MIN_FREQUENCY_STEP = 0.1
#: ... and by at least this one, when its first line holds 0 Hz with zero imaginary parts.
MIN_FREQUENCY_STEP_AT_DC = 0.01


def headerless_frf_table(head: bytes) -> str:
    """Why the table in ``head`` (a text file's first bytes, no header row) is an FRF
    table rather than time records, or "" when nothing says so.

    Its rows hold an odd number (3 or more) of numbers, the first column rising by a
    steady step: a frequency and Re/Im pairs. As time that step would be a sampling rate
    of 10 samples/s or less (MIN_FREQUENCY_STEP); or the first line is 0 with every
    imaginary part exactly 0 (an FRF is real at 0 Hz) and the step is 0.01 or more.
    A frequency table exported without a header (frequency, Re, Im, as MATLAB's
    ``writematrix`` does) otherwise reads as one hit sampled at 1 Hz."""
    import numpy as np

    found = _steady_first_column(head)
    if found is None:
        return ""
    table, step = found
    if table.shape[1] < 3 or table.shape[1] % 2 == 0:
        return ""
    why = frequency_axis_why(step, table[0, 0] == 0 and bool(np.all(table[0, 2::2] == 0)))
    return f"no header, and its first column steps by {step:g}: {why}" if why else ""


def hammer_pulse_rows(force: Any, response: Any) -> tuple[int, int] | None:
    """(first, last) row (0-based) of a hammer's pulse in ``force`` (n_rows,) that starts a
    response (n_rows,); None otherwise. The pulse: its values of half its peak or more, 2 or
    more, of one sign within max(3, 2 %) of the rows, starting at row PULSE_FIRST_ROW or
    later, 80 % of the rows below 5 % of the peak. The response: quiet before the pulse
    (under 1 % of its energy), largest after it, ringing (PULSE_RING_CROSSINGS) and
    decaying (its last quarter's RMS under half its first quarter's).

    An FRF table's columns are no such pair. Near a resonance the real part of a mobility
    is such a peak, but the imaginary part beside it is as large on either side (the
    dispersive half of the circle), and the other forms' real parts take both signs; a
    resonance narrower than a line leaves one large value, not two."""
    import numpy as np

    x, y = np.asarray(force, dtype=float), np.asarray(response, dtype=float)
    peak = float(np.max(np.abs(x))) if x.size else 0.0
    if x.size < 16 or not peak > 0:
        return None
    big = np.flatnonzero(np.abs(x) >= 0.5 * peak)
    first, last = int(big[0]), int(big[-1])
    one_sign = big.size >= 2 and np.all(np.sign(x[big]) == np.sign(x[first]))
    narrow = last - first + 1 <= max(3, 0.02 * x.size)
    quiet = np.mean(np.abs(x) < 0.05 * peak) >= 0.8
    if not (one_sign and narrow and quiet and first >= PULSE_FIRST_ROW):
        return None
    energy = y**2
    before = float(np.sum(energy[: first - 2]))
    starts = before < 0.01 * float(np.sum(energy)) and int(np.argmax(energy)) >= first
    after = y[first:]
    rings = np.count_nonzero(np.diff(np.sign(after[np.abs(after) > 0.05 * np.max(np.abs(after))])) != 0)
    quarter = max(after.size // 4, 1)
    decays = np.sqrt(np.mean(after[-quarter:] ** 2)) < 0.5 * np.sqrt(np.mean(after[:quarter] ** 2))
    return (first, last) if starts and rings >= PULSE_RING_CROSSINGS and decays else None


#: A hammer's pulse is told from an FRF's peak (hammer_pulse_rows) only after this many
#: rows: the response must be seen quiet before it ...
PULSE_FIRST_ROW = 8
#: ... and ring after it, crossing zero this many times, and decay (a phase column beside a
#: magnitude falls from 0 to -pi past a resonance and stays there, wrapping at +-pi).
PULSE_RING_CROSSINGS = 6


def check_not_time_in_ms(path: Path, head: bytes, why: str) -> None:
    """A headerless table read as FRFs (``why``) whose second column is a hammer's pulse
    (hammer_pulse_rows), not an FRF's real part: UserError, not a time record in ms (first
    column 0, 0.488, 0.977, ...) stored as an FRF table without a word."""
    from daq.formats.imported import show_path

    found = _steady_first_column(head)
    pulse = None if found is None else hammer_pulse_rows(found[0][:, 1], found[0][:, 2])
    if pulse is not None:
        first, last = (k + 1 for k in pulse)
        rows = f"row {first}" if first == last else f"rows {first}-{last}"
        raise UserError(
            f"{show_path(path)}: cannot tell its format: {why}, yet its second column is a pulse of one "
            f"sign ({rows}) as a hammer's force is, not an FRF's real part; if its first column is time "
            "in ms, give the file a header row with units (Time [ms], Force [N], Acc [m/s^2]), or "
            "import it with --format csv --columns 1,2 --sample-rate HZ; if it is an FRF table, give it "
            "a header row naming its columns (e.g. Frequency (Hz), H1 Re, H1 Im)"
        )


def frequency_axis_why(step: float, real_at_zero: bool) -> str:
    """Why a headerless table's first column, rising by a steady ``step``, is a frequency
    axis (Hz), or "" when nothing says so. ``real_at_zero``: its first line is 0 and every
    imaginary part there is exactly 0. The one rule of both auto-detection
    (headerless_frf_table) and a forced --format frf-text (check_frequency_axis): a step of
    MIN_FREQUENCY_STEP or more, as time 10 samples/s or fewer, which records no vibration;
    or MIN_FREQUENCY_STEP_AT_DC or more with a real value at 0 Hz, as an FRF is there."""
    as_rate = f"as time, sampled at {1 / step:.3g} Hz"
    if step >= MIN_FREQUENCY_STEP:
        # No "--format csv if it is time": a time record that slow is refused (check_read).
        return f"{as_rate}, which records no vibration; a frequency axis"
    if step >= MIN_FREQUENCY_STEP_AT_DC and real_at_zero:
        return (
            f"{as_rate}, and at 0 every second value is exactly 0, as an FRF's imaginary part is "
            "at 0 Hz; a frequency axis (--format csv if it is time)"
        )
    return ""


def check_not_slow_time(path: Path, head: bytes) -> None:
    """A headerless table whose first column steps by MIN_FREQUENCY_STEP or more but which
    is no FRF table (an even number of columns) is neither: UserError, not a time record
    sampled at 10 Hz or less stored without a word."""
    from daq.formats.imported import show_path

    found = _steady_first_column(head)
    if found is not None and found[1] >= MIN_FREQUENCY_STEP:
        table, step = found
        raise UserError(
            f"{show_path(path)}: cannot tell its format: its first column steps by {step:g}, as time a "
            f"sampling rate of {1 / step:.3g} Hz, which records no vibration, and as a frequency axis it "
            f"needs an odd number of columns (frequency, then Re/Im pairs), not {table.shape[1]}; if it "
            "is an FRF table, give it a header row naming the columns (e.g. Frequency (Hz), H1 Re, "
            "H1 Im, H1 coh)"
        )


def check_read(path: Path, chosen: str, forced: bool, data: Any) -> None:
    """What a reader gave, refused when no analysis could use it (UserError or FormatError):

    - csv: a time step of MIN_FREQUENCY_STEP s or more (10 samples/s or fewer), which
      records no vibration: most likely a frequency axis read as time;
    - frf-text forced on a headerless table whose first column steps as time does
      (check_frequency_axis, the rule auto-detection uses);
    - a text table whose records or FRFs give fewer than REFUSED_BELOW_LINES frequency
      lines above 0 Hz (daq/formats/imported.py, short_of_lines).
    ``forced``: the format was given with --format."""
    from daq.formats.imported import short_of_lines, show_path

    name = show_path(path)
    hits = data.hits
    short = short_of_lines(hits, [data.measured_frfs])
    if short is not None and chosen in (*TIME_TEXT, "frf-text") and short[0] < REFUSED_BELOW_LINES:
        # First: a table of 2 rows is nothing at all, whatever its step.
        raise UserError(f"{name}: too short to analyse: {short[1]}")
    if chosen in TIME_TEXT and hits is not None:
        step = 1.0 / float(hits.sample_rate_hz)
        if step * (1 + 1e-9) >= MIN_FREQUENCY_STEP:
            header = data.details.get("header")
            if data.details.get("time_unit") is None:
                # No time column: the rate was given, and is what is wrong.
                raise UserError(
                    f"{name}: a sampling rate of {hz(hits.sample_rate_hz)} Hz records no vibration (a time "
                    f"record steps by less than {MIN_FREQUENCY_STEP:g} s); give the rate the file was "
                    "recorded at with --sample-rate HZ"
                )
            raise UserError(
                f"{name}: its time column steps by {step:g} s, a sampling rate of "
                f"{hz(hits.sample_rate_hz)} Hz, which records no vibration (a time record steps by less "
                f"than {MIN_FREQUENCY_STEP:g} s); if the first column is a frequency, import it with "
                "--format frf-text"
                + ("; if the times are in ms, say so in the header (e.g. Time (ms))" if header else "")
            )
    if chosen == "frf-text" and forced and not data.details.get("header"):
        check_frequency_axis(name, data.measured_frfs)


def check_frequency_axis(name: str, frfs: Any) -> None:
    """--format frf-text on a headerless table: UserError when its first column rises by a
    steady step that auto-detection would not take for a frequency axis (frequency_axis_why),
    e.g. 2e-5, a 51.2 kHz time record, which as frequency would be FRFs from 0 to 1 Hz.
    A header naming the column a frequency (Frequency (Hz)) says otherwise, and is heeded."""
    import numpy as np

    f = np.asarray(frfs.frequency_hz, dtype=float)
    if f.size < 2:
        return  # one line has no step (and is too short to analyse: short_of_lines says so)
    steps = np.diff(f)
    middle = float(np.median(steps))
    if not middle > 0 or np.any(np.abs(steps - middle) > 0.01 * middle):
        return  # no steady step (a log-spaced axis): nothing says it is time
    # The mean step: printed to 7 digits, a 51.2 kHz axis has single steps of 1.95e-05 and
    # 1.96e-05, while its span over its steps is 1.953125e-05. The slack, as in
    # _steady_first_column: 0.09999999999999998 counts as 0.1.
    step = float(f[-1] - f[0]) / (f.size - 1) * (1 + 1e-9)
    if frequency_axis_why(step, f[0] == 0 and bool(np.all(np.asarray(frfs.frf)[:, 0].imag == 0))):
        return
    raise UserError(
        f"{name}: its first column steps by {step:g}, which as frequency would be FRFs from {f[0]:g} to "
        f"{f[-1]:g} Hz, and as time a record sampled at {hz(1 / step)} Hz; without a header a frequency "
        f"axis steps by {MIN_FREQUENCY_STEP:g} Hz or more ({MIN_FREQUENCY_STEP_AT_DC:g} Hz from a real "
        "value at 0 Hz): import it with --format csv, or if it is a frequency, name it in a header row "
        "(e.g. Frequency (Hz))"
    )


def short_note(run: Any) -> str:
    """The note of a run too short for any analysis (daq/formats/imported.py, short_of_lines),
    or "": imported all the same, but told now rather than by `daq analyze` later."""
    from daq.formats.imported import short_of_lines

    short = short_of_lines(run.hits, [run.measured_frfs, run.analyzer])
    return f"too short to analyse: {short[1]}; daq analyze will refuse this run" if short else ""


def hz(value: float) -> str:
    """A rate or frequency for a message: whole hertz from 100 Hz up (51200, not 5.12e+04)."""
    return f"{value:.0f}" if value >= 100 else f"{value:.3g}"


#: The newest run files earlier_imports opens.
EARLIER_IMPORTS_CHECKED = 200


def earlier_imports(store_dir: Path, digest: str) -> list[str]:
    """Ids of the runs of the store at ``store_dir`` imported from a file of SHA-256
    ``digest`` (hex), newest first, among its EARLIER_IMPORTS_CHECKED newest run files:
    only runs of kind "imported" are opened, for their provenance alone. A run that cannot
    be read is passed over (runs verify tells of it)."""
    from daq.store import StoreError, read_summary
    from daq.store.h5io import get_json
    from daq.store.layout import ATTR_PROVENANCE, ENTRY
    from daq.store.reader import open_h5
    from daq.store.store import is_run_file_name

    try:
        names = sorted((e.name for e in os.scandir(store_dir) if is_run_file_name(e.name)), reverse=True)
    except OSError:
        return []
    # A few milliseconds per run opened: a store of thousands would slow every import by
    # seconds for a note, so only the newest are looked at (a file imported twice is
    # most often imported twice in a row).
    names = names[:EARLIER_IMPORTS_CHECKED]
    found = []
    for file_name in names:
        path = store_dir / file_name
        try:
            summary = read_summary(path)
            if summary.error is not None or summary.kind != "imported":
                continue
            with open_h5(path) as f:
                provenance = get_json(f[ENTRY], ATTR_PROVENANCE)
        except (StoreError, OSError, KeyError, TypeError, ValueError):
            continue
        source = provenance.get("imported_from") if isinstance(provenance, dict) else None
        if isinstance(source, dict) and source.get("sha256") == digest:
            found.append(summary.run_id)
    return found


def _steady_first_column(head: bytes) -> tuple[Any, float] | None:
    """(the numbers of the headerless table in ``head``, (rows, columns), and its first
    column's steady step) or None: not all numbers, ragged, fewer than 3 rows, or a first
    column that does not rise by one step within 1 %. A step read back from print as
    0.09999999999999998 counts as 0.1."""
    import numpy as np

    from daq.formats.csv_text import COMMENT_MARKS
    from daq.formats.frf_text import decode_line, split_cells

    if b"\0" in head:
        return None
    rows: list[list[float]] = []
    for k, raw in enumerate(head.splitlines()[:-1]):  # the last line may be cut by the read
        line = decode_line(raw, k == 0).strip()
        if not line or line.startswith(COMMENT_MARKS):
            continue
        cells, delimiter = split_cells(line)
        while cells and not cells[-1]:  # a delimiter at the end of the line: no cell
            cells.pop()
        try:
            rows.append([float(c.replace(",", ".") if delimiter != "," else c) for c in cells])
        except ValueError:
            return None
    if len(rows) < 3 or len({len(r) for r in rows}) != 1:
        return None
    table = np.array(rows)
    steps = np.diff(table[:, 0])
    step = float(np.median(steps))
    if not step > 0 or np.any(np.abs(steps - step) > 0.01 * step):
        return None
    return table, step * (1 + 1e-9)


def f_then_frf_columns(header: list[str]) -> bool:
    from daq.formats.frf_text import f_then_frf_columns as names_frfs

    return names_frfs(header)


def is_frequency_header(cell: str) -> bool:
    from daq.formats.csv_text import header_name_unit, is_frequency_name

    return is_frequency_name(*header_name_unit(cell))


def looks_like_sdf(head: bytes) -> bool:
    """``head`` (a file's first bytes) starts with SDF's "B\\0" and a FILE_HDR record of
    revision 1-3 whose size is one a FILE_HDR has (64 or 80 bytes, or more)."""
    if len(head) < 10 or not head.startswith(b"B\0"):
        return False
    kind = int.from_bytes(head[2:4], "big", signed=True)
    size = int.from_bytes(head[4:8], "big", signed=True)
    revision = int.from_bytes(head[8:10], "big", signed=True)
    return kind == 10 and 0 <= revision <= 3 and size >= 64


def sha256_of(path: Path) -> tuple[str, int]:
    """SHA-256 (hex) and size of the regular file at ``path``; UserError otherwise."""
    import hashlib

    from daq.formats.imported import check_regular_file, show_path

    check_regular_file(path)
    digest = hashlib.sha256()
    size = 0
    try:
        with open(path, "rb") as handle:
            while chunk := handle.read(1 << 20):
                digest.update(chunk)
                size += len(chunk)
    except OSError as exc:
        raise UserError(f"{show_path(path)}: cannot read it ({exc.strerror or exc})") from None
    return digest.hexdigest(), size


def _read(
    file: Path,
    chosen: str,
    columns: str | None,
    force_unit: str | None,
    response_unit: str | None,
    frf_form: str | None,
    sample_rate: float | None = None,
) -> Any:
    if chosen == "csv":
        from daq.formats.csv_text import read_csv

        return read_csv(file, columns, force_unit, response_unit, sample_rate_hz=sample_rate)
    if chosen == "lvm":
        from daq.formats.lvm import read_lvm

        return read_lvm(file, columns, force_unit, response_unit, sample_rate_hz=sample_rate)
    if chosen == "frf-text":
        from daq.formats.frf_text import read_frf_text

        return read_frf_text(file, None if frf_form is None else str(frf_form))
    if chosen == "sdf":
        from daq.formats.sdf.run_import import read_sdf_run

        return read_sdf_run(file)
    from daq.formats.uff58 import read_uff

    return read_uff(file)


def _from_run_file(file: Path) -> dict[str, Any]:
    """The data parts of another store's run file, checked as every run is."""
    from daq.formats.imported import check_regular_file
    from daq.store import StoreError, open_run

    check_regular_file(file)
    try:
        other = open_run(file, require_finite=True)  # NaN would fail analyze or replay later
    except StoreError as exc:
        raise UserError(str(exc)) from None
    return {
        "instrument": other.instrument,
        "sample": other.sample,
        "hits": other.hits,
        "analyzer": other.analyzer,
        "measured_frfs": other.measured_frfs,
        "spectra": other.spectra,
        "details": {
            "run_id": other.run_id,
            "kind": other.kind,
            "complete": other.complete,
            "operator": other.operator,
            "note": other.note,
        },
    }
