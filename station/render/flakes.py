"""Flake sparkle in the renderer: scale, level of detail, and the shader's uniforms.

The flake layer's parameters are :class:`station.model.flakes.FlakeLayer`. Per pixel the GL renderer
(``shaders/render.frag.glsl``) draws one random flake normal m per surface cell (hash of the cell, so the
sparkle sticks to the surface while orbiting), about the shading normal with the layer's spread, and adds

    tint · reflectance · (L_sharp(R_m) − C_E(R)) / √N

where R_m is the view mirrored about m, L_sharp the sharpest prefiltered map (the environment with its sun
and lights), C_E(R) the lobe map whose width matches the flakes' spread (E ≈ 1/(2σ)², the expected flake
reflection), tint the paint's directionally diffuse colour Σ w_DD,i, and N the flakes in the cell:
a cell is the pixel's footprint (or one flake when flakes are larger than a pixel). The term has zero
mean, so the colour averaged over an area is the design's (:func:`station.model.flakes.sparkle_amplitude`),
except where it would darken a pixel by more than the flakes' share (reflectance × the pixel's
radiance): there it is clipped (beside the sun's reflection, where the expected flake reflection holds
the sun and a flake that misses it reflects sky), a small brightening of those pixels.

Scale: one scene unit is UNIT_MM millimetres (the shapes are desk-size models: the speed shape is 24 cm
long). Level of detail (:func:`flake_lod`): flakes smaller than a pixel are averaged; when the sparkle
amplitude 1/√N of a pixel falls below SPARKLE_MIN the layer is switched off, and the choice says why.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from station.model.flakes import FlakeLayer, sparkle_amplitude
from station.render.camera import Camera

#: Millimetres per scene unit.
UNIT_MM = 100.0
#: Sparkle amplitude 1/√N below which the layer is switched off (2 %: under ~0.5 ΔE00 on a bright glint).
SPARKLE_MIN = 0.02


@dataclass(frozen=True)
class FlakeChoice:
    """What the level of detail chose for the flakes of one frame."""

    on: bool
    pixel_mm: float  # footprint of one pixel at the camera's target distance
    flakes_per_pixel: float
    amplitude: float  # 1/√N
    reason: str


def pixel_footprint_mm(camera: Camera, height: int, distance: float | None = None) -> float:
    """Side of one pixel on a surface facing the camera at *distance* (default: eye to target), mm."""
    d = float(np.linalg.norm(np.subtract(camera.target, camera.eye))) if distance is None else distance
    return 2.0 * d * math.tan(math.radians(camera.fov_deg) / 2.0) / height * UNIT_MM


def flake_lod(flakes: FlakeLayer | None, camera: Camera, height: int) -> FlakeChoice:
    """Flakes on or off for this view (module docstring), with the numbers and the reason."""
    px = pixel_footprint_mm(camera, height)
    if flakes is None:
        return FlakeChoice(False, px, 0.0, 0.0, "no flake layer")
    cell = max(px, flakes.size_um / 1000.0)
    n = flakes.flakes_in(cell * cell)
    amp = sparkle_amplitude(flakes, cell * cell)
    size = "larger than a pixel" if flakes.size_um / 1000.0 >= px else "smaller than a pixel"
    if amp < SPARKLE_MIN:
        return FlakeChoice(
            False, px, n, amp, f"flakes {size}: {n:.0f} per pixel, sparkle {amp:.1%} < {SPARKLE_MIN:.0%}: off"
        )
    return FlakeChoice(True, px, n, amp, f"flakes {size}: {max(n, 1.0):.0f} per pixel, sparkle {amp:.1%}: on")


def flake_uniforms(flakes: FlakeLayer) -> dict[str, float]:
    """Uniform values of the layer for ``render.frag.glsl``."""
    return {
        "u_flake_size_mm": flakes.size_um / 1000.0,
        "u_flake_density": flakes.density_per_mm2,
        "u_flake_sigma": math.radians(flakes.spread_deg),
        "u_flake_reflectance": flakes.reflectance,
        "u_unit_mm": UNIT_MM,
    }
