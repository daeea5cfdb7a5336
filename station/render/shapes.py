"""Analytic test shapes, ray-cast identically by the NumPy renderer and ``shaders/shapes.glsl``.

Units are arbitrary (the environment is distant). Every shape carries two paints: paint 0 on x < 0
and paint 1 on x ≥ 0 (design vs. nearest library match side by side, thesis Fig. 5.11), except the
panels (left panel 0, right panel 1) and the seam (fender 0, bumper 1).

* ``sphere`` — unit sphere at the origin.
* ``cylinder`` — the colour-proposal cylinder: vertical axis, radius 0.8, y ∈ [−1, 1], top cap.
* ``speedshape`` — a procedural automotive "speed shape", a teardrop of two half-ellipsoids joined
  at x = 0 with a common cross-section (height 0.42, width 0.55): a blunt nose (semi-axis 0.7) at
  −x and a long tail (1.7) at +x. The join is C¹ (both normals are (0, y/h², z/w²) there), and
  each half is intersected in closed form. Nose = paint 0, tail = paint 1.
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
from station.render.stage import Stage

SHAPES = ("sphere", "cylinder", "speedshape", "panels", "seam")
#: The shapes that cannot shadow themselves: a convex closed body's self-shadow is its terminator N·l <= 0,
#: which the shading applies anyway (the cylinder, open below, is left out: a light from below reaches inside).
CONVEX_SHAPES = ("sphere",)
SHAPE_INDEX = {name: i for i, name in enumerate(SHAPES)}
SPEED_NOSE, SPEED_TAIL, SPEED_H, SPEED_W = 0.7, 1.7, 0.42, 0.55
CYL_R = 0.8
SEAM_R = 0.6
#: A shadow ray leaves its surface point this far along the normal (scene units), so it does not hit it.
SHADOW_RAY_OFFSET = 1e-4

DEFAULT_CAMERAS = {
    "sphere": Camera((0.0, 0.8, 4.5), (0.0, 0.0, 0.0), fov_deg=30.0),
    "cylinder": Camera((0.0, 1.2, 4.5), (0.0, 0.0, 0.0), fov_deg=32.0),
    "speedshape": Camera((1.4, 1.3, 4.8), (0.5, 0.0, 0.0), fov_deg=34.0),
    "panels": Camera((0.0, 0.4, 3.6), (0.0, 0.0, 0.0), fov_deg=36.0),
    "seam": Camera((0.9, 0.5, 3.4), (0.0, 0.0, 0.0), fov_deg=36.0),
}


#: Ground disc of each shape for :class:`station.render.stage.Stage`: (centre x, floor height y, centre z).
GROUNDS: dict[str, tuple[float, float, float]] = {
    "sphere": (0.0, -1.0, 0.0),
    "cylinder": (0.0, -1.0, 0.0),
    "speedshape": (0.5, -SPEED_H, 0.0),
    "panels": (0.0, -0.7, 0.0),
    "seam": (0.0, -0.9 * SEAM_R, 0.0),
}
#: Sphere proxies (centre x, y, z, radius) of each shape for the contact shadow (``stage.sphere_occlusion``).
OCCLUDERS: dict[str, tuple[tuple[float, float, float, float], ...]] = {
    "sphere": ((0.0, 0.0, 0.0, 1.0),),
    "cylinder": ((0.0, -0.2, 0.0, 0.8), (0.0, 0.6, 0.0, 0.8)),
    "speedshape": (
        (-0.3, 0.0, 0.0, 0.4),
        (0.2, 0.0, 0.0, 0.42),
        (0.75, 0.0, 0.0, 0.36),
        (1.25, 0.0, 0.0, 0.25),
    ),
    "panels": ((-0.52, -0.5, 0.0, 0.2), (0.52, -0.5, 0.0, 0.2)),
    "seam": ((0.0, -0.2, -0.3, 0.35),),
}


@dataclass(frozen=True)
class Scene:
    """A shape, its parameters, the camera looking at it and the stage around it.

    ``stage``: backdrop, environment rotation and ground (:class:`station.render.stage.Stage`); None shows
    the shape on the flat grey background in the unrotated environment.
    """

    shape: str = "sphere"
    misalignment_deg: float = 0.0
    camera: Camera | None = None
    stage: Stage | None = None

    def __post_init__(self) -> None:
        if self.shape not in SHAPES:
            raise RenderInputError("shape", " | ".join(SHAPES), self.shape)
        if not -45.0 <= self.misalignment_deg <= 45.0:
            raise RenderInputError("misalignment_deg", "-45 <= misalignment_deg <= 45", self.misalignment_deg)
        if self.camera is None:
            object.__setattr__(self, "camera", DEFAULT_CAMERAS[self.shape])
        if self.stage is not None and not isinstance(self.stage, Stage):
            raise RenderInputError("stage", "a Stage or None", self.stage)

    @property
    def view_camera(self) -> Camera:
        """The camera in use: the one given, else the shape's default (never None)."""
        return self.camera if self.camera is not None else DEFAULT_CAMERAS[self.shape]


@dataclass(frozen=True)
class Hits:
    """Per-ray intersection: mask (...,), position (..., 3), unit normal (..., 3), paint id (...,)."""

    mask: np.ndarray
    position: np.ndarray
    normal: np.ndarray
    paint: np.ndarray


def _nearest(
    ts: list[np.ndarray], normals: list[np.ndarray], paints: list[np.ndarray], o: np.ndarray, d: np.ndarray
) -> Hits:
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


#: Per candidate surface: ray parameters t (inf: miss), unit normals, paint ids (what _nearest picks from).
_Candidates = tuple[list[np.ndarray], list[np.ndarray], list[np.ndarray]]


def _sphere(o: np.ndarray, d: np.ndarray) -> _Candidates:
    b = np.sum(d * o, axis=-1)
    c = np.sum(o * o, axis=-1) - 1.0
    disc = b * b - c
    t = np.where(disc >= 0, -b - np.sqrt(np.maximum(disc, 0)), np.inf)
    t = np.where(t > 0, t, np.inf)
    p = o + np.where(np.isfinite(t), t, 0)[..., None] * d
    return [t], [p], [(p[..., 0] >= 0).astype(np.int8)]


def _cylinder(o: np.ndarray, d: np.ndarray) -> _Candidates:
    a = d[..., 0] ** 2 + d[..., 2] ** 2
    b = o[..., 0] * d[..., 0] + o[..., 2] * d[..., 2]
    c = o[..., 0] ** 2 + o[..., 2] ** 2 - CYL_R**2
    disc = b * b - a * c
    t = np.where(
        (disc >= 0) & (a > 1e-12), (-b - np.sqrt(np.maximum(disc, 0))) / np.maximum(a, 1e-12), np.inf
    )
    y = o[..., 1] + t * d[..., 1]
    t_side = np.where((t > 0) & (np.abs(y) <= 1.0), t, np.inf)
    p = o + np.where(np.isfinite(t_side), t_side, 0)[..., None] * d
    n_side = p * np.array([1.0, 0.0, 1.0])
    with np.errstate(divide="ignore", invalid="ignore"):
        tc = (1.0 - o[..., 1]) / d[..., 1]
    pc = o + np.where(np.isfinite(tc), tc, 0)[..., None] * d
    t_cap = np.where((tc > 0) & (pc[..., 0] ** 2 + pc[..., 2] ** 2 <= CYL_R**2), tc, np.inf)
    n_cap = np.broadcast_to(np.array([0.0, 1.0, 0.0]), p.shape)
    return (
        [t_side, t_cap],
        [n_side, n_cap],
        [(p[..., 0] >= 0).astype(np.int8), (pc[..., 0] >= 0).astype(np.int8)],
    )


def _ellipsoid_roots(o: np.ndarray, d: np.ndarray, axes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Both ray parameters of the hits with the origin-centred ellipsoid of semi-axes *axes* (inf: miss)."""
    oo, dd = o / axes, d / axes
    a = np.sum(dd * dd, axis=-1)
    b = np.sum(dd * oo, axis=-1)
    c = np.sum(oo * oo, axis=-1) - 1.0
    disc = b * b - a * c
    root = np.sqrt(np.maximum(disc, 0.0))
    hit = disc >= 0
    return np.where(hit, (-b - root) / a, np.inf), np.where(hit, (-b + root) / a, np.inf)


def _speedshape(o: np.ndarray, d: np.ndarray) -> _Candidates:
    ts, ns, ps = [], [], []
    halves = (
        (np.array([SPEED_NOSE, SPEED_H, SPEED_W]), -1.0),
        (np.array([SPEED_TAIL, SPEED_H, SPEED_W]), 1.0),
    )
    for axes, side in halves:
        for t in _ellipsoid_roots(o, d, axes):
            p = o + np.where(np.isfinite(t), t, 0.0)[..., None] * d
            ok = (t > 0) & (side * p[..., 0] >= 0)
            ts.append(np.where(ok, t, np.inf))
            ns.append(p / (axes * axes))
            ps.append(np.full(t.shape, 0 if side < 0 else 1, np.int8))
    return ts, ns, ps


def panel_frames(misalignment_deg: float) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """(centre, horizontal axis u, normal) of the left and right panels."""
    a = np.radians(misalignment_deg)
    u_r = np.array([np.cos(a), 0.0, -np.sin(a)])
    n_r = np.array([np.sin(a), 0.0, np.cos(a)])
    return [
        (np.array([-0.52, 0.0, 0.0]), np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0])),
        (np.array([0.02, 0.0, 0.0]) + 0.5 * u_r, u_r, n_r),
    ]


def _panels(o: np.ndarray, d: np.ndarray, misalignment_deg: float) -> _Candidates:
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


def _seam(o: np.ndarray, d: np.ndarray) -> _Candidates:
    with np.errstate(divide="ignore", invalid="ignore"):
        tf = -o[..., 2] / d[..., 2]
    pf = o + np.where(np.isfinite(tf), tf, 0)[..., None] * d
    ok = (tf > 0) & (np.abs(pf[..., 0]) <= 1.2) & (pf[..., 1] >= 0.01) & (pf[..., 1] <= 0.9)
    t_f = np.where(ok, tf, np.inf)
    n_f = np.broadcast_to(np.array([0.0, 0.0, 1.0]), pf.shape)
    oz = o[..., 2] + SEAM_R
    a = d[..., 1] ** 2 + d[..., 2] ** 2
    b = o[..., 1] * d[..., 1] + oz * d[..., 2]
    c = o[..., 1] ** 2 + oz**2 - SEAM_R**2
    disc = b * b - a * c
    tb = np.where(
        (disc >= 0) & (a > 1e-12), (-b - np.sqrt(np.maximum(disc, 0))) / np.maximum(a, 1e-12), np.inf
    )
    pb = o + np.where(np.isfinite(tb), tb, 0)[..., None] * d
    ok = (
        (tb > 0)
        & (np.abs(pb[..., 0]) <= 1.2)
        & (pb[..., 1] <= -0.01)
        & (pb[..., 1] >= -0.9 * SEAM_R)
        & (pb[..., 2] >= -SEAM_R)
    )
    t_b = np.where(ok, tb, np.inf)
    n_b = (pb - np.array([0.0, 0.0, -SEAM_R])) * np.array([0.0, 1.0, 1.0])
    return [t_f, t_b], [n_f, n_b], [np.zeros(tf.shape, np.int8), np.ones(tb.shape, np.int8)]


def intersect(scene: Scene, origin: np.ndarray, dirs: np.ndarray) -> Hits:
    """Intersect rays from *origin* (3,) along unit *dirs* (..., 3) with the scene's shape; *origin* may also
    be one point per ray (..., 3) (shadow rays, :func:`ray_cast_visibility`)."""
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


def ray_cast_visibility(
    scene: Scene, points: np.ndarray, normals: np.ndarray, directions: np.ndarray
) -> np.ndarray:
    """Whether each light is visible from each point: (P, k) of 0.0 (the shape is in the way) or 1.0, for
    surface *points* (P, 3) with unit *normals* (P, 3) and unit light *directions* (k, 3) (world space). Each
    point casts one ray per light at the scene's own shape (:func:`intersect`), from SHADOW_RAY_OFFSET along
    its normal: the shape's own outline, not sphere proxies; a point light, so no penumbra. Deterministic."""
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    o = p + SHADOW_RAY_OFFSET * np.asarray(normals, dtype=float).reshape(-1, 3)
    ls = np.asarray(directions, dtype=float).reshape(-1, 3)
    vis = np.ones((p.shape[0], ls.shape[0]))
    for k, ell in enumerate(ls):
        vis[:, k] = ~intersect(scene, o, np.broadcast_to(ell, o.shape)).mask
    return vis
