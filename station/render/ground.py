"""The ground under a ray-cast shape shaded by the shape itself, as the GL renderer's maps shade it
(``station.render.gl_shadows``), for the NumPy renderer's stage (``numpy_renderer.stage_background``).

* **Which lights.** Of the lights taken out of the environment the SHADOW_LIGHTS of largest luminous flux
  (:func:`shadow_lights`: the sun, a booth's main lamps) are shadowed by the shape's own ray cast; the
  others keep the sphere proxies' sun shadow (``station.render.stage.light_visibility``), as GL keeps them
  where it draws no shadow map (:func:`ground_light_visibility`).
* **Soft shadows.** A shadowed light is a disc of angular radius a (:func:`light_radius_rad` of its spread,
  at least the sun's SUN_RADIUS_DEG, the rule GL's percentage-closer soft shadows use): a ground point's
  visibility is the share of LIGHT_SAMPLES directions spread uniformly (in solid angle) over that disc
  (:func:`disc_directions`, a Fibonacci spiral: deterministic) whose rays, from SHADOW_RAY_OFFSET above the
  point, miss the shape (``station.render.shapes.ray_cast_visibility``); 0 for a light below the horizon.
  Hard at the contact, soft away from it. Cost: a point whose cone of directions misses the shape's
  bounding box (:func:`bounding_box`, :func:`cone_misses`) is lit without a ray; elsewhere the disc's
  centre and RIM_SAMPLES directions on its rim are cast first (:func:`rim_directions`), and a point where
  they all agree (deep in the shadow or clear of it) takes that answer, 0 or 1; only the penumbra casts
  the LIGHT_SAMPLES. The shortcut differs from casting them all only where the outline enters the disc
  between two rim directions without crossing one: for an outline much wider than the disc, a sliver of
  depth at most (1 − cos(π/RIM_SAMPLES)) a, under 1.3 % of the disc's area.
* **Sky occlusion.** For the closed solids (CLOSED_SHAPES: sphere, cylinder, speed shape) the occluded
  fraction O of the sky above the ground is GL's definition (``shaders/ao.frag.glsl``) and GL's map: the
  shape taken as columns between its bottom and top heights on a grid of HEIGHT_MAP texels on the long
  side of its footprint's box, each height by one vertical ray at the shape (:func:`height_columns`; the
  cylinder, open below, as the solid column it bounds, its bottom at y = −1); from a ground point, along
  each of AO_AZIMUTHS azimuths, AO_STEPS columns across the box, the cosine-weighted hidden fraction
  sin² φ_max − sin² φ_min of the elevations [φ_min, φ_max] the columns span (exact for a convex body); O
  is the mean over the azimuths, baked at the texel centres of an AO_MAP² map over the ground disc's
  square (:func:`occlusion_map`, once per shape and ground: about 2 s) and read bilinearly, clamped at
  its edges, as GL's texture is (:func:`ground_occlusion`). GL's definition is height-map based, so this
  reproduces it rather than a ray-cast hemisphere estimate: the two engines differ only by where the
  height texels fall. The open panels and the seam, which a view from above sees edge-on, keep the
  proxies' open sky (``station.render.stage.sphere_occlusion``), as in GL.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from station.jit import CompiledLoops
from station.model.colorimetry import REC709_LUMINANCE
from station.render.errors import RenderInputError
from station.render.footprint import bound_points
from station.render.shapes import OCCLUDERS, SHADOW_RAY_OFFSET, Scene, intersect, ray_cast_visibility
from station.render.stage import light_visibility

#: Lights whose shadows come from the shape itself (the strongest by luminous flux); GL's shader holds as
#: many shadow maps.
SHADOW_LIGHTS = 2
#: Smallest angular radius of a shadowed light, degrees (the sun's disc).
SUN_RADIUS_DEG = 0.27
#: Directions per shadowed light and ground point over the light's disc (:func:`disc_directions`). The
#: share of them inside a blocking disc (radius a, 3a or 1000a, every offset, 48 orientations) is within
#: 0.046 of its exact area share at 64 (RMS 0.013; 32: 0.075, 128: 0.029); only the penumbra casts them.
LIGHT_SAMPLES = 64
#: Directions on the rim of a light's disc cast first, with its centre (:func:`rim_directions`).
RIM_SAMPLES = 8
#: Texels of the long side of the top and bottom height maps (ambient occlusion).
HEIGHT_MAP = 512
#: Texels per side of the ground's ambient-occlusion map over the disc's square.
AO_MAP = 512
#: Azimuths and steps per azimuth of the occlusion estimate.
AO_AZIMUTHS = 24
AO_STEPS = 64
#: The shapes that are closed solids (their top and bottom heights bound them: the ambient occlusion's columns).
CLOSED_SHAPES = ("sphere", "cylinder", "speedshape")


def shadow_lights(lights: Any, count: int = SHADOW_LIGHTS) -> tuple[int, ...]:
    """Indices of the *count* lights of *lights* (``station.render.environment.Lights`` or None) of largest
    luminous flux (Rec. 709 luma of the flux, linear sRGB), strongest first; () without lights."""
    if lights is None or lights.count == 0:
        return ()
    if count < 0:
        raise RenderInputError("count", "count >= 0", count)
    luma = np.asarray(lights.flux, float) @ REC709_LUMINANCE
    order = np.argsort(-luma, kind="stable")
    return tuple(int(i) for i in order[:count])


def light_radius_rad(spread: float) -> float:
    """Angular radius (radians) of a light of angular spread *spread* = s² (rad², per-axis variance of its
    directions, ``Lights.spreads``): a uniform disc of radius a has E[θ²] = a²/2, s² = a²/4, so a = 2 s;
    at least SUN_RADIUS_DEG."""
    if not math.isfinite(spread) or spread < 0.0:
        raise RenderInputError("spread", "a finite spread >= 0 rad²", spread)
    return max(2.0 * math.sqrt(spread), math.radians(SUN_RADIUS_DEG))


def _frame(ell: NDArray) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Two unit vectors (3,) that make a right-handed frame with the unit *ell* (3,) (the same for the same
    input)."""
    ref = np.array([0.0, 1.0, 0.0]) if abs(ell[1]) < 0.9 else np.array([1.0, 0.0, 0.0])
    u = np.cross(ell, ref)
    u /= np.linalg.norm(u)
    return u, np.cross(ell, u)


def disc_directions(direction: NDArray, radius_rad: float, count: int = LIGHT_SAMPLES) -> NDArray[np.float64]:
    """*count* unit directions (count, 3) spread uniformly in solid angle over the cone of half angle
    *radius_rad* (radians) about the unit *direction* (3,): a Fibonacci spiral, sample i at cos θ_i =
    1 − (i + ½)/count · (1 − cos a) and azimuth i times the golden angle about the direction (the same
    directions for the same input)."""
    if count < 1:
        raise RenderInputError("count", "count >= 1", count)
    if not math.isfinite(radius_rad) or not 0.0 <= radius_rad < 0.5 * math.pi:
        raise RenderInputError("radius_rad", "0 <= radius_rad < π/2", radius_rad)
    ell = np.asarray(direction, dtype=float).reshape(3)
    ell = ell / np.linalg.norm(ell)
    u, v = _frame(ell)
    i = np.arange(count)
    cos_t = 1.0 - (i + 0.5) / count * (1.0 - math.cos(radius_rad))
    sin_t = np.sqrt(np.maximum(1.0 - cos_t * cos_t, 0.0))
    phi = i * math.pi * (3.0 - math.sqrt(5.0))
    out = cos_t[:, None] * ell + sin_t[:, None] * (np.cos(phi)[:, None] * u + np.sin(phi)[:, None] * v)
    return np.asarray(out / np.linalg.norm(out, axis=1, keepdims=True))


def bounding_box(
    shape: str, misalignment_deg: float = 0.0
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(lo (3,), hi (3,)) world corners of an axis-aligned box about *shape*: the box of its bound
    (``station.render.footprint.bound_points``), which holds every surface point a ray can hit."""
    pts = bound_points(shape, misalignment_deg)
    return pts.min(axis=0), pts.max(axis=0)


def cone_misses(
    points: NDArray, direction: NDArray, radius_rad: float, box: tuple[NDArray, NDArray]
) -> NDArray[np.bool_]:
    """Whether no ray from each of *points* (P, 3) within *radius_rad* (radians) of the unit *direction*
    can meet the *box* (lo, hi) (:func:`bounding_box`): a ray at angle ≤ a from the direction is, at a
    distance s, within s sin a of the half-line along it, and s ≤ the farthest corner's distance; so the
    half-line missing the box grown by that much on every side is enough (conservative)."""
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    ell = np.asarray(direction, dtype=float).reshape(3)
    lo, hi = np.asarray(box[0], dtype=float), np.asarray(box[1], dtype=float)
    far = np.linalg.norm(np.maximum(np.abs(p - lo), np.abs(p - hi)), axis=1)
    grow = (far * math.sin(radius_rad) + SHADOW_RAY_OFFSET)[:, None] + 1e-9
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / ell
        t0, t1 = (lo - grow - p) * inv, (hi + grow - p) * inv
    flat = ell == 0.0  # parallel to a slab: inside it or never
    inside = (p >= lo - grow) & (p <= hi + grow)
    t_near = np.where(flat, np.where(inside, -np.inf, np.inf), np.minimum(t0, t1)).max(axis=1)
    t_far = np.where(flat, np.where(inside, np.inf, -np.inf), np.maximum(t0, t1)).min(axis=1)
    return np.asarray(t_far < np.maximum(t_near, 0.0))


def rim_directions(direction: NDArray, radius_rad: float, count: int = RIM_SAMPLES) -> NDArray[np.float64]:
    """The unit *direction* (3,) and *count* unit directions evenly spaced on the rim of the cone of half
    angle *radius_rad* (radians) about it: (1 + count, 3), the rays that decide whether a ground point is
    wholly lit or wholly shadowed (:func:`area_light_visibility`)."""
    ell = np.asarray(direction, dtype=float).reshape(3)
    ell = ell / np.linalg.norm(ell)
    u, v = _frame(ell)
    phi = 2.0 * math.pi * np.arange(count) / count
    rim = math.cos(radius_rad) * ell + math.sin(radius_rad) * (
        np.cos(phi)[:, None] * u + np.sin(phi)[:, None] * v
    )
    return np.vstack([ell[None, :], rim])


def area_light_visibility(
    scene: Scene, points: NDArray, direction: NDArray, radius_rad: float, count: int = LIGHT_SAMPLES
) -> NDArray[np.float64]:
    """Visible share (P,) in [0, 1] of a light of angular radius *radius_rad* (radians) about the unit
    world *direction* from ground *points* (P, 3), normal +Y: the share of the *count* directions of
    :func:`disc_directions` whose rays miss the scene's shape (module docstring). 1 without a ray where the
    cone misses the shape's box (:func:`cone_misses`); 1 or 0 where the rays of :func:`rim_directions`
    all miss or all meet the shape."""
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    ell = np.asarray(direction, dtype=float).reshape(3)
    ell = ell / np.linalg.norm(ell)
    vis = np.ones(p.shape[0])
    near = np.flatnonzero(~cone_misses(p, ell, radius_rad, bounding_box(scene.shape, scene.misalignment_deg)))
    if not len(near):
        return vis
    q = p[near]
    up = np.broadcast_to(np.array([0.0, 1.0, 0.0]), q.shape)
    seen = ray_cast_visibility(scene, q, up, rim_directions(ell, radius_rad)).mean(axis=1)
    vis[near] = seen
    mixed = (seen > 0.0) & (seen < 1.0)
    if mixed.any():
        rays = ray_cast_visibility(
            scene, q[mixed], up[: int(mixed.sum())], disc_directions(ell, radius_rad, count)
        )
        vis[near[mixed]] = rays.mean(axis=1)
    return vis


def ground_light_visibility(
    scene: Scene, points: NDArray, directions: NDArray, slots: tuple[int, ...], spreads: NDArray
) -> NDArray[np.float64]:
    """Visibility (P, k) in [0, 1] of the lights in world *directions* (k, 3) of angular *spreads* (k,)
    (rad², ``Lights.spreads``) from ground *points* (P, 3): the lights *slots* (:func:`shadow_lights`) as
    discs of angular radius :func:`light_radius_rad` by the shape's own ray cast
    (:func:`area_light_visibility`; lights below the horizon 0), the others past the sphere proxies (module
    docstring)."""
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    ls = np.asarray(directions, dtype=float).reshape(-1, 3)
    sp = np.asarray(spreads, dtype=float).reshape(-1)
    if sp.shape[0] != ls.shape[0]:
        raise RenderInputError("spreads", f"{ls.shape[0]} spreads, one per light", sp.shape[0])
    vis = light_visibility(p, OCCLUDERS[scene.shape], ls)
    if not len(p):
        return vis
    for i in (i for i in slots if 0 <= i < len(ls)):
        if ls[i, 1] > 0.0:
            vis[:, i] = area_light_visibility(scene, p, ls[i], light_radius_rad(float(sp[i])))
        else:
            vis[:, i] = 0.0
    return vis


@functools.cache
def height_columns(
    shape: str,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """(box lo (x, z), box hi (x, z), top (nx, nz), bottom (nx, nz)) of the closed *shape*: its heights over a grid of
    texel centres across its footprint's box (HEIGHT_MAP texels on the long side), each by one vertical
    ray down from above and up from below at the shape; −inf / +inf where the column misses it (read-only
    arrays)."""
    if shape not in CLOSED_SHAPES:
        raise RenderInputError("shape", " | ".join(CLOSED_SHAPES), shape)
    pts = bound_points(shape, 0.0)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    ext = np.maximum(hi - lo, 1e-6)
    nx = HEIGHT_MAP if ext[0] >= ext[2] else max(16, math.ceil(HEIGHT_MAP * ext[0] / ext[2]))
    nz = HEIGHT_MAP if ext[2] > ext[0] else max(16, math.ceil(HEIGHT_MAP * ext[2] / ext[0]))
    xs = lo[0] + (np.arange(nx) + 0.5) * ext[0] / nx
    zs = lo[2] + (np.arange(nz) + 0.5) * ext[2] / nz
    x, z = np.meshgrid(xs, zs, indexing="ij")
    scene = Scene(shape)
    columns = []
    for y0, dy in ((hi[1] + 1.0, -1.0), (lo[1] - 1.0, 1.0)):
        o = np.stack([x, np.full(x.shape, y0), z], -1)
        hit = intersect(scene, o, np.broadcast_to(np.array([0.0, dy, 0.0]), o.shape))
        y = hit.position[..., 1]
        if shape == "cylinder" and dy > 0:  # open below: the solid column it bounds
            y = np.full(y.shape, -1.0)
        columns.append(np.where(hit.mask, y, -np.inf if dy < 0 else np.inf))
    out = (lo[[0, 2]].copy(), hi[[0, 2]].copy(), columns[0], columns[1])
    for a in out:
        a.setflags(write=False)
    return out


def occlusion_sum(
    px: NDArray, pz: NDArray, box: NDArray, top: NDArray, bottom: NDArray, azimuths: int, steps: int
) -> NDArray[np.float64]:
    """O (P,) at ground points (*px*, *pz*) of the columns *top*, *bottom* (heights above the ground, over
    the box (lo x, lo z, hi x, hi z) *box*): per azimuth sin² φ_max − sin² φ_min over *steps* columns
    across the box, the mean over *azimuths* (``shaders/ao.frag.glsl``, one point at a time)."""
    nx, nz = top.shape
    out = np.zeros(px.shape[0])
    for k in range(px.shape[0]):
        occluded = 0.0
        for j in range(azimuths):
            a = 2.0 * math.pi * (j + 0.5) / azimuths
            dx, dz = math.cos(a), math.sin(a)
            ix = math.copysign(1.0, dx + 1e-12) / (abs(dx) + 1e-9)
            iz = math.copysign(1.0, dz + 1e-12) / (abs(dz) + 1e-9)
            t0x, t1x = (box[0] - px[k]) * ix, (box[2] - px[k]) * ix
            t0z, t1z = (box[1] - pz[k]) * iz, (box[3] - pz[k]) * iz
            s_in = max(max(min(t0x, t1x), min(t0z, t1z)), 0.0)
            s_out = min(max(t0x, t1x), max(t0z, t1z))
            if s_out <= s_in:
                continue
            lo2, hi2 = 1.0, 0.0
            for i in range(steps):
                s = s_in + (s_out - s_in) * (i + 0.5) / steps
                u = int(math.floor((px[k] + s * dx - box[0]) / (box[2] - box[0]) * nx))
                v = int(math.floor((pz[k] + s * dz - box[1]) / (box[3] - box[1]) * nz))
                u, v = min(max(u, 0), nx - 1), min(max(v, 0), nz - 1)
                h_top, h_bottom = top[u, v], bottom[u, v]
                if h_top > h_bottom and h_top > 0.0:
                    b = max(h_bottom, 0.0)
                    lo2 = min(lo2, b * b / (b * b + s * s))
                    hi2 = max(hi2, h_top * h_top / (h_top * h_top + s * s))
            occluded += max(hi2 - lo2, 0.0)
        out[k] = min(max(occluded / azimuths, 0.0), 1.0)
    return out


def _warm_up(kernel: Callable[..., NDArray[np.float64]]) -> None:
    """Compile (or load from the cache) now, not midway through a ground."""
    z = np.zeros(1)
    kernel(z, z, np.array([0.0, 0.0, 1.0, 1.0]), np.zeros((1, 1)), np.zeros((1, 1)), 1, 1)


#: The occlusion loop compiled by numba.
_LOOPS = CompiledLoops((occlusion_sum,), warm_up=_warm_up)


def _kernel() -> Callable[..., NDArray[np.float64]]:
    """The compiled occlusion loop, or the plain one where numba cannot compile here."""
    loops = _LOOPS.get()
    return occlusion_sum if loops is None else loops[0]


@functools.lru_cache(maxsize=4)
def occlusion_map(shape: str, ground_y: float, centre_x: float, centre_z: float, radius: float) -> NDArray:
    """The AO_MAP² map (rows z, columns x; read-only) of O at the texel centres of the ground disc's square
    (centre (*centre_x*, *centre_z*), half side *radius*, height *ground_y*) under the closed *shape*
    (module docstring), in [0, 1]; the last few grounds are kept."""
    if not math.isfinite(radius) or radius <= 0.0:
        raise RenderInputError("radius", "a finite radius > 0", radius)
    lo, hi, top, bottom = height_columns(shape)
    q = 2.0 * (np.arange(AO_MAP) + 0.5) / AO_MAP - 1.0
    x, z = np.meshgrid(centre_x + q * radius, centre_z + q * radius)
    box = np.array([lo[0], lo[1], hi[0], hi[1]])
    occ = _kernel()(
        np.ascontiguousarray(x.ravel()),
        np.ascontiguousarray(z.ravel()),
        box,
        np.ascontiguousarray(top - ground_y),
        np.ascontiguousarray(bottom - ground_y),
        AO_AZIMUTHS,
        AO_STEPS,
    ).reshape(AO_MAP, AO_MAP)
    occ.setflags(write=False)
    return occ


def ground_occlusion(
    scene: Scene, points: NDArray, ground_y: float, centre: tuple[float, float], radius: float
) -> NDArray[np.float64]:
    """Cosine-weighted occluded fraction O (P,) of the sky above ground *points* (P, 3) by the scene's
    closed shape: :func:`occlusion_map` of the ground (height *ground_y*, disc *centre* (x, z) and *radius*)
    read bilinearly at the points, clamped at its edges (module docstring), in [0, 1]."""
    if scene.shape not in CLOSED_SHAPES:
        raise RenderInputError("shape", " | ".join(CLOSED_SHAPES), scene.shape)
    occ = occlusion_map(scene.shape, float(ground_y), float(centre[0]), float(centre[1]), float(radius))
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    n = occ.shape[0]
    fx = (0.5 * (p[:, 0] - centre[0]) / radius + 0.5) * n - 0.5
    fz = (0.5 * (p[:, 2] - centre[1]) / radius + 0.5) * n - 0.5
    ix, iz = np.floor(fx), np.floor(fz)
    ax, az = fx - ix, fz - iz
    x0, x1 = np.clip(ix, 0, n - 1).astype(int), np.clip(ix + 1, 0, n - 1).astype(int)
    z0, z1 = np.clip(iz, 0, n - 1).astype(int), np.clip(iz + 1, 0, n - 1).astype(int)
    top = occ[z0, x0] * (1.0 - ax) + occ[z0, x1] * ax
    bottom = occ[z1, x0] * (1.0 - ax) + occ[z1, x1] * ax
    return np.asarray(top * (1.0 - az) + bottom * az)
