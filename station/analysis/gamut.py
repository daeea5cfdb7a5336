"""What a paint can be: the "paintable" bound used by the inverse trompe l'oeil.

Documented bound (not a pigment database): a colour is paintable when

* its chromaticity lies inside the sRGB gamut: linear sRGB ≥ 0 on every channel (a conservative subset
  of real surface colours; Pointer's gamut of real surface colours is also reported, via colour-science,
  for colours at or below L* = 100);
* its reflectance factor is bounded: every linear-sRGB channel ≤ 1 for a flop or a solid (no surface
  reflects more than a white diffuser far from specular), ≤ :data:`FACE_RGB_MAX` for an effect paint's
  face at 15° (flake reflection near specular exceeds a white diffuser: bright silvers read L*15 of
  120–140, linear channel values up to about 2.2);
* the face is not darker than the flop (L*face ≥ L*flop) unless a retroreflective design is allowed.

A paint already outside these bounds (a measured panel) relaxes each bound to its own value, so a
corrected paint is never required to be more paintable than the original.

This is the physical pre-check. Whether the shipped colorants can mix a paint is a different rule,
kept in one place with the colorant model (``station.formulate.gamut.colorant_gamut``: formulable
within the formulation tolerance, else the nearest achievable paint); the CLI and the service apply it
to the seam QA's corrected paint (``corrected_colorant_gamut``).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from station.model.colorimetry import lab_to_linear_srgb, lab_to_xyz
from station.model.domain import DIFFUSE_WHITE_L
from station.wire import wire_form

if TYPE_CHECKING:
    from station.model import FaceFlopTravelGloss

#: Upper bound of a face's linear-sRGB channels (reflectance factor at 15°).
FACE_RGB_MAX = 2.5
#: Upper bound of a flop's / solid's linear-sRGB channels.
FLOP_RGB_MAX = 1.0


@dataclass(frozen=True)
class GamutReport:
    """Paintability of a design.

    Attributes
    ----------
    paintable
        True when every check passes.
    problems
        One sentence per failed check.
    pointer_gamut
        Whether the flop (and a face at L* ≤ 100) lies in Pointer's gamut of real surface colours;
        ``None`` when colour-science could not decide.
    """

    paintable: bool
    problems: tuple[str, ...]
    pointer_gamut: bool | None

    def to_dict(self) -> dict[str, object]:
        """JSON-able form."""
        return wire_form(self)


def rgb_bounds(
    face: ArrayLike, flop: ArrayLike, solid: bool
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(lower, upper) channel bounds for face and flop, shape (2, 3) each (rows face, flop)."""
    lo = np.zeros((2, 3))
    hi = np.array([[FLOP_RGB_MAX if solid else FACE_RGB_MAX] * 3, [FLOP_RGB_MAX] * 3])
    return lo, hi


def check_paintable(
    paint: FaceFlopTravelGloss,
    *,
    allow_face_darker: bool = False,
    tol: float = 1e-6,
    relax_to: FaceFlopTravelGloss | None = None,
) -> GamutReport:
    """Check a ``FaceFlopTravelGloss`` against the documented bound (see module docstring).

    *relax_to*: a reference paint (the original); bounds it already violates are relaxed to its values.
    """
    face = np.asarray(paint.face, dtype=float)
    flop = np.asarray(paint.flop, dtype=float)
    solid = bool(paint.is_solid)
    rgb = lab_to_linear_srgb(np.stack([face, flop]))
    lo, hi = rgb_bounds(face, flop, solid)
    if relax_to is not None:
        ref = lab_to_linear_srgb(np.stack([np.asarray(relax_to.face), np.asarray(relax_to.flop)]))
        lo, hi = np.minimum(lo, ref), np.maximum(hi, ref)
    problems = []
    for i, name in enumerate(("face", "flop")):
        if solid and i == 1:
            break
        if np.any(rgb[i] < lo[i] - tol):
            problems.append(
                f"{name} chromaticity outside the sRGB gamut (linear RGB {np.round(rgb[i], 3).tolist()})"
            )
        if np.any(rgb[i] > hi[i] + tol):
            problems.append(
                f"{name} reflects more than a real surface can (linear RGB max {rgb[i].max():.3g} > "
                f"{hi[i].max():g})"
            )
    if not allow_face_darker and not solid and face[0] < flop[0] - tol:
        ref_ok = relax_to is not None and relax_to.face[0] < relax_to.flop[0]
        if not ref_ok:
            problems.append(f"face darker than flop (L* {face[0]:.2f} < {flop[0]:.2f})")
    return GamutReport(not problems, tuple(problems), _pointer(face, flop))


@functools.cache
def _pointer_hull() -> Any:
    """Delaunay triangulation of Pointer's gamut in XYZ, built once (as ``colour.is_within_pointer_gamut``
    does on every call: same data, same test, without rebuilding the hull)."""
    from colour.volume.pointer_gamut import (
        CCS_ILLUMINANT_POINTER_GAMUT,
        DATA_POINTER_GAMUT_VOLUME,
        Lab_to_XYZ,
        LCHab_to_Lab,
    )
    from scipy.spatial import Delaunay

    return Delaunay(Lab_to_XYZ(LCHab_to_Lab(DATA_POINTER_GAMUT_VOLUME), CCS_ILLUMINANT_POINTER_GAMUT))


def in_pointer_gamut(lab: ArrayLike) -> NDArray[np.bool_]:
    """Whether Lab colour(s) lie in Pointer's gamut of real surface colours (colour-science's data)."""
    return _pointer_hull().find_simplex(lab_to_xyz(np.asarray(lab, dtype=float))) >= 0


def _pointer(face: NDArray[np.float64], flop: NDArray[np.float64]) -> bool | None:
    labs = [flop] + ([face] if face[0] <= DIFFUSE_WHITE_L else [])  # Pointer's gamut ends at the white
    try:
        return bool(np.all(in_pointer_gamut(np.stack(labs))))
    except (ValueError, ArithmeticError):  # pragma: no cover - hull test failed; the sRGB bound still holds
        return None
