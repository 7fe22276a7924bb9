"""The line `daq analyze` prints per mode (daq/cli/commands/analyze.py)."""

from __future__ import annotations

from daq.cli.commands.analyze import _mode_text

MODE = {"frequency_hz": 2608.906, "damping_ratio": 0.0226, "frequency_u_hz": 1.0, "damping_u": 0.0027}
QUALITY = {"n_stable_orders": 16, "synthesis_share": 0.16, "accepted": True}


def test_a_mode_read_with_the_second_normalisation_says_so():
    first = _mode_text({**MODE, "quality": {**QUALITY, "normalisation": "highest"}})
    assert (
        first == "2608.9 Hz ± 1.0 Hz, damping 2.26 % ± 0.27 %; stable over 16 orders, 16 % of the synthesis"
    )
    second = _mode_text({**MODE, "quality": {**QUALITY, "normalisation": "lowest"}})
    assert "stable over 16 orders with alpha_0 = 1, 16 %" in second
    # An analysis stored before the second normalisation has no such key: the first.
    assert _mode_text({**MODE, "quality": QUALITY}) == first


def test_a_mode_added_among_close_ones_says_how_it_was_found():
    """A mode with no chain (analysis/modal_id/refine.py, missing) is not 'stable over 0 orders'."""
    added = _mode_text(
        {**MODE, "quality": {**QUALITY, "n_stable_orders": 0, "added": True, "normalisation": None}}
    )
    assert added == (
        "2608.9 Hz ± 1.0 Hz, damping 2.26 % ± 0.27 %; found by refitting the close modes beside it "
        "(LSCF missed it), 16 % of the synthesis"
    )
