"""A damaged ASCII UFF 58 is refused naming the dataset and the line that does not read
(hypothesis). pyuff says only "Error when reading data-set(s)", which a new user could not
act on in a file of hundreds of datasets."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from daq.formats.errors import FormatError
from daq.formats.uff58 import read_uff
from tests.formats.test_uff58 import frf_set, write_sets

WORK = Path(tempfile.mkdtemp(prefix="uff-garbled-"))


def three_frfs(path: Path) -> list[str]:
    """Three FRFs of 64 lines; the file's lines."""
    f = np.arange(64.0)
    sets = [frf_set((k + 1) / (100.0 - f + 1j * (k + 1)), f, id1=f"FRF {k}") for k in range(3)]
    for dset in sets[1:]:
        dset.update(rsp_ent_name="Acc pt", ref_ent_name="Hammer")  # text in record 6
    path.unlink(missing_ok=True)
    write_sets(path, sets)
    return path.read_text(encoding="latin-1").splitlines()


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    dataset=st.integers(0, 2),
    row=st.integers(0, 20),
    garble=st.sampled_from(["1.2.3", "abc", "8OO", "#"]),
)
def test_a_garbled_value_is_named_by_dataset_and_line(dataset, row, garble):
    path = WORK / "frfs.uff"
    lines = three_frfs(path)
    starts = [i for i, line in enumerate(lines) if line.strip() == "58"]
    target = starts[dataset] + 12 + row  # "58", 11 header records, then the values
    cells = lines[target].split()
    cells[0] = garble
    lines[target] = "  ".join(cells)
    path.write_text("\n".join(lines) + "\n", encoding="latin-1")
    with pytest.raises(FormatError) as info:
        read_uff(path)
    message = str(info.value)
    assert f"at dataset #{dataset + 1}: line {target + 1} holds {garble!r}, which is no number" in message
    assert "\n" not in message
