"""Maps a GL renderer derives from its prefiltered basis on first use (:class:`DerivedMaps`), one per
parameter and uploaded once: the flakes' glint map (the sharpest lobe map) and their mean map C_E per
flake spread (:func:`station.render.flakes.flake_mean_cube`), both shared-exponent, and the clear coat's
coat-transmitted diffuse map per refractive index (:func:`station.render.prefilter.coat_diffuse_map`)."""

from __future__ import annotations

from typing import Any

import numpy as np

from station.model.flakes import FlakeLayer
from station.model.gloss import ClearCoat
from station.render import gl_textures as tx
from station.render.flakes import flake_mean_cube
from station.render.prefilter import coat_diffuse_map

__all__ = ["DerivedMaps"]


class DerivedMaps:
    """The derived cube textures of *basis* on *ctx* (*half_float*: the coat map's texel format)."""

    def __init__(self, ctx: Any, basis: Any, half_float: bool) -> None:
        self.ctx, self.basis, self.half_float = ctx, basis, half_float
        self._flake_means: dict[float, Any] = {}  # spread → mean map texture
        self._coat: dict[float, Any] = {}  # coat index → coat-transmitted diffuse cube
        self._glint: Any = None  # the sharpest lobe map, shared-exponent

    def glint(self) -> Any:
        """The flakes' glint map L_sharp: the basis's sharpest lobe map as a shared-exponent cube
        (:func:`station.render.gl_textures.shared_exponent_cube`), uploaded once."""
        if self._glint is None:
            sharp = int(np.argmax(self.basis.exponents))
            self._glint = tx.shared_exponent_cube(self.ctx, np.asarray(self.basis.cubes[sharp]))
        return self._glint

    def flake_mean(self, flakes: FlakeLayer) -> Any:
        """The flakes' mean map C_E for this layer's spread, uploaded once per spread."""
        key = round(flakes.spread_deg, 6)
        if key not in self._flake_means:
            self._flake_means[key] = tx.shared_exponent_cube(self.ctx, flake_mean_cube(self.basis, flakes))
        return self._flake_means[key]

    def bind_flakes(self, flakes: FlakeLayer, glint_unit: int, mean_unit: int) -> None:
        """Bind the glint map (:meth:`glint`) and the mean map of *flakes* (:meth:`flake_mean`) to the
        texture units *glint_unit* and *mean_unit*."""
        self.glint().use(glint_unit)
        self.flake_mean(flakes).use(mean_unit)

    def coat_diffuse(self, coat: ClearCoat) -> Any:
        """The coat-transmitted diffuse cube of *coat* (summed on this context, which binds its own target
        and textures: bind the frame's after it), made once per coat index."""
        if coat.index not in self._coat:
            cube = coat_diffuse_map(self.basis, coat, self.ctx)
            self._coat[coat.index] = tx.cube_texture(self.ctx, cube, self.half_float)
        return self._coat[coat.index]

    def release(self) -> None:
        """Free every derived map."""
        for tex in [*self._flake_means.values(), *self._coat.values(), self._glint]:
            if tex is not None:
                tex.release()
        self._glint = None
        self._flake_means.clear()
        self._coat.clear()
