"""The screen footprint of a ray-cast shape: which pixels can hit it, and the rest of the frame.

The shapes are ray cast per pixel in ``shaders/render.frag.glsl``; on a CPU rasteriser (Mesa llvmpipe)
every fragment pays for every instruction of that shader, the paint's lobes, coat and flakes included,
whether its ray hits the shape or not (branches are masks, not jumps). So a frame is drawn in two passes
over two pieces of the screen that tile it: the paint program over a convex polygon that contains every
pixel whose ray can hit the shape (:func:`shape_polygon`), and the background program (the stage or the
flat grey) over the rest (:func:`footprint_triangles`). A pixel inside the polygon whose ray misses is
shaded by the paint program's own background branch, so the frame is the single full-screen pass's,
pixel for pixel.

Coordinates are normalised device coordinates (NDC, x right, y up, [-1, 1]² the viewport), the camera's
ray generator (:meth:`station.render.camera.Camera.rays`) in the other direction: a direction d maps to
x = (d·right)/(d·forward)/(tan(fov/2)·aspect), y = (d·up)/(d·forward)/tan(fov/2).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from station.render.camera import Camera, cross3
from station.render.shapes import CYL_R, SEAM_R, SPEED_H, SPEED_NOSE, SPEED_TAIL, SPEED_W, panel_frames

#: Sides of the polygon circumscribing the sphere's silhouette (its area is 1.3 % above the disc's).
SPHERE_SIDES = 24
#: Margin of the polygon beyond the shape's bound, pixels (float rounding of the shader's ray cast).
MARGIN_PX = 2.0
#: A bound point nearer the eye's plane than this share of its distance (or behind it) leaves the frame
#: to one full-screen pass (a polygon would not be bounded).
MIN_DEPTH_SHARE = 0.05
#: A polygon covering more than this share of the viewport is not worth a second pass.
MAX_AREA_SHARE = 0.9


def _box(lo: tuple[float, float, float], hi: tuple[float, float, float]) -> np.ndarray:
    """The 8 corners (8, 3) of the axis-aligned box [lo, hi]."""
    return np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])


def bound_points(shape: str, misalignment_deg: float = 0.0) -> np.ndarray:
    """World points (k, 3) whose convex hull contains every surface point of *shape* a ray can hit
    (``station.render.shapes``; the sphere's is its cube, :func:`shape_polygon` bounds it by its cone)."""
    if shape == "sphere":
        return _box((-1.0, -1.0, -1.0), (1.0, 1.0, 1.0))
    if shape == "cylinder":
        return _box((-CYL_R, -1.0, -CYL_R), (CYL_R, 1.0, CYL_R))
    if shape == "speedshape":
        return _box((-SPEED_NOSE, -SPEED_H, -SPEED_W), (SPEED_TAIL, SPEED_H, SPEED_W))
    if shape == "panels":  # the two 1 × 1.4 panels' corners
        return np.array(
            [
                c + a * 0.5 * u + np.array([0.0, b * 0.7, 0.0])
                for c, u, _ in panel_frames(misalignment_deg)
                for a in (-1.0, 1.0)
                for b in (-1.0, 1.0)
            ]
        )
    if shape == "seam":  # fender y in [0.01, 0.9] at z = 0; bumper y in [-0.9 R, -0.01], z in [-R, 0]
        return _box((-1.2, -0.9 * SEAM_R, -SEAM_R), (1.2, 0.9, 0.0))
    raise ValueError(f"unknown shape {shape!r}")


def _hull(p: np.ndarray) -> np.ndarray:
    """Convex hull (k, 2) of points *p* (n, 2), counter-clockwise (Andrew's monotone chain)."""
    pts = sorted({(float(x), float(y)) for x, y in p})
    if len(pts) < 3:
        return np.asarray(pts)

    def chain(seq: list[tuple[float, float]]) -> list[tuple[float, float]]:
        out: list[tuple[float, float]] = []
        for q in seq:
            while len(out) >= 2:
                (ax, ay), (bx, by) = out[-2], out[-1]
                if (bx - ax) * (q[1] - ay) - (by - ay) * (q[0] - ax) > 0.0:
                    break
                out.pop()
            out.append(q)
        return out

    lower, upper = chain(pts), chain(pts[::-1])
    return np.asarray(lower[:-1] + upper[:-1])


def _ccw(poly: np.ndarray) -> np.ndarray:
    """The convex polygon *poly* (k, 2), its vertices already in order around it, counter-clockwise."""
    x, y = poly[:, 0], poly[:, 1]
    signed = float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))
    return poly if signed >= 0.0 else poly[::-1].copy()


def _project(dirs: np.ndarray, camera: Camera, aspect: float) -> np.ndarray | None:
    """NDC (k, 2) of world directions *dirs* (k, 3) from the eye; None when one is too near the eye's
    plane or behind it."""
    f, r, u = camera.basis()
    t = np.tan(np.radians(camera.fov_deg) / 2.0)
    depth = dirs @ f
    if np.any(depth <= MIN_DEPTH_SHARE * np.linalg.norm(dirs, axis=1)):
        return None
    return np.stack([(dirs @ r) / depth / (t * aspect), (dirs @ u) / depth / t], axis=1)


@dataclass(frozen=True)
class Footprint:
    """A shape's screen footprint in NDC: the convex counter-clockwise polygon *outer* (k, 2) that holds
    every pixel whose ray can hit the shape, and *inner* (k, 2) or None, the same polygon scaled about
    the vertex mean of *outer* to lie inside the shape's silhouette (every pixel in it hits: the sphere)."""

    outer: np.ndarray
    inner: np.ndarray | None = None


def _sphere_cone(eye: np.ndarray, tan_half: float, phi: np.ndarray) -> np.ndarray:
    """World directions (k, 3) from *eye* on the cone about the unit sphere's centre of half-angle
    atan(*tan_half*), at azimuths *phi* (radians)."""
    axis = -eye / np.linalg.norm(eye)
    helper = np.array([1.0, 0.0, 0.0]) if abs(axis[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = cross3(axis, helper)
    e1 /= np.linalg.norm(e1)
    e2 = cross3(axis, e1)
    return axis + tan_half * (np.cos(phi)[:, None] * e1 + np.sin(phi)[:, None] * e2)


def _exit_scale(c: np.ndarray, rays: np.ndarray, poly: np.ndarray) -> np.ndarray:
    """For each ray c + t·rays[i] (rays (k, 2)), the t where it leaves the convex counter-clockwise
    polygon *poly* (m, 2) that holds c."""
    edges = np.roll(poly, -1, axis=0) - poly
    normals = np.stack([edges[:, 1], -edges[:, 0]], axis=1)  # outward for a counter-clockwise polygon
    reach = np.sum(normals * (poly - c), axis=1)  # > 0: c inside
    rate = rays @ normals.T  # (k, m)
    with np.errstate(divide="ignore"):
        t = np.where(rate > 0.0, reach[None, :] / rate, np.inf)
    return t.min(axis=1)


def sphere_radius_px(camera: Camera, height: int) -> float:
    """The unit sphere's radius on screen (pixels of a frame *height* high) seen from *camera* on its view's
    axis: tan of the silhouette's half-angle asin(1/d) over tan(fov/2), d the eye's distance from the
    origin; 0 with the eye inside the sphere."""
    dist = float(np.linalg.norm(np.asarray(camera.eye, np.float64)))
    if dist <= 1.0:
        return 0.0
    return float(height / 2.0 / np.sqrt(dist * dist - 1.0) / np.tan(np.radians(camera.fov_deg) / 2.0))


def shape_footprint(
    shape: str,
    camera: Camera,
    width: int,
    height: int,
    misalignment_deg: float = 0.0,
    inner_margin_px: float = MARGIN_PX,
    inner_min_ndv: float = 0.0,
) -> Footprint | None:
    """The :class:`Footprint` of *shape* in a *width* × *height* frame: *outer* contains every pixel
    centre whose ray can hit the shape, with MARGIN_PX to spare; *inner* (the sphere only) lies
    *inner_margin_px* (pixels, at least MARGIN_PX) inside its silhouette, and within the part of the sphere
    seen at N·V >= *inner_min_ndv* (a ray at impact parameter b meets the unit sphere at N·V = √(1 − b²)).
    None when the shape's bound reaches the eye's plane (or the eye is inside it)
    or the polygon covers more than MAX_AREA_SHARE of the viewport: then one full-screen pass draws the
    frame."""
    eye = np.asarray(camera.eye, np.float64)
    aspect = width / height
    margin = MARGIN_PX * 2.0 / min(width, height)
    if shape == "sphere":
        # The silhouette cone of the unit sphere (half-angle asin(1/|C - E|)), circumscribed by a cone of
        # SPHERE_SIDES planes through the eye: its edge directions lie at tan(b) = tan(a)/cos(pi/n).
        dist = float(np.linalg.norm(eye))
        if dist <= 1.0 / np.sin(np.radians(80.0)):
            return None
        alpha = np.arcsin(1.0 / dist)
        phi = 2.0 * np.pi * np.arange(SPHERE_SIDES) / SPHERE_SIDES
        dirs = _sphere_cone(eye, np.tan(alpha) / np.cos(np.pi / SPHERE_SIDES), phi)
    else:
        dirs = bound_points(shape, misalignment_deg) - eye
    ndc = _project(dirs, camera, aspect)
    if ndc is None:
        return None
    # the sphere's cone, wholly in front of the eye, projects to an ellipse traced in order of azimuth:
    # its points are the convex polygon already
    poly = _ccw(ndc) if shape == "sphere" else _hull(ndc)
    if len(poly) < 3:
        return None
    # Grow the polygon about its vertex mean c by a factor that moves every edge out by >= the margin.
    c = poly.mean(axis=0)
    edges = np.roll(poly, -1, axis=0) - poly
    normals = np.stack([edges[:, 1], -edges[:, 0]], axis=1) / np.linalg.norm(edges, axis=1)[:, None]
    inradius = float(np.min(np.abs(np.sum((poly - c) * normals, axis=1))))
    poly = c + (poly - c) * (1.0 + margin / max(inradius, 1e-9))
    inside_view = bool(np.all(np.abs(poly) <= 1.0))  # then clipping would return it unchanged
    if _area(poly if inside_view else _clip_to_viewport(poly)) > MAX_AREA_SHARE * 4.0:
        return None
    inner = None
    if shape == "sphere" and len(poly) == SPHERE_SIDES:
        # A polygon inscribed in the silhouette shrunk by the margin (angles: the pixel's angular size is
        # largest on the axis), then the outer polygon scaled about c to fit inside it.
        inner_margin = max(inner_margin_px, MARGIN_PX) * 2.0 / min(width, height)
        shrink = np.arctan(inner_margin * np.tan(np.radians(camera.fov_deg) / 2.0))
        beta = min(
            alpha - shrink, np.arcsin(np.sqrt(1.0 - min(max(inner_min_ndv, 0.0), 1.0) ** 2) / dist) - shrink
        )
        dense = _project(
            _sphere_cone(eye, np.tan(beta), np.linspace(0, 2 * np.pi, 180, False)), camera, aspect
        )
        if dense is not None:
            hull = _ccw(dense)
            s = float(np.min(_exit_scale(c, poly - c, hull))) if len(hull) >= 3 else 0.0
            if 0.5 < s < 1.0:
                inner = c + s * (poly - c)
    return Footprint(poly, inner)


def _area(poly: np.ndarray) -> float:
    """Area of polygon *poly* (k, 2) (shoelace; 0 for fewer than 3 points)."""
    if len(poly) < 3:
        return 0.0
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))


def _clip_to_viewport(poly: np.ndarray) -> np.ndarray:
    """*poly* clipped to [-1, 1]² (Sutherland-Hodgman)."""
    out = [tuple(p) for p in poly]
    for axis in (0, 1):
        for sign in (-1.0, 1.0):
            src, out = out, []
            for i, p in enumerate(src):
                q = src[(i + 1) % len(src)]
                pin, qin = sign * p[axis] <= 1.0, sign * q[axis] <= 1.0
                if pin:
                    out.append(p)
                if pin != qin:
                    s = (sign - p[axis]) / (q[axis] - p[axis])
                    out.append((p[0] + s * (q[0] - p[0]), p[1] + s * (q[1] - p[1])))
            if not out:
                return np.zeros((0, 2))
    return np.asarray(out)


def footprint_triangles(footprint: Footprint) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(inside, ring, outside): triangle vertices (3a, 2), (3b, 2), (3c, 2) in NDC, float32, that tile the
    viewport: *inside* fans the inner polygon from the outer's vertex mean c (empty without one); *ring*
    covers the outer polygon less the inner (the whole outer polygon without one: a fan from c); *outside*
    the rest, one convex sector per outer edge, from the edge out to radius R about c, beyond every
    viewport corner (arc points at most 90° apart, so each chord stays outside the viewport). Adjacent
    pieces share their vertices exactly (float32), so the rasteriser's rule draws every pixel centre
    once."""
    poly = np.asarray(footprint.outer, np.float32).astype(np.float64)
    c = poly.mean(axis=0)
    inner = None if footprint.inner is None else np.asarray(footprint.inner, np.float32).astype(np.float64)
    corners = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
    reach = float(max(np.max(np.linalg.norm(corners - c, axis=1)), np.max(np.linalg.norm(poly - c, axis=1))))
    radius = 2.0 * reach + 1.0
    theta = np.arctan2(poly[:, 1] - c[1], poly[:, 0] - c[0])
    far = c + radius * np.stack([np.cos(theta), np.sin(theta)], axis=1)
    n = len(poly)
    nxt = (np.arange(n) + 1) % n
    centre = np.broadcast_to(c, poly.shape)
    if inner is None:
        inside = np.zeros((0, 2))
        ring = np.stack([centre, poly, poly[nxt]], axis=1)
    else:
        inside = np.stack([centre, inner, inner[nxt]], axis=1)
        ring = np.stack([inner, poly, poly[nxt], inner, poly[nxt], inner[nxt]], axis=1)  # counter-clockwise
    # one sector per edge, a convex fan from poly[i]: poly[i], far[i], arc points, far[j], poly[j]
    gap = (theta[nxt] - theta) % (2.0 * np.pi)
    steps = np.ceil(gap / (np.pi / 2.0)).astype(int)
    plain = steps <= 1  # no arc point: the fan's two triangles
    ends, far_ends = poly[nxt][plain], far[nxt][plain]
    outside = [
        np.stack([poly[plain], far[plain], far_ends, poly[plain], far_ends, ends], axis=1).reshape(-1, 2)
    ]
    for i in np.nonzero(~plain)[0]:
        j = nxt[i]
        angles = theta[i] + gap[i] * np.arange(1, steps[i]) / steps[i]
        fan = [
            poly[i],
            far[i],
            *(c + radius * np.stack([np.cos(angles), np.sin(angles)], axis=1)),
            far[j],
            poly[j],
        ]
        outside.append(
            np.array([[fan[0], fan[k], fan[k + 1]] for k in range(1, len(fan) - 1)]).reshape(-1, 2)
        )
    out = [np.asarray(t, np.float32).reshape(-1, 2) for t in (inside, ring, np.concatenate(outside))]
    return out[0], out[1], out[2]
