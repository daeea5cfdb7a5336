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


def flake_lobes(exponents: tuple[float, ...] | list[float], flakes: FlakeLayer) -> tuple[int, int]:
    """(sharp, mean) lobe indices of a basis for the sparkle: the sharpest map (L_sharp, the glint) and the
    map whose exponent is nearest in log to the flakes' E ≈ 1/(2σ)² (C_E, the expected flake reflection)."""
    sharp = int(np.argmax(exponents))
    target = math.log(flakes.reflected_exponent)
    mean = int(np.argmin([abs(math.log(float(e)) - target) for e in exponents]))
    return sharp, mean


def flake_tint(dd_map_weights: np.ndarray) -> np.ndarray:
    """Tint (3,) of a paint's flakes: its directionally diffuse colour Σ_i w_DD,i (map weights (m, 3),
    :meth:`station.render.weights.LobeWeights.map_weights`)."""
    return np.asarray(dd_map_weights, dtype=np.float64).reshape(-1, 3).sum(axis=0)


def cell_mm(flakes: FlakeLayer, distance: np.ndarray, tan_half_fov: float, height: int) -> np.ndarray:
    """Side of a flake cell per pixel, mm: the pixel's footprint at eye *distance* (scene units), or one
    flake when flakes are larger (the shader's ``cell_mm``)."""
    px = 2.0 * np.asarray(distance, dtype=np.float64) * tan_half_fov / height * UNIT_MM
    return np.maximum(flakes.size_um / 1000.0, px)


def _pcg3d(v: np.ndarray) -> np.ndarray:
    """The shader's ``pcg3d`` hash on (P, 3) uint32 (wrapping arithmetic)."""
    v = v.astype(np.uint32) * np.uint32(1664525) + np.uint32(1013904223)
    x, y, z = v[:, 0].copy(), v[:, 1].copy(), v[:, 2].copy()
    x += y * z
    y += z * x
    z += x * y
    x ^= x >> np.uint32(16)
    y ^= y >> np.uint32(16)
    z ^= z >> np.uint32(16)
    x += y * z
    y += z * x
    z += x * y
    return np.stack([x, y, z], axis=-1)


def flake_normals(
    flakes: FlakeLayer, positions: np.ndarray, cells_mm: np.ndarray, normals: np.ndarray
) -> np.ndarray:
    """One flake normal m (P, 3) per surface cell, as ``render.frag.glsl`` draws it: the cell of a world
    *position* (P, 3) is floor(p · UNIT_MM / cell) hashed with pcg3d to two uniforms, Box–Muller to a
    standard normal pair g, and m = normalize(N + σ (g_x T + g_y B)) about the shading normal N (P, 3)
    with σ = spread_deg in radians and the frame T = normalize(N × Y) (N × X near ±Y), B = N × T."""
    p = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
    scale = (UNIT_MM / np.asarray(cells_mm, dtype=np.float64)).reshape(-1, 1)
    cells = np.floor(p * scale).astype(np.int64) + (1 << 20)
    h = _pcg3d((cells & 0xFFFFFFFF).astype(np.uint32))
    u = ((h[:, :2] >> np.uint32(8)).astype(np.float64) + 0.5) / 16777216.0
    rad = np.sqrt(-2.0 * np.log(u[:, 0]))
    g = rad[:, None] * np.stack([np.cos(2.0 * np.pi * u[:, 1]), np.sin(2.0 * np.pi * u[:, 1])], axis=-1)
    n = np.asarray(normals, dtype=np.float64).reshape(-1, 3)
    helper = np.where(np.abs(n[:, 1:2]) < 0.9, np.array([[0.0, 1.0, 0.0]]), np.array([[1.0, 0.0, 0.0]]))
    t = np.cross(n, helper)
    t /= np.linalg.norm(t, axis=-1, keepdims=True)
    b = np.cross(n, t)
    sigma = math.radians(flakes.spread_deg)
    m = n + sigma * (g[:, :1] * t + g[:, 1:] * b)
    return m / np.linalg.norm(m, axis=-1, keepdims=True)


def clip_sparkle(sparkle: np.ndarray, radiance: np.ndarray, flakes: FlakeLayer) -> np.ndarray:
    """The sparkle added to a pixel of *radiance*: never darker by more than the flakes' share,
    max(sparkle, −reflectance · radiance) (module docstring)."""
    return np.maximum(sparkle, -flakes.reflectance * np.asarray(radiance))


def sparkle_pixels(
    basis,
    flakes: FlakeLayer,
    tint: np.ndarray,
    positions: np.ndarray,
    distance: np.ndarray,
    normal: np.ndarray,
    view: np.ndarray,
    reflect: np.ndarray,
    tan_half_fov: float,
    height: int,
) -> np.ndarray:
    """Zero-mean sparkle (P, 3) of the NumPy renderer: tint · reflectance · (L_sharp(R_m) − C_E(R)) / √N
    (module docstring), the same terms as the shader. *positions* (P, 3) world, *distance* (P,) to the eye,
    *normal*, *view*, *reflect* (P, 3) in the environment's frame, *basis* a
    :class:`~station.render.prefilter.PrefilteredBasis` (its lights added to C_E where that map lacks them)."""
    from station.render.cubemap import sample_cube

    cells = cell_mm(flakes, distance, tan_half_fov, height)
    count = np.maximum(1.0, flakes.density_per_mm2 * cells * cells)
    m = flake_normals(flakes, positions, cells, normal)
    rm = 2.0 * np.sum(m * view, axis=-1, keepdims=True) * m - view
    sharp, mean_i = flake_lobes(basis.exponents, flakes)
    up = np.sum(rm * normal, axis=-1) > 0.0
    glint = np.where(up[:, None], sample_cube(basis.cubes[sharp], rm), 0.0)
    mean = sample_cube(basis.cubes[mean_i], reflect).astype(np.float64)
    if basis.lights is not None and basis.wide and basis.wide[mean_i]:
        e = float(basis.exponents[mean_i])
        p = (e + 1.0) / (2.0 * np.pi) * np.clip(reflect @ basis.lights.directions.T, 0.0, None) ** e
        mean = mean + p @ basis.lights.flux
    return np.asarray(tint)[None, :] * flakes.reflectance * (glint - mean) / np.sqrt(count)[:, None]
