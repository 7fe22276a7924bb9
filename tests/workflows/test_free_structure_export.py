"""A test on a free structure (the default of `daq import FILE.uff --as-test`) is exported
with its nodes' coordinates: before, every such export failed with "node 1 has some
coordinates but not all three" (x unknown, y and z written as 0)."""

from __future__ import annotations

import numpy as np

from daq.formats.uff_multipoint import (
    Dof,
    MultiPointExchange,
    Node,
    read_multipoint_uff,
    write_multipoint_uff,
)
from tests.cli_helpers import invoke_daq

#: Three nodes of a free structure, m, off every axis.
NODES = (Node(11, "a", 0.0, 0.1, 0.25), Node(12, "b", 0.5, -0.2, 0.25), Node(13, "c", 1.0, 0.3, -0.5))


def two_mode_test() -> MultiPointExchange:
    """Roving hammer +Z at the three nodes, accelerometer +Z at node 11 (the driving point):
    modes at 40 and 110 Hz, 1 % damping, as accelerance on 0.25 Hz lines."""
    f = np.arange(1.0, 200.0, 0.25)
    s = 2j * np.pi * f
    shapes = np.array([[1.0, 0.6, -0.4], [1.0, -0.8, 0.5]])
    h = np.zeros((3, f.size), complex)
    for fn, shape in zip((40.0, 110.0), shapes, strict=True):
        wn = 2 * np.pi * fn
        h += s**2 * np.outer(shape * shape[0], 1.0 / (wn**2 + s**2 + 2 * 0.01 * wn * s))
    return MultiPointExchange(
        nodes=NODES, lines=((11, 12), (12, 13)), frequency_hz=f, frf=h,
        references=tuple(Dof(n.number, "+Z") for n in NODES), responses=(Dof(11, "+Z"),) * 3,
        form="accelerance",
    )  # fmt: skip


def test_a_free_structures_test_is_exported_with_its_nodes_coordinates(tmp_path):
    source, out, store = tmp_path / "in.uff", tmp_path / "out.uff", tmp_path / "runs"
    write_multipoint_uff(source, two_mode_test())
    imported = invoke_daq("import", str(source), "--as-test", "free3", "--store", str(store))
    assert imported.returncode == 0, imported.stderr
    exported = invoke_daq("test", "export", "free3", "-o", str(out), "--store", str(store))
    assert exported.returncode == 0, exported.stderr
    back = read_multipoint_uff(out)
    assert [(n.name, n.x, n.y, n.z) for n in back.nodes] == [(n.name, n.x, n.y, n.z) for n in NODES]
    np.testing.assert_allclose(back.modes.frequency_hz, [40.0, 110.0], rtol=1e-3)
