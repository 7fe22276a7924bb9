"""A CSV header that names its force and response columns is read by those names,
whatever their order (hypothesis): `Time (s),Acceleration (g),Force (N)` used to be
refused, and `t,a,F` stored the acceleration as the force. Where the names say nothing
unambiguous (two force-like columns, two response-like, one of each missing, a name and
a unit that disagree) the columns are still taken by position, as before, and a
--columns given always wins. Stored runs are read back through the store."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from daq.store import Store, open_run
from tests.cli_helpers import assert_one_line_error, invoke_daq, run_daq

SETTINGS = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
WORK = Path(tempfile.mkdtemp(prefix="csv-column-names-"))
FS = 4096.0
N = 256
FORCE_NAMES = ["force", "f", "hammer", "excitation", "input", "load"]
RESPONSE_NAMES = ["response", "acc", "accel", "acceleration", "a", "resp", "output", "accelerometer"]
OTHER_NAMES = ["m_1", "ch2", "sensor", "voltage", "x"]
FORCE_UNITS = {"N": 1.0, "kN": 1000.0}
RESPONSE_UNITS = {"g": 9.80665, "m/s^2": 1.0}
NOTE = "note: columns taken by their "


def _signals() -> tuple[np.ndarray, np.ndarray]:
    """A hammer pulse and the response it gives (a decaying 100 Hz mode)."""
    t = np.arange(N) / FS
    force = np.zeros(N)
    force[10:14] = [1.0, 3.0, 3.0, 1.0]
    response = np.convolve(force, np.exp(-30 * t) * np.sin(2 * np.pi * 100 * t))[:N]
    return force, response


def _cased(draw, name: str) -> str:
    return "".join(c.upper() if draw(st.booleans()) else c.lower() for c in name)


def _write(path: Path, header: list[str], columns: list[np.ndarray]) -> None:
    rows = [",".join(header)]
    rows += [",".join(repr(float(c[i])) for c in columns) for i in range(N)]
    path.write_text("\n".join(rows) + "\n", encoding="utf-8")


def _import(path: Path, *options: str):
    """(result, the stored run or None) of `daq import path` into a new store."""
    store = Path(tempfile.mkdtemp(dir=WORK))
    result = invoke_daq("import", str(path), "--store", str(store), *options)
    runs = list(store.glob("*.h5"))
    if result.returncode != 0:
        assert not runs
        return result, None
    (run,) = runs
    return result, Store(store).open(run.stem)


@st.composite
def named_files(draw):
    """(header, columns, expected force, expected response, whether not in position order)
    of a file whose header names one force and one response column (by name, by unit, or
    both), the time column first (or, for the names time/force/response, anywhere)."""
    force, response = _signals()
    time = np.arange(N) / FS
    force_unit = draw(st.sampled_from([None, *FORCE_UNITS]))
    response_unit = draw(st.sampled_from([None, *RESPONSE_UNITS]))
    trio = draw(st.booleans())
    if trio:
        names = ["time", "force", "response"]
    else:
        names = [draw(st.sampled_from(["t", "time", "Zeit"]))]
        # A name that says nothing is fine where the unit does.
        names.append(draw(st.sampled_from(FORCE_NAMES + (["kraft"] if force_unit else []))))
        names.append(draw(st.sampled_from(RESPONSE_NAMES + (["beschl"] if response_unit else []))))
    units = [draw(st.sampled_from([None, "s"])), force_unit, response_unit]
    brackets = draw(st.sampled_from(["({})", "[{}]"]))
    cells = [
        _cased(draw, name) + (f" {brackets.format(unit)}" if unit else "")
        for name, unit in zip(names, units, strict=True)
    ]
    scale = [1.0, FORCE_UNITS.get(force_unit or "N"), RESPONSE_UNITS.get(response_unit or "m/s^2")]
    values = [time, force / scale[1], response / scale[2]]
    order = draw(st.permutations([0, 1, 2]) if trio else st.permutations([1, 2]).map(lambda p: [0, *p]))
    header = [cells[k] for k in order]
    columns = [values[k] for k in order]
    roles: list[int | None] = list(order)  # 0 time, 1 force, 2 response, None left out
    if draw(st.booleans()):  # a column the run leaves out, after the time column
        at = draw(st.integers(1, 3))
        header.insert(at, draw(st.sampled_from(OTHER_NAMES)))
        columns.insert(at, np.full(N, 7.0))
        roles.insert(at, None)
    if draw(st.booleans()):
        header.insert(0, "hit")
        columns.insert(0, np.zeros(N))
        roles.insert(0, None)
    # Read by position, the first three columns but hit would be time, force, response.
    moved = [role for role, cell in zip(roles, header, strict=True) if cell != "hit"][:3] != [0, 1, 2]
    return header, columns, values[1] * scale[1], values[2] * scale[2], moved


@SETTINGS
@given(named_files())
def test_named_force_and_response_columns_are_read_by_name_in_any_order(case):
    header, columns, force, response, moved = case
    path = WORK / "named.csv"
    _write(path, header, columns)
    result, run = _import(path)
    assert result.returncode == 0, result.stderr
    np.testing.assert_allclose(run.hits.force_n[0], force, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(run.hits.response_m_s2[0], response, rtol=1e-12, atol=1e-15)
    notes = [line for line in result.stdout.splitlines() if line.startswith(NOTE)]
    # Said, in one line, only where the names put the columns out of position order.
    assert len(notes) == (1 if moved else 0), result.stdout
    if moved:
        (note,) = notes
        for role in ("time", "force", "response"):
            assert f"{role} '" in note, note
    assert "look swapped" not in result.stdout


@st.composite
def ambiguous_files(draw):
    """(header, columns) of a file whose names say no one force and one response column:
    two force-like, two response-like, or one of them (or both) missing."""
    how = draw(st.sampled_from(["two forces", "two responses", "no response", "no force", "neither"]))
    pools = {
        "two forces": [FORCE_NAMES, FORCE_NAMES, RESPONSE_NAMES],
        "two responses": [RESPONSE_NAMES, RESPONSE_NAMES, FORCE_NAMES],
        "no response": [FORCE_NAMES, OTHER_NAMES],
        "no force": [RESPONSE_NAMES, OTHER_NAMES],
        "neither": [OTHER_NAMES, OTHER_NAMES],
    }[how]
    names = draw(st.permutations([draw(st.sampled_from(pool)) for pool in pools]))
    header = [draw(st.sampled_from(["t", "Time (s)"]))] + [_cased(draw, name) for name in names]
    # A column named "force" and one named "response", each the only one, name them
    # exactly (Table.find) whatever the others are called: no ambiguity there.
    folded = [h.lower() for h in header]
    assume(not (folded.count("force") == 1 and folded.count("response") == 1))
    columns = [np.arange(N) / FS] + [(k + 1.0) * (1.0 + np.arange(N) % 5) for k in range(len(names))]
    return header, columns


@SETTINGS
@given(ambiguous_files())
def test_ambiguous_names_keep_the_columns_in_position(case):
    header, columns = case
    path = WORK / "ambiguous.csv"
    _write(path, header, columns)
    result, run = _import(path)
    assert result.returncode == 0, result.stderr
    np.testing.assert_array_equal(run.hits.force_n[0], columns[1])
    np.testing.assert_array_equal(run.hits.response_m_s2[0], columns[2])
    assert NOTE not in result.stdout


def test_a_name_and_a_unit_that_disagree_keep_todays_refusal(tmp_path):
    force, response = _signals()
    path = tmp_path / "contradicts.csv"
    # "Force" in g: the name says force, the unit acceleration; nothing is guessed.
    _write(path, ["Time (s)", "Force (g)", "Acceleration (N)"], [np.arange(N) / FS, response, force])
    result, run = _import(path)
    assert run is None
    assert_one_line_error(result, "'Force (g)' is read as the force", "--columns")


def test_given_columns_win_over_the_names(tmp_path):
    force, response = _signals()
    path = tmp_path / "given.csv"
    _write(path, ["t", "a", "F"], [np.arange(N) / FS, response, force])
    result, run = _import(path, "--columns", "0,1,2")
    assert result.returncode == 0, result.stderr
    np.testing.assert_array_equal(run.hits.force_n[0], response)
    assert NOTE not in result.stdout
    result, run = _import(path)
    np.testing.assert_array_equal(run.hits.force_n[0], force)
    np.testing.assert_array_equal(run.hits.response_m_s2[0], response)
    assert f"{NOTE}names: time 't', force 'F', response 'a'" in result.stdout


# --- the two files of the report, through a real `daq import` process -------------------


def _report_file(path: Path, header: str, force_scale: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    fs = 4096
    t = np.arange(4096) / fs
    f = np.zeros_like(t)
    f[10:14] = [1, 3, 3, 1]
    a = np.convolve(f, np.exp(-30 * t) * np.sin(2 * np.pi * 100 * t))[: t.size]
    rows = (f"{x:.8g},{y:.6g},{z:.6g}\n" for x, y, z in zip(t, a, f, strict=True))
    path.write_text(header + "\n" + "".join(rows))
    return np.array([float(f"{v:.6g}") for v in f]), np.array([float(f"{v:.6g}") for v in a])


def _stored(store: Path):
    (run,) = store.glob("*.h5")
    return open_run(run)


def test_time_response_force_imports_by_name_in_a_real_process(tmp_path):
    path = tmp_path / "hdr2.csv"
    force, response = _report_file(path, "time,response,force")
    store = tmp_path / "runs"
    result = run_daq("import", str(path), "--store", str(store))
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""
    notes = [line for line in result.stdout.splitlines() if line.startswith(NOTE)]
    assert notes == ["note: columns taken by their names: time 'time', force 'force', response 'response'"]
    run = _stored(store)
    np.testing.assert_array_equal(run.hits.force_n[0], force)
    np.testing.assert_array_equal(run.hits.response_m_s2[0], response)


def test_time_acceleration_force_with_units_imports_in_a_real_process(tmp_path):
    path = tmp_path / "hdr.csv"
    force, response = _report_file(path, "Time (s),Acceleration (g),Force (N)")
    store = tmp_path / "runs"
    result = run_daq("import", str(path), "--store", str(store))
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""
    notes = [line for line in result.stdout.splitlines() if line.startswith(NOTE)]
    assert notes == [
        "note: columns taken by their names: time 'Time (s)', force 'Force (N)', response 'Acceleration (g)'"
    ]
    assert "units: time s, force N (header), response g (header)" in result.stdout.splitlines()
    run = _stored(store)
    np.testing.assert_array_equal(run.hits.force_n[0], force)
    np.testing.assert_allclose(run.hits.response_m_s2[0], response * 9.80665, rtol=1e-15)


def test_an_ambiguous_header_is_still_refused_in_a_real_process(tmp_path):
    path = tmp_path / "two-forces.csv"
    # Two force-like columns (the last with no unit): which is the force is not guessed;
    # by position the acceleration is read as the force and refused, as before, with the
    # --columns that the units say.
    _report_file(path, "Time (s),Acceleration (g),Force (N)")
    lines = path.read_text().splitlines()
    lines[0] = "Time (s),Acceleration (g),Force (N),hammer"
    path.write_text("\n".join(line + (",0" if k else "") for k, line in enumerate(lines)) + "\n")
    store = tmp_path / "runs"
    result = run_daq("import", str(path), "--store", str(store))
    assert result.returncode == 1
    assert result.stdout == ""
    assert_one_line_error(
        result, "'Acceleration (g)' is read as the force", "--columns Time,Force,Acceleration (time, force"
    )
    assert not list(store.glob("*.h5"))


def test_the_detected_line_quotes_the_header_after_a_preamble(tmp_path):
    path = tmp_path / "preamble.csv"
    _report_file(path, "Time (s),Acceleration (g),Force (N)")
    path.write_text("Sample rate: 4096 Hz\nOperator: jo\n" + path.read_text())
    result = invoke_daq("import", str(path), "--store", str(tmp_path / "runs"))
    assert result.returncode == 0, result.stderr
    assert (
        "format csv: detected: the name ends in .csv, and the header's first column 'Time (s)' is no "
        "frequency" in result.stdout.splitlines()
    )


def test_two_columns_of_one_exact_name_keep_the_columns_in_position(tmp_path):
    """Hypothesis found it: 'Time (s),force,force,response' took its first 'force' by name
    and the response by name, out of position; two forces name no one force."""
    path = tmp_path / "two_forces.csv"
    columns = [np.arange(N) / FS] + [(k + 1.0) * (1.0 + np.arange(N) % 5) for k in range(3)]
    _write(path, ["Time (s)", "force", "force", "response"], columns)
    result, run = _import(path)
    assert result.returncode == 0, result.stderr
    np.testing.assert_array_equal(run.hits.force_n[0], columns[1])
    np.testing.assert_array_equal(run.hits.response_m_s2[0], columns[2])
    assert NOTE not in result.stdout
