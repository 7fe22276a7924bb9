"""A CSV file whose force and response columns are read the wrong way round: the import
says so in one note with the --columns that reads it right, `daq analyze` cautions, and
importing again with that --columns gives a clean run."""

from __future__ import annotations

from tests.analysis.impact_synth import impact_hits
from tests.cli_helpers import daq_json, invoke_daq

FS = 5120.0


def _write(path, header: str, first, second) -> None:
    rows = [header]
    for k in range(first.shape[0]):
        rows += [f"{k},{i / FS:.9g},{first[k, i]:.9g},{second[k, i]:.9g}" for i in range(first.shape[1])]
    path.write_text("\n".join(rows) + "\n")


def test_swapped_columns_are_one_note_and_one_caution_pointing_to_columns(tmp_path):
    force, response = impact_hits([42.0, 155.0, 388.0, 710.0], [0.012, 0.006, 0.02, 0.004],
                                  [1.0, -0.6, 0.4, 0.3], FS, 1.0, 3, 0.01, 1e-3, 4)  # fmt: skip
    path = tmp_path / "swapped.csv"
    _write(path, "hit,t,F,a", response, force)  # F holds the response, a the force
    store = tmp_path / "runs"
    result = invoke_daq("import", str(path), "--store", str(store))
    assert result.returncode == 0, result.stderr
    notes = [line for line in result.stdout.splitlines() if line.startswith("note: ")]
    assert len(notes) == 1, notes  # not one per hit, nor the double impacts of a response read as force
    (note,) = notes
    assert note.startswith("note: the force and response columns look swapped in every hit (hit 1: ")
    assert note.endswith("; if so, import the file again with --columns t,a,F")
    (info,) = daq_json("analyze", store, "latest")
    (caution,) = [c for c in info["cautions"] if "swapped" in c]
    assert "--columns t,a,F" in caution
    assert not [c for c in info["cautions"] if "failed" in c]
    again = invoke_daq("import", str(path), "--columns", "t,a,F", "--store", str(store))
    assert again.returncode == 0, again.stderr
    assert "look swapped" not in again.stdout
    assert "failed the" not in again.stdout
    (info,) = daq_json("analyze", store, "latest")
    assert not [c for c in info["cautions"] if "swapped" in c or "failed" in c]


def test_a_file_the_right_way_round_says_nothing_of_swapped_columns(tmp_path):
    force, response = impact_hits([42.0, 155.0, 388.0, 710.0], [0.012, 0.006, 0.02, 0.004],
                                  [1.0, -0.6, 0.4, 0.3], FS, 1.0, 3, 0.01, 1e-3, 4)  # fmt: skip
    path = tmp_path / "right.csv"
    _write(path, "hit,Time (s),Force [N],acc [m/s^2]", force, response)
    result = invoke_daq("import", str(path), "--store", str(tmp_path / "runs"))
    assert result.returncode == 0, result.stderr
    assert "note:" not in result.stdout


def test_a_swapped_file_with_units_in_its_header_is_offered_a_command_that_works(tmp_path):
    """A new user's file: 'Time (s),Force (N),Accel (g)' above the response and the force.
    The note offered --columns 'Time (s),Accel (g),Force (N)', which was refused ('Accel
    (g)' read as the force has an acceleration unit) with a suggestion of the swapped
    reading again. The note now keeps each unit with its quantity, and its command imports."""
    force, response = impact_hits([42.0, 155.0, 388.0, 710.0], [0.012, 0.006, 0.02, 0.004],
                                  [1.0, -0.6, 0.4, 0.3], FS, 1.0, 3, 0.01, 1e-3, 4)  # fmt: skip
    path = tmp_path / "swapped.csv"
    _write(path, "hit,Time (s),Force (N),Accel (g)", response / 9.80665, force)
    store = tmp_path / "runs"
    result = invoke_daq("import", str(path), "--store", str(store))
    assert result.returncode == 0, result.stderr
    (note,) = [line for line in result.stdout.splitlines() if line.startswith("note: ")]
    offered = "--columns 'Time (s),Accel (g),Force (N)' --force-unit N --response-unit g"
    assert note.endswith(f"; if so, import the file again with {offered}")
    again = invoke_daq(
        "import", str(path), "--columns", "Time (s),Accel (g),Force (N)", "--force-unit", "N",
        "--response-unit", "g", "--store", str(store),
    )  # fmt: skip
    assert again.returncode == 0, again.stderr
    assert "look swapped" not in again.stdout
    (info,) = daq_json("analyze", store, "latest")
    assert not [c for c in info["cautions"] if "swapped" in c or "failed" in c]
    assert any(abs(m["frequency_hz"] - 155.0) < 0.5 for m in info["modes"])
