"""LabVIEW files whose channel names say they hold a spectrum (hypothesis): LabVIEW's FFT
VIs log one with X_Dimension still 'Time' (a public cantilever file's 'Acceleration (FFT
- (RMS))'). Refused as a spectrum in one line, whatever surrounds the word; channel names
of time records, however worded, are read."""

from __future__ import annotations

import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from daq.formats.errors import FormatError
from daq.formats.lvm import read_lvm
from tests.formats.test_lvm import hammer_hit, lvm_text, write

SETTINGS = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
WORK = Path(tempfile.mkdtemp(prefix="lvm-spectrum-"))
SPECTRUM_WORDS = ["FFT", "fft", "Spectrum", "Power Spectrum", "PSD", "Auto Spectrum", "Frequency Response"]
TIME_WORDS = ["Accel", "Acceleration", "a1", "Response", "Resp 2", "Accelerometer tip", "m_1"]
AFFIXES = (
    st.sampled_from(["", "Ch1 ", "Acceleration ", "Dev1/ai0 "]),
    st.sampled_from(["", " 1", " - RMS", " (avg)"]),
)


@SETTINGS
@given(word=st.sampled_from(SPECTRUM_WORDS), before=AFFIXES[0], after=AFFIXES[1], with_force=st.booleans())
def test_a_spectrum_channel_is_refused_as_one(word, before, after, with_force):
    force, a1, _ = hammer_hit(256, 1024.0, 87.5)
    name = f"{before}{word}{after}"
    channels = ([("F", "N", force)] if with_force else []) + [(name, "g", a1)]
    path = write(WORK / "spectrum.lvm", lvm_text([channels]))
    with pytest.raises(FormatError) as refused:
        read_lvm(path)
    message = str(refused.value)
    assert "\n" not in message
    assert "holds a spectrum (" in message
    assert "not time records" in message


@SETTINGS
@given(word=st.sampled_from(TIME_WORDS), after=AFFIXES[1])
def test_time_record_names_are_read(word, after):
    force, a1, _ = hammer_hit(256, 1024.0, 87.5)
    name = f"{word}{after}"
    data = read_lvm(write(WORK / "time.lvm", lvm_text([[("Force", "N", force), (name, "m/s^2", a1)]])))
    assert data.hits.n_samples == 256
