"""UFF 58 files a new user wrote with pyuff (trial D): what the reader converts, refuses and
says it left out.

Before: a frequency axis in rad/s or kHz (or time) was read as Hz; ft/s^2, mg, mil and
volts were stored as SI with only a warning; a real (magnitude or dB) FRF was taken as
complex; a stray time record blocked a file of FRFs; coherence went to FRFs by file
order; Latin-1 labels came out as U+FFFD and '(1/N)*(m/s^2)' was refused; a falling
frequency axis was refused with an internal name; a gzipped file echoed its bytes.
The SI factors below come from the units' definitions, not from the code under test.
"""

from __future__ import annotations

import gc
import gzip
import math
import tempfile
import warnings
from pathlib import Path

import numpy as np
import pytest
import pyuff
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from daq.formats.errors import FormatError
from daq.formats.uff58 import read_uff
from daq.formats.uff_multipoint import read_multipoint_uff
from tests.cli_helpers import daq_import, refused, runs_in

SETTINGS = settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
WORK = Path(tempfile.mkdtemp(prefix="uff-trial-d-"))

G = 9.80665  # m/s^2, standard gravity (exact)
LBF = 0.45359237 * G  # N, pound-force (exact)
INCH, FOOT = 0.0254, 0.3048  # m (exact)


def record(
    data,
    x,
    *,
    func: int = 4,
    kind: int = 12,
    unit: str = "m/s^2",
    den_kind: int = 13,
    den_unit: str = "N",
    x_kind: int = 18,
    x_unit: str = "Hz",
    nodes: tuple[int, int, int, int] = (1, 3, 1, 3),
    binary: int = 1,
    id1: str = "H",
) -> dict:
    """One dataset 58 for pyuff; nodes (reference node, direction, response node, direction).
    Binary with uneven spacing keeps every abscissa value as a double."""
    ref_node, ref_dir, rsp_node, rsp_dir = nodes
    dset = pyuff.prepare_58(
        binary=binary, id1=id1, func_type=func, rsp_node=rsp_node, rsp_dir=rsp_dir, ref_node=ref_node,
        ref_dir=ref_dir, abscissa_spacing=0, abscissa_spec_data_type=x_kind,
        ordinate_spec_data_type=kind, orddenom_spec_data_type=den_kind, z_axis_spec_data_type=0,
        data=np.asarray(data), x=np.asarray(x, dtype=np.float64),
    )  # fmt: skip
    dset.update(
        abscissa_axis_units_lab=x_unit, ordinate_axis_units_lab=unit, orddenom_axis_units_lab=den_unit
    )
    return dset


def write(path: Path, sets: list[dict]) -> Path:
    path.unlink(missing_ok=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ResourceWarning)  # pyuff leaves files to the collector
        pyuff.UFF(str(path)).write_sets(sets, mode="add")
        gc.collect()
    return path


def frf_values(n: int = 16, seed: int = 1) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return rng.normal(size=n) + 1j * rng.normal(size=n)


FREQ = 5.0 + 2.5 * np.arange(16)  # Hz


def refused_by_reader(path: Path, *fragments: str) -> str:
    with pytest.raises(FormatError) as info:
        read_uff(path)
    message = str(info.value)
    assert "\n" not in message
    assert path.name in message
    for fragment in fragments:
        assert fragment in message, message
    return message


# --- 1. the abscissa's unit ----------------------------------------------------------------------

#: Frequency labels and the factor to Hz: by definition (2 pi rad per cycle, 60 s per minute).
FREQUENCY_LABELS = {"Hz": 1.0, "hz": 1.0, "NONE": 1.0, "kHz": 1e3, "KHZ": 1e3, "rad/s": 1 / (2 * math.pi),
                    "cpm": 1 / 60, "CPM": 1 / 60}  # fmt: skip


@SETTINGS
@given(
    label=st.sampled_from(sorted(FREQUENCY_LABELS)),
    start=st.floats(0.0, 1e3),
    step=st.floats(1e-3, 50.0),
    n=st.integers(2, 40),
)
def test_frequency_axis_in_any_known_unit_comes_back_in_hz(label, start, step, n):
    x = start + step * np.arange(n)
    coherence = record(np.linspace(0.5, 1.0, n), x, func=6, kind=0, unit="NONE", den_kind=0, x_unit=label)
    path = write(WORK / "axis.uff", [record(frf_values(n), x, x_unit=label), coherence])
    got = read_uff(path)
    np.testing.assert_allclose(got.measured_frfs.frequency_hz, x * FREQUENCY_LABELS[label], rtol=1e-12)
    np.testing.assert_array_equal(got.measured_frfs.coherence[0], np.linspace(0.5, 1.0, n))  # same axis
    said = [note for note in got.details["notes"] if "abscissa in" in note]
    if FREQUENCY_LABELS[label] == 1.0:
        assert said == []
    else:
        assert len(said) == 1
        assert said[0].startswith(f"datasets 58 #1, #2: abscissa in {label}, converted to Hz (")


@SETTINGS
@given(
    case=st.sampled_from(
        [(17, "s"), (17, "Hz"), (18, "s"), (18, "ms"), (0, "sec"), (19, "RPM"), (18, "rpm"), (20, "NONE"),
         (18, "furlong"), (18, "Pa"), (1, "MHz"), (5, "Hz")]
    )
)  # fmt: skip
def test_frf_over_time_or_an_unknown_abscissa_is_refused(case):
    x_kind, label = case
    path = write(WORK / "time-axis.uff", [record(frf_values(), FREQ, x_kind=x_kind, x_unit=label)])
    message = refused_by_reader(path, "FRF record #1")
    assert repr(label) in message or "'none'" in message, message


def test_rad_per_s_khz_and_time_axes_through_the_command_line(tmp_path):
    rad = write(tmp_path / "rad.uff", [record(frf_values(), FREQ * 2 * math.pi, x_unit="rad/s")])
    result = daq_import(tmp_path / "s1", rad)
    assert result.returncode == 0, result.stderr
    assert "note: FRF record #1: abscissa in rad/s, converted to Hz (divided by 2π)" in result.stdout
    khz = write(tmp_path / "khz.uff", [record(frf_values(), FREQ / 1000, x_unit="kHz")])
    assert "abscissa in kHz, converted to Hz" in daq_import(tmp_path / "s2", khz).stdout
    time = write(tmp_path / "time.uff", [record(frf_values(), FREQ, x_kind=17, x_unit="s")])
    refused(daq_import(tmp_path / "s3", time), tmp_path / "s3", "FRF record #1", "abscissa is time", "'s'")


# --- 2. unit labels --------------------------------------------------------------------------------

#: Numerator labels, their form's ordinate data type and SI factor, from the units' definitions.
NUMERATORS = {
    "m/s^2": (12, 1.0), "mm/s^2": (12, 1e-3), "g": (12, G), "G": (12, G), "mg": (12, 1e-3 * G),
    "ft/s^2": (12, FOOT), "in/s^2": (12, INCH), "m/s²": (12, 1.0),
    "m/s": (11, 1.0), "mm/s": (11, 1e-3), "in/s": (11, INCH), "in/sec": (11, INCH), "ft/s": (11, FOOT),
    "m": (8, 1.0), "mm": (8, 1e-3), "um": (8, 1e-6), "µm": (8, 1e-6), "in": (8, INCH),
    "mil": (8, 1e-3 * INCH), "ft": (8, FOOT),
}  # fmt: skip
FORCES = {"N": 1.0, "kN": 1e3, "lbf": LBF, "kgf": G}


@SETTINGS
@given(
    numerator=st.sampled_from(sorted(NUMERATORS)),
    force=st.sampled_from(sorted(FORCES)),
    whole=st.sampled_from(["pair", "X/F", "(X)/F", "(1/F)*(X)", "(X)(F)"]),
)
def test_frf_unit_labels_are_converted_to_si(numerator, force, whole):
    kind, factor = NUMERATORS[numerator]
    if whole == "pair":
        unit, den = numerator, force
    else:
        unit, den = whole.replace("X", numerator).replace("F", force), "NONE"
    data = frf_values()
    path = write(WORK / "units.uff", [record(data, FREQ, kind=kind, unit=unit, den_unit=den)])
    got = read_uff(path)
    np.testing.assert_allclose(got.measured_frfs.frf[0], data * factor / FORCES[force], rtol=1e-12)
    assert got.measured_frfs.form == {8: "receptance", 11: "mobility", 12: "accelerance"}[kind]
    converted = [note for note in got.details["notes"] if note.startswith("FRF unit ")]
    assert bool(converted) == (factor / FORCES[force] != 1.0)


@SETTINGS
@given(
    labels=st.sampled_from(
        [("V", "V"), ("EU", "EU"), ("mV", "N"), ("m/s^2", "V"), ("V/V", "NONE"), ("g", "EU")]
    ),
    kind=st.sampled_from([12, 1]),
)
def test_volts_are_refused_for_want_of_a_sensitivity(labels, kind):
    path = write(
        WORK / "volts.uff", [record(frf_values(), FREQ, kind=kind, unit=labels[0], den_unit=labels[1])]
    )
    refused_by_reader(path, "FRF record #1", "no sensor sensitivity", "engineering units")


@pytest.mark.parametrize("labels", [("furlong", "N"), ("m/s^2", "furlong"), ("dB", "N"), ("Pa", "NONE")])
def test_an_unknown_frf_label_is_refused_naming_record_label_and_understood_labels(tmp_path, labels):
    path = write(tmp_path / "u.uff", [record(frf_values(), FREQ, unit=labels[0], den_unit=labels[1])])
    message = refused(daq_import(tmp_path / "s", path), tmp_path / "s", "FRF record #1", "understood are")
    assert "furlong" in message or "dB" in message or "Pa" in message
    assert "m/s^2" in message  # what the reader does understand
    assert "lbf" in message


def test_time_records_in_volts_are_refused(tmp_path):
    x = np.arange(64) / 1024.0
    sets = [
        record(np.sin(x), x, func=1, kind=13, unit="V", den_kind=0, den_unit="NONE", x_kind=17, x_unit="s"),
        record(np.cos(x), x, func=1, kind=12, unit="V", den_kind=0, den_unit="NONE", x_kind=17, x_unit="s"),
    ]
    path = write(tmp_path / "v.uff", sets)
    refused(
        daq_import(tmp_path / "s", path), tmp_path / "s", "time record #1", "'V'", "no sensor sensitivity"
    )


def test_time_records_in_mg_and_kgf_are_converted(tmp_path):
    x = np.arange(64) / 1024.0
    sets = [
        record(np.sin(x), x, func=1, kind=13, unit="kgf", den_kind=0, den_unit="NONE", x_kind=17, x_unit="s"),
        record(np.cos(x), x, func=1, kind=12, unit="mg", den_kind=0, den_unit="NONE", x_kind=17, x_unit="s"),
    ]
    got = read_uff(write(tmp_path / "t.uff", sets))
    np.testing.assert_allclose(got.hits.force_n[0], np.sin(x) * G, rtol=1e-12)
    np.testing.assert_allclose(got.hits.response_m_s2[0], np.cos(x) * 1e-3 * G, rtol=1e-12)


def test_one_force_and_two_sensors_is_refused_naming_the_points_and_what_to_do(tmp_path):
    x = np.arange(64) / 1024.0
    time = {"func": 1, "den_kind": 0, "den_unit": "NONE", "x_kind": 17, "x_unit": "s"}
    sets = [
        record(np.sin(x), x, kind=13, unit="N", **time),
        record(np.cos(x), x, kind=12, nodes=(1, 3, 1, 3), **time),
        record(np.cos(2 * x), x, kind=12, nodes=(1, 3, 2, 3), **time),
    ]
    path = write(tmp_path / "two.uff", sets)
    refused(
        daq_import(tmp_path / "s", path), tmp_path / "s", "1 force and 2 acceleration time records",
        "2 response points (node 1 dir 3, node 2 dir 3)", "one file per response point",
    )  # fmt: skip


def multi_point(path: Path, units: list[str]) -> Path:
    sets = [
        record(frf_values(seed=k), FREQ, unit=unit, nodes=(1, 3, k + 1, 3), id1=f"H{k + 1}1")
        for k, unit in enumerate(units)
    ]
    return write(path, sets)


@pytest.mark.parametrize("units", [["mg", "mg", "mg"], ["m/s^2", "ft/s^2", "m/s^2"]])
def test_a_multi_point_test_converts_each_records_unit(tmp_path, units):
    ex = read_multipoint_uff(multi_point(tmp_path / "t.uff", units))
    factors = {"mg": 1e-3 * G, "ft/s^2": FOOT, "m/s^2": 1.0}
    for k, unit in enumerate(units):
        np.testing.assert_allclose(ex.frf[k], frf_values(seed=k) * factors[unit], rtol=1e-12)
    assert any("converted to (m/s^2)/N" in note for note in ex.notes)
    assert not any("values kept" in note for note in ex.notes)


def test_a_multi_point_test_in_volts_is_refused_and_nothing_stored(tmp_path):
    path = multi_point(tmp_path / "t.uff", ["m/s^2", "V", "m/s^2"])
    result = daq_import(tmp_path / "s", path, "--as-test", "volts")
    refused(result, tmp_path / "s", "FRF record #2", "no sensor sensitivity")


# --- 3. a real FRF -----------------------------------------------------------------------------------


@pytest.mark.parametrize(("binary", "unit"), [(0, "m/s^2"), (1, "m/s^2"), (1, "dB")])
def test_a_real_valued_frf_is_refused(tmp_path, binary, unit):
    path = write(tmp_path / "mag.uff", [record(np.abs(frf_values()), FREQ, unit=unit, binary=binary)])
    assert pyuff.UFF(str(path)).read_sets(0)["ord_data_type"] in (2, 4)  # real, as the file says
    refused(
        daq_import(tmp_path / "s", path), tmp_path / "s", "FRF record #1", "magnitude without its phase",
        "complex FRF",
    )  # fmt: skip


# --- 4. stray time records and other datasets ---------------------------------------------------------


def mixed_file(path: Path) -> Path:
    """Like s07_multi_mixed.uff: nodes (15), 3 FRFs with coherence, an auto spectrum,
    one response time record."""
    nodes = pyuff.prepare_15(
        node_nums=[1, 2, 3], def_cs=[0] * 3, disp_cs=[0] * 3, color=[1] * 3,
        x=[0.0, 0.1, 0.2], y=[0.0] * 3, z=[0.0] * 3,
    )  # fmt: skip
    sets: list[dict] = [nodes]
    for k in range(3):
        dof = (1, 3, k + 1, 3)
        sets.append(record(frf_values(seed=k), FREQ, nodes=dof, id1=f"H{k + 1}1"))
        sets.append(record(np.full(16, 0.9 - 0.1 * k), FREQ, func=6, kind=0, unit="NONE", den_kind=0,
                           den_unit="NONE", nodes=dof))  # fmt: skip
    sets.append(record(np.ones(16), FREQ, func=2, kind=13, unit="N^2/Hz", den_kind=0, den_unit="NONE"))
    t = np.arange(64) / 1024.0
    sets.append(
        record(
            np.sin(t), t, func=1, kind=12, unit="m/s^2", den_kind=0, den_unit="NONE", x_kind=17, x_unit="s"
        )
    )
    return write(path, sets)


def test_a_stray_time_record_beside_frfs_is_skipped_and_named(tmp_path):
    path = mixed_file(tmp_path / "mixed.uff")
    result = daq_import(tmp_path / "s", path)
    assert result.returncode == 0, result.stderr
    assert "3 FRFs of 16 points" in result.stdout
    assert "note: skipped datasets 15 (nodes)" in result.stdout
    assert "#7 (auto spectrum)" in result.stdout
    assert "#8 (time record of acceleration)" in result.stdout
    assert "do not pair up" in result.stdout
    got = read_uff(path)
    assert got.hits is None
    np.testing.assert_array_equal(got.measured_frfs.coherence[:, 0], [0.9, 0.8, 0.7])


# --- 5. coherence by DOF -----------------------------------------------------------------------------


@SETTINGS
@given(order=st.permutations(range(4)), extra=st.booleans())
def test_coherence_goes_to_the_frf_of_its_dof_whatever_its_order(order, extra):
    sets = [record(frf_values(seed=k), FREQ, nodes=(1, 3, k + 1, 3)) for k in range(4)]
    cohs = [
        record(np.full(16, 0.5 + 0.1 * k), FREQ, func=6, kind=0, unit="NONE", den_kind=0, den_unit="NONE",
               nodes=(1, 3, k + 1, 3))
        for k in order
    ]  # fmt: skip
    if extra:  # a coherence of a DOF no FRF has
        cohs.insert(
            1, record(np.full(16, 0.1), FREQ, func=6, kind=0, unit="NONE", den_kind=0, nodes=(9, 1, 9, 1))
        )
    got = read_uff(write(WORK / "coh.uff", sets + cohs))
    np.testing.assert_array_equal(got.measured_frfs.coherence[:, 0], [0.5, 0.6, 0.7, 0.8])
    skipped = [note for note in got.details["notes"] if "coherence of no FRF" in note]
    assert len(skipped) == int(extra)
    if extra:
        assert "dataset 58 #6 (coherence)" in skipped[0]


# --- 6. Latin-1 labels, '(1/N)*(m/s^2)' ----------------------------------------------------------------


def latin1(path: Path, placeholder: bytes = b"#") -> Path:
    """The file with its placeholder byte made a Latin-1 '²' (0xB2), as Windows tools write it."""
    data = path.read_bytes()
    assert data.count(placeholder) >= 1
    path.write_bytes(data.replace(placeholder, b"\xb2"))
    return path


@pytest.mark.parametrize("binary", [0, 1])
def test_latin1_label_and_general_type_with_one_over_n(tmp_path, binary):
    data = frf_values()
    sets = [record(data, FREQ, kind=1, unit="(1/N)*(m/s#)", den_kind=0, den_unit="NONE", binary=binary)]
    path = latin1(write(tmp_path / "l1.uff", sets))
    got = read_uff(path)
    assert got.measured_frfs.form == "accelerance"
    np.testing.assert_allclose(got.measured_frfs.frf[0], data, rtol=1e-10)  # ASCII: 12 digits
    plain = write(tmp_path / "plain.uff", [record(data, FREQ, kind=1, unit="(1/N)*(m/s^2)", den_kind=0,
                                                  den_unit="NONE")])  # fmt: skip
    result = daq_import(tmp_path / "s", plain)
    assert result.returncode == 0, result.stderr


def test_a_latin1_label_is_shown_as_written_when_refused(tmp_path):
    psd = record(np.ones(16), FREQ, func=9, kind=0, unit="g#/Hz", den_kind=0, den_unit="NONE")
    path = latin1(write(tmp_path / "psd.uff", [psd]))
    message = refused(daq_import(tmp_path / "s", path), tmp_path / "s", "(g²/Hz)")
    assert "\ufffd" not in message


# --- 7. a falling axis, a gzipped file ----------------------------------------------------------------


def test_a_falling_axis_shared_by_every_record_is_read_rising(tmp_path):
    data = frf_values()
    sets = [
        record(data[::-1], FREQ[::-1]),
        record(np.linspace(0.1, 0.9, 16)[::-1], FREQ[::-1], func=6, kind=0, unit="NONE", den_kind=0),
    ]
    got = read_uff(write(tmp_path / "down.uff", sets))
    np.testing.assert_array_equal(got.measured_frfs.frequency_hz, FREQ)
    np.testing.assert_array_equal(got.measured_frfs.frf[0], data)
    np.testing.assert_array_equal(got.measured_frfs.coherence[0], np.linspace(0.1, 0.9, 16))
    assert any("fall from 42.5 to 5 Hz" in note for note in got.details["notes"])


def test_an_axis_that_does_not_rise_is_refused_in_user_words(tmp_path):
    x = FREQ.copy()
    x[5], x[6] = x[6], x[5]
    path = write(tmp_path / "zigzag.uff", [record(frf_values(), x)])
    message = refused(
        daq_import(tmp_path / "s", path), tmp_path / "s", "FRF record #1", "frequencies must increase"
    )
    assert "frf.frequency_hz" not in message


def test_a_gzipped_uff_is_told_to_unpack_it(tmp_path):
    path = write(tmp_path / "plain.uff", [record(frf_values(), FREQ)])
    packed = tmp_path / "packed.uff"
    packed.write_bytes(gzip.compress(path.read_bytes()))
    message = refused(daq_import(tmp_path / "s", packed), tmp_path / "s", "gzip-compressed: unpack it first")
    assert "\\x1f" not in message
    assert runs_in(tmp_path / "s") == []
