"""Properties of a uniform rectangular beam, with the seed paper's Table 1 as defaults.

The seed tabulates both the cross-section dimensions and A, I. The two do not
agree exactly (b*h = 10.461e-5 m^2, b*h^3/12 = 9.4934e-11 m^4): the tabulated
values drive the seed's own model, the derived ones reproduce its
"experimental" column best. Both are available here.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields, replace
from typing import Literal

SectionSource = Literal["tabulated", "derived"]


@dataclass(frozen=True)
class BeamProperties:
    """A uniform Euler-Bernoulli beam. All values SI.

    Defaults are the seed's Table 1 (aluminium, 0.7 m long).
    """

    density_kg_m3: float = 2710.0
    youngs_modulus_pa: float = 7.1e10
    width_m: float = 31.7e-3
    height_m: float = 3.3e-3
    length_m: float = 0.7
    area_m2: float = 10.46e-5
    second_moment_m4: float = 9.493e-11

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if not isinstance(value, (int, float)) or isinstance(value, bool):
                raise ValueError(f"beam property {f.name} must be a number, got {value!r}")
            try:
                value = float(value)
            except OverflowError:
                raise ValueError(f"beam property {f.name} is too large") from None
            if not math.isfinite(value) or value <= 0.0:
                raise ValueError(f"beam property {f.name} must be positive and finite, got {value!r}")
            object.__setattr__(self, f.name, value)
        # Products the models form must stay finite and non-zero too (1e200 m is a number).
        rho_a_l4 = self.density_kg_m3 * self.area_m2 * self.length_m**4
        derived = {
            "rho*A*L": self.density_kg_m3 * self.area_m2 * self.length_m,
            "E*I": self.youngs_modulus_pa * self.second_moment_m4,
            "b*h^3/12": self.width_m * self.height_m**3 / 12.0,
            "rho*A*L^4": rho_a_l4,
            "E*I/(rho*A*L^4)": self.youngs_modulus_pa * self.second_moment_m4 / rho_a_l4 if rho_a_l4 else 0.0,
        }
        for name, value in derived.items():
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"beam properties out of range: {name} is {value!r}")

    @property
    def mass_per_length_kg_m(self) -> float:
        """rho * A, in kg/m."""
        return self.density_kg_m3 * self.area_m2

    @property
    def mass_kg(self) -> float:
        """rho * A * L, in kg: the leading factor of the seed's eq (10)."""
        return self.mass_per_length_kg_m * self.length_m

    @property
    def flexural_rigidity_n_m2(self) -> float:
        """E * I, in N m^2."""
        return self.youngs_modulus_pa * self.second_moment_m4

    def with_section(self, source: SectionSource) -> BeamProperties:
        """Return this beam with A and I as tabulated, or derived from width and height.

        ``"derived"`` sets A = b*h and I = b*h^3/12.
        """
        if source == "tabulated":
            return self
        if source == "derived":
            return replace(
                self,
                area_m2=self.width_m * self.height_m,
                second_moment_m4=self.width_m * self.height_m**3 / 12.0,
            )
        raise ValueError(f"unknown section source {source!r}; use 'tabulated' or 'derived'")

    def to_dict(self) -> dict[str, float]:
        return asdict(self)

    @classmethod
    def from_dict(cls, values: dict[str, object]) -> BeamProperties:
        """Build from a mapping of field names to numbers; missing keys keep Table 1 values.

        A mapping that changes width or height but gives neither area nor second
        moment gets A = b*h and I = b*h^3/12 from them: keeping Table 1's A and I
        for another cross-section would silently model the wrong beam.
        """
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(values) - known)
        if unknown:
            raise ValueError(
                f"unknown beam propert{'y' if len(unknown) == 1 else 'ies'} {', '.join(unknown)}; "
                f"known: {', '.join(sorted(known))}"
            )
        beam = cls(**values)  # type: ignore[arg-type]
        changes_section = {"width_m", "height_m"} & set(values)
        gives_section = {"area_m2", "second_moment_m4"} & set(values)
        if changes_section and not gives_section:
            beam = beam.with_section("derived")
        return beam


#: The seed paper's Table 1.
TABLE_1 = BeamProperties()
