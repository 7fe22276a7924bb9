"""Four real `daq` processes capture (simulated) and import into one store at the
same time: every run they report is there, sealed, verified and holding its own data."""

from __future__ import annotations

import math
import os
import subprocess

import numpy as np
import pytest

from daq.store import Store
from tests.cli_helpers import DAQ, ENV

N_PROCESSES = 4
STEPS = 3  # each process: capture, import, capture (alternating with its neighbours)


def write_csv(path, scale: float) -> None:
    t = [i / 1000.0 for i in range(64)]
    rows = [f"{ti!r},{scale * math.sin(40 * ti)!r},{scale * math.cos(40 * ti)!r}" for ti in t]
    path.write_text("time,force,response\n" + "\n".join(rows) + "\n")


@pytest.mark.timeout(180)
def test_four_processes_capture_and_import_into_one_store(tmp_path):
    store = tmp_path / "store"
    scripts = []
    for k in range(N_PROCESSES):
        csv = tmp_path / f"p{k}.csv"
        write_csv(csv, scale=1.0 + k)
        steps = []
        for j in range(STEPS):
            note = f"p{k}-s{j}"
            if (k + j) % 2 == 0:
                steps.append(
                    f"'{DAQ}' capture --sim --yes --hits 2 --seed {10 * k + j} --time-scale 0 "
                    f"--note {note} --store '{store}'"
                )
            else:
                steps.append(f"'{DAQ}' import '{csv}' --note {note} --store '{store}'")
        scripts.append(" && ".join(steps))
    env = {**os.environ, **ENV}
    procs = [
        subprocess.Popen(["sh", "-c", s], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
        for s in scripts
    ]
    for p in procs:
        _, err = p.communicate(timeout=170)
        assert p.returncode == 0, err
    the_store = Store(store)
    summaries = the_store.list()
    notes = sorted(s.note for s in summaries)
    assert notes == sorted(f"p{k}-s{j}" for k in range(N_PROCESSES) for j in range(STEPS))
    assert len({s.run_id for s in summaries}) == len(summaries)
    assert all(s.error is None for s in summaries)
    assert the_store.temporaries() == []
    for s in summaries:
        assert the_store.verify(s.run_id) == [], s.run_id
        run = the_store.open(s.run_id)
        k = int(s.note[1])
        if s.kind == "imported":
            # Each import holds its own process's file (amplitude 1 + k), not a neighbour's.
            assert np.max(np.abs(run.hits.force_n)) == pytest.approx(1.0 + k, rel=0.01)
        else:
            assert run.provenance["simulator"]["seed"] == 10 * k + int(s.note[-1])
