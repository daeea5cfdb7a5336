"""Analytic test shapes, ray-cast identically by the NumPy renderer and ``shaders/shapes.glsl``.

Units are arbitrary (the environment is distant). Every shape carries two paints: paint 0 on x < 0
and paint 1 on x ≥ 0 (design vs. nearest library match side by side, thesis Fig. 5.11), except the
panels (left panel 0, right panel 1) and the seam (fender 0, bumper 1).

* ``sphere`` — unit sphere at the origin.
* ``cylinder`` — the colour-proposal cylinder: vertical axis, radius 0.8, y ∈ [−1, 1], top cap.
* ``speedshape`` — a procedural automotive "speed shape": the tapered ellipsoid
  (x/a)² + ((y/h)² + (z/w)²)/s(x)² = 1, s(x) = 1 − k·x/a, a = 1.4, h = 0.45, w = 0.6, k = 0.3
  (thick nose at −x, thin tail at +x), found by 24 bracketing steps and 14 bisections (it is
  convex, so a ray enters it once; only grazing rays at the silhouette can step over it).
* ``panels`` — two 1 × 1.4 flat panels facing +z, hinged 0.04 apart at x = 0; the right panel is
  turned about its hinge (vertical axis) by ``misalignment_deg`` (thesis ch. 4 misalignment).
* ``seam`` — a flat fender (y ∈ [0.01, 0.9]) above a bumper curving away below (cylinder of radius
  0.6 about the x axis, tangent to the fender at the 0.02-wide seam).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from station.render.camera import Camera
from station.render.errors import RenderInputError

SHAPES = ("sphere", "cylinder", "speedshape", "panels", "seam")
SHAPE_INDEX = {name: i for i, name in enumerate(SHAPES)}
SPEED_A, SPEED_H, SPEED_W, SPEED_K = 1.4, 0.45, 0.6, 0.3
CYL_R = 0.8
SEAM_R = 0.6

DEFAULT_CAMERAS = {
    "sphere": Camera((0.0, 0.8, 4.5), (0.0, 0.0, 0.0), fov_deg=30.0),
    "cylinder": Camera((0.0, 1.2, 4.5), (0.0, 0.0, 0.0), fov_deg=32.0),
    "speedshape": Camera((1.0, 1.2, 3.6), (0.1, 0.0, 0.0), fov_deg=30.0),
    "panels": Camera((0.0, 0.4, 3.6), (0.0, 0.0, 0.0), fov_deg=36.0),
    "seam": Camera((0.9, 0.5, 3.4), (0.0, 0.0, 0.0), fov_deg=36.0),
}


@dataclass(frozen=True)
class Scene:
    """A shape, its parameters and the camera looking at it."""

    shape: str = "sphere"
    misalignment_deg: float = 0.0
    camera: Camera | None = None

    def __post_init__(self) -> None:
        if self.shape not in SHAPES:
            raise RenderInputError("shape", " | ".join(SHAPES), self.shape)
        if not -45.0 <= self.misalignment_deg <= 45.0:
            raise RenderInputError("misalignment_deg", "-45 <= misalignment_deg <= 45", self.misalignment_deg)
        if self.camera is None:
            object.__setattr__(self, "camera", DEFAULT_CAMERAS[self.shape])


@dataclass(frozen=True)
class Hits:
    """Per-ray intersection: mask (...,), position (..., 3), unit normal (..., 3), paint id (...,)."""

    mask: np.ndarray
    position: np.ndarray
    normal: np.ndarray
    paint: np.ndarray


def _nearest(ts: list[np.ndarray], normals: list[np.ndarray], paints: list[np.ndarray], o, d) -> Hits:
    t = np.stack(ts)
    k = np.argmin(t, axis=0)
    tmin = np.take_along_axis(t, k[None], 0)[0]
    mask = np.isfinite(tmin)
    n = np.take_along_axis(np.stack(normals), k[None, ..., None], 0)[0]
    p = np.take_along_axis(np.stack(paints), k[None], 0)[0]
    pos = o + np.where(mask, tmin, 0.0)[..., None] * d
    n = n / np.maximum(np.linalg.norm(n, axis=-1, keepdims=True), 1e-30)
    # Shade the side facing the camera (panels and bumper are open surfaces).
    n = np.where((np.sum(n * d, axis=-1) > 0)[..., None], -n, n)
    return Hits(mask, pos, n, np.where(mask, p, -1).astype(np.int8))


def _sphere(o, d):
    b = d @ o
    c = o @ o - 1.0
    disc = b * b - c
    t = np.where(disc >= 0, -b - np.sqrt(np.maximum(disc, 0)), np.inf)
    t = np.where(t > 0, t, np.inf)
    p = o + np.where(np.isfinite(t), t, 0)[..., None] * d
    return [t], [p], [(p[..., 0] >= 0).astype(np.int8)]


def _cylinder(o, d):
    a = d[..., 0] ** 2 + d[..., 2] ** 2
    b = o[0] * d[..., 0] + o[2] * d[..., 2]
    c = o[0] ** 2 + o[2] ** 2 - CYL_R**2
    disc = b * b - a * c
    t = np.where((disc >= 0) & (a > 1e-12), (-b - np.sqrt(np.maximum(disc, 0))) / np.maximum(a, 1e-12), np.inf)
    y = o[1] + t * d[..., 1]
    t_side = np.where((t > 0) & (np.abs(y) <= 1.0), t, np.inf)
    p = o + np.where(np.isfinite(t_side), t_side, 0)[..., None] * d
    n_side = p * np.array([1.0, 0.0, 1.0])
    with np.errstate(divide="ignore", invalid="ignore"):
        tc = (1.0 - o[1]) / d[..., 1]
    pc = o + np.where(np.isfinite(tc), tc, 0)[..., None] * d
    t_cap = np.where((tc > 0) & (pc[..., 0] ** 2 + pc[..., 2] ** 2 <= CYL_R**2), tc, np.inf)
    n_cap = np.broadcast_to(np.array([0.0, 1.0, 0.0]), p.shape)
    return ([t_side, t_cap], [n_side, n_cap],
            [(p[..., 0] >= 0).astype(np.int8), (pc[..., 0] >= 0).astype(np.int8)])


def speed_f(p: np.ndarray) -> np.ndarray:
    """Implicit function of the speed shape (negative inside)."""
    s = 1.0 - SPEED_K * p[..., 0] / SPEED_A
    q = (p[..., 1] / SPEED_H) ** 2 + (p[..., 2] / SPEED_W) ** 2
    return (p[..., 0] / SPEED_A) ** 2 + q / (s * s) - 1.0


def speed_grad(p: np.ndarray) -> np.ndarray:
    """Gradient of :func:`speed_f` (outward normal direction)."""
    s = 1.0 - SPEED_K * p[..., 0] / SPEED_A
    q = (p[..., 1] / SPEED_H) ** 2 + (p[..., 2] / SPEED_W) ** 2
    gx = 2.0 * p[..., 0] / SPEED_A**2 + 2.0 * q * SPEED_K / (SPEED_A * s**3)
    gy = 2.0 * p[..., 1] / (SPEED_H**2 * s * s)
    gz = 2.0 * p[..., 2] / (SPEED_W**2 * s * s)
    return np.stack([gx, gy, gz], axis=-1)


def _box(o, d, lo, hi):
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / d
        t0 = (lo - o) * inv
        t1 = (hi - o) * inv
    tn = np.nanmax(np.minimum(t0, t1), axis=-1)
    tf = np.nanmin(np.maximum(t0, t1), axis=-1)
    return np.maximum(tn, 0.0), tf


def _speedshape(o, d, steps: int = 24, bisections: int = 14):
    ext = np.array([SPEED_A, SPEED_H * (1 + SPEED_K), SPEED_W * (1 + SPEED_K)])
    tn, tf = _box(o, d, -ext, ext)
    valid = tf > tn
    dt = np.where(valid, (tf - tn) / steps, 0.0)
    t_prev = tn
    found = np.zeros(tn.shape, bool)
    lo, hi = tn.copy(), tn.copy()
    for k in range(1, steps + 1):
        t = tn + k * dt
        inside = speed_f(o + t[..., None] * d) < 0
        new = inside & ~found & valid
        lo = np.where(new, t_prev, lo)
        hi = np.where(new, t, hi)
        found |= new
        t_prev = t
    for _ in range(bisections):
        mid = 0.5 * (lo + hi)
        inside = speed_f(o + mid[..., None] * d) < 0
        hi = np.where(inside, mid, hi)
        lo = np.where(inside, lo, mid)
    t = np.where(found, 0.5 * (lo + hi), np.inf)
    p = o + np.where(found, t, 0)[..., None] * d
    return [t], [speed_grad(p)], [(p[..., 0] >= 0).astype(np.int8)]


def panel_frames(misalignment_deg: float) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """(centre, horizontal axis u, normal) of the left and right panels."""
    a = np.radians(misalignment_deg)
    u_r = np.array([np.cos(a), 0.0, -np.sin(a)])
    n_r = np.array([np.sin(a), 0.0, np.cos(a)])
    return [(np.array([-0.52, 0.0, 0.0]), np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0])),
            (np.array([0.02, 0.0, 0.0]) + 0.5 * u_r, u_r, n_r)]


def _panels(o, d, misalignment_deg: float):
    ts, ns, ps = [], [], []
    for k, (c, u, n) in enumerate(panel_frames(misalignment_deg)):
        denom = d @ n
        with np.errstate(divide="ignore", invalid="ignore"):
            t = ((c - o) @ n) / denom
        p = o + np.where(np.isfinite(t), t, 0)[..., None] * d
        rel = p - c
        ok = (t > 0) & (np.abs(rel @ u) <= 0.5) & (np.abs(rel[..., 1]) <= 0.7)
        ts.append(np.where(ok, t, np.inf))
        ns.append(np.broadcast_to(n, p.shape))
        ps.append(np.full(t.shape, k, np.int8))
    return ts, ns, ps


def _seam(o, d):
    with np.errstate(divide="ignore", invalid="ignore"):
        tf = -o[2] / d[..., 2]
    pf = o + np.where(np.isfinite(tf), tf, 0)[..., None] * d
    ok = (tf > 0) & (np.abs(pf[..., 0]) <= 1.2) & (pf[..., 1] >= 0.01) & (pf[..., 1] <= 0.9)
    t_f = np.where(ok, tf, np.inf)
    n_f = np.broadcast_to(np.array([0.0, 0.0, 1.0]), pf.shape)
    oz = o[2] + SEAM_R
    a = d[..., 1] ** 2 + d[..., 2] ** 2
    b = o[1] * d[..., 1] + oz * d[..., 2]
    c = o[1] ** 2 + oz**2 - SEAM_R**2
    disc = b * b - a * c
    tb = np.where((disc >= 0) & (a > 1e-12), (-b - np.sqrt(np.maximum(disc, 0))) / np.maximum(a, 1e-12), np.inf)
    pb = o + np.where(np.isfinite(tb), tb, 0)[..., None] * d
    ok = ((tb > 0) & (np.abs(pb[..., 0]) <= 1.2) & (pb[..., 1] <= -0.01)
          & (pb[..., 1] >= -0.9 * SEAM_R) & (pb[..., 2] >= -SEAM_R))
    t_b = np.where(ok, tb, np.inf)
    n_b = (pb - np.array([0.0, 0.0, -SEAM_R])) * np.array([0.0, 1.0, 1.0])
    return [t_f, t_b], [n_f, n_b], [np.zeros(tf.shape, np.int8), np.ones(tb.shape, np.int8)]


def intersect(scene: Scene, origin: np.ndarray, dirs: np.ndarray) -> Hits:
    """Intersect rays from *origin* (3,) along unit *dirs* (..., 3) with the scene's shape."""
    o = np.asarray(origin, dtype=np.float64)
    d = np.asarray(dirs, dtype=np.float64)
    if scene.shape == "sphere":
        ts, ns, ps = _sphere(o, d)
    elif scene.shape == "cylinder":
        ts, ns, ps = _cylinder(o, d)
    elif scene.shape == "speedshape":
        ts, ns, ps = _speedshape(o, d)
    elif scene.shape == "panels":
        ts, ns, ps = _panels(o, d, scene.misalignment_deg)
    else:
        ts, ns, ps = _seam(o, d)
    return _nearest(ts, ns, ps, o, d)
