"""The procedural car: a smooth body with a glasshouse and four wheels, for stylists with no mesh at hand.

Body: a sphere with its poles at the nose (−x) and tail (+x), deformed smoothly: semi-axes 1.2 long,
0.5 wide, 0.27 high, the cross-section a superellipse of exponent 3 (square-ish shoulders, C²), the lower
side flattened, and a cabin 0.2·exp(−((x − 0.15)/0.5)⁴) raised on the upper side and narrowed towards the
roof. The cabin's flanks, windscreen and rear window (upper side between the belt line and the roof, where
the cabin rises) are glass; the rest is paint. Wheels: four cylinders of radius WHEEL_RADIUS and width
WHEEL_WIDTH at x = ±WHEEL_BASE/2 under the body, their treads and sidewalls tyre (the faces' outer ring,
from HUB_RADIUS out) and a chrome hub in the middle of each face. Normals
smooth (area-weighted on the body, exact on the wheels). Placed on the stage like a loaded model
(:func:`station.render.meshes.place_on_stage`): the wheels stand on the ground.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from station.render.meshes import CHROME, GLASS, PAINT, TYRE, Mesh, place_on_stage

#: Wheel radius, width, base (axle distance) and track (half the distance between the wheels' centres
#: across), in body units (the body is 2.4 long before placing).
WHEEL_RADIUS = 0.17
WHEEL_WIDTH = 0.13
WHEEL_BASE = 1.5
WHEEL_TRACK = 0.37
#: Radius of the chrome hub on each wheel face (body units); the ring outside it is the tyre's sidewall.
HUB_RADIUS = 0.6 * WHEEL_RADIUS
#: Glass: the upper side where the cabin term exceeds this share of its peak, between belt and roof.
GLASS_CABIN = 0.45


def _body(n_u: int, n_v: int) -> tuple[NDArray, NDArray, NDArray, NDArray]:
    """(vertices, normals, faces, material codes) of the body (module docstring)."""
    import trimesh

    theta = np.linspace(0.0, np.pi, n_v)  # 0: tail (+x), π: nose (−x)
    phi = np.linspace(-np.pi, np.pi, n_u, endpoint=False)
    tt, pp = np.meshgrid(theta, phi, indexing="ij")
    a, b, c, p = 1.2, 0.27, 0.5, 3.0
    r = (np.abs(np.cos(pp)) ** p + np.abs(np.sin(pp)) ** p) ** (-1.0 / p)
    x = a * np.cos(tt)
    up = np.sin(tt) * np.cos(pp) * r  # in [−1, 1] across the section
    side = np.sin(tt) * np.sin(pp) * r
    y = b * np.where(up < 0.0, 0.6 * up, up)
    top = np.clip(up, 0.0, None) ** 2
    cabin = np.exp(-(((x - 0.15) / 0.5) ** 4))
    y = y + 0.2 * cabin * top
    z = c * side * (1.0 - 0.3 * cabin * top)
    glass = (cabin > GLASS_CABIN) & (up > 0.55) & (up < 0.93)
    verts = np.stack([x, y, z], axis=-1).reshape(-1, 3)
    idx = np.arange(n_v * n_u).reshape(n_v, n_u)
    nxt = np.roll(idx, -1, axis=1)
    q = np.stack([idx[:-1], nxt[:-1], nxt[1:], idx[1:]], axis=-1).reshape(-1, 4)
    faces = np.concatenate([q[:, [0, 1, 2]], q[:, [0, 2, 3]]])
    tm = trimesh.Trimesh(verts, faces, process=False)
    tm.fix_normals()  # consistent outward winding (the body is closed)
    normals = np.asarray(tm.vertex_normals, float)
    outward = np.einsum("ij,ij->i", normals, verts - verts.mean(axis=0))
    if (outward > 0).mean() < 0.5:
        normals = -normals
    codes = np.where(glass.ravel(), GLASS, PAINT)
    return verts, normals, np.asarray(tm.faces, np.int64), codes


def _wheel(centre: NDArray, segments: int = 48) -> tuple[NDArray, NDArray, NDArray, NDArray]:
    """(vertices, normals, faces, codes) of one wheel: a cylinder about z, tread TYRE (radial normals),
    each face (axial normals) a CHROME hub disc of HUB_RADIUS inside a TYRE sidewall ring; vertices not
    shared between tread, sidewall and hub (each keeps its normal and its code, read flat per triangle)."""
    ang = np.linspace(0.0, 2.0 * np.pi, segments, endpoint=False)
    ring = np.stack([np.cos(ang), np.sin(ang), np.zeros_like(ang)], axis=-1)
    h = 0.5 * WHEEL_WIDTH
    verts, normals, faces, codes = [], [], [], []
    nxt = np.roll(np.arange(segments), -1)
    # tread: two rings with radial normals
    tread = np.concatenate([WHEEL_RADIUS * ring + [0, 0, -h], WHEEL_RADIUS * ring + [0, 0, h]])
    verts.append(tread)
    normals.append(np.concatenate([ring, ring]))
    i = np.arange(segments)
    faces.append(
        np.concatenate(
            [np.stack([i, nxt, nxt + segments], 1), np.stack([i, nxt + segments, i + segments], 1)]
        )
    )
    codes.append(np.full(2 * segments, TYRE))
    base = 2 * segments
    for sign in (-1.0, 1.0):  # each face: a chrome hub (a centre and a ring), a tyre sidewall (two rings)
        z = [0.0, 0.0, sign * h]
        hub = np.concatenate([[z], HUB_RADIUS * ring + z])
        wall = np.concatenate([HUB_RADIUS * ring + z, WHEEL_RADIUS * ring + z])
        verts += [hub, wall]
        normals.append(np.tile([0.0, 0.0, sign], (3 * segments + 1, 1)))
        tri = np.stack([np.zeros(segments, int), 1 + i, 1 + nxt], 1)
        quad = np.concatenate(
            [np.stack([i, i + segments, nxt + segments], 1), np.stack([i, nxt + segments, nxt], 1)]
        )
        flip = [0, 1, 2] if sign > 0 else [0, 2, 1]
        faces += [base + tri[:, flip], base + segments + 1 + quad[:, flip]]
        codes += [np.full(segments + 1, CHROME), np.full(2 * segments, TYRE)]
        base += 3 * segments + 1
    return (
        np.concatenate(verts) + centre,
        np.concatenate(normals),
        np.concatenate(faces),
        np.concatenate(codes),
    )


def car_body(n_u: int = 160, n_v: int = 96) -> Mesh:
    """The procedural car (module docstring) as one mesh with material codes, placed on the stage."""
    parts = [_body(n_u, n_v)]
    wheel_y = -0.6 * 0.27 * 0.75  # the body's underside near the axles
    for wx in (-0.5 * WHEEL_BASE, 0.5 * WHEEL_BASE):
        for wz in (-WHEEL_TRACK, WHEEL_TRACK):
            parts.append(_wheel(np.array([wx, wheel_y, wz])))
    verts, normals, faces, codes = [], [], [], []
    base = 0
    for v, n, f, c in parts:
        verts.append(v)
        normals.append(n)
        faces.append(f + base)
        codes.append(c)
        base += len(v)
    return place_on_stage(
        "car", np.concatenate(verts), np.concatenate(normals), np.concatenate(faces), np.concatenate(codes)
    )
