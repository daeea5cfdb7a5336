"""The maps a point in a light's shadow reflects, on the GPU (:class:`ShadowedMaps`).

The narrow lobes, the flakes' glint map and their mean map are prefiltered from the whole environment,
sun included (``station.render.prefilter``: only the wide lobes lose the extracted lights, which the
shader adds back exactly). Where a light's shadow map says a point does not see that light, the point
must not reflect it either: not in its sharp gloss highlight and not in its flakes' glints. The light's
share of those maps is the map of its own pixels alone (:func:`station.render.light_maps.light_lobe_maps`,
the same prefilter, which is linear), so the map without the light is the map less that share, taken here
in float32 once. A point that has lost L_j = 1 − V_j of the shadowed lights j reads
X (1 − Σ L_j) + Σ L_j X_j (X the map, X_j the map without light j): the full map in the light, the
map without the light in its shadow. Mixing the two maps, rather than taking the share from the map on the
GPU, keeps the rest of the environment exact in the shadow: the sun's texels hold thousands of times the
sky's radiance, and half floats (or shared exponents) of the full map carry the sun's rounding.

Per shadowed light this module holds both paints' narrow gloss and directionally diffuse sums without the
light, as atlases laid out like the frame's own (:class:`station.render.gl_textures.NarrowAtlas`, redrawn
when the weights change), the glint map without it, and the flakes' mean map without it for a flake spread
(:func:`station.render.flakes.flake_mean_cube`), shared-exponent as the maps they stand in for. They are
made on first use: a frame without object shadows never pays for them.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from station.model.flakes import FlakeLayer
from station.render import gl_textures as tx
from station.render.flakes import flake_mean_cube, glint_lobe
from station.render.light_maps import light_lobe_maps

__all__ = ["ShadowedMaps"]


class ShadowedMaps:
    """Maps without each shadowed light for one renderer on *ctx*: *basis* (with ``basis.lights``), the
    renderer's binding *order* and its *narrow* mask (1 per bound lobe summed into the atlases), *face*
    the atlases' texels a face, *half_float* their format."""

    def __init__(
        self, ctx: Any, basis: Any, order: np.ndarray, narrow: np.ndarray, face: int, half_float: bool
    ) -> None:
        self.ctx, self.basis, self.order, self.narrow = ctx, basis, order, narrow
        self.face, self.half_float = face, half_float
        self._atlas: dict[int, tuple[list, tx.NarrowAtlas]] = {}  # light → (lobe textures, atlas)
        self._glint: dict[int, tuple[Any, np.ndarray]] = {}  # light → (glint texture, its cube)
        self._mean: dict[tuple[int, float], Any] = {}  # (light, spread) → mean texture

    def _without(self, light: int) -> list[np.ndarray]:
        """The basis's maps without *light*, in bound order: the map less the light's share for the lobes
        that keep the whole environment, the map itself for the others (their lights are shaded exactly)."""
        keep = {int(self.order[k]) for k in np.nonzero(self.narrow)[0]} | {glint_lobe(self.basis.exponents)}
        lobes = sorted(i for i in keep if not self.basis.wide[i])
        shares = light_lobe_maps(self.basis, light, lobes, self.ctx)
        cubes = [np.asarray(c, np.float32) for c in self.basis.cubes]
        for i, share in shares.items():
            cubes[i] = np.maximum(cubes[i] - share, 0.0)
        return cubes

    def _make(self, light: int) -> None:
        cubes = self._without(light)
        texs = [tx.cube_texture(self.ctx, cubes[int(i)], self.half_float) for i in self.order]
        atlas = tx.NarrowAtlas(self.ctx, texs, self.narrow, self.face, self.half_float)
        self._atlas[light] = (texs, atlas)
        glint = cubes[glint_lobe(self.basis.exponents)]
        self._glint[light] = (tx.shared_exponent_cube(self.ctx, glint), glint)

    def atlases(self, light: int, mw: list) -> list:
        """[gloss, dd] atlases without *light* for the paints' bound weights *mw*."""
        if light not in self._atlas:
            self._make(light)
        return self._atlas[light][1].atlases(mw)

    def glint(self, light: int) -> Any:
        """The glint map without *light* (shared-exponent cube)."""
        if light not in self._glint:
            self._make(light)
        return self._glint[light][0]

    def flake_mean(self, light: int, flakes: FlakeLayer) -> Any:
        """The flakes' mean map without *light* for this layer's spread."""
        key = (light, round(flakes.spread_deg, 6))
        if key not in self._mean:
            self.glint(light)
            cube = flake_mean_cube(self.basis, flakes, self._glint[light][1])
            self._mean[key] = tx.shared_exponent_cube(self.ctx, cube)
        return self._mean[key]

    def prepare(self, slots: tuple[int, ...], mw: list, flakes: FlakeLayer | None) -> None:
        """Make (or redraw for new weights) every map of the shadowed lights *slots* that :meth:`bind`
        binds: the atlases draw on their own target and bind their own textures, so this comes before the
        frame binds its own."""
        for light in slots:
            self.atlases(light, mw)
            if flakes is not None:
                self.flake_mean(light, flakes)

    def bind(self, slots: tuple[int, ...], mw: list, flakes: FlakeLayer | None, first_unit: int) -> dict:
        """Bind the maps without the shadowed lights *slots* from texture unit *first_unit* on (four a
        light: gloss atlas, dd atlas, glint, mean) and return their uniforms (``_shadowed_*`` arrays for
        ``set_uniforms``), made by :meth:`prepare` for the same *mw*."""
        units: dict[str, list[int]] = {"gloss": [], "dd": [], "glint": [], "mean": []}
        for j, light in enumerate(slots):
            base = first_unit + 4 * j
            gloss, dd = self.atlases(light, mw)
            gloss.use(base)
            dd.use(base + 1)
            if flakes is not None:
                self.glint(light).use(base + 2)
                self.flake_mean(light, flakes).use(base + 3)
            for k, name in enumerate(units):
                units[name].append(base + k)
        return {f"_shadowed_{name}": values for name, values in units.items()}

    def release(self) -> None:
        """Free every map."""
        for texs, atlas in self._atlas.values():
            atlas.release()
            for tex in texs:
                tex.release()
        for tex, _ in self._glint.values():
            tex.release()
        for tex in self._mean.values():
            tex.release()
        self._atlas.clear()
        self._glint.clear()
        self._mean.clear()
