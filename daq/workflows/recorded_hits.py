"""Reading the hits of a recorded run, for the simulator's replay mode.

Two kinds of file are accepted:

- a run of the store (it has the ``schema`` root attribute): its hits read by
  ``daq.store.read_hits``, so it is checked as every stored run is;
- a minimal hand-made file laid out as docs/simulator.md (replay) describes:
  ``/entry/hits/force`` and ``/entry/hits/response`` (n_hits x 1024 float64, or
  n_hits x 512 complex with a ``center_hz`` attribute on ``/entry/hits``, N and
  m/s^2; or the record of another model of the family: 2.56 x lines real samples,
  half as many complex, docs/dialects.md), ``/entry/hits/time`` (n_samples, s,
  relative to the trigger) and optionally
  ``/entry/hits/accepted`` and ``/entry/hits/overload`` (n_hits x 2).

Either way a file that links or maps data outside itself is refused.

The store has no reader of the minimal layout (it is no run of the store): that part
alone (``_read_minimal``) still opens the file with h5py here, until the store
offers it. Every failure is a WorkflowError naming the file.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from daq.store import Hits, NotARunError, StoreError, read_hits
from daq.store.h5io import refuse_outside_references
from daq.workflows.errors import WorkflowError
from drivers.dialects import DIALECTS, Geometry
from sims.sources import RecordedHit

#: Real samples of a baseband record of any model of the family, at any of its lines.
FAMILY_RECORD_SAMPLES = sorted(
    {Geometry(n).record_samples for d in DIALECTS.values() for n in d.line_choices}
)


def recorded_hits(hits: Hits, accepted_only: bool = False) -> list[RecordedHit]:
    """The stored ``hits`` as the replay source serves them, in recorded order."""
    out = []
    for i in range(hits.n_hits):
        if accepted_only and not hits.accepted[i]:
            continue
        out.append(
            RecordedHit(
                hits.force_n[i],
                hits.response_m_s2[i],
                hits.sample_rate_hz,
                hits.start_s,
                (bool(hits.overload[i, 0]), bool(hits.overload[i, 1])),
                hits.center_hz,
            )
        )
    return out


def load_recorded_hits(path: Path, accepted_only: bool = False) -> list[RecordedHit]:
    """The hits of the run at ``path``, in recorded order; WorkflowError naming the file."""
    if not path.is_file():
        raise WorkflowError(f"{path}: no such run file")
    try:
        out = recorded_hits(read_hits(path), accepted_only)
    except NotARunError:  # HDF5, but no run of the store: the minimal layout
        out = _load_minimal(path, accepted_only)
    except StoreError as exc:
        _refuse_unreadable(path)
        raise WorkflowError(str(exc)) from None
    if not out:
        raise WorkflowError(f"{path}: no hits to replay")
    return out


def _refuse_unreadable(path: Path) -> None:
    """WorkflowError saying the file at ``path`` is not HDF5 at all, as replay has always
    said it (the store's reader calls that damage)."""
    import h5py

    try:
        with h5py.File(path, "r", locking=False):
            pass
    except OSError as exc:
        raise WorkflowError(f"{path}: not a readable HDF5 file ({exc})") from None


def _load_minimal(path: Path, accepted_only: bool) -> list[RecordedHit]:
    import h5py

    try:
        with h5py.File(path, "r", locking=False) as f:
            refuse_outside_references(f)
            return _read_minimal(f, path, accepted_only)
    except StoreError as exc:
        raise WorkflowError(f"{path}: {exc}") from None
    except OSError as exc:
        raise WorkflowError(f"{path}: not a readable HDF5 file ({exc})") from None


def _read_minimal(f, path: Path, accepted_only: bool) -> list[RecordedHit]:
    import h5py

    if not isinstance(f.get("entry/hits"), h5py.Group):
        raise WorkflowError(f"{path}: not a run (no /entry/hits group)")
    hits = f["entry/hits"]

    def read(name: str, kinds: str, required: bool = True) -> np.ndarray | None:
        node = hits.get(name)
        if node is None and not required:
            return None
        if not isinstance(node, h5py.Dataset):
            raise WorkflowError(f"{path}: /entry/hits/{name} is missing or not a dataset")
        value = np.asarray(node[()])
        if value.dtype.kind not in kinds:
            raise WorkflowError(f"{path}: /entry/hits/{name} is not numeric (dtype {value.dtype})")
        return value

    force = read("force", "fiuc")
    response = read("response", "fiuc")
    time_s = read("time", "fiu")
    accepted = read("accepted", "b", required=False)
    overload = read("overload", "b", required=False)
    assert force is not None
    assert response is not None
    assert time_s is not None
    zoom = force.dtype.kind == "c" or response.dtype.kind == "c"
    force = force.astype(complex if zoom else float)
    response = response.astype(complex if zoom else float)
    time_s = time_s.astype(float)
    lengths = [m // 2 for m in FAMILY_RECORD_SAMPLES] if zoom else FAMILY_RECORD_SAMPLES
    n = force.shape[1] if force.ndim == 2 else -1
    if force.ndim != 2 or force.shape != response.shape or n not in lengths:
        raise WorkflowError(
            f"{path}: force and response must both be n_hits x one of {', '.join(map(str, lengths))}"
            f"{' (complex, zoom)' if zoom else ''} (a record of the family), "
            f"got {force.shape} and {response.shape}"
        )
    if time_s.shape != (n,) or not np.all(np.isfinite(time_s)):
        raise WorkflowError(f"{path}: /entry/hits/time must hold {n} finite instants")
    steps = np.diff(time_s)
    if np.any(steps <= 0) or not np.allclose(steps, steps[0], rtol=1e-9, atol=0):
        raise WorkflowError(f"{path}: /entry/hits/time is not evenly spaced")
    if not (np.all(np.isfinite(force)) and np.all(np.isfinite(response))):
        raise WorkflowError(f"{path}: the recorded hits hold non-finite values")
    center_hz = float(np.asarray(hits.attrs.get("center_hz", 0.0)).real) if zoom else 0.0
    if zoom and not (np.isfinite(center_hz) and center_hz > 0):
        raise WorkflowError(f"{path}: complex (zoom) records need a center_hz > 0 attribute on /entry/hits")
    n_hits = force.shape[0]
    if accepted is not None and accepted.shape != (n_hits,):
        raise WorkflowError(
            f"{path}: /entry/hits/accepted must hold {n_hits} flags, got shape {accepted.shape}"
        )
    if overload is not None and overload.shape != (n_hits, 2):
        raise WorkflowError(f"{path}: /entry/hits/overload must be {n_hits} x 2, got shape {overload.shape}")
    sample_rate_hz = 1.0 / float(steps.mean())
    out = []
    for i in range(n_hits):
        if accepted_only and accepted is not None and not accepted[i]:
            continue
        over = (bool(overload[i, 0]), bool(overload[i, 1])) if overload is not None else (False, False)
        out.append(RecordedHit(force[i], response[i], sample_rate_hz, float(time_s[0]), over, center_hz))
    return out
