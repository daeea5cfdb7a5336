"""Seam geometry: light and view directions, the hinge of the misaligned panel, aspecular angles.

Frame (thesis §4.3.1): panel A lies in the x–y plane with its normal ``N_A = +z``. Light and view are
given as signed polar angles in the x–z plane (the plane of incidence), in degrees from the normal,
positive on the +x side; a light at ``+45`` and a view at ``-30`` is the 15° aspecular geometry of a
multi-angle instrument (aspecular angle = view + light for in-plane directions, thesis §3.3.3).

Panel B is panel A rotated by β about a *hinge* (the seam line) lying in the panel plane. Rotating
the panel by β is the same as rotating the light and view by −β (thesis §4.3.1, "Ω_β, Ψ_β"):

* ``"in-plane"``: the hinge is the y axis, perpendicular to the plane of incidence; light and view
  stay in one plane and the aspecular angle changes by 2β;
* ``"out-of-plane"``: the hinge is the x axis, inside the plane of incidence; the rotation moves the
  light and the view out of their plane;
* a number: the hinge azimuth in degrees, 0 = in-plane, 90 = out-of-plane.

A positive β turns panel B's normal towards +x (in-plane) or towards +y (out-of-plane): for a light on
the +x side it faces panel B towards the light. ``direction="-"`` turns it the other way.

The aspecular angle is the unsigned 3-D angle between the view and the mirror direction of the light,
``arccos(R·V)`` with ``R = 2(L·N)N − L``, as the thesis's shader computes it (§2.4); it equals
``|view + light|`` in-plane. Degrees at the boundary, radians inside.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from station.analysis.errors import AnalysisInputError
from station.model.shading import aspecular_deg
from station.wire import wire_form

Hinge = Literal["in-plane", "out-of-plane"] | float
Direction = Literal["+", "-", "either"]

#: Largest polar angle (degrees) accepted for a light or a view on panel A; beyond it the panel is
#: lit or seen edge-on and its colour is undefined.
POLAR_MAX_DEG = 89.0


@dataclass(frozen=True)
class SeamGeometry:
    """One lighting / viewing geometry of a seam.

    Attributes
    ----------
    light_deg
        Signed polar angle of the light in the plane of incidence, degrees from panel A's normal.
    view_deg
        Signed polar angle of the viewer, same convention.
    hinge
        ``"in-plane"``, ``"out-of-plane"`` or the hinge azimuth in degrees (0 = in-plane).
    """

    light_deg: float
    view_deg: float
    hinge: Hinge = "in-plane"

    @property
    def aspecular_deg(self) -> float:
        """Aspecular angle on panel A in degrees (thesis §3.3.3)."""
        return float(
            aspecular_deg(direction(self.light_deg), direction(self.view_deg), np.array([0, 0, 1.0]))
        )

    def to_dict(self) -> dict[str, float | str]:
        """JSON-able form (angles in degrees; a hinge azimuth as a float)."""
        return wire_form(
            self,
            convert={"hinge": lambda h: h if isinstance(h, str) else float(h)},
            after={"hinge": {"aspecular_deg": self.aspecular_deg}},
        )


def check_polar(value: float, field: str) -> float:
    """Validate a signed polar angle in degrees: finite and ``|value| <= POLAR_MAX_DEG``."""
    try:
        v = float(value)
    except (TypeError, ValueError) as exc:
        raise AnalysisInputError(
            field, f"a number of degrees in [-{POLAR_MAX_DEG:g}, {POLAR_MAX_DEG:g}]", value
        ) from exc
    if not math.isfinite(v) or abs(v) > POLAR_MAX_DEG:
        raise AnalysisInputError(
            field, f"a number of degrees in [-{POLAR_MAX_DEG:g}, {POLAR_MAX_DEG:g}]", value
        )
    return v


def hinge_azimuth_deg(hinge: Hinge) -> float:
    """Return the hinge azimuth in degrees (0 = in-plane, 90 = out-of-plane) or raise."""
    if isinstance(hinge, str):
        if hinge == "in-plane":
            return 0.0
        if hinge == "out-of-plane":
            return 90.0
        raise AnalysisInputError("hinge", '"in-plane", "out-of-plane" or an azimuth in degrees', hinge)
    try:
        v = float(hinge)
    except (TypeError, ValueError) as exc:
        raise AnalysisInputError(
            "hinge", '"in-plane", "out-of-plane" or an azimuth in degrees', hinge
        ) from exc
    if not math.isfinite(v):
        raise AnalysisInputError("hinge", "a finite azimuth in degrees", hinge)
    return v


def direction(polar_deg: ArrayLike) -> NDArray[np.float64]:
    """Unit vector(s) in the x–z plane at signed polar angle(s) *polar_deg* from +z; shape (..., 3)."""
    t = np.radians(np.asarray(polar_deg, dtype=float))
    return np.stack([np.sin(t), np.zeros_like(t), np.cos(t)], axis=-1)


def rotated_normals(beta_deg: ArrayLike, hinge: Hinge = "in-plane") -> NDArray[np.float64]:
    """Normal(s) of panel B, panel A's normal +z rotated by β degrees about the hinge; shape (..., 3).

    Positive β tilts the normal towards the hinge's left-hand side: +x for the in-plane hinge (the y
    axis), +y for the out-of-plane hinge (the x axis).
    """
    b = np.radians(np.asarray(beta_deg, dtype=float))
    az = math.radians(hinge_azimuth_deg(hinge))
    # The tilt direction is perpendicular to the hinge axis (cos az·ŷ + sin az·x̂ rotated): for az = 0
    # the hinge is ŷ and the normal tilts towards x̂; for az = 90° the hinge is x̂ and it tilts to ŷ.
    tilt = np.array([math.cos(az), math.sin(az), 0.0])
    s, c = np.sin(b)[..., None], np.cos(b)[..., None]
    return s * tilt + c * np.array([0.0, 0.0, 1.0])
