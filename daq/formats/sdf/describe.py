"""A JSON-able summary of an SDF file for a run's provenance ("imported_from")."""

from __future__ import annotations

import math
from typing import Any

from daq.formats.sdf import codes
from daq.formats.sdf.model import DataHeader, SdfFile

#: At most this many data headers and channels are listed one by one (the counts are always given).
MAX_LISTED = 32


def data_kind(dh: DataHeader) -> str:
    return codes.name_of(codes.DATA_TYPES, dh.data_type)


def describe(sdf: SdfFile) -> dict[str, Any]:
    """Revision, instrument, its software version and clock, and every data header
    (title, kind, domain, points, traces, scans, storage, x axis) and channel."""
    logical = 1
    later = sdf.next_file
    while later is not None:
        logical, later = logical + 1, later.next_file
    out: dict[str, Any] = {
        "sdf_revision": sdf.file.revision,
        "instrument": sdf.file.instrument,
        "applic": sdf.file.applic,
        "applic_version": sdf.file.applic_version,
        "measurement_start_local": sdf.file.stamp,
        "logical_files": logical,
        "n_data_headers": len(sdf.data),
        "data_headers": [_data_header(dh) for dh in sdf.data[:MAX_LISTED]],
        "n_channels": len(sdf.channels),
        "channels": [
            {
                "label": ch.label,
                "unit": ch.eng_unit.label,
                "int2engr": ch.int2engr if math.isfinite(ch.int2engr) else repr(ch.int2engr),
                "window": codes.name_of(codes.WINDOWS, ch.window.type),
            }
            for ch in sdf.channels[:MAX_LISTED]
        ],
        "n_scans": sdf.scans.n_scans if sdf.scans else None,
        "unique_records": len(sdf.unique),
        "comments": [c.text[:400] for c in sdf.comments[:4]],
        "notes": [],
    }
    if sdf.meas.title:
        out["measurement_title"] = sdf.meas.title
    return out


def _data_header(dh: DataHeader) -> dict[str, Any]:
    return {
        "title": dh.title,
        "data_type": data_kind(dh),
        "domain": codes.name_of(codes.DOMAINS, dh.domain),
        "points": dh.n_points,
        "traces": len(dh.vectors),
        "scans": int(dh.y.shape[0]),
        "ydata": codes.NUMBER_TYPES[dh.ydata_type][1],
        "complex": bool(dh.y_is_complex),
        "x": codes.name_of(codes.X_RESOLUTIONS, dh.x_resolution),
    }


def what_it_holds(sdf: SdfFile) -> str:
    """E.g. "1 auto-power spectrum ('Pwr Spec')" for a one-line message."""
    counts: dict[str, list[str]] = {}
    for dh in sdf.data:
        counts.setdefault(data_kind(dh), []).append(dh.title)
    parts = []
    for kind, titles in counts.items():
        shown = ", ".join(repr(t) for t in titles[:3]) + (", ..." if len(titles) > 3 else "")
        parts.append(f"{len(titles)} {kind} data header{'s' if len(titles) > 1 else ''} ({shown})")
    return "; ".join(parts)
