"""A phase column with no unit that holds radians (hypothesis): an FRF table `frequency,
magnitude, phase` whose every phase lies within ±π. A phase without a unit is read as
degrees (the documented default, unchanged); where it never leaves ±π yet spans more
than a radian, the import says it looks like radians and how to say so, `[rad]` in the
header, which is read. Before, such a file was read as degrees without a word: an FRF
whose phase barely turns."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from daq.formats.frf_text import read_frf_text

SETTINGS = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
WORK = Path(tempfile.mkdtemp(prefix="radian-phase-"))


def _write(header: list[str], columns: list[np.ndarray], delimiter: str) -> Path:
    rows = [delimiter.join(header)]
    rows += [delimiter.join(f"{c[k]:.7g}" for c in columns) for k in range(columns[0].size)]
    path = WORK / "magphase.csv"
    path.write_text("\n".join(rows) + "\n", encoding="utf-8")
    return path


def _radian_notes(details: dict) -> list[str]:
    return [n for n in details.get("notes", []) if "looks like radians" in n]


@SETTINGS
@given(
    n=st.integers(8, 200),
    seed=st.integers(0, 2**16),
    n_frf=st.integers(1, 3),
    span=st.floats(1.2, 2 * np.pi),
    unit=st.sampled_from([None, "[rad]", "(rad)", "[deg]"]),
    delimiter=st.sampled_from([",", ";", "\t"]),
)
def test_a_unitless_phase_within_pi_is_read_as_degrees_with_a_note(n, seed, n_frf, span, unit, delimiter):
    rng = np.random.default_rng(seed)
    freq = 0.25 * np.arange(1, n + 1)
    header, columns, phases = ["Frequency (Hz)"], [freq], []
    for k in range(n_frf):
        phase = np.clip(rng.uniform(-span / 2, span / 2, n), -np.pi, np.pi)
        phase[0], phase[-1] = -span / 2, span / 2  # the span as drawn
        header += [f"H{k + 1}1 mag", f"H{k + 1}1 phase" + (f" {unit}" if unit else "")]
        columns += [rng.uniform(0.1, 2.0, n), phase]
        phases.append(phase)
    data = read_frf_text(_write(header, columns, delimiter))
    got = data.measured_frfs.frf
    written = [np.array([float(f"{v:.7g}") for v in p]) for p in phases]
    as_radians = unit in ("[rad]", "(rad)")
    for k, phase in enumerate(written):
        want = phase if as_radians else np.deg2rad(phase)
        np.testing.assert_allclose(got[k] / np.abs(got[k]), np.exp(1j * want), atol=1e-9)  # modulo 2 pi
    notes = _radian_notes(data.details)
    if unit is not None:
        assert notes == []
        return
    assert len(notes) == n_frf
    for k, note in enumerate(notes):
        name = f"H{k + 1}1 phase"
        assert note.startswith(f"column {2 * k + 3} {name!r} has no unit and all its values lie within ±π")
        assert note.endswith(
            f"read as degrees, but it looks like radians; if it is, write the unit in the header, "
            f"'{name} [rad]' ('{name} [deg]' says degrees)"
        )


@SETTINGS
@given(
    n=st.integers(8, 200),
    seed=st.integers(0, 2**16),
    how=st.sampled_from(["wide", "small"]),
)
def test_a_phase_in_degrees_gets_no_note(n, seed, how):
    rng = np.random.default_rng(seed)
    if how == "wide":  # a phase in degrees leaves +-pi
        phase = rng.uniform(-180.0, 180.0, n)
        phase[0] = 4.0 * np.sign(phase[0] or 1.0)
    else:  # a small phase in degrees: within +-pi, but spanning 1 or less
        phase = rng.uniform(-0.5, 0.5, n)
    path = _write(["f [Hz]", "H mag", "H phase"], [0.5 * np.arange(1, n + 1), np.ones(n), phase], ",")
    data = read_frf_text(path)
    assert _radian_notes(data.details) == []
    # A note that says nothing new would be noise; the radian case says something.
    radians = np.linspace(-3.0, 3.0, n)
    path = _write(["f [Hz]", "H mag", "H phase"], [0.5 * np.arange(1, n + 1), np.ones(n), radians], ",")
    assert len(_radian_notes(read_frf_text(path).details)) == 1
