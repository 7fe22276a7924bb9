"""daq/report/numbers.py: numbers and ranges as the report and the command line write
them (a new user read "1e+02 %" for 100 % and "5.12e+04 Hz" for a 51.2 kHz sample rate)."""

from __future__ import annotations

import math

import pytest

from daq.report.numbers import plain, span, with_uncertainty


@pytest.mark.parametrize(
    ("value", "spec", "text"),
    [
        (99.6, ".2g", "100"),  # g gives 1e+02
        (100.0, ".2g", "100"),
        (123.0, ".2g", "120"),  # g gives 1.2e+02
        (51200.0, ".4g", "51200"),  # g gives 5.12e+04
        (-512000.0, "+.3g", "-512000"),  # flags kept
        (1436.99999, ".6g", "1437"),
        (0.0049, ".2g", "0.0049"),  # g's own form below 1
        (1.2e-05, ".2g", "1.2e-05"),  # tiny: the exponent says it best
        (1e20, ".3g", "1e+20"),  # huge: likewise
        (12.5, ".3f", "12.500"),  # not a g format: as given
        (math.inf, ".2g", "inf"),
    ],
)
def test_plain_writes_out_what_g_would_put_in_exponent_form(value, spec, text):
    assert plain(value, spec) == text


def test_plain_of_nan_is_nan():
    assert plain(math.nan, ".2g") == "nan"


@pytest.mark.parametrize(
    ("low", "high", "spec", "text"),
    [
        (1.0, 5000.0, ".6g", "1-5000 Hz"),
        (0.9999999986, 1436.9999980, ".6g", "1-1437 Hz"),
        (1.0, 51200.0, ".4g", "1-51200 Hz"),
        (1.953125e-05, 0.999981, ".6g", "1.95313e-05 to 0.999981 Hz"),  # not ...e-05-0.99...
        (0.5, 2e-05, ".6g", "0.5 to 2e-05 Hz"),
    ],
)
def test_span_joins_with_to_when_an_end_keeps_its_exponent(low, high, spec, text):
    assert span(low, high, spec) == text


@pytest.mark.parametrize(
    ("value", "u", "written"),
    [
        (1073.2692, 2.5, ("1073.3", "2.5")),  # a new user's trial: '1073.2692 Hz ± 2.5 Hz'
        (19.768523, 0.0017, ("19.7685", "0.0017")),
        (2608.906, 1.0, ("2608.9", "1.0")),
        (30.0, 123.0, ("30", "120")),
        (1967.14, 18.0, ("1967", "18")),
        (0.20612, 0.0123, ("0.206", "0.012")),
        (5.0, None, ("5.0000", "–")),
        (5.0, float("nan"), ("5.0000", "–")),
        (5.0, 0.0, ("5.0000", "–")),
    ],
)
def test_a_value_is_written_to_the_place_of_its_uncertainty(value, u, written):
    assert with_uncertainty(value, u) == written
