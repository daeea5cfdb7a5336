"""A light's share of the prefiltered maps (:func:`light_lobe_maps`): the maps of its own pixels alone,
prefiltered as the basis's maps were. The narrow lobes and the flakes' glint map keep the whole environment,
sun included; a point in a light's shadow reflects the map less that light's share
(``station.render.gl_light_maps`` on the GPU, ``numpy_renderer.light_share_loss``)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from station.render.envcache import PrefilterCache
from station.render.errors import RenderError, RenderInputError
from station.render.prefilter import PrefilteredBasis, compute_maps, sample_count, source_size

__all__ = ["light_lobe_maps"]


def light_lobe_maps(
    basis: PrefilteredBasis, light: int, lobes: Sequence[int], ctx=None
) -> dict[int, np.ndarray]:
    """The share of the maps of *lobes* (indices into ``basis.exponents``) that extracted light *light*
    holds: its environment alone (:meth:`station.render.environment.Lights.light_environment`) prefiltered
    by the rule and engine of the basis's own maps (face size, quadrature grid), so a map less this share
    is the map without that light (prefiltering is linear). Meant for lobes that keep the full environment
    (``basis.wide`` False): a shadowed point loses the light's share of them. Disk-cached in
    ``basis.cache`` as the basis's maps are, and kept in ``basis.light_maps``; RenderInputError naming
    ``light`` without such a light (or for lights that carry no pixels)."""
    asked = list(lobes)
    lobes = [i for i in lobes if (light, i) not in basis.light_maps]
    if lobes:
        _light_maps(basis, light, lobes, ctx)
    return {i: basis.light_maps[(light, i)] for i in asked}


def _light_maps(basis: PrefilteredBasis, light: int, lobes: Sequence[int], ctx) -> None:
    """Prefilter light *light*'s share of *lobes* into ``basis.light_maps`` (:func:`light_lobe_maps`)."""
    if basis.lights is None:
        raise RenderInputError("light", "a basis with lights taken out of its environment", light)
    env = basis.lights.light_environment(light)
    src = source_size(env)
    engine = "gl" if basis.engine == "gl" else "numpy"
    plan = [
        (basis.exponents[i], int(basis.cubes[i].shape[1]), sample_count(int(basis.cubes[i].shape[1])))
        for i in lobes
    ]
    keys = ["share-" + PrefilterCache.key(env.content_hash, e, size, src, n, engine) for e, size, n in plan]
    cache = basis.cache
    cubes: list[np.ndarray | None] = [
        cache.get(k, (6, p[1], p[1], 3)) if cache else None for k, p in zip(keys, plan, strict=True)
    ]
    todo = [j for j, c in enumerate(cubes) if c is None]
    if todo:
        compute_maps(env, env, src, plan, [False] * len(plan), todo, cubes, engine, ctx, {}, basis.diffuse)
    for j, i in enumerate(lobes):
        cube = cubes[j]
        if cube is None:
            raise RenderError("prefilter: a light's map was neither cached nor computed")
        if j in todo and cache:  # kept in float32: a map less the share must not lose the rest to rounding
            cache.put(keys[j], cube, np.float32)
        basis.light_maps[(light, i)] = cube
