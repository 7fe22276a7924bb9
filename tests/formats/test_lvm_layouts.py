"""LabVIEW files as a third new user wrote and found them (public ladisk/lvm_read files and
their own): X_Columns Multi's per-channel rows, a file cut short, a Comma file's blank
lines, unused channels, spelled-out units, and rates at the edge of what Delta_X allows."""

from __future__ import annotations

import numpy as np
import pytest

from daq.formats.errors import FormatError
from daq.formats.lvm import read_lvm
from tests.formats.test_lvm import hammer_hit, lvm_text, write

G = 9.80665  # m/s^2 per g


def two_channels(units=("N", "g"), n=400, rate=1024.0):
    force, a1, _ = hammer_hit(n, rate, 87.5)
    return force, a1, [("F", units[0], force), ("a1", units[1], a1)]


def test_multi_files_take_each_channel_s_unit_from_its_own_cell(tmp_path):
    # "Y_Unit_Label<TAB>N<TAB><TAB>g<TAB>": the accelerometer's g was read from the empty
    # cell under the force's time column, and the response stored 9.8 times too small.
    force, a1, channels = two_channels()
    times = [f"{k / 1024:.6f}" for k in range(len(force))]
    data = read_lvm(write(tmp_path / "multi.lvm", lvm_text([channels], x_columns="Multi", times=times)))
    assert data.details["response_unit"] == "g"
    np.testing.assert_allclose(data.hits.response_m_s2[0], np.array(a1) * G, rtol=1e-15)


def test_a_last_row_cut_mid_value_keeps_its_note_and_a_short_segment_says_so(tmp_path):
    _, _, channels = two_channels(("N", "m/s^2"))
    text = lvm_text([channels]).rstrip("\n")
    cut = text[: text.rindex("\t") + 3]  # the last value cut to its first two characters
    data = read_lvm(write(tmp_path / "cut.lvm", cut))
    notes = data.details["notes"]
    assert any("the last, has no line end" in n for n in notes), notes
    declared = [n for n in notes if "where its header declares" in n]
    assert declared == [], notes  # all 400 rows are there, the last one cut


def test_a_last_row_cut_before_its_last_channel_is_left_out_with_a_note(tmp_path):
    _, _, channels = two_channels(("N", "m/s^2"))
    text = lvm_text([channels]).rstrip("\n")
    cut = text[: text.rindex("\t")]  # the last row lost its response value
    data = read_lvm(write(tmp_path / "cut.lvm", cut))
    assert data.hits.force_n.shape == (1, 399)
    notes = data.details["notes"]
    assert any("the last, is cut short" in n for n in notes), notes
    assert any("holds 399 samples where its header declares 400" in n for n in notes), notes


def test_a_last_segment_saved_while_written_is_left_out_with_a_note(tmp_path):
    segments = [two_channels(("N", "m/s^2"))[2] for _ in range(3)]
    short = [(name, unit, values[:250]) for name, unit, values in two_channels(("N", "m/s^2"))[2]]
    text = lvm_text([*segments, short])
    text = text.replace("Samples\t250\t250", "Samples\t400\t400")  # LabVIEW wrote the header first
    data = read_lvm(write(tmp_path / "partial.lvm", text))
    assert data.hits.force_n.shape == (3, 400)
    assert any("the last segment" in n and "left out" in n for n in data.details["notes"])


def test_a_comma_file_s_blank_lines_of_commas_are_blank(tmp_path):
    force, _, channels = two_channels(("N", "m/s^2"))
    text = lvm_text([channels], separator="Comma")
    text = text.replace("\n\n", "\n,\n")  # LabVIEW writes the separator on its blank lines
    assert "\n,\n" in text
    data = read_lvm(write(tmp_path / "comma.lvm", text))
    np.testing.assert_array_equal(data.hits.force_n[0], force)


def test_unused_channels_of_zero_samples_are_left_out(tmp_path):
    # ladisk/lvm_read's with_empty_fields.lvm: "Untitled" channels with Samples 0 and
    # Delta_X 1.000000 beside the measured ones, their cells empty.
    force, a1, channels = two_channels(("N", "m/s^2"), n=300)
    lines = lvm_text([channels]).splitlines()
    for k, line in enumerate(lines):
        key = line.split("\t")[0]
        cells = line.split("\t")
        if key == "Samples":
            lines[k] = "\t".join([key, cells[1], "0", cells[2], ""])
        elif key in ("Y_Unit_Label", "Delta_X", "Date", "Time", "X_Dimension", "X0") and len(cells) > 3:
            lines[k] = "\t".join([key, cells[1], "1.000000" if key == "Delta_X" else "", cells[2], ""])
        elif key == "Channels":
            lines[k] = "Channels\t3\t\t\t"
        elif key == "X_Value":
            lines[k] = "X_Value\tF\tUntitled\ta1\tComment"
        elif line.startswith("\t") and k > 20:
            _, f_cell, a_cell = cells
            lines[k] = "\t".join(["", f_cell, "", a_cell])
    data = read_lvm(write(tmp_path / "unused.lvm", "\n".join(lines) + "\n"))
    np.testing.assert_array_equal(data.hits.force_n[0], force)
    np.testing.assert_array_equal(data.hits.response_m_s2[0], a1)
    assert data.details["lvm"]["channels"] == ["F (N)", "a1 (m/s^2)"]


@pytest.mark.parametrize(("unit", "factor"), [("Newtons", 1.0), ("N", 1.0)])
def test_labview_s_newtons_is_a_force_unit(tmp_path, unit, factor):
    force, _, channels = two_channels((unit, "m/s^2"))
    data = read_lvm(write(tmp_path / "newtons.lvm", lvm_text([channels])))
    np.testing.assert_array_equal(data.hits.force_n[0], np.array(force) * factor)


def test_volts_asks_for_the_sensitivity_as_v_does(tmp_path):
    _, _, channels = two_channels(("Volts", "m/s^2"))
    with pytest.raises(FormatError) as excinfo:
        read_lvm(write(tmp_path / "volts.lvm", lvm_text([channels])))
    assert "is in Volts: give the sensor's sensitivity, e.g. --force-unit V@" in str(excinfo.value)


@pytest.mark.parametrize(
    ("delta_x", "rate"), [("0.000313", 3200.0), ("0.000625", 1600.0), ("0.000156", 6400.0)]
)
def test_a_rate_at_the_edge_of_what_delta_x_allows_is_taken(tmp_path, delta_x, rate):
    # 1 / 0.0003125 is 3200 Hz exactly: the edge of 0.000313's range, lost to rounding before.
    _, _, channels = two_channels(("N", "m/s^2"))
    assert (
        read_lvm(write(tmp_path / "edge.lvm", lvm_text([channels], delta_x=delta_x))).hits.sample_rate_hz
        == rate
    )


def test_channels_in_the_wrong_order_are_told_the_columns_by_channel(tmp_path):
    _, _, channels = two_channels(("N", "g"))
    path = write(tmp_path / "order.lvm", lvm_text([channels]))
    with pytest.raises(FormatError) as excinfo:
        read_lvm(path, columns="a1,F")
    message = str(excinfo.value)
    assert message.endswith("(force, response channels)"), message
    suggested = message.rsplit("--columns ", 1)[1].split()[0]
    assert read_lvm(path, columns=suggested).details["response_unit"] == "g"
    with pytest.raises(FormatError) as excinfo:
        read_lvm(path, columns="Force,a1")
    message = str(excinfo.value)
    assert "no channel 'Force' (the channels: F (N), a1 (g))" in message
    assert "hit" not in message


def test_a_later_segment_without_its_own_headings_row_takes_the_first_s_names(tmp_path):
    segments = [two_channels(("N", "m/s^2"))[2] for _ in range(2)]
    lines = lvm_text(segments).splitlines()
    second = [k for k, line in enumerate(lines) if line.startswith("X_Value")][1]
    del lines[second]
    data = read_lvm(write(tmp_path / "two.lvm", "\n".join(lines) + "\n"))
    assert data.hits.force_n.shape == (2, 400)
    assert data.details["lvm"]["channels"] == ["F (N)", "a1 (m/s^2)"]
