"""A peak of the FRF too shallow for the second pass (6-10 dB above the dips beside it)
that no mode accounts for is named (ModalResult.weak_peaks_hz, a caution in
run_analysis): a public spruce plate's 409 Hz, 7 dB above the dip after its 404 Hz mode,
was left out unsaid and 404 Hz read 0.92 % for 0.58 % by half power; its 1418 Hz (the
source lists 1414.5 Hz) too. The second pass is not made for such peaks: the zones it
moves cost pyfrf-impact its 5074 Hz mode at 6 dB."""

from __future__ import annotations

import numpy as np
from scipy.signal import find_peaks

from analysis.modal_id import identify_modes
from analysis.modal_id.identify import WEAK_PEAK_PROMINENCE_DB, unexplained_peaks
from analysis.modal_id.zones import PEAK_PROMINENCE_DB, mode_indicator


def _pair(noise: float = 1e-3, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Accelerance of 404 Hz and a smaller 409 Hz, both at 0.3 %, on 0.5 Hz lines: the
    second peak stands 7 dB above the dip between them, as the plate's did."""
    f = np.arange(200, 1200) * 0.5
    w = 2 * np.pi * f
    h = sum(a * -(w**2) / ((2 * np.pi * r) ** 2 - w**2 + 2j * z * 2 * np.pi * r * w)
            for a, r, z in ((1.0, 404.0, 0.003), (0.6, 409.0, 0.003)))  # fmt: skip
    rng = np.random.default_rng(seed)
    scale = noise * np.sqrt(np.mean(np.abs(h) ** 2))
    return f, h + scale * (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size))


def test_the_case_is_a_shallow_peak():
    f, h = _pair()
    db = 10 * np.log10(mode_indicator(h[None]))
    peaks, props = find_peaks(db, prominence=1.0)
    (second,) = [p for i, p in zip(peaks, props["prominences"], strict=True) if abs(f[i] - 409) < 1]
    assert WEAK_PEAK_PROMINENCE_DB <= second < PEAK_PROMINENCE_DB


def test_a_shallow_peak_no_mode_accounts_for_is_named_and_a_clear_one_only_with_its_pass():
    f, h = _pair()
    line = float(f[1] - f[0])
    one = identify_modes(f, h, frequencies_hz=np.array([404.0]))
    assert [round(m.frequency_hz) for m in one.modes] == [404]
    assert unexplained_peaks(f, h[None], one, line) == []
    (named,) = unexplained_peaks(f, h[None], one, line, prominence_db=WEAK_PEAK_PROMINENCE_DB)
    assert abs(named - 409.0) <= 2 * line


def test_a_named_shallow_peak_is_a_caution_with_the_band_to_look_with():
    from analysis.run_analysis import _cautions, analyze_frfs

    f, h = _pair()
    result = analyze_frfs(f, h[None], None, "measured_frf")
    assert not [c for c in result.cautions if c.startswith("a peak of the FRF")]
    result.modal.weak_peaks_hz = [409.0]
    (said,) = [c for c in _cautions(result) if c.startswith("a peak of the FRF")]
    assert said.startswith("a peak of the FRF at 409 Hz (6 dB or more above the dips beside it, 25 dB above")
    assert said.endswith("look with --band 368.1:449.9")
