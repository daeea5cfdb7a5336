"""The environment as the truth engine integrates it (:mod:`station.render.truth`): directions and solid
angles of an equirectangular map, bilinear lookups, and the split into point lights, a box-filtered
quadrature and a residual map (units: the map's radiance; convention in ``station.render.truth``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from station.model.colorimetry import REC709_LUMINANCE
from station.render.errors import RenderInputError

#: Pixels brighter than this multiple of the map's mean luminance become point lights.
POINT_THRESHOLD = 50.0
#: Most point lights extracted (the threshold rises until they fit).
MAX_POINT_LIGHTS = 4096
#: Width of the box-filtered quadrature map for broad kernels.
QUADRATURE_WIDTH = 256
#: Lobes whose half maximum is narrower than this many map pixels sample the whole map, the bright pixels
#: as area lights, instead of taking them as point lights (:func:`resolves_pixels`).
MIRROR_PIXELS = 2.0

#: Pixels per chunk of the truth engine's per-pixel sample sets (memory: chunk × samples × 3 floats).
PIXEL_CHUNK = 48


def _as_equirect(environment: Any) -> NDArray[np.float64]:
    img = np.asarray(getattr(environment, "equirect", environment), dtype=np.float64)
    if img.ndim != 3 or img.shape[2] != 3 or img.shape[1] != 2 * img.shape[0] or img.shape[0] < 2:
        raise RenderInputError(
            "environment", "an equirectangular radiance map (H, 2H, 3)", getattr(img, "shape", None)
        )
    if not np.all(np.isfinite(img)) or np.any(img < 0.0):
        raise RenderInputError("environment", "finite radiance >= 0", "non-finite or negative pixels")
    return img


def equirect_directions(height: int, width: int) -> NDArray[np.float64]:
    """Unit direction of each pixel centre, (H, W, 3) (convention in the module docstring)."""
    theta = np.pi * (np.arange(height) + 0.5) / height
    phi = 2.0 * np.pi * ((np.arange(width) + 0.5) / width - 0.5)
    st = np.sin(theta)[:, None]
    return np.stack(
        [st * np.sin(phi)[None, :], np.repeat(np.cos(theta)[:, None], width, 1), -st * np.cos(phi)[None, :]],
        axis=-1,
    )


def equirect_solid_angles(height: int, width: int) -> NDArray[np.float64]:
    """Solid angle (sr) of each pixel, (H, W); they sum to 4π."""
    edges = np.pi * np.arange(height + 1) / height
    band = 2.0 * np.pi * (np.cos(edges[:-1]) - np.cos(edges[1:])) / width
    return np.repeat(band[:, None], width, axis=1)


def sample_equirect(img: NDArray[np.float64], dirs: NDArray[np.float64]) -> NDArray[np.float64]:
    """Bilinear lookup of an equirect map along unit directions (..., 3) → (..., 3), wrapping in φ."""
    h, w = img.shape[:2]
    theta = np.arccos(np.clip(dirs[..., 1], -1.0, 1.0))
    phi = np.arctan2(dirs[..., 0], -dirs[..., 2])
    x = (phi / (2.0 * np.pi) + 0.5) * w - 0.5
    y = np.clip(theta / np.pi * h - 0.5, 0.0, h - 1.0)
    x0 = np.floor(x).astype(np.int64)
    y0 = np.minimum(np.floor(y).astype(np.int64), h - 2)
    tx = (x - x0)[..., None]
    ty = (y - y0)[..., None]
    x0 %= w
    x1 = (x0 + 1) % w
    top = img[y0, x0] * (1 - tx) + img[y0, x1] * tx
    bottom = img[y0 + 1, x0] * (1 - tx) + img[y0 + 1, x1] * tx
    return top * (1 - ty) + bottom * ty


def _box_downsample(
    img: NDArray[np.float64], weights: NDArray[np.float64], width: int
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Solid-angle-weighted box filter to (width/2, width); returns (radiance, solid angles)."""
    h, w = img.shape[:2]
    if w <= width:
        return img, weights
    f = w // width
    if w % width:
        raise RenderInputError("quadrature_width", f"a divisor of the map width {w}", width)
    flux = (img * weights[..., None]).reshape(h // f, f, width, f, 3).sum(axis=(1, 3))
    om = weights.reshape(h // f, f, width, f).sum(axis=(1, 3))
    return flux / om[..., None], om


@dataclass(frozen=True)
class Lighting:
    """An environment split for integration (module docstring).

    Attributes
    ----------
    residual
        (H, W, 3) the map with point-light pixels removed (set to their neighbours' median level).
    quad_dirs, quad_flux
        (M, 3) directions and (M, 3) radiance × solid angle of the box-filtered residual.
    point_dirs, point_flux
        (P, 3) directions and (P, 3) radiance × solid angle of the extracted point lights.
    full
        (H, W, 3) the whole map, point-light pixels included: what lobes narrower than a pixel
        (:func:`resolves_pixels`) sample, the bright pixels then being small area lights.
    """

    residual: NDArray[np.float64]
    quad_dirs: NDArray[np.float64]
    quad_flux: NDArray[np.float64]
    point_dirs: NDArray[np.float64]
    point_flux: NDArray[np.float64]
    full: NDArray[np.float64]


def resolves_pixels(exponent: float, height: int) -> bool:
    """True when a cos^E lobe is narrower than MIRROR_PIXELS pixels of a map of *height* rows.

    Its half-maximum angle ψ_½ = arccos 2^(−1/E) is then below MIRROR_PIXELS · π/H: a point light at a
    pixel centre would fall in or out of the lobe by where the centre lies (a mirror misses the sun
    altogether), so the lobe samples the whole map instead, bright pixels as the areas they cover.
    """
    half = math.acos(2.0 ** (-1.0 / max(float(exponent), 1e-12)))
    return half < MIRROR_PIXELS * math.pi / height


def prepare_lighting(
    environment: Any, quadrature_width: int = QUADRATURE_WIDTH, point_threshold: float = POINT_THRESHOLD
) -> Lighting:
    """Split *environment* into point lights, a quadrature and a residual map (module docstring)."""
    img = _as_equirect(environment)
    h, w = img.shape[:2]
    dirs = equirect_directions(h, w)
    om = equirect_solid_angles(h, w)
    lum = img @ REC709_LUMINANCE
    mean_lum = float((lum * om).sum() / (4.0 * np.pi))
    threshold = point_threshold * max(mean_lum, 1e-30)
    bright = lum > threshold
    while bright.sum() > MAX_POINT_LIGHTS:
        threshold *= 2.0
        bright = lum > threshold
    residual = img.copy()
    if bright.any():
        fill = np.median(img[~bright], axis=0) if (~bright).any() else np.zeros(3)
        residual[bright] = np.minimum(img[bright], fill)
    point_flux = (img[bright] - residual[bright]) * om[bright][:, None]
    q_img, q_om = _box_downsample(residual, om, quadrature_width)
    q_dirs = equirect_directions(*q_img.shape[:2])
    return Lighting(
        residual,
        q_dirs.reshape(-1, 3),
        (q_img * q_om[..., None]).reshape(-1, 3),
        dirs[bright],
        point_flux,
        img,
    )


def tangent_frames(axis: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Two unit vectors completing an orthonormal frame about each unit *axis* (P, 3)."""
    helper = np.where(np.abs(axis[:, 1:2]) < 0.9, np.array([[0.0, 1.0, 0.0]]), np.array([[1.0, 0.0, 0.0]]))
    t = np.cross(helper, axis)
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    return t, np.cross(axis, t)
