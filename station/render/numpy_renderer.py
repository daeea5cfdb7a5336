"""NumPy reference renderer of the lobe-blend model (thesis eqs 2.5.1–2.5.3).

Per pixel, with N the normal, V the unit vector to the eye and R = 2(N·V)N − V the reflected view:

    radiance = π K_D · D(N) + Σ_i (2π/(E_i+1)) · (K_G,i + (R·N) K_DD,i) · C_i(R)

where C_i is the environment prefiltered with the normalised lobe of exponent E_i and D the diffuse
map E(N)/π (:mod:`station.render.prefilter`), and the factors π and 2π/(E+1) convert the sr⁻¹
weights of unnormalised lobes (:mod:`station.render.weights`) to these normalised maps
(:meth:`LobeWeights.map_weights`). The directionally diffuse sum is scaled by R·N (= N·V), the
thesis's stand-in for L·N under environment lighting (§2.5.2: "R in this case is an approximation of
the light source direction"); it is exact for narrow lobes and errs for wide ones, as the thesis notes.
The diffuse map is either the exponent-1 cube (``diffuse="cube"``, default — exact up to resolution)
or the 9-coefficient SH irradiance (``diffuse="sh"``, thesis §2.5.3; up to ~10 % off beside a sun).

Pixels that miss the object show a constant grey background. Output is linear sRGB radiance; the
display transform is :mod:`station.render.tonemap`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from station.render.cubemap import sample_cube
from station.render.errors import RenderInputError
from station.render.prefilter import PrefilteredBasis
from station.render.sh import sh_diffuse
from station.render.shapes import Scene, intersect
from station.render.weights import LobeWeights

BACKGROUND = 0.18


@dataclass(frozen=True)
class GBuffer:
    """Per-pixel geometry of one view: mask, unit normal, unit view (to eye), reflected view, paint id."""

    mask: np.ndarray      # (H, W) bool
    normal: np.ndarray    # (H, W, 3)
    view: np.ndarray      # (H, W, 3)
    reflect: np.ndarray   # (H, W, 3)
    paint: np.ndarray     # (H, W) int8, −1 off the object
    position: np.ndarray  # (H, W, 3)

    @property
    def n_dot_v(self) -> np.ndarray:
        """N·V = R·N per pixel (H, W), ≥ 0."""
        return np.clip(np.sum(self.normal * self.view, axis=-1), 0.0, 1.0)


def check_size(width: int, height: int) -> None:
    """Validate an image size (1..8192 each)."""
    for name, v in (("width", width), ("height", height)):
        if not (isinstance(v, (int, np.integer)) and 1 <= v <= 8192):
            raise RenderInputError(name, "integer 1..8192", v)


def gbuffer(scene: Scene, width: int, height: int) -> GBuffer:
    """Ray-cast the scene from its camera: per-pixel geometry (row 0 at the top)."""
    check_size(width, height)
    origin, dirs = scene.camera.rays(width, height)
    hits = intersect(scene, origin, dirs)
    v = -dirs
    n = hits.normal
    r = 2.0 * np.sum(n * v, axis=-1, keepdims=True) * n - v
    return GBuffer(hits.mask, n, v, r, hits.paint, hits.position)


def check_paints(basis: PrefilteredBasis, paints: Sequence[LobeWeights]) -> list[LobeWeights]:
    """One or two paints whose exponents match the basis; one paint is used for both halves."""
    paints = list(paints)
    if not 1 <= len(paints) <= 2:
        raise RenderInputError("paints", "one or two LobeWeights", len(paints))
    for i, w in enumerate(paints):
        if len(w.exponents) != len(basis.exponents) or not np.allclose(w.exponents, basis.exponents):
            raise RenderInputError(f"paints[{i}].exponents", f"the basis exponents {basis.exponents}",
                                   w.exponents)
    return paints if len(paints) == 2 else paints * 2


def shade_pixels(basis: PrefilteredBasis, weights: LobeWeights, normal: np.ndarray, reflect: np.ndarray,
                 n_dot_v: np.ndarray, diffuse: str = "cube") -> np.ndarray:
    """Radiance (P, 3) of pixels with normals/reflected views (P, 3) and N·V (P,) (module equation)."""
    w_d, w_dd, w_g = weights.map_weights()
    d = sample_cube(basis.diffuse, normal) if diffuse == "cube" else sh_diffuse(basis.sh, normal)
    out = w_d * d
    for i, cube in enumerate(basis.cubes):
        out = out + (w_g[i] + n_dot_v[:, None] * w_dd[i]) * sample_cube(cube, reflect)
    return out


def render_linear(scene: Scene, basis: PrefilteredBasis, paints: Sequence[LobeWeights], width: int,
                  height: int, diffuse: str = "cube") -> np.ndarray:
    """Linear sRGB radiance image (H, W, 3) float32 of the scene lit by the prefiltered basis."""
    if diffuse not in ("cube", "sh"):
        raise RenderInputError("diffuse", "cube | sh", diffuse)
    pair = check_paints(basis, paints)
    g = gbuffer(scene, width, height)
    img = np.full((height, width, 3), BACKGROUND, dtype=np.float64)
    ndv = g.n_dot_v
    for k in (0, 1):
        m = g.mask & (g.paint == k)
        if m.any():
            img[m] = shade_pixels(basis, pair[k], g.normal[m], g.reflect[m], ndv[m], diffuse)
    return img.astype(np.float32)
