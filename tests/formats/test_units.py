"""Unit conversion: factors checked against hand-computed values, errors are one line."""

import numpy as np
import pytest

from daq.formats.errors import FormatError
from daq.formats.units import frf_unit, parse_unit, to_si


@pytest.mark.parametrize(
    ("unit", "quantity", "factor"),
    [
        ("N", "force", 1.0),
        ("kN", "force", 1000.0),
        # 1 lbf = 0.45359237 kg * 9.80665 m/s^2 (both exact by definition)
        ("lbf", "force", 4.4482216152605),
        ("m/s^2", "response", 1.0),
        ("m/s2", "response", 1.0),
        ("mm/s^2", "response", 0.001),
        ("g", "response", 9.80665),
        (" g ", "response", 9.80665),
        # 10.2 mV per g: 1 mV is 1/10.2 g = 0.9614362745... m/s^2
        ("mV@10.2mV/g", "response", 9.80665 / 10.2),
        # the column in V, the sensor 2.25 mV per N: 1 V is 444.44... N
        ("V@2.25mV/N", "force", 1000 / 2.25),
        ("V@0.1V/lbf", "force", 10 * 4.4482216152605),
        ("mV @ 100 mV/m/s^2", "response", 0.01),
        ("mV@1e1mV/N", "force", 0.1),
    ],
)
def test_factor(unit, quantity, factor):
    assert parse_unit(unit, quantity) == pytest.approx(factor, rel=1e-14)


def test_to_si_values():
    assert to_si(np.array([1.0, -2.0]), "g", "response").tolist() == pytest.approx([9.80665, -19.6133])
    # 10.2 mV from a 10.2 mV/g accelerometer is exactly one g
    assert to_si(np.array([10.2]), "mV@10.2mV/g", "response")[0] == pytest.approx(9.80665, rel=1e-14)
    assert to_si(np.array([2.25e-3]), "V@2.25mV/N", "force")[0] == pytest.approx(1.0, rel=1e-14)


def test_to_si_identity_keeps_bits_and_copies():
    values = np.array([-0.0, 1e-300, 0.1, 3 + 4j])
    out = to_si(values, "N", "force")
    assert out.tobytes() == values.tobytes()
    assert out is not values


@pytest.mark.parametrize(
    ("unit", "quantity"),
    [
        ("newton", "force"),
        ("g", "force"),
        ("N", "response"),
        ("", "force"),
        ("mV@10.2mV/N", "response"),
        ("uV@10mV/g", "response"),
        ("mV@mV/g", "response"),
        ("mV@10.2mV", "response"),
        ("mV@0mV/g", "response"),
        ("mV@-3mV/g", "response"),
        ("mV@nanmV/g", "response"),
        ("mV@infmV/g", "response"),
        ("mV@1e999mV/g", "response"),
        ("g\nm/s^2", "response"),
    ],
)
def test_bad_units_are_one_line_user_errors(unit, quantity):
    with pytest.raises(FormatError) as info:
        parse_unit(unit, quantity)
    assert "\n" not in str(info.value)
    assert quantity in str(info.value)


def test_unknown_unit_lists_accepted_forms():
    with pytest.raises(FormatError, match=r"N, kN, lbf.*mV@"):
        parse_unit("dyn", "force")


@pytest.mark.parametrize(
    ("unit", "quantity", "shown"), [("mV", "force", "mV@2.25mV/N"), (" V", "response", "V@10.2mV/g")]
)
def test_a_bare_voltage_asks_for_the_sensitivity_not_unknown(unit, quantity, shown):
    with pytest.raises(FormatError) as info:
        parse_unit(unit, quantity)
    assert "is a voltage" in str(info.value)
    assert shown in str(info.value)
    assert "unknown" not in str(info.value)


@pytest.mark.parametrize(
    ("unit", "quantity", "said"),
    [
        ("V@2.25mV/g", "force", "'g' is an acceleration unit"),
        ("mV@10.2mV/N", "response", "'N' is a force unit"),
        ("V@2mV/furlong", "force", "'furlong' is not one of them"),
    ],
)
def test_a_sensitivity_per_the_wrong_quantity_says_which_unit_it_must_be_per(unit, quantity, said):
    with pytest.raises(FormatError) as info:
        parse_unit(unit, quantity)
    message = str(info.value)
    assert f"the sensitivity must be per a {quantity} unit" in message
    assert said in message
    assert "unknown" not in message
    assert "\n" not in message


# Every reader takes the same units (daq/formats/units.py PHYSICAL_UNITS): the factors by
# definition (standard gravity 9.80665 m/s^2, the international inch and foot).
@pytest.mark.parametrize(
    ("unit", "quantity", "factor"),
    [("kgf", "force", 9.80665), ("mN", "force", 1e-3), ("mg", "response", 9.80665e-3),
     ("ft/s^2", "response", 0.3048), ("cm/s^2", "response", 1e-2)],
)  # fmt: skip
def test_a_csv_column_takes_the_units_the_uff_reader_takes(unit, quantity, factor):
    # Before, the CSV reader refused these while UFF records in them were converted.
    assert parse_unit(unit, quantity) == pytest.approx(factor, rel=1e-15)


@pytest.mark.parametrize(
    ("unit", "form", "factor"),
    [("(ft/s^2)/N", "accelerance", 0.3048), ("mg/N", "accelerance", 9.80665e-3),
     ("mil/lbf", "receptance", 2.54e-5 / (0.45359237 * 9.80665)), ("(cm/s)/kgf", "mobility", 1e-2 / 9.80665)],
)  # fmt: skip
def test_an_frf_text_unit_takes_the_units_the_uff_reader_takes(unit, form, factor):
    got_form, got_factor = frf_unit(unit)
    assert got_form == form
    assert got_factor == pytest.approx(factor, rel=1e-15)
