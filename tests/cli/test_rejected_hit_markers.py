"""Hits of an imported file that failed their checks: the caution of `daq analyze` about
them, and the '# rejected hit K: reason' lines that leave them out, read by position in
the file (from 0) whatever the file's own hit column says."""

from __future__ import annotations

import numpy as np

from daq.store import Store
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


def add_line(path, line: str) -> None:
    path.write_text(line + "\n" + path.read_text())


def accepted(store) -> list[bool]:
    """The accepted flags of the newest run of ``store``."""
    runs = Store(store)
    newest = max(s.run_id for s in runs.list())
    return runs.open(newest).hits.accepted.tolist()


def test_the_caution_prints_the_marker_line_that_leaves_the_hit_out_of_a_file_labelled_from_1(tmp_path):
    """The file labels its hits 1-5 and the 3rd has a double tap: the caution names it
    hit 3 and gives the line for it, '# rejected hit 2', which then leaves out that hit."""
    force, response = _hits(5, double=(2,))
    store, _ = imported(tmp_path, "from1.csv", force, response, first_label=1)
    caution = failed_caution(store)
    assert caution.startswith("1 hit in the average failed its checks, hit 3: double impact (")
    marker = "# rejected hit 2: double impact"
    assert f"to leave it out, add the line '{marker}' to the file and import it again (" in caution
    assert "from 0 in file order" in caution
    add_line(tmp_path / "from1.csv", marker)
    result = invoke_daq("import", str(tmp_path / "from1.csv"), "--store", str(store))
    assert result.returncode == 0, result.stderr
    assert accepted(store) == [True, True, False, True, True]
    assert "'# rejected hit 2'" in result.stdout  # labelled 3, not 2: the import says which it took
    (info,) = daq_json("analyze", store, "latest")
    assert not any("failed" in c for c in info["cautions"])
    assert info["n_averages"] == 4


def test_several_hits_get_one_marker_line_each(tmp_path):
    store, _ = imported(tmp_path, "two.csv", *_hits(5, double=(1, 4)))
    caution = failed_caution(store)
    assert (
        "to leave them out, add the lines '# rejected hit 1: double impact' and "
        "'# rejected hit 4: double impact' to the file and import it again" in caution
    )


def test_a_marker_that_names_a_label_of_a_hit_column_from_1_says_which_hit_it_rejected(tmp_path):
    """'# rejected hit 3' in a file whose hit column counts 1-5 leaves out the 4th hit (the
    marker counts from 0 in file order, as the docs say); the import says so, by the hit's
    label and position, and which marker the hit labelled 3 would need."""
    force, response = _hits(5, double=(2,))
    store, result = imported(tmp_path, "rej.csv", force, response, first_label=1,
                             markers=("rejected hit 3: double",))  # fmt: skip
    assert accepted(store) == [True, True, True, False, True]
    (said,) = [line for line in result.stdout.splitlines() if "'# rejected hit 3'" in line]
    assert said == (
        "note: '# rejected hit 3' rejected the file's 4th hit, labelled 4 in its hit column: the marker "
        "counts hits from 0 in file order, not by the hit column; the hit labelled 3 is kept (its marker "
        "would be '# rejected hit 2')"
    )


def test_a_marker_beyond_the_last_hit_says_it_rejects_nothing(tmp_path):
    force, response = _hits(5, double=())
    store, result = imported(tmp_path, "far.csv", force, response, first_label=1,
                             markers=("rejected hit 5: bad",))  # fmt: skip
    assert accepted(store) == [True] * 5
    (said,) = [line for line in result.stdout.splitlines() if "'# rejected hit 5'" in line]
    assert said == (
        "note: '# rejected hit 5' names no hit and rejects nothing: the marker counts the file's 5 hits "
        "from 0 in file order (0-4); the hit labelled 5 in the hit column is '# rejected hit 4'"
    )


def test_markers_agree_with_a_hit_column_from_0_and_say_nothing_more(tmp_path):
    force, response = _hits(4, double=())
    store, result = imported(tmp_path, "from0.csv", force, response, first_label=0,
                             markers=("rejected hit 2: bad",))  # fmt: skip
    assert accepted(store) == [True, True, False, True]
    assert "rejected hit" not in result.stdout


def test_a_run_imported_from_uff_is_told_to_go_through_a_csv_export(tmp_path):
    """A UFF file has no '# rejected hit' lines: the caution says how to leave the hit out
    through the run exported as CSV, and following it works."""
    store, _ = imported(tmp_path, "src.csv", *_hits(4, double=(1,)))
    uff = tmp_path / "run.uff"
    exported = invoke_daq("export", "latest", "--format", "uff", "-o", str(uff), "--store", str(store))
    assert exported.returncode == 0, exported.stderr
    uff_store = tmp_path / "uff_runs"
    assert invoke_daq("import", str(uff), "--store", str(uff_store)).returncode == 0
    caution = failed_caution(uff_store)
    (run_id,) = [s.run_id for s in Store(uff_store).list()]
    told = (
        f"to leave it out, export the run as CSV (daq export {run_id} --format csv), add the line "
        "'# rejected hit 1: double impact' to that file and import it"
    )
    assert caution.endswith(told)
    csv = tmp_path / "again.csv"
    exported = invoke_daq("export", run_id, "--format", "csv", "-o", str(csv), "--store", str(uff_store))
    assert exported.returncode == 0, exported.stderr
    add_line(csv, "# rejected hit 1: double impact")
    assert invoke_daq("import", str(csv), "--store", str(uff_store)).returncode == 0
    assert accepted(uff_store) == [True, False, True, True]


def test_the_import_note_of_a_hit_the_file_rejects_says_it_is_left_out(tmp_path):
    """A new user's file marked its double hit rejected, and the import's note still said
    'it is kept and averaged'. Notes now follow the marker; an unmarked hit is kept."""
    _, result = imported(
        tmp_path, "marked.csv", *_hits(double=(1, 2)), markers=("rejected hit 1: double impact",)
    )
    notes = [line for line in result.stdout.splitlines() if "failed the double impact check" in line]
    assert len(notes) == 2, result.stdout
    assert notes[0].startswith("note: hit 2 failed")
    assert notes[0].endswith("the file rejects it, so it is left out of the average")
    assert notes[1].startswith("note: hit 3 failed")
    assert notes[1].endswith("it is kept and averaged, and daq analyze cautions about it")
