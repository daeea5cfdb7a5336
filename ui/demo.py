"""Demo content for screenshots and tests: a synthetic mood-board photo (two painted spheres rendered by
:func:`station.design.scene.shade` under the default point light) and a patch image of known colours."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from station.design.images import save_png
from station.design.scene import shade, sphere_scene, srgb_encode
from station.model import FaceFlopTravelGloss

DEMO_DESIGNS = (
    FaceFlopTravelGloss((62.0, 48.0, 30.0), (24.0, 38.0, 18.0), 70.0, 88.0),
    FaceFlopTravelGloss((70.0, -8.0, 42.0), (38.0, -14.0, 18.0), 60.0, 40.0),
)


def demo_photo(path: str | Path, size: int = 180) -> Path:
    """Write a PNG of two shaded spheres side by side (sRGB); returns the path."""
    scene = sphere_scene(size)
    halves = [srgb_encode(shade(scene, d, background=(0.05, 0.05, 0.06))) for d in DEMO_DESIGNS]
    return save_png(path, np.concatenate(halves, axis=1))


def patch_image(path: str | Path, colours: tuple[tuple[float, float, float], ...], size: int = 40) -> Path:
    """Write a PNG of uniform square patches of sRGB-encoded *colours* (0–1) side by side."""
    img = np.concatenate([np.broadcast_to(np.asarray(c, float), (size, size, 3)) for c in colours], axis=1)
    return save_png(path, img)
