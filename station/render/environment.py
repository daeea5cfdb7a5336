"""Distant lighting environments: scene-linear sRGB radiance over the sphere of directions.

An :class:`Environment` holds an equirectangular radiance image (H = W/2, see
:mod:`station.render.cubemap` for the direction convention) in linear sRGB primaries (D65 white),
relative units: a constant environment of radiance 1 lights a white Lambertian surface to radiance 1.
Environments come from HDR files (:func:`load_environment`) or the procedural generators in
:mod:`station.render.procedural`.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np

from station.render import cubemap
from station.render.errors import EnvironmentFileError, RenderInputError
from station.render.hdr_io import ACCEPTED, read_hdr_image, validate_image


@dataclass(frozen=True, eq=False)
class Environment:
    """An equirectangular radiance map (H, W, 3) float32 with W = 2H, and a name for reports."""

    name: str
    equirect: np.ndarray = field(repr=False)

    def __post_init__(self) -> None:
        img = np.ascontiguousarray(self.equirect, dtype=np.float32)
        validate_image(img, self.name)
        h, w = img.shape[:2]
        if w != 2 * h:
            raise EnvironmentFileError(
                self.name, ACCEPTED + " in equirectangular layout (width = 2 × height)", f"got {w}x{h}"
            )
        img.setflags(write=False)
        object.__setattr__(self, "equirect", img)

    @property
    def height(self) -> int:
        """Rows of the equirectangular image."""
        return int(self.equirect.shape[0])

    @cached_property
    def content_hash(self) -> str:
        """SHA-256 of the pixel data and shape (hex), the disk-cache key of prefiltered maps."""
        digest = hashlib.sha256(str(self.equirect.shape).encode())
        digest.update(self.equirect.tobytes())
        return digest.hexdigest()

    def radiance(self, dirs: np.ndarray) -> np.ndarray:
        """Radiance along directions (..., 3) by bilinear lookup, (..., 3) float64."""
        return cubemap.sample_equirect(self.equirect, dirs)

    def to_cube(self, size: int) -> np.ndarray:
        """Cube map (6, size, size, 3) float32 of this environment."""
        return cubemap.equirect_to_cube(self.equirect, size)

    def mean_radiance(self) -> np.ndarray:
        """Solid-angle-weighted mean radiance (3,): the value of every map for a constant environment."""
        w = cubemap.equirect_solid_angles(*self.equirect.shape[:2])
        return (self.equirect * w[..., None]).sum(axis=(0, 1)) / (4.0 * np.pi)

    def downsampled(self, width: int) -> Environment:
        """This environment box-filtered to width ≤ *width* (powers of two)."""
        img = cubemap.downsample_equirect(self.equirect, width)
        return Environment(f"{self.name}@{img.shape[1]}", img)


def load_environment(path: str | Path) -> Environment:
    """Load an equirectangular .hdr or .exr file; EnvironmentFileError when it is not usable."""
    path = Path(path)
    return Environment(path.stem, read_hdr_image(path))


LIGHT_THRESHOLD = 5.0  # × the mean luminance
MAX_LIGHTS = 8


def spread_exponent(exponent: float, spread: np.ndarray) -> np.ndarray:
    """Exponent E / (1 + E s²) of a Phong lobe of *exponent* E smoothed over lights of angular *spread*
    s² (rad², :class:`Lights`): the Gaussian variances add, 1/E' = 1/E + s² (dimensionless)."""
    return exponent / (1.0 + exponent * np.asarray(spread, dtype=float))


@dataclass(frozen=True, eq=False)
class Lights:
    """Directional lights taken out of an environment: unit directions (k, 3), flux (k, 3), and their
    angular spread (k,) in rad² (default: none, point lights).

    The flux of a light is Σ radiance × solid angle over its pixels (linear sRGB, radiance × sr), so a
    lobe p(ω) integrates it as flux · p(direction). The spread s² is the per-axis variance of the light's
    directions about its mean direction, 1 − |Σ w ω| / Σ w over its pixels (w: luminous flux), which is
    E[θ²]/2 for small angles θ. A Phong lobe of exponent E is, near its axis, a Gaussian of per-axis
    variance 1/E, so over a light of spread s² it integrates like the point light under the lobe of
    exponent E / (1 + E s²) (:func:`spread_exponent`): a booth's lamp, tens of degrees wide, is not a
    point for the wide lobes that shade it (with the point, the directionally diffuse highlight of a
    silver under the booth's lamps was 3–5 ΔE00 too sharp at p95).
    """

    directions: np.ndarray
    flux: np.ndarray
    spread: np.ndarray | None = None
    #: The pixels each light was made of in its environment (:func:`extract_lights`): (H, W) of the
    #: equirectangular image and, per light, the flat pixel indices and their radiance (n, 3); None for
    #: lights given by direction and flux alone.
    pixels: tuple[tuple[int, int], tuple[tuple[np.ndarray, np.ndarray], ...]] | None = field(
        default=None, repr=False
    )

    def light_environment(self, k: int) -> Environment:
        """Light *k* alone: an environment dark but for the pixels it was taken from (prefiltered like the
        full map, the share of a lobe map this light holds: prefiltering is linear in the radiance);
        RenderInputError naming ``light`` when the lights carry no pixels or *k* is out of range."""
        if self.pixels is None or not 0 <= k < self.count:
            raise RenderInputError("light", f"0 <= light < {self.count}, lights from an environment", k)
        (h, w), parts = self.pixels
        index, radiance = parts[k]
        img = np.zeros((h * w, 3), np.float32)
        img[index] = radiance
        return Environment(f"light{k}", img.reshape(h, w, 3))

    def spreads(self) -> np.ndarray:
        """Angular spread s² (k,) in rad², zeros for point lights."""
        return np.zeros(self.count) if self.spread is None else np.asarray(self.spread, dtype=float)

    @property
    def count(self) -> int:
        """Number of lights."""
        return int(self.directions.shape[0])


def extract_lights(
    env: Environment, threshold: float = LIGHT_THRESHOLD, max_lights: int = MAX_LIGHTS
) -> tuple[Environment, Lights]:
    """Split *env* into a residual map and up to *max_lights* compact bright sources (the sun).

    Pixels brighter than *threshold* × the mean luminance are grouped into 8-connected components
    (wrapping in azimuth); the *max_lights* components of largest luminous flux become lights at
    their flux-weighted mean direction, and their pixels are zeroed in the residual. Smaller
    components stay in the map. The residual is what wide lobes are prefiltered from, the lights
    are shaded exactly (``numpy_renderer``).
    """
    from scipy import ndimage

    from station.model.colorimetry import REC709_LUMINANCE

    img = env.equirect
    h, w = img.shape[:2]
    sa = cubemap.equirect_solid_angles(h, w)
    lum = img @ REC709_LUMINANCE.astype(np.float32)
    mean = float((lum * sa).sum() / (4.0 * np.pi))
    bright = lum > threshold * mean
    if not bright.any():
        return env, Lights(np.zeros((0, 3)), np.zeros((0, 3)))
    labels, n = ndimage.label(bright, structure=np.ones((3, 3), bool))
    # join components split by the azimuth seam (union-find over the labels met across it)
    parent = np.arange(n + 1)

    def root(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for a, b in zip(labels[:, 0], labels[:, -1], strict=True):
        if a and b:
            ra, rb = root(int(a)), root(int(b))
            if ra != rb:
                parent[rb] = ra
    labels = np.array([root(i) for i in range(n + 1)])[labels]
    flat = labels.ravel()
    weight = (lum * sa).ravel()
    size = n + 1
    flux_lum = np.bincount(flat, weights=weight, minlength=size)
    flux_lum[0] = 0.0
    keep = [int(i) for i in np.argsort(-flux_lum) if flux_lum[i] > 0][:max_lights]
    dirs = cubemap.equirect_directions(h, w).reshape(-1, 3)
    rad_sa = (img * sa[..., None]).reshape(-1, 3)
    vec = np.stack([np.bincount(flat, weights=weight * dirs[:, c], minlength=size) for c in range(3)], -1)
    flux = np.stack([np.bincount(flat, weights=rad_sa[:, c], minlength=size) for c in range(3)], -1)
    kept = np.zeros(size, bool)
    kept[keep] = True
    residual = img.copy()
    residual[kept[labels]] = 0.0
    out_dirs = vec[keep] / np.linalg.norm(vec[keep], axis=1, keepdims=True)
    out_flux = flux[keep]
    total = np.bincount(flat, weights=weight, minlength=size)[keep]
    spread = np.clip(1.0 - np.linalg.norm(vec[keep], axis=1) / np.maximum(total, 1e-30), 0.0, 1.0)
    flat_img = img.reshape(-1, 3)
    parts = tuple((idx, flat_img[idx].copy()) for idx in (np.flatnonzero(flat == k) for k in keep))
    lights = Lights(out_dirs, out_flux, spread, pixels=((h, w), parts))
    return Environment(f"{env.name}-lights", residual), lights
