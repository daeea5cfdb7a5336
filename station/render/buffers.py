"""Per-pixel aspecular-angle and light-direction buffers of a view (for the tweaker and sketch fitting).

For a light direction L (unit, pointing from the surface towards the light) the specular direction
at a pixel is the mirror of L about the normal, S = 2(N·L)N − L, and the aspecular angle is the angle
between S and the view direction V (degrees, 0 at the highlight), the angle multi-angle
instruments index colour by (ASTM E2194: 45as15 … 45as110). Under environment lighting the thesis
takes the reflected view R as the light direction (§2.5.2), which is what
:func:`light_direction_buffer` returns when no light is given; the dominant light of an environment
(the direction of its first-order SH term, Sloan 2008 "Stupid SH tricks") is a common single L.

Off-object pixels hold 0 and are flagged in the returned mask; nothing is NaN.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from station.model.colorimetry import REC709_LUMINANCE
from station.model.shading import aspecular_deg
from station.render.errors import RenderInputError
from station.render.numpy_renderer import GBuffer


@dataclass(frozen=True)
class AngleBuffers:
    """Aspecular angle (H, W) and incidence angle (H, W) in degrees, with the object mask."""

    aspecular_deg: np.ndarray
    incidence_deg: np.ndarray
    mask: np.ndarray


def _unit(v: ArrayLike) -> np.ndarray:
    v = np.asarray(v, dtype=np.float64)
    n = np.linalg.norm(v)
    if v.shape != (3,) or not np.isfinite(n) or n < 1e-12:
        raise RenderInputError("light_dir", "a finite non-zero 3-vector", v.tolist() if v.ndim else v)
    return v / n


def light_direction_buffer(g: GBuffer, light_dir: ArrayLike | None = None) -> np.ndarray:
    """Unit light direction per pixel (H, W, 3): *light_dir* everywhere, or R (thesis §2.5.2)."""
    if light_dir is None:
        return np.where(g.mask[..., None], g.reflect, 0.0)
    return np.where(g.mask[..., None], _unit(light_dir), 0.0)


def angle_buffers(g: GBuffer, light_dir: ArrayLike) -> AngleBuffers:
    """Aspecular and incidence angles (degrees) per pixel for a distant light along *light_dir*."""
    lvec = _unit(light_dir)
    n_dot_l = g.normal @ lvec
    asp = np.where(g.mask, aspecular_deg(lvec, g.view, g.normal), 0.0)
    inc = np.where(g.mask, np.degrees(np.arccos(np.clip(n_dot_l, -1.0, 1.0))), 0.0)
    return AngleBuffers(asp.astype(np.float32), inc.astype(np.float32), g.mask.copy())


def dominant_light_direction(sh: np.ndarray) -> np.ndarray:
    """Unit direction of the first-order SH term of radiance coefficients (9, 3) (luminance weights)."""
    lum = sh @ REC709_LUMINANCE
    v = np.array([lum[3], lum[1], lum[2]])  # Y_11 ∝ x, Y_1−1 ∝ y, Y_10 ∝ z
    n = np.linalg.norm(v)
    if n < 1e-12:
        raise RenderInputError("environment", "an environment with a dominant direction", "uniform")
    return v / n
