"""Ground truth of the flake layer's sparkle (the truth engine's flakes; :mod:`station.render.truth`)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from station.model.flakes import FlakeLayer
from station.render.truth_lighting import (
    PIXEL_CHUNK,
    Lighting,
    _as_equirect,
    prepare_lighting,
    sample_equirect,
    tangent_frames,
)

__all__ = ["flake_sparkle_truth"]


def flake_sparkle_truth(
    environment: Any,
    flakes: FlakeLayer,
    tint: ArrayLike,
    positions: ArrayLike,
    normals: ArrayLike,
    views: ArrayLike,
    distance: ArrayLike,
    tan_half_fov: float,
    height: int,
    *,
    samples: int = 256,
    lighting: Lighting | None = None,
) -> NDArray[np.float64]:
    """Ground truth of the flake layer's sparkle per pixel, (P, 3), unclipped (the renderers then add
    max(sparkle, −reflectance · radiance), :func:`station.render.flakes.clip_sparkle`).

    The flake model of :mod:`station.render.flakes` (the same cell levels, weights w_k and flake normals m,
    :func:`~station.render.flakes.flake_levels`) without its two map approximations:
    tint · reflectance · Σ_k w_k (L(R_m,k) 1[R_m,k·N > 0] − E_m[L(R_m) 1[R_m·N > 0]]), with L the full-resolution
    map (sun disc included) looked up bilinearly at the flake's mirror direction R_m instead of the
    sharpest prefiltered map, and the expectation over the flake-normal distribution itself instead of a
    Phong lobe map: for the map without its point lights by *samples* stratified normals (Box–Muller on a
    √samples × √samples grid), and for each point light l (flux Φ) exactly as Φ p_R(l): the flake normal
    reflecting V to l is the half vector H = (l + V)/|l + V|, whose density under
    m = normalize(N + σ g), g ~ N(0, I₂), is exp(−|g|²/2) / (2π σ² (H·N)³) with σ g = (H·T, H·B)/(H·N)
    (the gnomonic projection), and p_R(l) = p_m(H) / (4 V·H).

    *positions* (P, 3) world, *normals*, *views* (P, 3) unit (the environment's frame), *distance* (P,)
    from the eye (scene units), *tan_half_fov* and *height* the camera's (they set the cells), *tint* (3,)
    the paint's flake tint (:func:`station.render.flakes.flake_tint`).
    """
    from station.render.flakes import flake_levels

    n = np.asarray(normals, dtype=float).reshape(-1, 3)
    v = np.asarray(views, dtype=float).reshape(-1, 3)
    full = _as_equirect(environment)
    light = prepare_lighting(full) if lighting is None else lighting
    glint = np.zeros_like(n)
    weight = np.zeros(n.shape[0])
    ndv = np.clip(np.sum(n * v, axis=-1), 0.0, 1.0)
    d = np.asarray(distance, dtype=float).reshape(-1)
    for w, m in flake_levels(flakes, np.asarray(positions, dtype=float), n, d, ndv, tan_half_fov, height):
        rm = 2.0 * np.sum(m * v, axis=-1, keepdims=True) * m - v
        glint += w[:, None] * sample_equirect(full, rm) * (np.sum(rm * n, axis=-1) > 0.0)[:, None]
        weight += w
    # Expected reflection: stratified flake normals over the residual map ...
    side = max(4, int(round(math.sqrt(samples))))
    u1, u2 = np.meshgrid((np.arange(side) + 0.5) / side, (np.arange(side) + 0.5) / side)
    rad = np.sqrt(-2.0 * np.log(u1.ravel()))
    gs = np.stack([rad * np.cos(2.0 * np.pi * u2.ravel()), rad * np.sin(2.0 * np.pi * u2.ravel())], -1)
    t, b = tangent_frames(n)
    sigma = math.radians(flakes.spread_deg)
    mean = np.zeros_like(n)
    for s in range(0, n.shape[0], PIXEL_CHUNK):
        sl = slice(s, min(n.shape[0], s + PIXEL_CHUNK))
        ms = n[sl, None, :] + sigma * (gs[None, :, 0:1] * t[sl, None, :] + gs[None, :, 1:2] * b[sl, None, :])
        ms /= np.linalg.norm(ms, axis=-1, keepdims=True)
        rs = 2.0 * np.einsum("pkc,pc->pk", ms, v[sl])[..., None] * ms - v[sl, None, :]
        up = np.einsum("pkc,pc->pk", rs, n[sl]) > 0.0
        mean[sl] = (sample_equirect(light.residual, rs) * up[..., None]).mean(axis=1)
    # ... and the point lights exactly.
    if light.point_dirs.shape[0]:
        for s in range(0, n.shape[0], PIXEL_CHUNK):
            sl = slice(s, min(n.shape[0], s + PIXEL_CHUNK))
            hv = light.point_dirs[None, :, :] + v[sl, None, :]
            hv /= np.maximum(np.linalg.norm(hv, axis=-1, keepdims=True), 1e-12)
            hn = np.einsum("pkc,pc->pk", hv, n[sl])
            ok = (hn > 1e-6) & ((light.point_dirs @ n[sl].T).T > 0.0)
            hn_safe = np.where(ok, hn, 1.0)
            gx = np.einsum("pkc,pc->pk", hv, t[sl]) / hn_safe / sigma
            gy = np.einsum("pkc,pc->pk", hv, b[sl]) / hn_safe / sigma
            pm = np.exp(-0.5 * (gx * gx + gy * gy)) / (2.0 * np.pi * sigma * sigma * hn_safe**3)
            vh = np.maximum(np.einsum("pkc,pc->pk", hv, v[sl]), 1e-6)
            mean[sl] += (np.where(ok, pm / (4.0 * vh), 0.0)) @ light.point_flux
    return np.asarray(tint, dtype=float)[None, :] * flakes.reflectance * (glint - weight[:, None] * mean)
