"""Hits of an imported file that failed their checks: the caution of `daq analyze` about
them, and the '# rejected hit K: reason' lines that leave them out, read by position in
the file (from 0) whatever the file's own hit column says."""

from __future__ import annotations

import numpy as np

from tests.cli_helpers import daq_json, invoke_daq

FS = 2048.0


def _hits(n_hits: int = 4, double: tuple[int, ...] = (1,)) -> tuple[np.ndarray, np.ndarray]:
    """Force and response of ``n_hits`` clean hits, a second tap added to the hits at the
    0-based positions ``double``."""
    from tests.analysis.impact_synth import impact_hits

    force, response = impact_hits([45.0, 132.0, 310.0], [0.015, 0.008, 0.02], [1.0, -0.6, 0.4], FS, 2.0,
                                  n_hits, 0.01, 2e-3, 7)  # fmt: skip
    shift = round(0.055 * FS)
    for k in double:
        force[k] += 0.6 * np.concatenate([np.zeros(shift), force[k, :-shift]])
    return force, response


def write_hits(path, force, response, first_label: int = 0, markers: tuple[str, ...] = ()) -> None:
    """A CSV with a hit column labelled from ``first_label`` and the comment ``markers``."""
    rows = [f"# {m}" for m in markers] + ["hit,time,force,response"]
    for k in range(force.shape[0]):
        rows += [
            f"{k + first_label},{i / FS:.9g},{force[k, i]:.9g},{response[k, i]:.9g}"
            for i in range(force.shape[1])
        ]
    path.write_text("\n".join(rows) + "\n")


def imported(tmp_path, name: str, force, response, **kwargs):
    path = tmp_path / name
    write_hits(path, force, response, **kwargs)
    store = tmp_path / (name + "_runs")
    result = invoke_daq("import", str(path), "--store", str(store))
    assert result.returncode == 0, result.stderr
    return store, result


def failed_caution(store) -> str:
    (info,) = daq_json("analyze", store, "latest")
    (caution,) = [c for c in info["cautions"] if "failed" in c]
    return caution


def test_one_hit_that_failed_its_checks_is_cautioned_in_the_singular(tmp_path):
    store, _ = imported(tmp_path, "one.csv", *_hits(double=(1,)))
    caution = failed_caution(store)
    assert caution.startswith("1 hit in the average failed its checks, hit 2: double impact (")
    assert ": its FRF is wrong and pulls the modes and damping; " in caution
    assert "their" not in caution
    assert "them" not in caution


def test_two_hits_that_failed_their_checks_are_cautioned_in_the_plural(tmp_path):
    store, _ = imported(tmp_path, "two.csv", *_hits(double=(1, 3)))
    caution = failed_caution(store)
    assert caution.startswith("2 hits in the average failed their checks, hit 2: double impact (")
    assert ": their FRFs are wrong and pull the modes and damping; " in caution
