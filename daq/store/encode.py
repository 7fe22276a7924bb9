"""Run -> HDF5 tree (the inverse of decode.py). Only the writer calls this."""

from __future__ import annotations

import h5py
import numpy as np

from daq.store import layout
from daq.store.h5io import add_dataset, compact_json, nx_group, set_json, set_number, set_text, text_array
from daq.store.model import (
    FRF_FORM_UNITS,
    SOFTWARE,
    Hits,
    MeasuredFrf,
    Run,
    Spectra,
    check_points_against_sample,
)


def encode_run(f: h5py.File, run: Run) -> None:
    """Write ``run`` into the empty, open file ``f`` following layout.py."""
    set_text(f, layout.ATTR_SCHEMA, layout.SCHEMA_NAME)
    forms = {frf.form for frf in (run.analyzer, run.measured_frfs) if frf is not None}
    version = layout.SCHEMA_VERSION if forms <= {"accelerance"} else layout.SCHEMA_VERSION_FRF_FORMS
    set_number(f, layout.ATTR_SCHEMA_VERSION, version)
    set_text(f, layout.ATTR_CREATOR, SOFTWARE)
    set_text(f, layout.ATTR_DEFAULT, layout.ENTRY)

    entry = nx_group(f, layout.ENTRY, "NXentry")
    for name in ("run_id", "kind", "start_time", "end_time", "operator", "note"):
        set_text(entry, name, getattr(run, name))
    set_number(entry, "complete", run.complete)
    set_text(entry, layout.ATTR_SOFTWARE, run.software)
    set_json(entry, layout.ATTR_PROVENANCE, run.provenance)
    if run.points is not None:  # a run that does not say writes nothing: it reads back the same
        check_points_against_sample(run.points, run.sample)  # the sample may have changed since
        set_text(entry, layout.ATTR_TEST, run.points.test)
        set_json(entry, layout.ATTR_ARTICLE, run.points.article)
        set_json(entry, layout.ATTR_FORCE_POINT, run.points.force_point.to_dict())
        set_json(entry, layout.ATTR_RESPONSE_POINTS, [p.to_dict() for p in run.points.response_points])
    # What a viewer plots when the file is opened: the hits if there are any, else the
    # FRFs, else the spectra.
    default = next(
        name
        for name, part in (
            ("hits", run.hits),
            ("analyzer", run.analyzer),
            ("measured_frf", run.measured_frfs),
            ("spectra", run.spectra),
        )
        if part is not None
    )
    set_text(entry, layout.ATTR_DEFAULT, default)

    if run.instrument is not None:
        group = nx_group(entry, "instrument", "NXinstrument")
        for name in layout.INSTRUMENT_ATTRS:
            set_text(group, name, getattr(run.instrument, name))
        set_json(group, layout.ATTR_SETTINGS, run.instrument.settings)
    if run.sample is not None:
        group = nx_group(entry, "sample", "NXsample")
        for name in layout.SAMPLE_ATTRS + layout.SAMPLE_OPTIONAL_ATTRS:
            value = getattr(run.sample, name)
            if value is not None:  # an unknown position is an absent attribute
                set_number(group, name, float(value))
    if run.hits is not None:
        _encode_hits(entry, run.hits)
    if run.analyzer is not None:
        _encode_frf(entry, "analyzer", run.analyzer, "FRF averaged by the analyzer")
    if run.measured_frfs is not None:
        _encode_frf(entry, "measured_frf", run.measured_frfs, "imported FRF")
    if run.spectra is not None:
        _encode_spectra(entry, run.spectra)


def _encode_hits(entry: h5py.Group, hits: Hits) -> None:
    group = nx_group(entry, "hits", "NXdata")
    set_text(group, layout.ATTR_SIGNAL, layout.D_RESPONSE)
    set_text(group, layout.ATTR_AUX_SIGNALS, layout.D_FORCE)
    # NeXus wants `axes` as a list of names, one per dimension of the signal.
    group.attrs.create(layout.ATTR_AXES, text_array([layout.D_HIT, layout.D_TIME]))
    set_number(group, "sample_rate_hz", hits.sample_rate_hz)
    set_number(group, "start_s", hits.start_s)
    set_number(group, "center_hz", hits.center_hz)
    zoom = " (complex envelope)" if hits.is_zoom else ""
    add_dataset(group, layout.D_FORCE, hits.force_n, "N", f"force{zoom}")
    add_dataset(group, layout.D_RESPONSE, hits.response_m_s2, "m/s^2", f"response acceleration{zoom}")
    add_dataset(group, layout.D_TIME, hits.time_s(), "s", "time after trigger")
    add_dataset(group, layout.D_HIT, np.arange(hits.n_hits, dtype=np.int64), None, "hit number")
    add_dataset(group, layout.D_ACCEPTED, hits.accepted, None, "hit accepted")
    add_dataset(
        group, layout.D_REJECT_REASON, text_array(hits.reject_reason), None, "why the hit was rejected"
    )
    add_dataset(group, layout.D_OVERLOAD, hits.overload, None, "overload [force, response]")
    add_dataset(group, layout.D_PEAK_FORCE, hits.peak_force_n, "N", "peak force")
    add_dataset(group, layout.D_TIMESTAMP, text_array(hits.timestamp_utc), None, "hit time (ISO 8601 UTC)")
    checks = [compact_json(c) for c in hits.checks]
    add_dataset(group, layout.D_CHECKS, text_array(checks), None, "per-hit check results (JSON)")


def _encode_frf(entry: h5py.Group, name: str, frf: MeasuredFrf, what: str) -> None:
    group = nx_group(entry, name, "NXdata")
    set_text(group, layout.ATTR_SIGNAL, layout.D_FRF)
    set_text(group, layout.ATTR_FRF_FORM, frf.form)
    group.attrs.create(layout.ATTR_AXES, text_array([layout.D_FRF_INDEX, layout.D_FREQUENCY]))
    if frf.coherence is not None:
        set_text(group, layout.ATTR_AUX_SIGNALS, layout.D_COHERENCE)
    add_dataset(group, layout.D_FREQUENCY, frf.frequency_hz, "Hz", "frequency")
    add_dataset(group, layout.D_FRF, frf.frf, FRF_FORM_UNITS[frf.form], f"{what} ({frf.form})")
    add_dataset(group, layout.D_FRF_INDEX, np.arange(frf.n_frf, dtype=np.int64), None, "FRF number")
    if frf.coherence is not None:
        add_dataset(group, layout.D_COHERENCE, frf.coherence, "", "coherence")
    add_dataset(group, layout.D_LABEL, text_array(frf.labels), None, "FRF label")


def _encode_spectra(entry: h5py.Group, spectra: Spectra) -> None:
    group = nx_group(entry, "spectra", "NXdata")
    set_text(group, layout.ATTR_SIGNAL, layout.D_SPECTRUM)
    group.attrs.create(layout.ATTR_AXES, text_array([layout.D_SPECTRUM_INDEX, layout.D_FREQUENCY]))
    add_dataset(group, layout.D_FREQUENCY, spectra.frequency_hz, "Hz", "frequency")
    # One dataset for every trace, so no single `units` attribute fits when the traces
    # differ: the per-trace units are the `unit` dataset; `units` is set when they agree.
    units = set(spectra.units)
    add_dataset(
        group, layout.D_SPECTRUM, spectra.values, units.pop() if len(units) == 1 else None, "spectrum"
    )
    index = np.arange(spectra.n_traces, dtype=np.int64)
    add_dataset(group, layout.D_SPECTRUM_INDEX, index, None, "spectrum number")
    add_dataset(group, layout.D_KIND, text_array(spectra.kinds), None, "kind of spectrum")
    add_dataset(group, layout.D_UNIT, text_array(spectra.units), None, "unit of each spectrum")
    add_dataset(group, layout.D_LABEL, text_array(spectra.labels), None, "spectrum label")
