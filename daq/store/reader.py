"""Opening sealed runs: the whole run, its hits, or only the summary for listings.

Files are opened read-only with HDF5 file locking off (a sealed run never changes,
and locks fail on some network filesystems). Every failure, from a missing file to
a checksum mismatch deep in h5py, becomes one StoreError naming the file. A run held
in memory as bytes (e.g. sent to another process) is decoded by the same code, with
the same limits and refusals (open_run_bytes).
"""

from __future__ import annotations

import contextlib
import io
from collections.abc import Iterator
from pathlib import Path

import h5py

from daq.store import layout
from daq.store.decode import check_hits_counts, check_schema, decode_run, nonfinite_problems
from daq.store.errors import StoreError
from daq.store.h5io import get_bool, get_group, get_text, refuse_outside_references
from daq.store.model import Hits, Run
from daq.store.summary import parse_summary, read_root_summary
from daq.store.summary_model import RunSummary  # here too, under its old name


@contextlib.contextmanager
def open_h5(path: Path | str, whole_file_check: bool = True) -> Iterator[h5py.File]:
    """The HDF5 file at ``path`` opened read-only; errors become StoreError naming it.

    whole_file_check: refuse the file if any object links or maps data outside it.
    Callers that pass False must check each object they read (read_summary does).
    """
    path = Path(path)
    if not path.is_file():
        raise StoreError(f"{path}: no such run file")
    with _checked(lambda: h5py.File(path, "r", locking=False), str(path), whole_file_check) as f:
        yield f


@contextlib.contextmanager
def _checked(opener, name: str, whole_file_check: bool) -> Iterator[h5py.File]:
    try:
        with opener() as f:
            if whole_file_check:
                refuse_outside_references(f)
            yield f
    except StoreError as exc:
        # The same class (NotARunError stays one), the message naming the file.
        raise type(exc)(f"{name}: {exc}") from None
    except Exception as exc:
        # h5py reports damage as OSError, RuntimeError, KeyError or ValueError
        # depending on where HDF5 trips; all of it means "this file is damaged".
        raise StoreError(f"{name}: damaged or not an HDF5 run file ({_short(exc)})") from None


def open_run(path: Path | str, require_finite: bool = False) -> Run:
    """The complete run stored at ``path`` (all arrays read; checksums verified).

    require_finite: refuse a run whose records or spectra hold NaN or infinity (what
    an import of a run file wants: analysis and replay would fail on it later)."""
    with open_h5(path) as f:
        run = decode_run(f)
    return _finite(run, str(path), require_finite)


def open_run_bytes(data: bytes | bytearray | memoryview, name: str, require_finite: bool = False) -> Run:
    """The complete run whose file content is ``data`` (e.g. a run file read by another
    process and sent here), decoded exactly as open_run decodes a file on disk: the
    same refusals (links or data outside the file, declared sizes over the limits,
    another schema), checksums verified, every failure one StoreError naming ``name``
    (say the file's path where it was read)."""
    if not isinstance(data, (bytes, bytearray, memoryview)):
        raise StoreError(f"{name}: a run's bytes are needed, got {type(data).__name__}")
    with _checked(lambda: h5py.File(io.BytesIO(data), "r"), name, whole_file_check=True) as f:
        run = decode_run(f)
    return _finite(run, name, require_finite)


def read_hits(path: Path | str) -> Hits:
    """The time records of the run at ``path`` (what replay serves again), read as
    open_run reads the run: the whole file checked and decoded. StoreError naming the
    file when it is unreadable or holds no hits; NotARunError (a StoreError) when it
    is HDF5 but no run of the store at all (no ``schema`` attribute on its root)."""
    run = open_run(path)
    if run.hits is None:
        raise StoreError(f"{path}: run {run.run_id} holds no time records to replay")
    return run.hits


def _finite(run: Run, name: str, require_finite: bool) -> Run:
    if require_finite:
        problems = nonfinite_problems(run)
        if problems:
            raise StoreError(f"{name}: {problems[0]}")
    return run


def misnamed(path: Path, run_id: str) -> str | None:
    """Why the run file at ``path`` is misnamed (its name is not ``<run_id>.h5``), or None.
    Commands find runs by file name, so such a run could be listed but never picked."""
    if path.name == f"{run_id}{layout.RUN_SUFFIX}":
        return None
    return f"misnamed: the file holds run {run_id!r}; rename it to {run_id}{layout.RUN_SUFFIX}"


def read_summary(path: Path | str) -> RunSummary:
    """The listing line of the run at ``path``; StoreError if it is unreadable.

    Read from the summary attribute alone when the file has a trustworthy one (see
    daq/store/summary.py: well-formed, naming this file's run, giving this file's
    size), else from the run's data (runs sealed before the attribute existed, and
    any file whose attribute is damaged, edited or forged)."""
    path = Path(path)
    size = path.stat().st_size if path.exists() else 0
    return _summary_from_attribute(path, size) or _summary_from_data(path, size)


def _summary_from_attribute(path: Path, size: int) -> RunSummary | None:
    """The listing line from the root's summary attribute, or None when there is none
    or it cannot be trusted. Never raises: the reading from the data reports the errors.

    Only the root's attributes are read (three short ones, then the summary once its
    declared type and size are checked): nothing that links, maps or declares data."""
    run_id = path.name[: -len(layout.RUN_SUFFIX)] if path.name.endswith(layout.RUN_SUFFIX) else None
    if run_id is None:
        return None
    try:
        text = read_root_summary(path)
        if text is None:
            return None
        fields = parse_summary(text, run_id=run_id, size_bytes=size)
    except Exception:
        return None
    return RunSummary(file_name=path.name, **fields)


def _summary_from_data(path: Path, size: int) -> RunSummary:
    # Listing must be quick and small: the whole tree's metadata is checked (links,
    # declared sizes: no data read), then only the attributes and the accepted flags
    # (at most MAX_HITS bytes, once every dataset of the hits agrees on their count).
    with open_h5(path) as f:
        check_schema(f)
        entry = get_group(f, layout.ENTRY)
        n_hits = n_accepted = 0
        hits = get_group(f, layout.HITS, required=False)
        if hits is not None:
            link = hits.get(layout.D_ACCEPTED, getlink=True)
            accepted = hits.get(layout.D_ACCEPTED) if isinstance(link, h5py.HardLink) else None
            if (
                not isinstance(accepted, h5py.Dataset)
                or accepted.is_virtual
                or accepted.external
                or accepted.ndim != 1
                or accepted.dtype.kind != "b"
            ):
                raise StoreError(
                    f"dataset {layout.HITS}/{layout.D_ACCEPTED} is missing, linked or malformed; refused"
                )
            check_hits_counts(hits)  # at most MAX_HITS flags, agreeing with the records
            values = accepted[()]
            n_hits, n_accepted = int(values.size), int(values.sum())
        run_id = get_text(entry, "run_id")
        wrong = misnamed(path, run_id)
        if wrong is not None:
            raise StoreError(wrong)
        return RunSummary(
            file_name=path.name,
            run_id=run_id,
            start_time=get_text(entry, "start_time"),
            kind=get_text(entry, "kind"),
            complete=get_bool(entry, "complete"),
            n_hits=n_hits,
            n_accepted=n_accepted,
            operator=get_text(entry, "operator"),
            note=get_text(entry, "note"),
            size_bytes=size,
        )


def _short(exc: BaseException) -> str:
    text = " ".join(str(exc).split()) or type(exc).__name__
    if "file signature not found" in text:
        return "no HDF5 signature at its start"  # HDF5's own words name its C call
    return text if len(text) <= 160 else text[:157] + "..."
