"""daq.batch.memory_tuning: glibc's malloc takes the settings that keep a fit's freed
temporaries in the process (docs/damping.md, Speed)."""

from __future__ import annotations

import platform
import subprocess
import sys

import pytest

from daq.batch.memory_tuning import keep_freed_memory


@pytest.mark.skipif(platform.libc_ver()[0] != "glibc", reason="mallopt is glibc's")
def test_glibc_accepts_the_settings():
    assert keep_freed_memory() is True


_FIT_LOOP = """
import resource, sys
from daq.batch.memory_tuning import keep_freed_memory
if sys.argv[1] == "tuned":
    keep_freed_memory()
import numpy as np
from analysis.damping import bandlimited
from analysis.damping.params import theta_to_matrix
from analysis.ritz import RitzBeam
rng = np.random.default_rng(0)
data = bandlimited.BandLimitedData(
    RitzBeam.build(n_functions=3).structure(),
    rng.standard_normal((5, 1024)),
    rng.standard_normal((5, 1024)),
    512.0,
)
population = theta_to_matrix(rng.uniform(-10, 10, (90, 6)), 3, False)
bandlimited.psi(data, population)
before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
for _ in range(10):
    bandlimited.psi(data, population)
print(resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before)
"""


@pytest.mark.skipif(platform.libc_ver()[0] != "glibc", reason="mallopt is glibc's")
def test_a_fits_freed_temporaries_are_not_faulted_in_again():
    # Ten generations of a DE population of 90 on a 5-hit run: without the settings
    # glibc hands the spectra back to the kernel at every free and they fault in
    # again (about 7,500 minor faults a generation here).
    faults = {
        mode: int(
            subprocess.run(
                [sys.executable, "-c", _FIT_LOOP, mode], capture_output=True, text=True, check=True
            ).stdout
        )
        for mode in ("plain", "tuned")
    }
    assert faults["plain"] > 10 * 1_000
    assert faults["tuned"] < 1_000
