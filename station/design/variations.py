"""Variations control (thesis §3.4.4): the ring of designs around the current one.

Categories (thesis Figs 3.9–3.10): ``face`` colour, ``flop`` colour, ``travel-gloss``. The *degree* is
the size of one step, in CIELAB units for the colour categories:

=================  =====================================================================
variation          change (degree = d)
=================  =====================================================================
lighter / darker   L* ± d
more / less chroma C*ab ± d at constant hue angle (a*, b* scaled)
hue + / hue −      rotation of (a*, b*) about the origin by ±Δh with ΔH*ab = d, i.e.
                   Δh = 2·asin(d / 2C*ab) (the colour moves d along its hue circle)
more / less travel θ_clamp ± d degrees
more / less gloss  gloss ± d GU
=================  =====================================================================

The ring is deterministic (fixed order, :data:`RING`). A variation the model cannot represent (Lab
leaving the domain's effect-paint bound 0 <= L* <= 200, |a*|, |b*| <= 150 of
:mod:`station.model.domain` — a bright silver at L*15 = 125 gets lighter and darker like any colour —,
chroma below 0, a hue step on a near-neutral colour with C*ab < d/2, travel leaving 15–180°, gloss
leaving 0–100 GU, a solid that has no travel) is still listed, with ``design=None`` and the reason, so
the ring keeps its shape; nothing is clamped.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from station.design.errors import DesignInputError
from station.design.options import CATEGORIES, Category
from station.model import FaceFlopTravelGloss, ModelError
from station.model.design_io import design_to_dict
from station.model.domain import (
    FACE_ANGLE_DEG,
    GLOSS_MAX_GU,
    GLOSS_MIN_GU,
    L_MAX,
    L_MIN,
    TRAVEL_MAX_DEG,
    lab_accepted,
)
from station.model.errors import ModelInputError
from station.wire import wire_form

COLOUR_RING: tuple[str, ...] = ("lighter", "darker", "more chroma", "less chroma", "hue +", "hue -")
TRAVEL_GLOSS_RING: tuple[str, ...] = ("more travel", "less travel", "more gloss", "less gloss")
RING: dict[str, tuple[str, ...]] = {
    "face": COLOUR_RING,
    "flop": COLOUR_RING,
    "travel-gloss": TRAVEL_GLOSS_RING,
}
#: Accepted step size (CIELAB units, degrees or GU): 0 < degree <= DEGREE_MAX.
DEGREE_MAX = 50.0


@dataclass(frozen=True)
class Variation:
    """One cell of the ring: its label, the design (``None`` when unreachable) and why not."""

    label: str
    design: FaceFlopTravelGloss | None
    reason: str = ""

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form: the design as ``cacad.design/1`` (``None`` when unreachable)."""
        return wire_form(self, convert={"design": lambda d: None if d is None else design_to_dict(d)})


@dataclass(frozen=True)
class VariationRing:
    """The centre design, the category and degree asked for, and the ring in :data:`RING` order."""

    centre: FaceFlopTravelGloss
    category: str
    degree: float
    variations: tuple[Variation, ...]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form shared by every front: centre and cells as ``cacad.design/1`` (``None`` when a
        cell is unreachable, with its reason), category and degree."""
        return wire_form(self, convert={"centre": design_to_dict})


class _Unreachable(Exception):
    pass


def _vary_colour(lab: tuple[float, float, float], label: str, d: float) -> tuple[float, float, float]:
    L, a, b = lab
    c = math.hypot(a, b)
    if label in ("lighter", "darker"):
        L2 = L + (d if label == "lighter" else -d)
        if not L_MIN <= L2 <= L_MAX:
            raise _Unreachable(f"L* would be {L2:.4g}, outside {lab_accepted('L')}")
        return (L2, a, b)
    if label in ("more chroma", "less chroma"):
        c2 = c + (d if label == "more chroma" else -d)
        if c2 < 0:
            raise _Unreachable(f"chroma would be {c2:.4g} < 0")
        if c == 0:
            raise _Unreachable("an achromatic colour has no hue direction to add chroma along")
        return (L, a * c2 / c, b * c2 / c)
    # hue ±: ΔH*ab = 2 sqrt(C1 C2) sin(Δh/2) with C1 = C2 = C
    if c == 0:  # (d / 2 underflows to 0 for the smallest d, so the test below would let c = 0 through)
        raise _Unreachable("an achromatic colour has no hue to turn")
    if c < d / 2.0:
        raise _Unreachable(f"chroma {c:.4g} < degree/2: a hue step of ΔH = {d:g} is impossible")
    dh = 2.0 * math.asin(d / (2.0 * c)) * (1 if label == "hue +" else -1)
    cs, sn = math.cos(dh), math.sin(dh)
    return (L, cs * a - sn * b, sn * a + cs * b)


def _make(design: FaceFlopTravelGloss, category: str, label: str, d: float) -> FaceFlopTravelGloss:
    if category == "travel-gloss":
        if label.endswith("travel"):
            if design.is_solid or design.travel_deg is None:
                raise _Unreachable("a solid design has no travel")
            t = design.travel_deg + (d if label.startswith("more") else -d)
            if not FACE_ANGLE_DEG < t <= TRAVEL_MAX_DEG:
                raise _Unreachable(
                    f"travel would be {t:.4g}°, outside ({FACE_ANGLE_DEG:g}, {TRAVEL_MAX_DEG:g}]"
                )
            return design.replace(travel_deg=t)
        g = design.gloss_gu + (d if label.startswith("more") else -d)
        if not GLOSS_MIN_GU <= g <= GLOSS_MAX_GU:
            raise _Unreachable(f"gloss would be {g:.4g} GU, outside {GLOSS_MIN_GU:g}..{GLOSS_MAX_GU:g}")
        return design.replace(gloss_gu=g)
    if design.is_solid:
        # A solid is one colour: varying "face" or "flop" alone would invent travel; vary both.
        lab = _vary_colour(design.face, label, d)
        return design.replace(face=lab, flop=lab, travel_deg=None)
    if category == "face":
        return design.replace(face=_vary_colour(design.face, label, d))
    return design.replace(flop=_vary_colour(design.flop, label, d))


def variations(design: FaceFlopTravelGloss, degree: float, category: Category = "face") -> VariationRing:
    """Return the ring of variations of *design* (thesis §3.4.4; table in the module docstring).

    Parameters
    ----------
    design
        The centre design.
    degree
        Step size d: CIELAB units (colour categories), degrees (travel) and GU (gloss); 0 < d <= 50.
    category
        ``"face"``, ``"flop"`` or ``"travel-gloss"``.

    Raises
    ------
    DesignInputError
        Unknown category or a degree out of range.
    """
    if category not in CATEGORIES:
        raise DesignInputError("category", " | ".join(CATEGORIES), category)
    try:
        d = float(degree)
    except (TypeError, ValueError) as exc:
        raise DesignInputError("degree", f"0 < degree <= {DEGREE_MAX:g}", degree) from exc
    if not np.isfinite(d) or not 0.0 < d <= DEGREE_MAX:
        raise DesignInputError("degree", f"0 < degree <= {DEGREE_MAX:g}", degree)
    ring = []
    for label in RING[category]:
        try:
            ring.append(Variation(label, _make(design, category, label, d)))
        except _Unreachable as exc:
            ring.append(Variation(label, None, str(exc)))
        except (ModelInputError, ModelError) as exc:
            ring.append(Variation(label, None, str(exc)))
    return VariationRing(design, category, d, tuple(ring))
