"""The procedural car: a smooth body with a glasshouse and four wheels, for stylists with no mesh at hand.

Body (body units: 2.4 long, nose at +x, ground at y = 0 before placing): a lofted parametric surface.
Each station x carries a cross-section about its shoulder (0, centre height): two superellipse quarters
per side that meet with a vertical tangent at the section's widest point, the upper one (UPPER_EXPONENT)
up to the roof line, the lower one (LOWER_EXPONENT) down to the underside. The shoulder is at SHOULDER_Y
along the body and moves to halfway up towards the ends. The roof line is a monotone C¹ interpolation
(PCHIP) of TOP_PROFILE: a low nose, the hood, a raked windscreen, the roof, a rear window and the boot
deck. The underside (:func:`bottom_line`) runs along the sills at SILL_Y, rises in a soft-footed arch to
ARCH_TOP over each axle (the wheels stand in wheel arches) and lies at OVERHANG_Y under the bumpers; the
plan width swells by FLARE over the wheels. Above the belt line BELT_Y the cabin's sections are drawn in
by up to TUMBLEHOME (the glasshouse sits inboard of the shoulders). The ends close on superellipses in
(x, section size) (END_TOP, END_BOTTOM, END_WIDTH): a blunt nose and tail, each a single pole vertex.
Stations are spaced evenly in their largest step plus STATION_TURN times the surface normal's largest
turn between them (:func:`_stations`), so curved stretches get more of them.

The upper quarter's parameter σ ∈ [0, 1] (0: the widest point, 1: the top centre) is warped per station
so that σ = BELT_SIGMA lies on the belt line. The glass parts are rectangles in (x, σ): the side windows
(BELT_SIGMA to SIDE_SIGMA, B-pillar left as paint), windscreen and rear window (above SCREEN_SIGMA),
and the stations and section parameters of their edges are grid lines of the tessellation, so every
edge between glass and paint runs along a parameter curve (a plane section at constant x, or a curve
of constant σ): no saw-tooth. Vertices on those edges are doubled (one copy per material, the same
position and normal), as the shader reads a triangle's material from one of its vertices.

Normals are smooth (area-weighted over the closed body, before the doubling). Wheels: four cylinders of
radius WHEEL_RADIUS and width WHEEL_WIDTH at x = ±WHEEL_BASE/2, z = ±WHEEL_TRACK, standing on the
ground, their treads and sidewalls tyre (the faces' outer ring, from HUB_RADIUS out) and a chrome hub in
the middle of each face. Placed on the stage like a loaded model
(:func:`station.render.meshes.place_on_stage`): the wheels stand on the ground. The contact shadow's
sphere proxies (:meth:`CarMesh.occluders`) float inside the body above the sills, so the ground under
the car is shaded by the body but never fully black (no proxy touches the ground).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from station.render.meshes import CHROME, GLASS, PAINT, TYRE, Mesh, place_on_stage
from station.render.stage import MAX_OCCLUDERS

#: Wheel radius, width, base (axle distance) and track (half the distance between the wheels' centres
#: across), in body units (the body is 2.4 long before placing).
WHEEL_RADIUS = 0.15
WHEEL_WIDTH = 0.13
WHEEL_BASE = 1.42
WHEEL_TRACK = 0.40
#: Radius of the chrome hub on each wheel face (body units); the ring outside it is the tyre's sidewall.
HUB_RADIUS = 0.6 * WHEEL_RADIUS
#: Half length of the body; the nose is at +HALF_LENGTH.
HALF_LENGTH = 1.2
#: Height of the belt line, of the sills and of the shoulders (the sections' widest point; body units).
#: Towards the ends (|x| from END_BLEND[0] to END_BLEND[1]) the widest point moves to halfway between
#: the roof line and the underside, so the nose and tail close around their middle.
SHOULDER_Y = 0.47
END_BLEND = (0.95, 1.2)
BELT_Y = 0.56
SILL_Y = 0.09
#: Half width of the body between the wheels, and the fender flares' extra half width over the wheels.
HALF_WIDTH = 0.49
FLARE = 0.02
#: Roof line (x, height) from tail to nose: boot deck, rear window, roof, windscreen, hood, nose.
TOP_PROFILE: tuple[tuple[float, float], ...] = (
    (-1.20, 0.56),
    (-1.05, 0.575),
    (-0.90, 0.59),
    (-0.62, 0.75),
    (-0.30, 0.78),
    (0.10, 0.76),
    (0.52, 0.56),
    (0.60, 0.54),
    (0.95, 0.51),
    (1.20, 0.48),
)
#: Wheel arch: the underside rises to ARCH_TOP over each axle, falling to the sills over ARCH_FLANK
#: either side of the axle (profile (1 + cos πt)/2, t the distance beyond ARCH_FLAT over ARCH_FLANK: a soft foot).
ARCH_TOP = 0.32
ARCH_FLAT = 0.08
#: Underside of the overhangs (the bumpers' lower edge) beyond the wheel arches (body units).
OVERHANG_Y = 0.16
ARCH_FLANK = 0.22
#: Stations are spaced evenly in their largest step plus STATION_TURN (body units per radian) times the
#: largest turn of the surface normal between them, so curved stretches (nose, screens, arches) get more.
STATION_TURN = 0.25
#: Exponents of the section's superellipse quarters, and of the ends (in x against the section's height
#: above and depth below its centre, and its width): a rounded hood front, an underside that stays flat
#: to the bumpers, rounded corners in plan.
UPPER_EXPONENT = 4.0
LOWER_EXPONENT = 2.2
END_TOP = 3.0
END_BOTTOM = 5.0
END_WIDTH = 3.0
#: Share by which the glasshouse is drawn in (0 at the belt line, full from BELT_Y + 0.1 up; only where
#: the roof line stands up to 0.2 above the belt line, in full above that).
TUMBLEHOME = 0.12
#: Upper-quarter section parameters: the belt line, the side windows' top edge, the windscreen's and
#: rear window's side edges (the strip between the last two is the A/C pillar and roof rail).
BELT_SIGMA = 0.40
SIDE_SIGMA = 0.64
SCREEN_SIGMA = 0.70
#: Glass stations (x ranges): side windows, the B-pillar left as paint, windscreen and rear window.
SIDE_GLASS = (-0.80, 0.44)
B_PILLAR = (-0.21, -0.16)
WINDSCREEN = (0.14, 0.50)
REAR_WINDOW = (-0.86, -0.64)
#: Contact-shadow proxies: spheres staggered across (z = ±OCCLUDER_Z · half width) along the body.
OCCLUDER_Z = 0.34
#: Radius of the proxies as a share of the sill-to-belt height (they overlap along the body).
OCCLUDER_RADIUS = 0.68


@dataclass(frozen=True, eq=False)
class CarMesh(Mesh):
    """The procedural car's mesh: a :class:`~station.render.meshes.Mesh` whose contact-shadow proxies
    are fitted to the car's body instead of the generic ones resting on the floor."""

    def occluders(self) -> NDArray[np.float64]:
        """(MAX_OCCLUDERS, 4) sphere proxies (centre, radius; scene units) evenly along the body, staggered
        across (z = ±OCCLUDER_Z of the body's half width, alternately), radius OCCLUDER_RADIUS of the
        sill-to-belt height, resting on the sill height: inside the body's bounds, clear of the ground."""
        body = np.isin(self.painted, (PAINT, GLASS))
        p = self.positions[body].astype(float)
        lo, hi = p.min(axis=0), p.max(axis=0)
        scale = (hi[0] - lo[0]) / (2.0 * HALF_LENGTH)
        floor = float(self.positions[:, 1].min())
        bottom, top = floor + SILL_Y * scale, floor + BELT_Y * scale
        r = OCCLUDER_RADIUS * (top - bottom)
        xs = np.linspace(lo[0] + 1.1 * r, hi[0] - 1.1 * r, MAX_OCCLUDERS)
        zc = 0.5 * (lo[2] + hi[2])
        dz = OCCLUDER_Z * 0.5 * (hi[2] - lo[2])
        out = [(x, bottom + r, zc + (-1.0) ** i * dz, r) for i, x in enumerate(xs)]
        return np.asarray(out, float)


def _smoothstep(e0: float, e1: float, x: NDArray) -> NDArray:
    t = np.clip((x - e0) / (e1 - e0), 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def top_line(x: NDArray) -> NDArray[np.float64]:
    """Roof line height (body units) at stations *x* before the ends close (PCHIP of TOP_PROFILE)."""
    from scipy.interpolate import PchipInterpolator

    px, py = np.asarray(TOP_PROFILE).T
    return np.asarray(PchipInterpolator(px, py)(np.clip(x, px[0], px[-1])), float)


def _arch(x: NDArray) -> NDArray:
    """Share (0..1) of the wheel arch's rise at stations *x*."""
    out = np.zeros_like(x, dtype=float)
    for wx in (-0.5 * WHEEL_BASE, 0.5 * WHEEL_BASE):
        t = np.clip((np.abs(x - wx) - ARCH_FLAT) / ARCH_FLANK, 0.0, 1.0)
        out = np.maximum(out, 0.5 + 0.5 * np.cos(np.pi * t))
    return out


def bottom_line(x: NDArray) -> NDArray[np.float64]:
    """Underside height (body units) at stations *x* before the ends close: the sills, raised into an
    arch over each axle; the overhangs' underside (the bumpers) at OVERHANG_Y."""
    x = np.asarray(x, float)
    wx = 0.5 * WHEEL_BASE
    base = SILL_Y + (OVERHANG_Y - SILL_Y) * _smoothstep(wx, wx + ARCH_FLAT + ARCH_FLANK, np.abs(x))
    return base + (ARCH_TOP - base) * _arch(x)


def _centre(x: NDArray) -> NDArray:
    """Height of the sections' centre (their widest point) at stations *x*: SHOULDER_Y along the body,
    moving to halfway between roof line and underside towards the nose and tail (END_BLEND)."""
    x = np.asarray(x, float)
    mid = 0.5 * (top_line(x) + bottom_line(x))
    return SHOULDER_Y + _smoothstep(END_BLEND[0], END_BLEND[1], np.abs(x)) * (mid - SHOULDER_Y)


def _half_width(x: NDArray) -> NDArray:
    return HALF_WIDTH + FLARE * _arch(x)


def _end_scale(x: NDArray, exponent: float) -> NDArray:
    """Share (0..1) of a section's size at stations *x*: the superellipse of *exponent* closing the nose
    and tail."""
    t = np.clip(np.abs(x) / HALF_LENGTH, 0.0, 1.0)
    return (1.0 - t**exponent) ** (1.0 / exponent)


def _spaced(values: NDArray, edges: tuple[float, ...], min_gap: float) -> NDArray:
    """*values* (sorted) with the *edges* inserted exactly and the values closer than *min_gap* to an
    edge dropped."""
    v = np.asarray(values, float)
    e = np.asarray(edges, float)
    keep = np.min(np.abs(v[:, None] - e[None, :]), axis=1) >= min_gap
    return np.unique(np.concatenate([v[keep], e]))


def _stations(n_v: int, n_q: int) -> NDArray[np.float64]:
    """Interior stations x (tail to nose), *n_v* − 2 of them before the glass edges are inserted, spaced
    evenly in the largest step of any section point plus STATION_TURN times the largest turn of the
    surface normal between neighbouring stations (measured on a fine set of stations)."""
    x = -HALF_LENGTH * np.cos(np.pi * np.linspace(0.0, 1.0, 1201))[1:-1]
    z, y, _ = _section(x, n_q)
    p = np.stack([np.broadcast_to(x[:, None], z.shape), y, z], axis=-1)
    around = np.roll(p, -1, axis=1) - np.roll(p, 1, axis=1)
    along = np.gradient(p, axis=0)
    n = np.cross(around, along)
    n /= np.maximum(np.linalg.norm(n, axis=-1, keepdims=True), 1e-12)
    turn = np.arccos(np.clip(np.einsum("ijk,ijk->ij", n[1:], n[:-1]), -1.0, 1.0)).max(axis=1)
    step = np.linalg.norm(np.diff(p, axis=0), axis=-1).max(axis=1)
    s = np.concatenate([[0.0], np.cumsum(step + STATION_TURN * turn)])
    st = np.interp(np.linspace(0.0, s[-1], n_v)[1:-1], s, x)
    edges = (*SIDE_GLASS, *B_PILLAR, *WINDSCREEN, *REAR_WINDOW)
    return _spaced(st, edges, 0.35 * float(np.min(np.diff(st))))


def _section(x: NDArray, n_q: int) -> tuple[NDArray, NDArray, NDArray]:
    """(z, y, σ of the upper quarter or −1) on a grid (stations, around) at stations *x*: the loop
    starts at the top centre, goes down the right side (+z) and the bottom centre up the left side."""
    sig = _spaced(np.linspace(0.0, 1.0, n_q), (BELT_SIGMA, SIDE_SIGMA, SCREEN_SIGMA), 0.3 / n_q)
    lam = np.linspace(0.0, 1.0, n_q)[1:-1]  # lower quarter, without its ends (shared with the upper)
    xs = x[:, None]
    w = _end_scale(xs, END_WIDTH) * _half_width(xs)
    yc = _centre(xs)
    h_top = _end_scale(xs, END_TOP) * (top_line(xs) - yc)
    h_bot = _end_scale(xs, END_BOTTOM) * (yc - bottom_line(xs))
    # upper quarter: angle θ from the widest point (0) to the top (π/2), σ = BELT_SIGMA on the belt line
    pu = UPPER_EXPONENT
    eta_b = np.clip((BELT_Y - yc) / np.maximum(h_top, 1e-9), 0.0, 0.85)
    th_b = np.arcsin(eta_b ** (pu / 2.0))
    s = sig[None, :]
    th = np.where(
        s <= BELT_SIGMA,
        th_b * s / BELT_SIGMA,
        th_b + (0.5 * np.pi - th_b) * (s - BELT_SIGMA) / (1.0 - BELT_SIGMA),
    )
    zu = w * np.cos(th) ** (2.0 / pu)
    yu = yc + h_top * np.sin(th) ** (2.0 / pu)
    cabin = _smoothstep(0.0, 0.2, top_line(xs) - BELT_Y)  # no inset on the hood and deck
    zu = zu * (1.0 - TUMBLEHOME * cabin * _smoothstep(BELT_Y - 0.01, BELT_Y + 0.10, yu))
    pl = LOWER_EXPONENT
    tl = 0.5 * np.pi * lam[None, :]
    zl = w * np.cos(tl) ** (2.0 / pl)
    yl = yc - h_bot * np.sin(tl) ** (2.0 / pl)
    # right side: upper from the top centre (σ = 1) down, lower from the widest point down, without the
    # bottom centre; then the bottom centre; left side mirrored back up, without the top centre.
    bottom_z = np.zeros((len(x), 1))
    bottom_y = yc - h_bot
    z = np.concatenate([zu[:, ::-1], zl, bottom_z, -zl[:, ::-1], -zu[:, :-1]], axis=1)
    y = np.concatenate([yu[:, ::-1], yl, bottom_y, yl[:, ::-1], yu[:, :-1]], axis=1)
    n_l = lam.size
    sigma = np.concatenate([sig[::-1], -np.ones(2 * n_l + 1), sig[:-1]])
    return z, y, np.broadcast_to(sigma, z.shape)


def _glass(x: NDArray, sigma: NDArray) -> NDArray[np.bool_]:
    """Whether a cell with centre station *x* and upper-quarter parameter *sigma* (−1: lower) is glass."""
    side = (x > SIDE_GLASS[0]) & (x < SIDE_GLASS[1]) & (sigma > BELT_SIGMA) & (sigma < SIDE_SIGMA)
    side &= ~((x > B_PILLAR[0]) & (x < B_PILLAR[1]))
    screens = ((x > WINDSCREEN[0]) & (x < WINDSCREEN[1])) | ((x > REAR_WINDOW[0]) & (x < REAR_WINDOW[1]))
    return side | (screens & (sigma > SCREEN_SIGMA))


def _body(n_u: int, n_v: int) -> tuple[NDArray, NDArray, NDArray, NDArray]:
    """(vertices, normals, faces, material codes) of the body (module docstring): about *n_u* vertices
    around each section and *n_v* stations along the length (poles included)."""
    import trimesh

    n_q = max(n_u // 4 + 1, 4)
    x = _stations(n_v, n_q)
    z, y, sigma = _section(x, n_q)
    m, n = z.shape
    ring = np.stack([np.broadcast_to(x[:, None], z.shape), y, z], axis=-1).reshape(-1, 3)
    tail = [-HALF_LENGTH, float(_centre(np.array(-HALF_LENGTH))), 0.0]
    nose = [HALF_LENGTH, float(_centre(np.array(HALF_LENGTH))), 0.0]
    verts = np.concatenate([ring, [tail, nose]])
    idx = np.arange(m * n).reshape(m, n)
    nxt = np.roll(idx, -1, axis=1)
    q = np.stack([idx[:-1], nxt[:-1], nxt[1:], idx[1:]], axis=-1).reshape(-1, 4)
    quads = np.concatenate([q[:, [0, 1, 2]], q[:, [0, 2, 3]]])
    j = np.arange(n)
    jn = np.roll(j, -1)
    fan_tail = np.stack([np.full(n, m * n), jn, j], axis=1)
    fan_nose = np.stack([np.full(n, m * n + 1), idx[-1, j], idx[-1, jn]], axis=1)
    faces = np.concatenate([quads, fan_tail, fan_nose])
    # material per face: quad cells by their centre's station and σ; the fans are paint
    xc = 0.5 * (x[:-1] + x[1:])[:, None]
    sc = 0.5 * (sigma[:-1] + np.roll(sigma, -1, axis=1)[:-1])
    valid = (sigma[:-1] >= 0) & (np.roll(sigma, -1, axis=1)[:-1] >= 0)
    cell = np.where(_glass(np.broadcast_to(xc, sc.shape), np.where(valid, sc, -1.0)), GLASS, PAINT)
    cell = cell.reshape(-1)
    codes_f = np.concatenate([cell, cell, np.full(2 * n, PAINT)])
    tm = trimesh.Trimesh(verts, faces, process=False)
    if tm.volume < 0:
        faces = faces[:, ::-1]
        tm = trimesh.Trimesh(verts, faces, process=False)
    normals = np.asarray(tm.vertex_normals, float)
    # one vertex per (vertex, material): the glass edges get a copy of each vertex on them
    key = faces.astype(np.int64) * 8 + np.repeat(codes_f.astype(np.int64), 3).reshape(-1, 3)
    uniq, inverse = np.unique(key.reshape(-1), return_inverse=True)
    src = uniq // 8
    return verts[src], normals[src], inverse.reshape(-1, 3).astype(np.int64), (uniq % 8).astype(float)


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


def car_body(n_u: int = 160, n_v: int = 96) -> CarMesh:
    """The procedural car (module docstring) as one mesh with material codes, placed on the stage: about
    *n_u* vertices around each section of the body and *n_v* stations along it."""
    parts = [_body(n_u, n_v)]
    for wx in (-0.5 * WHEEL_BASE, 0.5 * WHEEL_BASE):
        for wz in (-WHEEL_TRACK, WHEEL_TRACK):
            parts.append(_wheel(np.array([wx, WHEEL_RADIUS, wz])))
    verts, normals, faces, codes = [], [], [], []
    base = 0
    for v, n, f, c in parts:
        verts.append(v)
        normals.append(n)
        faces.append(f + base)
        codes.append(c)
        base += len(v)
    m = place_on_stage(
        "car", np.concatenate(verts), np.concatenate(normals), np.concatenate(faces), np.concatenate(codes)
    )
    return CarMesh(m.name, m.positions, m.normals, m.faces, m.painted)
