"""Anisotropic gloss of a design: Ward's slope spreads and the direction of principal anisotropy.

Ward's anisotropic Gaussian (thesis §2.5.3, eq 2.5.4) has two micro-facet slope spreads:

* ``alpha_x`` — spread along the direction of principal anisotropy X (the narrower one), dimensionless
  slope (0.005–0.5);
* ``alpha_y`` — spread across it, along Y = N × X (α_y ≥ α_x, as the thesis assumes; up to 1);
* ``direction_deg`` — the direction of principal anisotropy: the world-space tangent hint
  (cos ψ, sin ψ, 0), ψ in degrees (0 = along +x, the length of the shapes and meshes; 90 = vertical),
  projected per point onto the surface's tangent plane.

α_x = α_y is isotropic. A design file carries these as the optional ``anisotropy`` object
(:mod:`station.model.design_io`); absent or ``null`` means the design's own isotropic gloss lobes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from station.model.domain import check_ranged
from station.model.errors import ModelInputError

#: Accepted ranges: field → (low, high); α_y is further bounded below by α_x.
ANISOTROPY_RANGES: dict[str, tuple[float, float]] = {
    "alpha_x": (0.005, 0.5),
    "alpha_y": (0.005, 1.0),
    "direction_deg": (-180.0, 180.0),
}


@dataclass(frozen=True)
class Anisotropy:
    """Ward slope spreads α_x ≤ α_y and direction ψ of principal anisotropy (module docstring)."""

    alpha_x: float
    alpha_y: float
    direction_deg: float = 0.0

    def __post_init__(self) -> None:
        for name, (lo, hi) in ANISOTROPY_RANGES.items():
            object.__setattr__(self, name, check_ranged(f"anisotropy.{name}", getattr(self, name), lo, hi))
        if self.alpha_y < self.alpha_x:
            raise ModelInputError(
                "anisotropy.alpha_y", f"alpha_x ({self.alpha_x}) <= alpha_y <= 1", self.alpha_y
            )

    @property
    def isotropic(self) -> bool:
        """True when α_x = α_y (eq 2.5.4 is then radially symmetric about N)."""
        return self.alpha_x == self.alpha_y

    @property
    def tangent(self) -> tuple[float, float, float]:
        """World-space tangent hint (cos ψ, sin ψ, 0)."""
        p = math.radians(self.direction_deg)
        return (math.cos(p), math.sin(p), 0.0)

    def to_dict(self) -> dict[str, float]:
        """The design-file object (``"anisotropy"`` key of ``cacad.design/1``)."""
        return {name: getattr(self, name) for name in ANISOTROPY_RANGES}

    @classmethod
    def from_dict(cls, data: Any) -> Anisotropy:
        """Parse the design-file object (``direction_deg`` defaults to 0); errors name the field."""
        if not isinstance(data, dict):
            raise ModelInputError(
                "anisotropy", "an object with " + ", ".join(ANISOTROPY_RANGES), type(data).__name__
            )
        unknown = set(data) - set(ANISOTROPY_RANGES)
        if unknown:
            raise ModelInputError("anisotropy", "keys " + ", ".join(ANISOTROPY_RANGES), sorted(unknown))
        for key in ("alpha_x", "alpha_y"):
            if key not in data:
                raise ModelInputError(f"anisotropy.{key}", "a slope spread (required)", None)
        return cls(**data)
