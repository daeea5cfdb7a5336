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
from station.render.errors import EnvironmentFileError
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
            raise EnvironmentFileError(self.name, ACCEPTED + " in equirectangular layout (width = 2 × height)",
                                       f"got {w}x{h}")
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
