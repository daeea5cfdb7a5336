"""The tweaker's view of the main scene (Qt-free): the shape, camera and environment of the 3D view.

:func:`main_scene` ray-casts the view's shape from its orbit camera (``station.render.numpy_renderer.gbuffer``)
and builds the environment-lit basis images of the 3D view (:class:`ui.models.view.BasisImages`), so the
tweaker shows the object as the 3D view does. The tweaker's geometry (θ per pixel for eq 3.6.4, the iso-angle
rings, the highlight edge) is taken against the environment's dominant light — the direction of its
first-order SH term (``station.render.buffers.dominant_light_direction``) — with
``station.render.buffers.angle_buffers``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from station.design.scene import Scene, scene_from_buffers
from station.model import FaceFlopTravelGloss
from station.render.buffers import angle_buffers, dominant_light_direction
from station.render.numpy_renderer import gbuffer
from ui.models.view import PREFILTER_MAX_SIZE, BasisImages, ViewSettings, paint_weights


@dataclass(frozen=True, eq=False)
class MainScene:
    """The view settings, their basis images and the tweaker's per-pixel geometry at one size."""

    settings: ViewSettings
    basis: BasisImages
    scene: Scene

    def image(self, design: FaceFlopTravelGloss) -> np.ndarray:
        """8-bit sRGB (H, W, 3) of *design* on the whole object, environment lit, at the view's exposure."""
        w = paint_weights(design)
        return np.ascontiguousarray(self.basis.composite_display((w, w), self.settings.exposure_ev))


def main_scene(
    settings: ViewSettings, width: int, height: int, prefilter_size: int = PREFILTER_MAX_SIZE
) -> MainScene:
    """Basis images and tweaker geometry of the 3D view's scene at *width* × *height* pixels (seconds at
    the canvas size, a tenth of a second at 160 pixels a side); *prefilter_size* caps the prefiltered
    environment's cube faces (:func:`ui.models.view.environment_basis`)."""
    basis = BasisImages.compute(settings, width, height, prefilter_size)
    g = gbuffer(settings.scene(), width, height)
    light = dominant_light_direction(basis.core.basis.sh)
    ab = angle_buffers(g, light)
    scene = scene_from_buffers(
        ab.aspecular_deg,
        ab.mask,
        incidence_deg=ab.incidence_deg,
        normals=np.where(ab.mask[..., None], g.normal, 0.0),
        light_dir=light,
        name=f"{settings.shape}-{settings.environment}",
    )
    return MainScene(settings, basis, scene)
