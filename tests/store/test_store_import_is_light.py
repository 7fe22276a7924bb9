"""`import daq.store` loads neither numpy nor h5py, and a listing served from a warm index
needs neither: `daq runs list` starts without them. Every public name of the package is
still importable from it, and is the same object as in its own module."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import daq.store
from daq.store import Store
from tests.store.store_helpers import make_run

ROOT = Path(__file__).resolve().parents[2]

WARM_LIST = textwrap.dedent(
    """
    import json, sys
    import daq.store
    after_import = sorted(m for m in ("numpy", "h5py") if m in sys.modules)
    from daq.store import Store, resolve_store_dir
    path, _ = resolve_store_dir(sys.argv[1])
    summaries = Store(path).list()
    print(json.dumps({
        "after_import": after_import,
        "after_list": sorted(m for m in ("numpy", "h5py") if m in sys.modules),
        "runs": [[s.run_id, s.n_hits, s.n_accepted, s.complete, s.error] for s in summaries],
    }))
    """
)


def _child(code: str, *args: str) -> dict:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")])
    done = subprocess.run(
        [sys.executable, "-c", code, *args], cwd=ROOT, env=env, capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


def test_a_warm_listing_loads_neither_numpy_nor_h5py(tmp_path):
    store = Store(tmp_path / "store")
    runs = [make_run(seed=seed, n_hits=3 + seed) for seed in range(2)]
    for run in runs:
        store.seal(run)
    want = [[s.run_id, s.n_hits, s.n_accepted, s.complete, s.error] for s in store.list()]  # builds the index
    assert (store.path / ".index.sqlite").exists()
    assert sorted(r.run_id for r in runs) == [w[0] for w in want]

    got = _child(WARM_LIST, str(store.path))

    assert got["runs"] == want
    assert got["after_import"] == []
    assert got["after_list"] == []


def test_a_cold_listing_still_reads_the_files(tmp_path):
    # No index yet: the summaries come from the run files (h5py), as before.
    store = Store(tmp_path / "store")
    run = make_run(n_hits=4)
    store.seal(run)

    got = _child(WARM_LIST, str(store.path))

    assert got["runs"] == [[run.run_id, 4, 3, True, None]]
    assert "h5py" in got["after_list"]


@pytest.mark.parametrize("name", daq.store.__all__)
def test_every_public_name_is_the_one_of_its_module(name):
    value = getattr(daq.store, name)
    module = sys.modules[f"daq.store.{daq.store._LAZY[name]}"]
    assert value is getattr(module, name)
    assert name in dir(daq.store)


def test_the_names_and_the_package_face_are_as_before():
    code = textwrap.dedent(
        """
        import json
        import daq.store.verify  # the submodule first: the package's name stays the function
        from daq.store import RunSummary, verify
        import daq.store, daq.store.reader
        print(json.dumps({
            "verify": [callable(verify), verify is daq.store.verify, type(verify).__name__],
            "summary": RunSummary is daq.store.reader.RunSummary,
            "submodule": daq.store.index.__name__,
        }))
        """
    )
    got = _child(code)
    assert got == {"verify": [True, True, "function"], "summary": True, "submodule": "daq.store.index"}
    with pytest.raises(AttributeError):
        daq.store.no_such_name  # noqa: B018
    with pytest.raises(ImportError):
        exec("from daq.store import no_such_name", {})
