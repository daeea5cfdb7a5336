"""Metallic flakes: the physical parameters of a paint's flake layer and the statistics the renderer uses.

A flake layer is a population of small mirror platelets in the basecoat (aluminium flakes, mica pearls):

* ``size_um`` — mean flake diameter, µm (aluminium 10–60 µm, pearls 5–25 µm);
* ``density_per_mm2`` — flakes per mm² of surface seen from above;
* ``spread_deg`` — standard deviation of the flake normals about the surface normal, per tangent axis,
  degrees (well-oriented silver 3–6°, coarse or poorly oriented 10–20°);
* ``reflectance`` — share of the paint's reflection that the flakes carry (0–1).

The measured paint colour already contains the flakes' average reflection, so flakes are rendered as a
zero-mean modulation of it (:func:`sparkle_amplitude`): within an area of A mm² there are N = density · A
flakes; the area's flake reflection is the mean of N mirrors with random normals, whose deviation from
the expected (prefiltered) reflection shrinks as 1/√N. Averaged over an area, the colour is unchanged.
A mirror with normal tilted by δ reflects the view by 2δ, so the reflected directions spread by
2·spread_deg, the width of a Phong lobe of exponent E ≈ 1/(2σ)² (σ in radians; cos^E ψ ≈ exp(−Eψ²/2)).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from station.model.domain import check_ranged
from station.model.errors import ModelInputError

#: Accepted ranges: field → (low, high).
FLAKE_RANGES: dict[str, tuple[float, float]] = {
    "size_um": (1.0, 500.0),
    "density_per_mm2": (1.0, 1.0e5),
    "spread_deg": (0.5, 45.0),
    "reflectance": (0.0, 1.0),
}


@dataclass(frozen=True)
class FlakeLayer:
    """Physical parameters of a flake layer (module docstring); validated, immutable."""

    size_um: float = 25.0
    density_per_mm2: float = 400.0
    spread_deg: float = 8.0
    reflectance: float = 0.5

    def __post_init__(self) -> None:
        for name, (lo, hi) in FLAKE_RANGES.items():
            object.__setattr__(self, name, check_ranged(f"flakes.{name}", getattr(self, name), lo, hi))

    @property
    def reflected_exponent(self) -> float:
        """Phong exponent E ≈ 1/(2σ)² of the spread of reflected directions (module docstring)."""
        return 1.0 / (2.0 * math.radians(self.spread_deg)) ** 2

    def flakes_in(self, area_mm2: float) -> float:
        """Expected number of flakes in *area_mm2* of surface."""
        return self.density_per_mm2 * area_mm2

    def to_dict(self) -> dict[str, float]:
        """The design-file object (``"flakes"`` key of ``cacad.design/1``)."""
        return {name: getattr(self, name) for name in FLAKE_RANGES}

    @classmethod
    def from_dict(cls, data: Any) -> FlakeLayer:
        """Parse the design-file object; missing keys take the defaults; ModelInputError names the field."""
        if not isinstance(data, dict):
            raise ModelInputError("flakes", "an object with " + ", ".join(FLAKE_RANGES), type(data).__name__)
        unknown = set(data) - set(FLAKE_RANGES)
        if unknown:
            raise ModelInputError("flakes", "keys " + ", ".join(FLAKE_RANGES), sorted(unknown))
        return cls(**data)


#: Defaults per paint type: metallic (aluminium) and pearl (mica) flakes; solids have none.
METALLIC_FLAKES = FlakeLayer(25.0, 400.0, 8.0, 0.5)
PEARL_FLAKES = FlakeLayer(12.0, 1500.0, 12.0, 0.3)


#: A paint with travel is a pearl (mica flakes, PEARL_FLAKES) when its face and flop hues differ by at
#: least PEARL_HUE_SHIFT_DEG with both chromas C*ab ≥ PEARL_MIN_CHROMA (an interference colour shift);
#: otherwise a metallic (aluminium flakes keep the hue from face to flop).
PEARL_HUE_SHIFT_DEG = 15.0
PEARL_MIN_CHROMA = 5.0


def is_pearl(face: tuple[float, float, float], flop: tuple[float, float, float]) -> bool:
    """Whether a paint with these face and flop Lab shifts hue like a pearl (constants above)."""
    (_, a1, b1), (_, a2, b2) = face, flop
    if min(math.hypot(a1, b1), math.hypot(a2, b2)) < PEARL_MIN_CHROMA:
        return False
    dh = abs(math.degrees(math.atan2(b1, a1) - math.atan2(b2, a2))) % 360.0
    return min(dh, 360.0 - dh) >= PEARL_HUE_SHIFT_DEG


def sparkle_amplitude(flakes: FlakeLayer, area_mm2: float) -> float:
    """Relative amplitude 1/√N of the flake-reflection fluctuation over *area_mm2* (N ≥ 1 flakes)."""
    return 1.0 / math.sqrt(max(1.0, flakes.flakes_in(area_mm2)))
