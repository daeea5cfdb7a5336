"""Image-based BRDF tweaker (thesis §3.6) on plain per-pixel buffers.

The tools index an aspecular-angle buffer (degrees, ``(H, W)``) and, for moving the light, a
light-direction buffer (``(H, W, 3)``: the light that would centre the highlight on the pixel) at a
crosshair pixel ``(x, y)`` = (column, row). :mod:`station.design.scene` makes both; the renderer makes
the same on the GPU.

Colour adjustment (eqs 3.6.1–3.6.6 with DESIGN.md §7 erratum 1)
--------------------------------------------------------------
Temporary colours ``Lab'`` of face and flop (3.6.1 lightness ``L + ΔL``; 3.6.2 chroma
``(a, b)·(1 + ΔC)``; 3.6.3 hue rotation by ΔH) are blended with the originals by the ratio

    R = 1                                θ ≤ 15°
    R = (θ_clamp − θ) / (θ_clamp − 15°)   15° < θ < θ_clamp                         (eq 3.6.4, corrected)
    R = 0                                θ ≥ θ_clamp

    Lab''(15°)      = (1 − R) Lab(15°) + R Lab'(15°)                               (eq 3.6.5)
    Lab''(θ_clamp)  = R Lab(θ_clamp) + (1 − R) Lab'(θ_clamp)                        (eq 3.6.6)

so a crosshair on the face region changes only the face, one beyond θ_clamp only the flop. The thesis's
printed eq 3.6.4 has the cases reversed against its own text; this is the corrected form.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from station.design.designer import L_EDIT_RANGE
from station.design.errors import DesignInputError
from station.design.scene import phong_of_gloss
from station.model import FaceFlopTravelGloss
from station.model.gloss import PHONG_MAX, STANDARD_INDEX, SpecularLobe, fresnel_unpolarised, gloss_from_lobe

Adjustment = Literal["L", "C", "H"]
FACE_DEG = 15.0


def ratio_r(theta_deg: ArrayLike, theta_clamp_deg: float) -> NDArray[np.float64]:
    """Ratio R of the face adjustment at aspecular angle θ (eq 3.6.4 corrected, erratum 1); vectorised."""
    t = np.asarray(theta_deg, dtype=float)
    tc = float(theta_clamp_deg)
    if not tc > FACE_DEG:
        raise DesignInputError("theta_clamp_deg", "> 15", tc)
    return np.clip((tc - t) / (tc - FACE_DEG), 0.0, 1.0)


def _pixel(buffer: NDArray, xy: tuple[int, int], mask: ArrayLike | None, name: str) -> NDArray:
    try:
        x, y = int(xy[0]), int(xy[1])
    except (TypeError, ValueError, IndexError) as exc:
        raise DesignInputError(name, "a pixel (x, y) of integers", xy) from exc
    h, w = buffer.shape[:2]
    if not (0 <= x < w and 0 <= y < h):
        raise DesignInputError(name, f"0 <= x < {w}, 0 <= y < {h}", (x, y))
    if mask is not None and not bool(np.asarray(mask)[y, x]):
        raise DesignInputError(name, "a pixel on the object (foreground mask)", (x, y))
    value = np.asarray(buffer[y, x], dtype=float)
    if not np.all(np.isfinite(value)):
        raise DesignInputError(name, "a pixel with a finite buffer value", (x, y))
    return value


def _temporary(lab: tuple[float, float, float], kind: str, delta: float) -> NDArray[np.float64]:
    L, a, b = lab
    if kind == "L":  # eq 3.6.1
        return np.array([L + delta, a, b])
    if kind == "C":  # eq 3.6.2
        return np.array([L, a * (1.0 + delta), b * (1.0 + delta)])
    h = math.radians(delta)  # eq 3.6.3, ΔH in degrees
    return np.array([L, a * math.cos(h) - b * math.sin(h), a * math.sin(h) + b * math.cos(h)])


@dataclass(frozen=True)
class Tweak:
    """Result of one crosshair adjustment: the new design, θ under the crosshair and the ratio R."""

    design: FaceFlopTravelGloss
    theta_deg: float
    ratio: float


def adjust_at(
    design: FaceFlopTravelGloss,
    aspecular_deg: ArrayLike,
    xy: tuple[int, int],
    kind: Adjustment,
    delta: float,
    mask: ArrayLike | None = None,
) -> Tweak:
    """Adjust lightness (``"L"``, ΔL in L* units), chroma (``"C"``, ΔC relative: 0.1 = +10 %) or hue
    (``"H"``, ΔH in degrees) at the crosshair pixel *xy* (eqs 3.6.1–3.6.6, erratum 1).

    A solid design has one colour, which is adjusted fully wherever the crosshair is.

    Raises
    ------
    DesignInputError
        Pixel off the buffer or off the mask, unknown kind, non-finite delta, chroma factor < −1, or a
        result the model refuses (e.g. L* out of range).
    """
    if kind not in ("L", "C", "H"):
        raise DesignInputError("kind", "L | C | H", kind)
    if not math.isfinite(delta):
        raise DesignInputError("delta", "a finite number", delta)
    if kind == "C" and delta < -1.0:
        raise DesignInputError("delta", "ΔC >= -1 (chroma cannot go below 0)", delta)
    theta = float(_pixel(np.asarray(aspecular_deg, dtype=float), xy, mask, "xy"))
    face, flop = np.asarray(design.face), np.asarray(design.flop)
    try:
        if design.is_solid or design.travel_deg is None:
            lab = tuple(float(v) for v in _temporary(design.face, kind, delta))
            if not L_EDIT_RANGE[0] <= lab[0] <= L_EDIT_RANGE[1]:
                raise DesignInputError(
                    "delta", "an adjustment keeping L* in 0..100", delta, f"L* {lab[0]:.4g}"
                )
            return Tweak(design.replace(face=lab, flop=lab), theta, 1.0)
        r = float(ratio_r(theta, design.travel_deg))
        face2 = (1.0 - r) * face + r * _temporary(design.face, kind, delta)  # eq 3.6.5
        flop2 = r * flop + (1.0 - r) * _temporary(design.flop, kind, delta)  # eq 3.6.6
        for name, edited in (("face", face2), ("flop", flop2)):
            if not L_EDIT_RANGE[0] <= edited[0] <= L_EDIT_RANGE[1]:
                raise DesignInputError(
                    "delta", f"an adjustment keeping {name} L* in 0..100", delta, f"L* {edited[0]:.4g}"
                )
        new = design.replace(face=tuple(float(v) for v in face2), flop=tuple(float(v) for v in flop2))
    except DesignInputError:
        raise
    except ValueError as exc:  # the model's ModelInputError (an InputError and a ValueError)
        raise DesignInputError("delta", "an adjustment that keeps the design valid", delta, str(exc)) from exc
    return Tweak(new, theta, r)


def drag_travel(
    design: FaceFlopTravelGloss, aspecular_deg: ArrayLike, xy: tuple[int, int], mask: ArrayLike | None = None
) -> FaceFlopTravelGloss:
    """Drag the θ_clamp ring to pixel *xy*: travel := θ at that pixel (thesis §3.6.2 "Adjust travel").

    Raises
    ------
    DesignInputError
        Solid design, pixel off the object, or θ there not in (15°, 180°].
    """
    if design.is_solid:
        raise DesignInputError("design", "a design with travel (face != flop)", "solid")
    theta = float(_pixel(np.asarray(aspecular_deg, dtype=float), xy, mask, "xy"))
    if not FACE_DEG < theta <= 180.0:
        raise DesignInputError("xy", "a pixel whose aspecular angle is in (15°, 180°]", theta)
    return design.replace(travel_deg=theta)


# ----------------------------------------------------------------------------------- gloss lobe edge


def highlight_edge_deg(gloss_gu: float) -> float:
    """Aspecular angle (degrees) of the highlight's edge for *gloss_gu*: where the Phong lobe of the
    gloss (:func:`~station.design.scene.phong_of_gloss`) falls to half its peak, ``cos(θ_e)^n = 1/2`` → ``θ_e = acos(2^(−1/n))``.

    This is the "mapping between gloss and aspecular angles" the thesis leaves to the implementation
    (§3.6.2 "Adjust gloss"); the half-maximum edge is the visible rim of the highlight. From 100 GU
    (a mirror, θ_e ≈ 0.02°) it widens to 60° at about 0.5 GU; below that the model keeps the widest
    lobe (n = 1) and dims it, so the edge no longer moves.
    """
    n, _ = phong_of_gloss(gloss_gu)
    return math.degrees(math.acos(0.5 ** (1.0 / n)))


def gloss_from_edge(theta_edge_deg: float) -> float:
    """Invert :func:`highlight_edge_deg`: the exponent of the edge, ``n = ln ½ / ln cos θ_e``, read by the
    simulated 60° gloss meter (``station.model.gloss.gloss_from_lobe``) with the coat's full Fresnel albedo.

    Raises
    ------
    DesignInputError
        The angle is outside the edges reachable between 0 and 100 GU.
    """
    t = float(theta_edge_deg)
    lo_edge = math.degrees(math.acos(0.5 ** (1.0 / PHONG_MAX)))
    if not math.isfinite(t) or not lo_edge <= t <= 60.0:
        raise DesignInputError("theta_edge_deg", f"{lo_edge:.2g}° (100 GU) .. 60° (about 0.5 GU)", t)
    n = math.log(0.5) / math.log(math.cos(math.radians(t))) if t > 0 else PHONG_MAX
    n = min(max(n, 1.0), PHONG_MAX)
    full = fresnel_unpolarised(60.0, STANDARD_INDEX)
    g = float(gloss_from_lobe(SpecularLobe(n, full, 0.0)))
    return min(g, 100.0) if g <= 100.0 + 1e-6 else g  # only round-off above 100 is trimmed


def drag_highlight_edge(
    design: FaceFlopTravelGloss, aspecular_deg: ArrayLike, xy: tuple[int, int], mask: ArrayLike | None = None
) -> FaceFlopTravelGloss:
    """Drag the highlight's edge to pixel *xy*: gloss := the gloss whose half-maximum edge lies at θ(xy)."""
    theta = float(_pixel(np.asarray(aspecular_deg, dtype=float), xy, mask, "xy"))
    return design.replace(gloss_gu=gloss_from_edge(theta))


def drag_highlight_centre(
    light_dirs: ArrayLike, xy: tuple[int, int], mask: ArrayLike | None = None
) -> NDArray[np.float64]:
    """Drag the highlight's centre to pixel *xy*: the new light direction is the light-direction buffer
    at that pixel (the view reflected about the normal, thesis §3.6.2 "Move light"); unit 3-vector."""
    v = _pixel(np.asarray(light_dirs, dtype=float), xy, mask, "xy")
    norm = float(np.linalg.norm(v))
    if v.shape != (3,) or norm == 0.0:
        raise DesignInputError("light_dirs", "(H, W, 3) non-zero light directions", v.shape)
    return v / norm


HitTarget = Literal["highlight-centre", "highlight-edge", "travel-ring", "object"]


def hit_test(design: FaceFlopTravelGloss, theta_deg: float, tolerance_deg: float = 3.0) -> HitTarget:
    """Classify a click at aspecular angle θ (thesis §3.6.2): the highlight's centre (θ below half the
    edge angle), its edge (within *tolerance_deg* of :func:`highlight_edge_deg`), the θ_clamp ring
    (within *tolerance_deg* of travel), or the object."""
    edge = highlight_edge_deg(design.gloss_gu)
    if theta_deg <= 0.5 * edge:
        return "highlight-centre"
    if abs(theta_deg - edge) <= tolerance_deg:
        return "highlight-edge"
    if design.travel_deg is not None and abs(theta_deg - design.travel_deg) <= tolerance_deg:
        return "travel-ring"
    return "object"
