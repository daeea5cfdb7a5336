"""Reference point-light shading of a design: clamped-quadratic colour plus the gloss lobe.

One directional ("point at infinity") light of irradiance E, normal to the beam, lights a surface with
normal N; L points to the light, V to the eye, R = 2(N·L)N − L is the mirror direction and the
aspecular angle is α = ∠(R, V) (thesis §3.7.1). The designed BRDF × cos (eqs 2.3.1–2.3.3) is

    f(L, V)·(L·N) = (L·N) ρ(α)/π + ρ_s (n + 1)/(2π) · max(cos α, 0)ⁿ        (L·N > 0; 0 otherwise)

* ρ(α): the design's colour as a linear-sRGB reflectance factor, Lab of the clamped quadratic
  (eq 3.3.2, :meth:`FaceFlopTravelGloss.lab_at`) → :func:`station.model.colorimetry.lab_to_linear_srgb`.
  This is eq 4.3.2, c = I · f · (L·N), with Lambert's term L·N (erratum 2) and I·f the paint's colour
  (eqs 4.3.3–4.3.4).
* the gloss lobe of :mod:`station.model.lobe`, not scaled by L·N (the K_G lobes of eq 2.3.2): the
  energy-conserving lobe sends ρ_s E (L·N) into (n + 1)/(2π) cosⁿψ per steradian, and at the mirror
  direction the (L·N) of the irradiance cancels the 1/cos θ_V of radiance, so the peak the gloss meter
  reads is ρ_s (n + 1)/(2π) E (consistent with :func:`station.model.gloss.simulate_gloss_meter`).

Expressed against a white diffuser facing the light (pixel value 1 = E/π radiance), the shaded
colour is the linear-sRGB pixel

    c = E · [ max(L·N, 0) · ρ(α) + 1[L·N > 0] · ρ_s (n + 1)/2 · max(cos α, 0)ⁿ ].

Shading in Lab (:func:`shade_lab`) scales tristimulus values, never Lab numbers: Lab → XYZ with
colour-science, × the shading factor, → Lab, so Y' = k·Y and L*' = 116 f(k·Y/Y_n) − 16.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from station.model.colorimetry import WHITEPOINT, lab_to_linear_srgb, lab_to_xyz, xyz_to_lab
from station.model.lobe import lobe_reflectance

__all__ = [
    "Design",
    "aspecular_deg",
    "design_reflectance",
    "point_light_rgb",
    "shade_lab",
    "shade_reflectance",
]


class Design(Protocol):
    """What the shader reads of a design (``FaceFlopTravelGloss`` and ``ClampedQuadratic`` qualify)."""

    @property
    def gloss_gu(self) -> float:
        """60° gloss, GU."""

    def lab_at(self, angles_deg: ArrayLike) -> NDArray[np.float64]:
        """Lab at aspecular angles (degrees), shape ``angles.shape + (3,)``."""


def aspecular_deg(light: ArrayLike, view: ArrayLike, normal: ArrayLike) -> NDArray[np.float64]:
    """Aspecular angle α = arccos(R·V) in degrees (0–180), R = 2(L·N)N − L (thesis §3.7.1, §2.4).

    *light*, *view*, *normal*: unit vectors, broadcast over leading axes (..., 3); L and V point away
    from the surface. R·V is formed as 2(L·N)(N·V) − L·V, without building R.
    """
    L = np.asarray(light, dtype=float)
    V = np.asarray(view, dtype=float)
    N = np.asarray(normal, dtype=float)
    cos = 2.0 * np.einsum("...i,...i->...", L, N) * np.einsum("...i,...i->...", N, V) - np.einsum(
        "...i,...i->...", L, V
    )
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


def design_reflectance(design: Design, aspecular_deg: ArrayLike) -> NDArray[np.float64]:
    """Linear-sRGB reflectance factor ρ(α) of *design* at aspecular angles α (degrees), shape (..., 3).

    Eq 3.3.2 (the clamped quadratic, as :meth:`lab_at` evaluates it) → linear sRGB (white = 1, 1, 1).
    """
    return np.asarray(lab_to_linear_srgb(design.lab_at(np.asarray(aspecular_deg, dtype=float))), dtype=float)


def shade_reflectance(
    lambert: ArrayLike, colour: ArrayLike, gloss: ArrayLike = 0.0, irradiance: float = 1.0
) -> NDArray[np.float64]:
    """Pixel c = E · [max(L·N, 0) · ρ + 1[L·N > 0] · g] (module docstring; eq 4.3.2 with the K_G lobe).

    Parameters
    ----------
    lambert
        L·N (any value; clamped at 0), shape (...).
    colour
        Reflectance factor ρ of the colour part, linear sRGB, shape (..., 3).
    gloss
        Neutral reflectance factor g of the gloss lobe, shape (...) (0 for none).
    irradiance
        E, linear units (1 = a white diffuser facing the light reads 1).
    """
    k = np.asarray(lambert, dtype=float)
    lit = k > 0.0
    c = np.maximum(k, 0.0)[..., None] * np.asarray(colour, dtype=float)
    g = np.asarray(gloss, dtype=float)
    if g.ndim or float(g) != 0.0:
        c = c + np.where(lit, g, 0.0)[..., None]
    return irradiance * c


def point_light_rgb(
    design: Design,
    lambert: ArrayLike,
    aspecular_deg: ArrayLike,
    *,
    irradiance: float = 1.0,
    specular: bool = True,
) -> NDArray[np.float64]:
    """Linear-sRGB pixel of *design* under one directional light (module docstring), shape (..., 3).

    Parameters
    ----------
    design
        The design: clamped-quadratic colour (eq 3.3.2) and 60° gloss (GU).
    lambert
        L·N per pixel (clamped at 0: a surface turned away from the light is black).
    aspecular_deg
        Aspecular angle α per pixel, degrees, same shape as *lambert*.
    irradiance
        E, linear units (1 = a white diffuser facing the light reads 1).
    specular
        Include the gloss lobe (the thesis's misalignment analysis leaves it out, §4.3.2 note).
    """
    alpha = np.asarray(aspecular_deg, dtype=float)
    gloss = lobe_reflectance(float(design.gloss_gu), alpha) if specular else 0.0
    return shade_reflectance(lambert, design_reflectance(design, alpha), gloss, irradiance)


def shade_lab(lab: ArrayLike, k: ArrayLike, add: ArrayLike = 0.0) -> NDArray[np.float64]:
    """Scale a colour's tristimulus values by the shading factor *k* (eq 4.3.2), returning Lab.

    Parameters
    ----------
    lab
        Colour, CIE Lab (D65 / 10°), shape (..., 3).
    k
        Shading factor(s) ≥ 0, broadcast against ``lab[..., 0]``.
    add
        Neutral reflectance factor added before shading: *add* × the white's XYZ (a grey lobe).

    Returns
    -------
    ndarray
        Lab of ``k · (XYZ + add · XYZ_white)``, shape (..., 3). The white point cancels.
    """
    xyz = lab_to_xyz(lab)
    a = np.asarray(add, dtype=float)
    if a.ndim or float(a) != 0.0:
        xyz = xyz + a[..., None] * lab_to_xyz(np.array([100.0, 0.0, 0.0]))
    return xyz_to_lab(xyz * np.asarray(k, dtype=float)[..., None], WHITEPOINT)
