"""Reading the hits of a recorded run, for the simulator's replay mode.

A run is an HDF5 file laid out as docs/simulator.md (replay) describes:
``/entry/hits/force`` and ``/entry/hits/response`` (n_hits x n_samples, N and
m/s^2), ``/entry/hits/time`` (n_samples, s, relative to the trigger), and
optionally ``/entry/hits/accepted`` and ``/entry/hits/overload`` (n_hits x 2).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from daq.errors import UserError
from sims.settings import RECORD_SAMPLES
from sims.sources import RecordedHit


def load_recorded_hits(path: Path, accepted_only: bool = False) -> list[RecordedHit]:
    """The hits of the run at ``path``, in recorded order."""
    import h5py

    if not path.is_file():
        raise UserError(f"{path}: no such run file")
    try:
        with h5py.File(path, "r") as f:
            if not isinstance(f.get("entry/hits"), h5py.Group):
                raise UserError(f"{path}: not a run (no /entry/hits group)")
            hits = f["entry/hits"]

            def read(name: str, dtype: type, required: bool = True) -> np.ndarray | None:
                node = hits.get(name)
                if node is None and not required:
                    return None
                if not isinstance(node, h5py.Dataset):
                    raise UserError(f"{path}: /entry/hits/{name} is missing or not a dataset")
                try:
                    return np.asarray(node[()], dtype=dtype)
                except (TypeError, ValueError) as exc:
                    raise UserError(f"{path}: /entry/hits/{name} is not numeric ({exc})") from None

            force = read("force", float)
            response = read("response", float)
            time_s = read("time", float)
            accepted = read("accepted", bool, required=False)
            overload = read("overload", bool, required=False)
    except OSError as exc:
        raise UserError(f"{path}: not a readable HDF5 file ({exc})") from None
    assert force is not None
    assert response is not None
    assert time_s is not None
    if force.ndim != 2 or force.shape != response.shape or force.shape[1] != RECORD_SAMPLES:
        raise UserError(
            f"{path}: force and response must both be n_hits x {RECORD_SAMPLES}, "
            f"got {force.shape} and {response.shape}"
        )
    if time_s.shape != (RECORD_SAMPLES,) or not np.all(np.isfinite(time_s)):
        raise UserError(f"{path}: /entry/hits/time must hold {RECORD_SAMPLES} finite instants")
    steps = np.diff(time_s)
    if np.any(steps <= 0) or not np.allclose(steps, steps[0], rtol=1e-9, atol=0):
        raise UserError(f"{path}: /entry/hits/time is not evenly spaced")
    if not (np.all(np.isfinite(force)) and np.all(np.isfinite(response))):
        raise UserError(f"{path}: the recorded hits hold non-finite values")
    n_hits = force.shape[0]
    if accepted is not None and accepted.shape != (n_hits,):
        raise UserError(f"{path}: /entry/hits/accepted must hold {n_hits} flags, got shape {accepted.shape}")
    if overload is not None and overload.shape != (n_hits, 2):
        raise UserError(f"{path}: /entry/hits/overload must be {n_hits} x 2, got shape {overload.shape}")
    sample_rate_hz = 1.0 / float(steps.mean())
    out = []
    for i in range(force.shape[0]):
        if accepted_only and accepted is not None and not accepted[i]:
            continue
        over = (bool(overload[i, 0]), bool(overload[i, 1])) if overload is not None else (False, False)
        out.append(RecordedHit(force[i], response[i], sample_rate_hz, float(time_s[0]), over))
    if not out:
        raise UserError(f"{path}: no hits to replay")
    return out
