"""HDF5 tree -> Run (the inverse of encode.py). Raises StoreError for anything amiss."""

from __future__ import annotations

import json

import h5py
import numpy as np

from daq.store import layout
from daq.store.errors import NotARunError, StoreError
from daq.store.h5io import (
    MAX_HITS,
    dataset,
    get_array,
    get_bool,
    get_float,
    get_group,
    get_int,
    get_json,
    get_text,
    get_text_array,
)
from daq.store.model import Hits, Instrument, MeasuredFrf, Point, Run, RunPoints, Sample, Spectra


def check_schema(f: h5py.File) -> int:
    """The file's schema version; StoreError unless it is a run this code can read."""
    if layout.ATTR_SCHEMA not in f.attrs:
        raise NotARunError("not a run file (no schema attribute on the root)")
    schema = get_text(f, layout.ATTR_SCHEMA)
    if schema != layout.SCHEMA_NAME:
        raise StoreError(f"not a run file (schema {schema!r}, expected {layout.SCHEMA_NAME!r})")
    version = get_int(f, layout.ATTR_SCHEMA_VERSION)
    if version > layout.READ_SCHEMA_VERSION:
        raise StoreError(
            f"run schema version {version} is newer than this software reads "
            f"({layout.READ_SCHEMA_VERSION}); update cantilever-daq"
        )
    if version < 1:
        raise StoreError(f"run schema version {version} is not valid")
    return version


def decode_run(f: h5py.File) -> Run:
    check_schema(f)
    entry = get_group(f, layout.ENTRY)
    provenance = get_json(entry, layout.ATTR_PROVENANCE)
    instrument = sample = None
    group = get_group(f, layout.INSTRUMENT, required=False)
    if group is not None:
        settings = get_json(group, layout.ATTR_SETTINGS)
        instrument = _build(
            Instrument, **{n: get_text(group, n) for n in layout.INSTRUMENT_ATTRS}, settings=settings
        )
    group = get_group(f, layout.SAMPLE, required=False)
    if group is not None:
        values = {n: get_float(group, n) for n in layout.SAMPLE_ATTRS}
        values |= {n: get_float(group, n) for n in layout.SAMPLE_OPTIONAL_ATTRS if n in group.attrs}
        sample = _build(Sample, **values)
    group = get_group(f, layout.HITS, required=False)
    hits = _decode_hits(group) if group is not None else None
    group = get_group(f, layout.ANALYZER, required=False)
    analyzer = _decode_frf(group) if group is not None else None
    group = get_group(f, layout.MEASURED_FRF, required=False)
    measured = _decode_frf(group) if group is not None else None
    # Optional, and absent from runs written before spectra had a place: None then.
    group = get_group(f, layout.SPECTRA, required=False)
    spectra = _decode_spectra(group) if group is not None else None
    points = decode_points(entry)
    return _build(
        Run,
        **{n: get_text(entry, n) for n in ("run_id", "kind", "start_time", "end_time", "operator", "note")},
        complete=get_bool(entry, "complete"),
        software=get_text(entry, layout.ATTR_SOFTWARE),
        provenance=provenance,
        instrument=instrument,
        sample=sample,
        hits=hits,
        analyzer=analyzer,
        measured_frfs=measured,
        spectra=spectra,
        points=points,
    )


def decode_points(entry: h5py.Group) -> RunPoints | None:
    """The run's points from ``/entry``'s attributes; None when the run has none (written
    before points existed, or by other software): Run.resolved_points then gives
    default_points of its sample, the seed's beam with hammer and sensor at the tip."""
    present = [name for name in layout.POINTS_ATTRS if name in entry.attrs]
    if not present:
        return None
    if len(present) != len(layout.POINTS_ATTRS):
        missing = sorted(set(layout.POINTS_ATTRS) - set(present))
        raise StoreError(f"attribute {entry.name}@{missing[0]} is missing (the run's points come together)")
    test = get_text(entry, layout.ATTR_TEST) if layout.ATTR_TEST in entry.attrs else ""
    article = get_json(entry, layout.ATTR_ARTICLE)
    force = get_json(entry, layout.ATTR_FORCE_POINT)
    responses = get_json(entry, layout.ATTR_RESPONSE_POINTS)
    try:
        if not isinstance(responses, list):
            raise ValueError(f"{layout.ATTR_RESPONSE_POINTS} must be a list")
        return RunPoints(
            article=article,
            force_point=Point.from_dict(force, "force point"),
            response_points=tuple(Point.from_dict(p, "response point") for p in responses),
            test=test,
        )
    except ValueError as exc:
        raise StoreError(f"inconsistent points data: {exc}") from None


def _shape(group: h5py.Group, name: str, required: bool = True) -> tuple[int, ...] | None:
    """The declared shape of dataset ``group/name`` (metadata only; None if absent and optional)."""
    node = dataset(group, name, required)
    return None if node is None else tuple(int(n) for n in node.shape or ())


def _agree(group: h5py.Group, expected: dict[str, tuple[int, ...]], optional: tuple[str, ...] = ()) -> None:
    for name, want in expected.items():
        got = _shape(group, name, required=name not in optional)
        if got is not None and got != want:
            raise StoreError(f"dataset {group.name}/{name} has shape {got}, the run's counts say {want}")


def check_hits_counts(group: h5py.Group) -> int:
    """n_hits of the hits group, once every dataset's declared shape agrees with it
    and with n_samples (metadata only: nothing is read before the counts agree)."""
    records = _shape(group, layout.D_FORCE)
    if len(records) != 2:
        raise StoreError(f"dataset {group.name}/{layout.D_FORCE} has shape {records}, expected 2 dimensions")
    n_hits, n_samples = records
    if n_hits > MAX_HITS:
        raise StoreError(f"{group.name} declares {n_hits} hits, more than the limit of {MAX_HITS}; refused")
    per_hit = (n_hits,)
    _agree(
        group,
        {
            layout.D_RESPONSE: records,
            layout.D_TIME: (n_samples,),
            layout.D_HIT: per_hit,
            layout.D_ACCEPTED: per_hit,
            layout.D_REJECT_REASON: per_hit,
            layout.D_OVERLOAD: (n_hits, 2),
            layout.D_PEAK_FORCE: per_hit,
            layout.D_TIMESTAMP: per_hit,
            layout.D_CHECKS: per_hit,
        },
        optional=(layout.D_HIT,),
    )
    return n_hits


def _check_table_counts(group: h5py.Group, table: str, optional: tuple[str, ...]) -> None:
    """An FRF or spectra group: (n, n_lines) tables over (n_lines,) frequencies."""
    lines = _shape(group, layout.D_FREQUENCY)
    values = _shape(group, table)
    if len(lines) != 1 or len(values) != 2:
        raise StoreError(f"{group.name}: frequency {lines} and {table} {values} have the wrong dimensions")
    n = values[0]
    # Only the numeric tables: the texts (labels, kinds, units) are counted by the model,
    # whose messages say which, and their bytes are bounded with every other dataset's.
    expected = {table: (n, lines[0])}
    if table == layout.D_FRF:
        expected[layout.D_COHERENCE] = (n, lines[0])
    _agree(group, expected, optional=optional)


def _decode_hits(group: h5py.Group) -> Hits:
    check_hits_counts(group)
    force = get_array(group, layout.D_FORCE, "fc", 2)
    response = get_array(group, layout.D_RESPONSE, "fc", 2)
    time_axis = get_array(group, layout.D_TIME, "f", 1)
    if force.shape[1:] != time_axis.shape:
        raise StoreError(
            f"{group.name}: time axis has {time_axis.size} samples, records have {force.shape[1]}"
        )
    checks_text = get_text_array(group, layout.D_CHECKS)
    try:
        checks = [json.loads(text) for text in checks_text]
    except json.JSONDecodeError:
        raise StoreError(f"{group.name}/{layout.D_CHECKS} holds text that is not JSON") from None
    hits = _build(
        Hits,
        force_n=force,
        response_m_s2=response,
        sample_rate_hz=get_float(group, "sample_rate_hz"),
        start_s=get_float(group, "start_s"),
        center_hz=get_float(group, "center_hz"),
        accepted=get_array(group, layout.D_ACCEPTED, "b", 1),
        reject_reason=get_text_array(group, layout.D_REJECT_REASON),
        overload=get_array(group, layout.D_OVERLOAD, "b", 2),
        peak_force_n=get_array(group, layout.D_PEAK_FORCE, "f", 1),
        timestamp_utc=get_text_array(group, layout.D_TIMESTAMP),
        checks=checks,
    )
    # The stored time axis is redundant with start_s and sample_rate_hz; a mismatch
    # means one of them was damaged or edited.
    if not np.allclose(time_axis, hits.time_s(), rtol=1e-12, atol=1e-15):
        raise StoreError(f"{group.name}/time disagrees with start_s and sample_rate_hz")
    return hits


def _decode_frf(group: h5py.Group) -> MeasuredFrf:
    _check_table_counts(group, layout.D_FRF, (layout.D_COHERENCE,))
    return _build(
        MeasuredFrf,
        frequency_hz=get_array(group, layout.D_FREQUENCY, "f", 1),
        frf=get_array(group, layout.D_FRF, "c", 2),
        coherence=get_array(group, layout.D_COHERENCE, "f", 2, required=False),
        labels=get_text_array(group, layout.D_LABEL),
        # Runs written before FRFs had a form hold accelerance, the only form there was.
        form=get_text(group, layout.ATTR_FRF_FORM) if layout.ATTR_FRF_FORM in group.attrs else "accelerance",
    )


def _decode_spectra(group: h5py.Group) -> Spectra:
    _check_table_counts(group, layout.D_SPECTRUM, ())
    return _build(
        Spectra,
        frequency_hz=get_array(group, layout.D_FREQUENCY, "f", 1),
        values=get_array(group, layout.D_SPECTRUM, "fc", 2),
        kinds=get_text_array(group, layout.D_KIND),
        units=get_text_array(group, layout.D_UNIT),
        labels=get_text_array(group, layout.D_LABEL),
    )


def nonfinite_problems(run: Run) -> list[str]:
    """One line per array of ``run`` holding NaN or infinity (analysis and replay need
    finite numbers); the model allows them, so a sealed run may hold them."""
    arrays: list[tuple[str, np.ndarray | None]] = []
    if run.hits is not None:
        arrays += [
            (layout.HITS + "/" + layout.D_FORCE, run.hits.force_n),
            (layout.HITS + "/" + layout.D_RESPONSE, run.hits.response_m_s2),
            (layout.HITS + "/" + layout.D_PEAK_FORCE, run.hits.peak_force_n),
        ]
    for where, frf in ((layout.ANALYZER, run.analyzer), (layout.MEASURED_FRF, run.measured_frfs)):
        if frf is not None:
            arrays += [(f"{where}/{layout.D_FRF}", frf.frf), (f"{where}/{layout.D_COHERENCE}", frf.coherence)]
    if run.spectra is not None:
        arrays.append((f"{layout.SPECTRA}/{layout.D_SPECTRUM}", run.spectra.values))
    problems = []
    for where, values in arrays:
        if values is None:
            continue
        bad = ~np.isfinite(values)
        if bad.any():
            first = np.unravel_index(int(np.argmax(bad)), values.shape)
            problems.append(
                f"dataset /{where} holds {int(bad.sum())} NaN or infinite value(s), first at index "
                f"{tuple(int(i) for i in first)}: analysis and replay need finite numbers"
            )
    return problems


def _build(cls: type, **values: object) -> object:
    try:
        return cls(**values)
    except ValueError as exc:
        raise StoreError(f"inconsistent {cls.__name__.lower()} data: {exc}") from None
