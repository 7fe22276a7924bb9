import math

import pytest

from analysis.beam import TABLE_1, BeamProperties


def test_table_1_defaults_are_the_seed_values():
    assert TABLE_1.density_kg_m3 == 2710.0
    assert TABLE_1.youngs_modulus_pa == 7.1e10
    assert TABLE_1.width_m == 31.7e-3
    assert TABLE_1.height_m == 3.3e-3
    assert TABLE_1.length_m == 0.7
    assert TABLE_1.area_m2 == 10.46e-5
    assert TABLE_1.second_moment_m4 == 9.493e-11


def test_derived_section_uses_width_and_height():
    derived = TABLE_1.with_section("derived")
    assert derived.area_m2 == pytest.approx(31.7e-3 * 3.3e-3, rel=1e-15)
    assert derived.second_moment_m4 == pytest.approx(31.7e-3 * 3.3e-3**3 / 12, rel=1e-15)
    # Tabulated and derived differ in the 4th-5th digit, which is why both exist.
    assert derived.area_m2 != TABLE_1.area_m2
    assert TABLE_1.with_section("tabulated") is TABLE_1


def test_mass_and_rigidity():
    assert TABLE_1.mass_kg == pytest.approx(2710 * 10.46e-5 * 0.7, rel=1e-15)
    assert TABLE_1.flexural_rigidity_n_m2 == pytest.approx(7.1e10 * 9.493e-11, rel=1e-15)


@pytest.mark.parametrize("bad", [0.0, -1.0, math.inf, math.nan])
def test_rejects_non_positive_or_non_finite(bad):
    with pytest.raises(ValueError, match="length_m"):
        BeamProperties(length_m=bad)


def test_from_dict_keeps_defaults_and_rejects_unknown_keys():
    beam = BeamProperties.from_dict({"length_m": 0.5})
    assert beam.length_m == 0.5
    assert beam.density_kg_m3 == 2710.0
    with pytest.raises(ValueError, match="unknown beam property lenght_m"):
        BeamProperties.from_dict({"lenght_m": 0.5})


def test_unknown_section_source():
    with pytest.raises(ValueError, match="unknown section source"):
        TABLE_1.with_section("measured")  # type: ignore[arg-type]
