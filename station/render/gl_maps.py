"""Maps a GL renderer derives from its prefiltered basis on first use (:class:`DerivedMaps`), one per
parameter and uploaded once: the flakes' glint map (the sharpest lobe map) and their mean map C_E per
flake spread (:func:`station.render.flakes.flake_mean_cube`), both shared-exponent, the clear coat's
coat-transmitted diffuse map per refractive index (:func:`station.render.prefilter.coat_diffuse_map`) and
both paints' diffuse base under the coat pre-mixed from the two diffuse maps (:meth:`DerivedMaps.coat_base`)."""

from __future__ import annotations

from typing import Any

import numpy as np

from station.model.flakes import FlakeLayer
from station.model.gloss import ClearCoat
from station.render import gl_textures as tx
from station.render.flakes import flake_mean_cube, glint_lobe
from station.render.prefilter import COAT_DIFFUSE_SIZE, coat_diffuse_map

__all__ = ["DerivedMaps"]


class DerivedMaps:
    """The derived cube textures of *basis* on *ctx* (*half_float*: the coat map's texel format)."""

    def __init__(self, ctx: Any, basis: Any, half_float: bool) -> None:
        self.ctx, self.basis, self.half_float = ctx, basis, half_float
        self._flake_means: dict[float, Any] = {}  # spread → mean map texture
        self._coat: dict[float, Any] = {}  # coat index → coat-transmitted diffuse cube
        self._glint: Any = None  # the sharpest lobe map, shared-exponent
        self._base: tuple | None = None  # (pass of gl_textures.diffuse_combine_pass, key of its atlas)
        #: Texels per face of the coat's diffuse-base atlas (:meth:`coat_base`): the finer of the two maps.
        self.base_face = max(int(basis.diffuse.shape[1]), COAT_DIFFUSE_SIZE)

    def glint(self) -> Any:
        """The flakes' glint map L_sharp: the basis's sharpest lobe map as a shared-exponent cube
        (:func:`station.render.gl_textures.shared_exponent_cube`), uploaded once."""
        if self._glint is None:
            sharp = glint_lobe(self.basis.exponents)
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

    def coat_base(self, diffuse: Any, coat: ClearCoat, w_plain: list, w_coat: list) -> Any:
        """Both paints' diffuse base under *coat* in one atlas (``shaders/combine_diffuse.frag.glsl``): the
        diffuse map *diffuse* times *w_plain* (pi K_A per paint, RGB) plus the coat-transmitted map
        (:meth:`coat_diffuse`) times *w_coat* (pi K_D), at the finer map's resolution; redrawn only when
        the coat or the weights change. Draws on this context's own target: bind the frame's after it."""
        coat_tex = self.coat_diffuse(coat)
        face = self.base_face
        key = (coat.index, np.asarray([w_plain, w_coat], np.float32).tobytes())
        if self._base is None:
            self._base = (tx.diffuse_combine_pass(self.ctx, face, self.half_float), None)
        combine, drawn = self._base
        if drawn != key:
            tx.draw_diffuse_combined(self.ctx, combine, diffuse, coat_tex, face, w_plain, w_coat)
            self._base = (combine, key)
        return combine[3]

    def _release_base(self) -> None:
        if self._base is not None:
            for obj in self._base[0]:
                obj.release()
            self._base = None

    def release(self) -> None:
        """Free every derived map."""
        self._release_base()
        for tex in [*self._flake_means.values(), *self._coat.values(), self._glint]:
            if tex is not None:
                tex.release()
        self._glint = None
        self._flake_means.clear()
        self._coat.clear()
