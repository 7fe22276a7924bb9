"""A whole multi-point test as UFF 15, 82, 58 and 55: pyuff reads what we write, we read what
pyuff writes, the real roving-hammer set reads, and what is no test is refused in one line."""

from __future__ import annotations

import math
import os
import tempfile
from pathlib import Path

import numpy as np
import pytest
import pyuff
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from daq.formats.errors import FormatError
from daq.formats.uff_multipoint import (
    DIRECTION_CODES,
    Dof,
    ModeShapes,
    MultiPointExchange,
    Node,
    as_written,
    read_multipoint_uff,
    write_multipoint_uff,
)
from tests.conftest import NO_CORPUS

PRINTED = 5e-6  # %13.5E / %13.5e keep 6 significant digits: relative error <= 5e-6


def beam_test(n_points: int = 5, n_lines: int = 64, even: bool = True, seed: int = 1) -> MultiPointExchange:
    """Roving hammer on a beam along x: hammer +Z at points 1..n, accelerometer -Z at point 3
    (so FRF 2 is the driving point), one clamp node 100 with coordinates and no FRF, one node
    200 in a trace line only, without coordinates."""
    rng = np.random.default_rng(seed)
    nodes = [Node(i, f"p{i}", 0.1 * i + 0.0123456789, 0.0, 0.25) for i in range(1, n_points + 1)]
    nodes += [Node(100, "100", 0.0, 0.0, 0.25), Node(200, "200")]
    freq = np.arange(n_lines) * 0.5 if even else np.arange(n_lines) * (1000 / 51200) + 1 / 3
    frf = rng.normal(size=(n_points, n_lines)) + 1j * rng.normal(size=(n_points, n_lines))
    shapes = rng.normal(size=(3, len(nodes))) + 1j * rng.normal(size=(3, len(nodes)))
    shapes[:, -2] = 0  # the clamp does not move
    lines = [(100, 1)] + [(i, i + 1) for i in range(1, n_points)] + [(n_points, 200)]
    return MultiPointExchange(
        nodes=tuple(nodes),
        lines=tuple(lines),
        frequency_hz=freq,
        frf=frf,
        references=tuple(Dof(i, "+Z") for i in range(1, n_points + 1)),
        responses=tuple(Dof(3, "-Z") for _ in range(n_points)),
        form="accelerance",
        coherence=rng.uniform(size=(n_points, n_lines)),
        modes=ModeShapes([12.5, 78.25, 219.125], [0.01, 0.0025, 0.03], shapes, ("Z",) * len(nodes)),
    )


def read_sets(path: Path) -> list[dict]:
    return pyuff.UFF(str(path)).read_sets()


def refused(path: Path) -> str:
    with pytest.raises(FormatError) as info:
        read_multipoint_uff(path)
    message = str(info.value)
    assert "\n" not in message
    assert str(path) in message
    return message


def assert_same(back: MultiPointExchange, ex: MultiPointExchange) -> None:
    """``back`` is ``ex`` as the file holds it: exactly as_written(ex)."""
    want = as_written(ex)
    assert back.nodes == want.nodes
    assert back.lines == want.lines
    assert back.references == want.references
    assert back.responses == want.responses
    assert back.form == want.form
    np.testing.assert_array_equal(back.frequency_hz, want.frequency_hz, strict=True)
    np.testing.assert_array_equal(back.frf, want.frf, strict=True)
    if want.coherence is None:
        assert back.coherence is None
    else:
        np.testing.assert_array_equal(back.coherence, want.coherence, strict=True)
    if want.modes is None:
        assert back.modes is None
    else:
        np.testing.assert_array_equal(back.modes.frequency_hz, want.modes.frequency_hz, strict=True)
        np.testing.assert_array_equal(back.modes.damping_ratio, want.modes.damping_ratio, strict=True)
        np.testing.assert_array_equal(back.modes.shapes, want.modes.shapes, strict=True)
        assert back.modes.axes == want.modes.axes


# ---------------------------------------------------------------------------------------------
# Round trip through our writer


@pytest.mark.parametrize("even", [True, False], ids=["even-axis", "uneven-axis"])
def test_pyuff_reads_what_we_write(tmp_path, even):
    ex = beam_test(even=even)
    path = tmp_path / "test.uff"
    write_multipoint_uff(path, ex)
    sets = read_sets(path)
    assert [d["type"] for d in sets] == [15] + [82] * 6 + [58] * 10 + [55] * 3

    # 15: the nodes with coordinates, printed with 6 significant digits.
    nodes = sets[0]
    placed = [n for n in ex.nodes if n.has_position]
    assert [int(v) for v in nodes["node_nums"]] == [n.number for n in placed]
    for key in "xyz":
        want = np.array([getattr(n, key) for n in placed])
        assert np.asarray(nodes[key]).tolist() == [float(f"{v:13.5E}") for v in want]
        np.testing.assert_allclose(nodes[key], want, rtol=PRINTED)

    # 82: one trace line per pair.
    assert [tuple(int(v) for v in d["nodes"]) for d in sets[1:7]] == list(ex.lines)

    # 58: the FRFs bit for bit with their DOFs, then the coherence.
    for i, d in enumerate(sets[7:12]):
        assert d["func_type"] == 4
        assert (d["ref_node"], d["ref_dir"], d["rsp_node"], d["rsp_dir"]) == (i + 1, 3, 3, -3)
        assert (d["ordinate_spec_data_type"], d["orddenom_spec_data_type"]) == (12, 13)
        assert (d["ordinate_axis_units_lab"], d["orddenom_axis_units_lab"]) == ("m/s^2", "N")
        assert d["abscissa_spacing"] == (1 if even else 0)
        np.testing.assert_array_equal(d["data"], ex.frf[i], strict=True)
        np.testing.assert_array_equal(d["x"], ex.frequency_hz, strict=True)
        assert f"ref_name=p{i + 1} rsp_name=p3" in d["id4"]
    driving = sets[7 + 2]
    assert driving["ref_node"] == driving["rsp_node"] == 3  # ONE node for reference and response
    for i, d in enumerate(sets[12:17]):
        assert d["func_type"] == 6
        assert (d["ref_node"], d["rsp_node"]) == (i + 1, 3)
        np.testing.assert_array_equal(d["data"], ex.coherence[i], strict=True)

    # 55: one complex mode per dataset, the shape along Z, frequency and damping.
    for k, d in enumerate(sets[17:]):
        assert (d["analysis_type"], d["data_ch"], d["mode_n"]) == (3, 2, k + 1)
        assert [int(v) for v in d["node_nums"]] == [n.number for n in ex.nodes]
        np.testing.assert_allclose(d["r3"], ex.modes.shapes[k], rtol=PRINTED, atol=0)
        assert not np.any(d["r1"])
        assert not np.any(d["r2"])
        f, zeta = float(ex.modes.frequency_hz[k]), float(ex.modes.damping_ratio[k])
        assert abs(d["eig"]) / (2 * np.pi) == pytest.approx(f, rel=PRINTED)
        assert -d["eig"].real / abs(d["eig"]) == pytest.approx(zeta, rel=2 * PRINTED)
        assert f"freq_hz={f!r} damping_ratio={zeta!r}" == d["id4"]

    # And our reader gives the same exchange back.
    back = read_multipoint_uff(path)
    assert_same(back, ex)
    assert back.notes == ()
    np.testing.assert_array_equal(back.frf, ex.frf, strict=True)
    np.testing.assert_allclose(back.modes.shapes, ex.modes.shapes, rtol=PRINTED, atol=0)
    assert [n.name for n in back.nodes] == [n.name for n in ex.nodes]


@pytest.mark.parametrize("form", ["receptance", "mobility"])
def test_every_form_round_trips_with_its_type_and_unit(tmp_path, form):
    ex = beam_test(n_points=3, n_lines=8)
    ex.form, ex.modes, ex.coherence = form, None, None
    path = tmp_path / "test.uff"
    write_multipoint_uff(path, ex)
    kinds = {
        (d["ordinate_spec_data_type"], d["ordinate_axis_units_lab"])
        for d in read_sets(path)
        if d["type"] == 58
    }
    assert kinds == {{"receptance": (8, "m"), "mobility": (11, "m/s")}[form]}
    assert_same(read_multipoint_uff(path), ex)


def test_geometry_without_coordinates_writes_no_dataset_15(tmp_path):
    ex = beam_test(n_points=3, n_lines=4)
    ex.nodes = tuple(Node(n.number, n.name) for n in ex.nodes)
    path = tmp_path / "test.uff"
    write_multipoint_uff(path, ex)
    assert 15 not in {d["type"] for d in read_sets(path)}
    back = read_multipoint_uff(path)
    assert_same(back, ex)
    assert not any(n.has_position for n in back.nodes)


# ---------------------------------------------------------------------------------------------
# Files written by pyuff itself


def write_pyuff_test(path: Path, *, forms=(12, 12, 12), axes=None, unit="g", geometry=True) -> None:
    """3 FRFs written by pyuff directly (ASCII 58): roving hammer +Y at nodes 11, 12, 13,
    accelerometer +Y at 12, in g/N; a UFF 15 with the three nodes."""
    uff = pyuff.UFF(str(path))
    if geometry:
        uff.write_sets(
            pyuff.prepare_15(
                node_nums=[11, 12, 13],
                x=[0.0, 0.5, 1.0],
                y=[0.0, 0.0, 0.0],
                z=[0.125, 0.125, 0.125],
            ),
            mode="add",
        )
    freq = np.arange(0.0, 101.0)
    for i in range(3):
        x = freq if axes is None else axes[i]
        data = (i + 1) * (np.cos(x / 7) + 1j * np.sin(x / 11))
        uff.write_sets(
            pyuff.prepare_58(
                func_type=4,
                rsp_node=12,
                rsp_dir=2,
                ref_node=11 + i,
                ref_dir=2,
                id1=f"pyuff FRF {i}",
                data=data,
                x=x,
                abscissa_spacing=1,
                abscissa_spec_data_type=18,
                abscissa_axis_units_lab="Hz",
                ordinate_spec_data_type=forms[i],
                ordinate_axis_units_lab=unit,
                orddenom_spec_data_type=13,
                orddenom_axis_units_lab="N",
            ),
            mode="add",
        )


def test_a_file_pyuff_wrote_with_3_frfs_and_geometry(tmp_path):
    path = tmp_path / "pyuff.uff"
    write_pyuff_test(path)
    ex = read_multipoint_uff(path)
    assert [(n.number, n.name, n.x, n.y, n.z) for n in ex.nodes] == [
        (11, "11", 0.0, 0.0, 0.125),
        (12, "12", 0.5, 0.0, 0.125),
        (13, "13", 1.0, 0.0, 0.125),
    ]
    assert ex.references == (Dof(11, "+Y"), Dof(12, "+Y"), Dof(13, "+Y"))
    assert ex.responses == (Dof(12, "+Y"),) * 3
    assert ex.form == "accelerance"
    assert ex.lines == ()
    assert ex.coherence is None
    assert ex.modes is None
    np.testing.assert_array_equal(ex.frequency_hz, np.arange(0.0, 101.0))
    # ASCII 58 prints complex values with 6 significant digits; g -> m/s^2 as the UFF 58 reader does.
    for i in range(3):
        want = 9.80665 * (i + 1) * (np.cos(ex.frequency_hz / 7) + 1j * np.sin(ex.frequency_hz / 11))
        np.testing.assert_allclose(ex.frf[i], want, rtol=1e-5, atol=1e-5 * 9.80665 * (i + 1))


def test_without_dataset_15_the_nodes_come_without_coordinates(tmp_path):
    path = tmp_path / "pyuff.uff"
    write_pyuff_test(path, geometry=False)
    ex = read_multipoint_uff(path)
    assert [n.number for n in ex.nodes] == [11, 12, 13]
    assert not any(n.has_position for n in ex.nodes)
    assert "no dataset 15" in " ".join(ex.notes)


# ---------------------------------------------------------------------------------------------
# The real roving-hammer set (not in the repository)


def test_real_roving_hammer_set():
    root = os.environ.get("DAQ_CORPUS")
    path = Path(root or ".") / "modelab-beam" / "modelab_beam.uff"
    if not root or not path.is_file():
        pytest.skip(f"{NO_CORPUS}: modelab-beam/modelab_beam.uff (set DAQ_CORPUS)")
    ex = read_multipoint_uff(path)
    assert ex.n_frf == 9
    assert ex.frf.shape == (9, 51_201)
    assert [n.number for n in ex.nodes] == list(range(1, 10))
    assert ex.references == tuple(Dof(i, "+X") for i in range(1, 10))
    assert ex.responses == (Dof(4, "-X"),) * 9
    assert ex.form == "accelerance"
    assert ex.frequency_hz[0] == 0.0
    assert ex.frequency_hz[-1] == pytest.approx(1000.0)
    np.testing.assert_allclose(np.diff(ex.frequency_hz), 1000 / 51200)
    raw = read_sets(path)
    for i in range(9):  # m/s^2 over N: the values as stored, bit for bit
        np.testing.assert_array_equal(ex.frf[i], raw[i]["data"])


# ---------------------------------------------------------------------------------------------
# What is no test: one line


def test_truncated_file(tmp_path):
    good = tmp_path / "good.uff"
    write_multipoint_uff(good, beam_test(n_points=3, n_lines=16))
    data = good.read_bytes()
    for k, cut in enumerate((len(data) // 2, len(data) - 20)):
        path = tmp_path / f"cut{k}.uff"
        path.write_bytes(data[:cut])
        assert "truncated" in refused(path) or "not a readable UFF" in refused(path)


def test_frfs_on_different_frequency_axes(tmp_path):
    path = tmp_path / "axes.uff"
    f = np.arange(0.0, 101.0)
    write_pyuff_test(path, axes=(f, f, f + 0.5))
    assert "different frequency axis" in refused(path)


def test_frfs_of_mixed_forms(tmp_path):
    path = tmp_path / "forms.uff"
    write_pyuff_test(path, forms=(12, 12, 11), unit="NONE")
    assert "different forms" in refused(path)


def test_unknown_ordinate_type(tmp_path):
    path = tmp_path / "stress.uff"
    write_pyuff_test(path, forms=(2, 2, 2), unit="Pa")  # stress over force: no FRF of a test
    assert "ordinate data type 2" in refused(path)


def test_no_dataset_58(tmp_path):
    path = tmp_path / "nodes.uff"
    pyuff.UFF(str(path)).write_sets(pyuff.prepare_15(node_nums=[1], x=[0.0], y=[0.0], z=[0.0]), mode="add")
    assert "no dataset 58" in refused(path)


def test_58_without_frfs(tmp_path):
    path = tmp_path / "time.uff"
    dset = pyuff.prepare_58(
        func_type=1,
        rsp_node=1,
        rsp_dir=3,
        ref_node=1,
        ref_dir=3,
        data=np.ones(8),
        x=np.arange(8.0),
        abscissa_spacing=1,
        ordinate_spec_data_type=12,
        orddenom_spec_data_type=0,
        abscissa_spec_data_type=17,
    )
    pyuff.UFF(str(path)).write_sets(dset, mode="add")
    assert "no FRFs" in refused(path)


def test_not_uff_and_missing(tmp_path):
    text = tmp_path / "table.csv"
    text.write_text("f,re,im\n1,2,3\n")
    assert "does not look like a UFF" in refused(text)
    assert refused(tmp_path / "absent.uff")


@pytest.mark.parametrize(
    ("change", "expected"),
    [
        (lambda ex: setattr(ex, "responses", (Dof(3, "-Z"),) * 4 + (Dof(9, "-Z"),)), "not a node"),
        (lambda ex: setattr(ex, "references", (Dof(1, "+Z"),) * 5), "one FRF per DOF pair"),
        (lambda ex: setattr(ex, "references", (Dof(1, "up"),) * 5), "no UFF direction"),
        (lambda ex: setattr(ex, "nodes", (Node(1, "two words"), *ex.nodes[1:])), "one word"),
        (lambda ex: setattr(ex, "nodes", (*ex.nodes, Node(1, "again"))), "listed twice"),
        (lambda ex: setattr(ex, "lines", ((1, 1),)), "loop"),
        (lambda ex: setattr(ex, "frf", ex.frf[:, :-1]), "frequency lines"),
        (lambda ex: setattr(ex, "form", "inertance"), "FRF form"),
        (lambda ex: setattr(ex.modes, "damping_ratio", np.array([0.1, 1.5, 0.1])), "damping ratio"),
    ],
    ids=[
        "unknown-node",
        "same-dofs-twice",
        "bad-direction",
        "bad-name",
        "node-twice",
        "loop",
        "shape",
        "form",
        "damping",
    ],
)
def test_writer_refuses_what_is_no_test(tmp_path, change, expected):
    ex = beam_test()
    change(ex)
    path = tmp_path / "bad.uff"
    with pytest.raises(FormatError, match=expected) as info:
        write_multipoint_uff(path, ex)
    assert "\n" not in str(info.value)
    assert not path.exists()
    assert list(tmp_path.iterdir()) == []


# ---------------------------------------------------------------------------------------------
# Property: any set of distinct DOF pairs maps to UFF node numbers and directions and back

WORK = Path(tempfile.mkdtemp(prefix="uff-multipoint-hypothesis-"))
node_numbers = st.integers(min_value=1, max_value=999_999_999)
directions = st.sampled_from(sorted(DIRECTION_CODES))
dof_pairs = st.lists(
    st.tuples(node_numbers, directions, node_numbers, directions),
    min_size=1,
    max_size=6,
    unique_by=lambda p: (p[0], p[1], p[2], p[3]),
)


@given(pairs=dof_pairs, driving=st.booleans())
@settings(max_examples=50, deadline=None, suppress_health_check=[HealthCheck.too_slow])
def test_node_and_direction_mapping_round_trips(pairs, driving):
    if driving:  # a driving point: the same node (and direction) for reference and response
        pairs = list(dict.fromkeys([(pairs[0][0], pairs[0][1], pairs[0][0], pairs[0][1]), *pairs]))
    numbers = sorted({p[0] for p in pairs} | {p[2] for p in pairs})
    nodes = tuple(Node(n, f"n{n}", float(k), -0.5 * k, math.pi) for k, n in enumerate(numbers))
    n = len(pairs)
    ex = MultiPointExchange(
        nodes=nodes,
        lines=(),
        frequency_hz=[1.0, 2.0, 3.0],
        frf=np.arange(3 * n).reshape(n, 3) * (1 - 2j),
        references=tuple(Dof(p[0], p[1]) for p in pairs),
        responses=tuple(Dof(p[2], p[3]) for p in pairs),
    )
    path = WORK / "dofs.uff"
    write_multipoint_uff(path, ex)
    raw = [d for d in read_sets(path) if d["type"] == 58]
    assert [(d["ref_node"], d["ref_dir"], d["rsp_node"], d["rsp_dir"]) for d in raw] == [
        (p[0], DIRECTION_CODES[p[1]], p[2], DIRECTION_CODES[p[3]]) for p in pairs
    ]
    back = read_multipoint_uff(path)
    assert back.references == ex.references
    assert back.responses == ex.responses
    assert [(n.number, n.name) for n in back.nodes] == [(n.number, n.name) for n in nodes]
    assert_same(back, ex)


def write_pyuff_modes(path: Path, r1: np.ndarray, r2: np.ndarray) -> None:
    """Two normal modes (analysis type 2, real shapes) of nodes 11-13, written by pyuff."""
    for k, (f, zeta) in enumerate(((21.5, 0.02), (63.0, 0.005))):
        dset = pyuff.prepare_55(
            model_type=1,
            analysis_type=2,
            data_ch=2,
            spec_data_type=8,
            data_type=2,
            n_data_per_node=3,
            node_nums=[11, 12, 13],
            r1=r1 * (k + 1),
            r2=r2 * (k + 1),
            r3=np.zeros(3),
            load_case=1,
            mode_n=k + 1,
            freq=f,
            modal_m=0,
            modal_damp_vis=zeta,
            modal_damp_his=0.0,
        )
        pyuff.UFF(str(path)).write_sets(dset, mode="add")


def test_normal_modes_pyuff_wrote(tmp_path):
    path = tmp_path / "modes.uff"
    write_pyuff_test(path)
    write_pyuff_modes(path, np.zeros(3), np.array([0.25, -1.0, 0.5]))
    modes = read_multipoint_uff(path).modes
    np.testing.assert_array_equal(modes.frequency_hz, [21.5, 63.0])
    np.testing.assert_array_equal(modes.damping_ratio, [0.02, 0.005])
    assert modes.axes == ("Y", "Y", "Y")
    np.testing.assert_array_equal(modes.shapes, [[0.25, -1.0, 0.5], [0.5, -2.0, 1.0]])


def test_shapes_along_two_axes_at_one_node(tmp_path):
    path = tmp_path / "modes.uff"
    write_pyuff_test(path)
    write_pyuff_modes(path, np.array([0.0, 0.1, 0.0]), np.array([0.25, -1.0, 0.5]))
    assert "node 12 along X and Y" in refused(path)


def test_frfs_without_a_unit_label_keep_their_values_and_say_so(tmp_path):
    path = tmp_path / "nounits.uff"
    write_pyuff_test(path, unit="NONE")
    ex = read_multipoint_uff(path)
    assert ex.form == "accelerance"  # ordinate type 12 decides, as for one run
    assert ex.notes == ("FRF units: unknown label 'NONE'/'N', values kept",)
    np.testing.assert_allclose(
        ex.frf[0, :3], np.cos(np.arange(3) / 7) + 1j * np.sin(np.arange(3) / 11), rtol=1e-5
    )
