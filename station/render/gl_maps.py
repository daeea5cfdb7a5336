"""Maps a GL renderer derives from its prefiltered basis on first use (:class:`DerivedMaps`), one per
parameter and uploaded once: the flakes' mean map C_E per flake spread
(:func:`station.render.flakes.flake_mean_cube`) and the clear coat's coat-transmitted diffuse map per
refractive index (:func:`station.render.prefilter.coat_diffuse_map`)."""

from __future__ import annotations

from typing import Any

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

    def flake_mean(self, flakes: FlakeLayer) -> Any:
        """The flakes' mean map C_E for this layer's spread, uploaded once per spread."""
        key = round(flakes.spread_deg, 6)
        if key not in self._flake_means:
            self._flake_means[key] = tx.cube_texture(self.ctx, flake_mean_cube(self.basis, flakes), False)
        return self._flake_means[key]

    def coat_diffuse(self, coat: ClearCoat) -> Any:
        """The coat-transmitted diffuse cube of *coat* (summed on this context, which binds its own target
        and textures: bind the frame's after it), made once per coat index."""
        if coat.index not in self._coat:
            cube = coat_diffuse_map(self.basis, coat, self.ctx)
            self._coat[coat.index] = tx.cube_texture(self.ctx, cube, self.half_float)
        return self._coat[coat.index]

    def release(self) -> None:
        """Free every derived map."""
        for tex in [*self._flake_means.values(), *self._coat.values()]:
            tex.release()
        self._flake_means.clear()
        self._coat.clear()
