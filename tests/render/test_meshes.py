"""Own meshes: trimesh loading (GLB incl. meshopt-compressed, OBJ, STL), part choice, placement, GL raster."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from station.render import meshes as me
from station.render import numpy_renderer as nr
from station.render import prefilter, procedural, shapes
from station.render.errors import RenderInputError
from station.render.weights import LobeWeights

EXPS = (1.0, 8.0, 64.0, 512.0)


def _pair() -> list[LobeWeights]:
    return [
        LobeWeights(
            EXPS, np.array([0.12, 0.02, 0.02]), np.full((4, 3), 0.02), np.array([0.0, 0.0, 0.1, 1.5])
        ),
        LobeWeights(
            EXPS, np.array([0.02, 0.03, 0.12]), np.full((4, 3), 0.01), np.array([0.0, 0.0, 0.2, 1.0])
        ),
    ]


@pytest.fixture(scope="module")
def sky_basis():
    return prefilter.prefilter_basis(procedural.sunny_sky(128), EXPS, max_size=32)


@pytest.fixture(scope="module")
def cc0_cars(shared_dir: Path) -> list[Path]:
    files = sorted((shared_dir / "data" / "meshes").glob("*.glb"))
    if not files:
        pytest.skip("no CC0 car meshes in ../shared/data/meshes")
    return files


def test_cc0_car_loads_and_is_placed(cc0_cars) -> None:
    for path in cc0_cars:
        mesh = me.load_mesh(path)
        lo, hi = mesh.bounds
        assert mesh.faces.shape[0] > 1000
        assert hi[0] - lo[0] == pytest.approx(me.MESH_LENGTH, rel=1e-5)  # longest side along x
        assert hi[2] - lo[2] < hi[0] - lo[0]
        assert lo[1] == pytest.approx(me.MESH_FLOOR_Y, abs=1e-6)
        assert abs(lo[0] + hi[0]) < 1e-5 and abs(lo[2] + hi[2]) < 1e-5
        assert np.linalg.norm(mesh.normals, axis=1) == pytest.approx(1.0, abs=1e-5)
        # one material with a palette texture: paint, tyres and glass by their swatches (mesh_parts)
        assert (mesh.painted == me.PAINT).mean() > 0.3
        assert (mesh.painted == me.TYRE).any() and (mesh.painted == me.GLASS).any()
        tyre_y = mesh.positions[mesh.painted == me.TYRE][:, 1]
        assert np.median(tyre_y) < np.median(mesh.positions[mesh.painted == me.PAINT][:, 1])  # low down
        # Normals point out of the body for most vertices (decoded octahedral normals, turned with it).
        out = np.einsum("ij,ij->i", mesh.normals, mesh.positions - mesh.positions.mean(axis=0))
        assert (out > 0).mean() > 0.7
    with pytest.raises(RenderInputError, match="paint") as err:
        me.load_mesh(cc0_cars[0], paint="wheel")
    assert "Mesh" in str(err.value)  # the message lists the parts


def test_parts_by_name_in_glb_obj_stl(tmp_path) -> None:
    import trimesh

    body = trimesh.creation.box((2.0, 0.6, 0.9))
    glass = trimesh.creation.box((0.8, 0.3, 0.7))
    glass.apply_translation((0.0, 0.45, 0.0))
    scene = trimesh.Scene({"body": body, "glass": glass})
    scene.export(tmp_path / "two.glb")
    mesh = me.load_mesh(tmp_path / "two.glb", paint="BODY")
    # No normals in the file: each box is shaded with its creases, 4 corners on each of its 6 faces.
    assert (mesh.painted == me.PAINT).sum() == 24  # the box's vertices painted
    assert (mesh.painted == me.GLASS).sum() == 24  # the part named glass drawn as glass
    assert mesh.painted.size == 48
    lo, hi = mesh.bounds
    assert hi[0] - lo[0] == pytest.approx(me.MESH_LENGTH) and lo[1] == pytest.approx(me.MESH_FLOOR_Y)
    # Height scales with the length: 0.6 + 0.15 + ... over 2.0 → (0.6/2 + 0.3) * 2.4/2.0 box top.
    assert hi[1] - lo[1] == pytest.approx((0.45 + 0.15 + 0.3) * me.MESH_LENGTH / 2.0)
    for suffix in (".obj", ".stl"):
        body.export(tmp_path / f"box{suffix}")
        m = me.load_mesh(tmp_path / f"box{suffix}")
        assert m.positions.shape[0] >= 8 and m.faces.shape[0] == 12
        assert (m.bounds[1] - m.bounds[0]) == pytest.approx([2.4, 0.72, 1.08], rel=1e-5)
    (tmp_path / "bad.obj").write_text("this is not a mesh\n")
    with pytest.raises(RenderInputError, match="mesh"):
        me.load_mesh(tmp_path / "bad.obj")
    with pytest.raises(RenderInputError, match="mesh"):
        me.load_mesh(tmp_path / "model.ply")


def test_imported_meshes_shade_smooth(tmp_path) -> None:
    """A flat-shaded sphere (one vertex per face corner, as an STL stores it) loads with smooth normals:
    each within 3° of the exact radial normal; a box keeps its 90° creases (axis-aligned normals)."""
    import trimesh

    ico = trimesh.creation.icosphere(subdivisions=3)
    ico.unmerge_vertices()
    ico.export(tmp_path / "ball.stl")
    mesh = me.load_mesh(tmp_path / "ball.stl")
    centre = 0.5 * (mesh.bounds[0] + mesh.bounds[1])
    radial = mesh.positions - centre
    radial /= np.linalg.norm(radial, axis=1, keepdims=True)
    assert np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", radial, mesh.normals), -1, 1))).max() < 3.0
    trimesh.creation.box((2.0, 1.0, 1.0)).export(tmp_path / "box.stl")
    box = me.load_mesh(tmp_path / "box.stl")
    assert np.allclose(np.abs(box.normals).max(axis=1), 1.0, atol=1e-6)


def test_shared_vertices_without_normals_shade_smooth_with_creases(tmp_path) -> None:
    """An OBJ with shared vertices and no normals: a box's 8 corners get axis-aligned normals (its creases
    kept, not the corner normals (±1, ±1, ±1)/√3 of area weighting) and an icosphere's normals lie within
    3° of the exact radial ones; an OBJ that gives its normals keeps them."""
    lines = [f"v {x} {y} {z}" for x in (0, 2) for y in (0, 1) for z in (0, 1)]
    quads = [(1, 2, 4, 3), (5, 7, 8, 6), (1, 5, 6, 2), (3, 4, 8, 7), (1, 3, 7, 5), (2, 6, 8, 4)]
    lines += [f"f {a} {b} {c}\nf {a} {c} {d}" for a, b, c, d in quads]
    (tmp_path / "box.obj").write_text("\n".join(lines) + "\n")
    box = me.load_mesh(tmp_path / "box.obj")
    assert np.allclose(np.abs(box.normals).max(axis=1), 1.0, atol=1e-6)
    import trimesh

    ico = trimesh.creation.icosphere(subdivisions=3)
    text = "".join(f"v {x} {y} {z}\n" for x, y, z in ico.vertices)
    text += "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in ico.faces)
    (tmp_path / "ball.obj").write_text(text)
    ball = me.load_mesh(tmp_path / "ball.obj")
    radial = ball.positions - 0.5 * (ball.bounds[0] + ball.bounds[1])
    radial /= np.linalg.norm(radial, axis=1, keepdims=True)
    assert np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", radial, ball.normals), -1, 1))).max() < 3.0
    given = "v 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nvn 0.6 0.8 0\nf 1//1 3//1 2//1\nf 1//1 4//1 3//1\n"
    (tmp_path / "given.obj").write_text(given)
    assert np.allclose(me.load_mesh(tmp_path / "given.obj").normals, [0.6, 0.8, 0.0], atol=1e-6)


def test_car_body_is_smooth_and_closed() -> None:
    from station.render.car import car_body

    car = car_body(96, 48)
    lo, hi = car.bounds
    assert hi[0] - lo[0] == pytest.approx(me.MESH_LENGTH)
    assert 0.4 < (hi[2] - lo[2]) / (hi[0] - lo[0]) < 0.5  # width 1.0 of 2.4
    # Closed: the body (paint and glass, their shared edge vertices merged) is one watertight sphere.
    import trimesh

    keep = np.isin(car.painted, (me.PAINT, me.GLASS))[car.faces].all(axis=1)
    shell = trimesh.Trimesh(car.positions.astype(float), car.faces[keep], process=False)
    shell.merge_vertices()
    assert shell.is_watertight and shell.euler_number == 2 and shell.volume > 0
    # Smooth: neighbouring vertex normals differ by < 25° everywhere along the edges, here and in the
    # default tessellation the CLI, viewer and service draw.
    for mesh in (car, car_body()):
        e = np.concatenate([mesh.faces[:, [0, 1]], mesh.faces[:, [1, 2]], mesh.faces[:, [2, 0]]])
        cosines = np.einsum("ij,ij->i", mesh.normals[e[:, 0]], mesh.normals[e[:, 1]])
        assert cosines.min() > np.cos(np.radians(25.0))
    body = np.isin(car.painted, (me.PAINT, me.GLASS))
    out = np.einsum("ij,ij->i", car.normals[body], car.positions[body] - car.positions.mean(axis=0))
    assert (out > 0).mean() > 0.95
    # A car, not a pebble: glass on the cabin, four wheels standing on the floor with chrome hubs.
    tyre = car.positions[car.painted == me.TYRE]
    assert tyre[:, 1].min() == pytest.approx(car.floor_y, abs=1e-6)
    assert car.positions[body][:, 1].min() > car.floor_y + 0.02  # the body clears the ground
    assert {(bool(x > 0), bool(z > 0)) for x, z in tyre[:, [0, 2]]} == {
        (a, b) for a in (0, 1) for b in (0, 1)
    }
    glass = car.positions[car.painted == me.GLASS]
    assert len(glass) > 0 and glass[:, 1].min() > car.positions[body][:, 1].mean()  # above the belt
    assert (car.painted == me.CHROME).any()
    # Each wheel face is a chrome hub inside a tyre sidewall: similar polygons, so the chrome share of the
    # faces' area is (HUB_RADIUS / WHEEL_RADIUS)² exactly (a face wholly chrome read as a mirror disc).
    from station.render.car import HUB_RADIUS, WHEEL_RADIUS

    tri = car.positions[car.faces].astype(np.float64)
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    code = car.painted[car.faces[:, 2]]
    axial = np.abs(car.normals[car.faces[:, 2]][:, 2]) > 0.999
    chrome, sidewall = area[code == me.CHROME].sum(), area[axial & (code == me.TYRE)].sum()
    assert chrome / (chrome + sidewall) == pytest.approx((HUB_RADIUS / WHEEL_RADIUS) ** 2, rel=1e-4)


def test_car_glass_edges_follow_parameter_curves() -> None:
    """The glass/paint edge runs along stations and section curves, not a saw-tooth: each vertex on it lies
    at a glass edge station, or is one of at most two per station and side (three (the side window's bottom and
    top, and a screen's side edge where both meet); the side windows' bottom edge lies on the belt line, at BELT_Y."""
    from station.render import car as cm

    car = cm.car_body()
    floor = car.floor_y
    key = np.round(car.positions.astype(float), 6)
    _, inv = np.unique(key, axis=0, return_inverse=True)
    inv = inv.ravel()
    glass = np.zeros(inv.max() + 1, bool)
    paint = np.zeros(inv.max() + 1, bool)
    glass[inv[car.painted == me.GLASS]] = True
    paint[inv[car.painted == me.PAINT]] = True
    first = np.zeros(inv.max() + 1, int)
    first[inv] = np.arange(inv.size)
    edge = car.positions[first[glass & paint]].astype(float)
    assert len(edge) > 100
    edges_x = np.array([*cm.SIDE_GLASS, *cm.B_PILLAR, *cm.WINDSCREEN, *cm.REAR_WINDOW])
    on_station = np.min(np.abs(edge[:, :1] - edges_x[None, :]), axis=1) < 1e-5
    rest = edge[~on_station]
    stations, counts = np.unique(
        np.stack([np.round(rest[:, 0], 5), np.sign(rest[:, 2])], 1), axis=0, return_counts=True
    )
    both = np.zeros(len(stations), bool)  # stations with a side window and a screen: a third edge
    for lo_x, hi_x in (cm.WINDSCREEN, cm.REAR_WINDOW):
        both |= (stations[:, 0] > max(lo_x, cm.SIDE_GLASS[0])) & (
            stations[:, 0] < min(hi_x, cm.SIDE_GLASS[1])
        )
    assert counts.max() <= 3 and counts[~both].max() <= 2, stations[~both & (counts > 2)][:5]
    # belt: the lowest edge vertex at each station inside the side windows (off the B-pillar)
    side = (rest[:, 0] > cm.SIDE_GLASS[0]) & (rest[:, 0] < cm.SIDE_GLASS[1])
    side &= (rest[:, 0] < cm.B_PILLAR[0]) | (rest[:, 0] > cm.B_PILLAR[1])
    side &= (rest[:, 0] < cm.WINDSCREEN[0]) | (rest[:, 0] > cm.WINDSCREEN[1])  # below the windscreen: none
    lows = [rest[side & (rest[:, 0] == x), 1].min() for x in np.unique(rest[side, 0])]
    assert len(lows) > 20
    assert np.array(lows) == pytest.approx(floor + cm.BELT_Y, abs=1e-5)


def _inside_by_vertical_rays(points: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Whether each point lies inside the closed triangle soup *tri* (T, 3, 3): the parity of the triangles
    crossed by a ray straight up (+y) from it (brute force over every triangle)."""
    out = np.zeros(len(points), bool)
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    for i, p in enumerate(points):
        # barycentric coordinates of (p.x, p.z) in each triangle's (x, z) projection
        v0, v1 = (b - a)[:, [0, 2]], (c - a)[:, [0, 2]]
        v2 = p[[0, 2]] - a[:, [0, 2]]
        den = v0[:, 0] * v1[:, 1] - v1[:, 0] * v0[:, 1]
        ok = np.abs(den) > 1e-14
        u = np.where(ok, (v2[:, 0] * v1[:, 1] - v1[:, 0] * v2[:, 1]) / np.where(ok, den, 1.0), -1.0)
        w = np.where(ok, (v0[:, 0] * v2[:, 1] - v2[:, 0] * v0[:, 1]) / np.where(ok, den, 1.0), -1.0)
        hit = ok & (u >= 0) & (w >= 0) & (u + w <= 1)
        y = a[hit, 1] + u[hit] * (b - a)[hit, 1] + w[hit] * (c - a)[hit, 1]
        out[i] = int(np.count_nonzero(y > p[1])) % 2 == 1
    return out


def test_car_wheels_stand_in_their_arches() -> None:
    """No tyre point lies inside the closed body (vertical-ray parity, brute force): the arches clear the
    wheels; a tyre lifted by 0.1 (scene units) would cut into the body, so the test can fail."""
    from station.render.car import car_body

    car = car_body()
    body = np.isin(car.painted, (me.PAINT, me.GLASS))
    tri = car.positions[car.faces[body[car.faces].all(axis=1)]].astype(float)
    tyre = car.positions[car.painted == me.TYRE].astype(float)
    axle_y = 0.5 * (tyre[:, 1].min() + tyre[:, 1].max())
    top = tyre[tyre[:, 1] > axle_y][::3]  # the upper half of each tyre, where an arch could cut it
    assert len(top) > 100
    assert not _inside_by_vertical_rays(top, tri).any()
    assert _inside_by_vertical_rays(top + [0.0, 0.1, 0.0], tri).sum() >= 10
    assert _inside_by_vertical_rays(np.array([[0.0, car.floor_y + 0.4, 0.0]]), tri).all()


def test_car_profile_has_hood_roof_and_boot() -> None:
    """Side profile (highest body point per station, above the floor): the roof stands at least 1.3 times
    as high as the hood and 1.25 times the boot (a saloon: about 1.45 m roof, 1.0 m hood and boot), and
    the windscreen is raked 20°-35° from the horizontal (saloons: about 25°-30°)."""
    from station.render.car import car_body

    car = car_body()
    body = np.isin(car.painted, (me.PAINT, me.GLASS))
    p = car.positions[body].astype(float)

    xs, inv = np.unique(np.round(p[:, 0], 6), return_inverse=True)
    top = np.full(xs.size, -np.inf)
    np.maximum.at(top, inv.ravel(), p[:, 1] - car.floor_y)

    def height(x0: float, x1: float) -> float:
        return float(np.interp(np.linspace(x0, x1, 9), xs, top).max())

    roof, hood, boot = height(-0.4, 0.0), height(0.7, 0.95), height(-1.1, -0.95)
    assert roof / hood > 1.3 and roof / boot > 1.25
    assert hood > height(1.18, 1.2) and boot > height(-1.2, -1.18)  # the ends fall away
    rake = np.degrees(np.arctan((height(0.2, 0.2) - height(0.4, 0.4)) / 0.2))
    assert 20.0 < rake < 35.0


def test_car_contact_shadow_proxies_clear_the_ground() -> None:
    """The procedural car's sphere proxies lie inside the body's bounds and above its sills: the ground
    under the car is shaded (occluded ≥ 0.5 under the middle) but nowhere fully black (< 0.95), where the
    generic proxies resting on the floor hide the whole sky at their contact points."""
    from station.render.car import car_body
    from station.render.stage import sphere_occlusion

    car = car_body()
    occ = car.occluders()
    body = np.isin(car.painted, (me.PAINT, me.GLASS))
    lo, hi = car.positions[body].min(axis=0), car.positions[body].max(axis=0)
    assert (occ[:, :3] - occ[:, 3:] >= lo - 1e-5).all() and (occ[:, :3] + occ[:, 3:] <= hi + 1e-5).all()
    xs, zs = np.meshgrid(np.linspace(-1.3, 1.3, 53), np.linspace(-0.6, 0.6, 25))
    ground = np.stack([xs.ravel(), np.full(xs.size, car.floor_y), zs.ravel()], 1)
    o = sphere_occlusion(ground, occ)
    assert o.max() < 0.95
    assert sphere_occlusion([[0.0, car.floor_y, 0.0]], occ)[0] >= 0.5
    generic = me.Mesh.occluders(car)
    assert sphere_occlusion(ground, generic).max() > 0.99


@pytest.mark.gl
def test_mesh_raster_matches_the_ray_cast_sphere(gl_ctx, sky_basis) -> None:
    """A finely tessellated unit sphere with exact normals, rasterised, shades like the ray-cast sphere."""
    import trimesh

    from station.render.gl_renderer import GLRenderer

    ico = trimesh.creation.icosphere(subdivisions=5)
    v = np.asarray(ico.vertices, np.float32)
    mesh = me.Mesh(
        "ico",
        v,
        v / np.linalg.norm(v, axis=1, keepdims=True),
        np.asarray(ico.faces, np.uint32),
        np.ones(len(v), np.float32),
    )
    scene = shapes.Scene("sphere")
    w = h = 72
    with GLRenderer(sky_basis, w, h, ctx=gl_ctx) as gl:
        raster = gl.render_mesh(mesh, _pair(), camera=scene.view_camera, linear=True)
        ray = gl.render_linear(scene, _pair())
    g = nr.gbuffer(scene, w, h)
    inner = g.mask & (g.n_dot_v > 0.2)
    rel = np.abs(raster[inner] - ray[inner]) / np.maximum(ray[inner], 0.02)
    assert np.median(rel) < 0.01 and np.percentile(rel, 95) < 0.05
    assert raster[~g.mask & (np.abs(ray - nr.BACKGROUND).max(axis=-1) < 1e-6)] == pytest.approx(nr.BACKGROUND)


@pytest.mark.gl
def test_neutral_parts_are_grey(gl_ctx, sky_basis, tmp_path) -> None:
    import trimesh

    from station.render.gl_renderer import GLRenderer

    body = trimesh.creation.box((2.0, 0.6, 0.9))
    glass = trimesh.creation.box((1.0, 0.3, 0.7))
    glass.apply_translation((0.0, 0.45, 0.0))
    glass.unmerge_vertices()  # flat faces: the roof's vertex normals are all +Y
    trimesh.Scene({"body": body, "cabin": glass}).export(tmp_path / "two.glb")
    mesh = me.load_mesh(tmp_path / "two.glb", paint="body")
    top = shapes.Camera((0.0, 4.0, 0.01), (0.0, 0.0, 0.0), fov_deg=20.0)  # looking down on the glass
    with GLRenderer(sky_basis, 64, 64, ctx=gl_ctx) as gl:
        img = gl.render_mesh(mesh, _pair(), camera=top, linear=True)
    centre = img[30:34, 28:36].reshape(-1, 3)  # glass roof: neutral grey diffuse
    up = sky_basis.diffuse  # the diffuse map at +Y, times the neutral albedo
    from station.render.cubemap import sample_cube

    expected = me.NEUTRAL_ALBEDO * sample_cube(up, np.array([[0.0, 1.0, 0.0]]))[0]
    assert centre == pytest.approx(np.broadcast_to(expected, centre.shape), rel=0.03)
    # The same part named glass: Schlick's F0 = 0.04 mirror (head-on) of the sharpest map at +Y over a
    # dark interior, 0.96 · GLASS_INTERIOR (0.03) × the diffuse map.
    trimesh.Scene({"body": body, "glass": glass}).export(tmp_path / "glass.glb")
    mesh = me.load_mesh(tmp_path / "glass.glb", paint="body")
    with GLRenderer(sky_basis, 64, 64, ctx=gl_ctx) as gl:
        img = gl.render_mesh(mesh, _pair(), camera=top, linear=True)
    sharp = sky_basis.cubes[int(np.argmax(sky_basis.exponents))]
    d = np.array([[0.0, 1.0, 0.0]])
    expected = 0.04 * sample_cube(sharp, d)[0] + 0.96 * 0.03 * sample_cube(up, d)[0]
    centre = img[30:34, 28:36].reshape(-1, 3)
    assert centre == pytest.approx(np.broadcast_to(expected, centre.shape), rel=0.05)


def test_palette_textured_model_is_split_into_parts(tmp_path) -> None:
    """One material with a 4-swatch palette (orange, black, dark grey, light grey): the faces on the
    largest-area swatch are paint, the black tyre, the dark grey glass, the light grey chrome."""
    import trimesh
    from PIL import Image

    palette = np.array([[[205, 141, 83], [10, 10, 10], [60, 60, 62], [170, 170, 170]]], np.uint8)
    boxes = []
    for k, size in enumerate((3.0, 0.6, 0.8, 0.4)):
        b = trimesh.creation.box((size, size, size))
        b.apply_translation((4.0 * k, 0.0, 0.0))
        b.visual = trimesh.visual.TextureVisuals(
            uv=np.tile([(k + 0.5) / 4.0, 0.5], (len(b.vertices), 1)),
            material=trimesh.visual.material.SimpleMaterial(image=Image.fromarray(palette)),
        )
        boxes.append(b)
    merged = trimesh.util.concatenate(boxes)
    merged.export(tmp_path / "palette.glb")
    mesh = me.load_mesh(tmp_path / "palette.glb")
    order = np.argsort(mesh.positions[:, 0])  # the boxes lie along x, biggest first
    third = len(order) // 4
    got = [np.unique(mesh.painted[order[i * third : (i + 1) * third]]) for i in range(4)]
    assert [g.tolist() for g in got] == [[me.PAINT], [me.TYRE], [me.GLASS], [me.CHROME]]
    assert me.load_mesh(tmp_path / "palette.glb", paint="geometry").painted.min() == me.PAINT  # by name: all


@pytest.mark.gl
def test_cc0_sport_car_on_the_sky_stage_has_no_unlit_pixel(shared_dir: Path, tmp_path, gl_ctx) -> None:
    # `station render --mesh car-sport.glb --env sky --stage --size 1024`: the ground under the car, seen
    # between a front tyre and the sill, read exactly 0 (no light at all) where the summed occlusion of
    # the car's overlapping sphere proxies reached 1. Every pixel must now receive some light, and none
    # be NaN.
    from station.cli import main
    from station.model import FaceFlopTravelGloss
    from station.model.design_io import save_design

    car = shared_dir / "data" / "meshes" / "car-sport.glb"
    if not car.is_file():
        pytest.skip("no car-sport.glb in ../shared/data/meshes")
    blue = FaceFlopTravelGloss((45.0, -5.0, -40.0), (20.0, 0.0, -30.0), 70.0, 85.0)
    design = save_design(blue, tmp_path / "d.json")
    out = tmp_path / "car.npy"
    args = ["render", "--design", str(design), "--mesh", str(car), "--env", "sky", "--stage"]
    args += ["--size", "1024", "--out", str(tmp_path / "car.png"), "--linear-out", str(out)]
    assert main([*args, "--cache-dir", str(tmp_path / "c")]) == 0
    lin = np.load(out)
    assert lin.shape == (1024, 1024, 3) and np.isfinite(lin).all()
    y = lin @ np.array([0.2126, 0.7152, 0.0722])
    assert float(y.min()) > 1e-3, np.argwhere(y <= 1e-3)[:5]
