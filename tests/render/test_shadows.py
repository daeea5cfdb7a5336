"""Shadow maps and ground ambient occlusion of meshes and ray-cast shapes in the GL renderer
(station.render.gl_shadows) against closed forms and brute force: a sphere's shadow ellipse, a box's shadow
on a plate, a sphere's occluded sky fraction, the speed shape's shadow against a NumPy ray cast."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from station.render import gl_shadows as gs
from station.render import prefilter
from station.render.camera import Camera
from station.render.cubemap import equirect_directions
from station.render.environment import Environment, Lights
from station.render.errors import RenderInputError
from station.render.meshes import Mesh
from station.render.stage import Stage, light_visibility, lookup_matrix, sphere_occlusion
from station.render.weights import LobeWeights

EXPS = (1.0, 8.0, 64.0, 512.0)
SUN = np.array([0.5, 0.6, 0.35]) / np.linalg.norm([0.5, 0.6, 0.35])


@pytest.fixture(scope="module")
def sun_basis():
    """A dim uniform sky with one sun of 1° radius towards SUN (taken out as the one light)."""
    d = equirect_directions(256, 512)
    eq = np.full((256, 512, 3), 0.2, np.float32)
    eq[d @ SUN > math.cos(math.radians(1.0))] = 2000.0
    basis = prefilter.prefilter_basis(Environment("sun", eq), EXPS, max_size=32)
    assert basis.lights is not None and basis.lights.count == 1
    return basis


def _diffuse() -> LobeWeights:
    return LobeWeights(EXPS, np.array([0.4, 0.4, 0.4]), np.zeros((4, 3)), np.zeros(4))


def _uv_sphere(r: float, centre, nu: int = 128, nv: int = 64) -> Mesh:
    th = np.linspace(0.0, np.pi, nv + 1)
    ph = np.linspace(0.0, 2.0 * np.pi, nu, endpoint=False)
    t, p = np.meshgrid(th, ph, indexing="ij")
    n = np.stack([np.sin(t) * np.cos(p), np.cos(t), np.sin(t) * np.sin(p)], -1).reshape(-1, 3)
    a = (np.arange(nv)[:, None] * nu + np.arange(nu)[None, :]).ravel()
    b = (np.arange(nv)[:, None] * nu + (np.arange(nu)[None, :] + 1) % nu).ravel()
    faces = np.concatenate([np.stack([a, a + nu, b], -1), np.stack([b, a + nu, b + nu], -1)])
    pos = n * r + np.asarray(centre, float)
    return Mesh(
        "sphere",
        pos.astype(np.float32),
        n.astype(np.float32),
        faces.astype(np.uint32),
        np.ones(len(n), np.float32),
    )


def _flat_boxes(boxes: list[tuple[np.ndarray, np.ndarray]]) -> Mesh:
    """Axis-aligned boxes (lo, hi) as one mesh with flat (per-face) normals."""
    import trimesh

    tris, normals = [], []
    for lo, hi in boxes:
        b = trimesh.creation.box(extents=hi - lo)
        tris.append(np.asarray(b.triangles) + 0.5 * (lo + hi))
        normals.append(np.repeat(np.asarray(b.face_normals), 3, axis=0))
    v = np.concatenate(tris).reshape(-1, 3)
    f = np.arange(len(v)).reshape(-1, 3)
    n = np.concatenate(normals)
    return Mesh(
        "boxes", v.astype(np.float32), n.astype(np.float32), f.astype(np.uint32), np.ones(len(v), np.float32)
    )


def _ray_hits_box(p: np.ndarray, ell: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Whether the rays p + t ell, t > 0 (p (N, 3)) meet the box [lo, hi] (slab test)."""
    with np.errstate(divide="ignore"):
        inv = 1.0 / ell
    t0, t1 = (lo - p) * inv, (hi - p) * inv
    t_in = np.minimum(t0, t1).max(axis=1)
    t_out = np.maximum(t0, t1).min(axis=1)
    return (t_out >= np.maximum(t_in, 0.0)) & (t_out > 0.0)


def test_shadow_lights_are_the_strongest_and_radius_from_spread() -> None:
    lights = Lights(np.eye(3), np.array([[1.0, 1.0, 1.0], [0.0, 0.0, 9.0], [3.0, 3.0, 3.0]]))
    # luma: 1, 9 · 0.0722 = 0.65, 3 → the third, then the first
    assert gs.shadow_lights(lights) == (2, 0)
    assert gs.shadow_lights(lights, 1) == (2,)
    assert gs.shadow_lights(None) == ()
    # a uniform disc of radius a: s² = E[θ²]/2 = a²/4
    a = math.radians(10.0)
    assert gs.light_radius_rad(a * a / 4.0) == pytest.approx(a)
    assert gs.light_radius_rad(0.0) == pytest.approx(math.radians(gs.SUN_RADIUS_DEG))
    with pytest.raises(RenderInputError, match="spread"):
        gs.light_radius_rad(-1.0)
    with pytest.raises(RenderInputError, match="count"):
        gs.shadow_lights(lights, -1)


def test_light_view_maps_the_box_into_the_unit_cube() -> None:
    lo, hi = np.array([-1.2, -0.5, -0.6]), np.array([1.2, 0.7, 0.6])
    view = gs.light_view(SUN, lo, hi, 256)
    corners = np.array(
        [[x, y, z, 1.0] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
    )
    s = corners @ view.matrix.T
    assert s[:, :3].min() > 0.0 and s[:, :3].max() < 1.0
    # depth grows away from the light: the corner farthest along SUN is the nearest
    assert np.argmin(s[:, 2]) == np.argmax(corners[:, :3] @ SUN)
    # u, v, depth are orthogonal world axes (an orthographic view), depth along −SUN
    axes = view.matrix[:3, :3] / np.linalg.norm(view.matrix[:3, :3], axis=1, keepdims=True)
    assert axes @ axes.T == pytest.approx(np.eye(3), abs=1e-12)
    assert axes[2] == pytest.approx(-SUN)


@pytest.mark.gl
@pytest.mark.parametrize("rotation", [0.0, 90.0])
def test_sphere_shadow_is_the_analytic_ellipse(gl_ctx, sun_basis, rotation) -> None:
    """A sphere (radius r, resting on the ground) under one sun of direction l: its shadow on the ground
    is the ellipse centred at c − l c_y / l_y with semi-axes r and r / l_y, area π r² / l_y."""
    from station.render.gl_renderer import GLRenderer

    r = 0.5
    mesh = _uv_sphere(r, (0.0, r, 0.0))
    stage = Stage(backdrop=False, rotation_deg=rotation)
    ell = lookup_matrix(rotation).T @ sun_basis.lights.directions[0]  # the sun's world direction
    with GLRenderer(sun_basis, 64, 48, ctx=gl_ctx) as gl:
        ground, _ = gl.shadow_probe(mesh, [_diffuse()], stage=stage, size=512)
    n, radius = ground.shape[0], stage.ground_radius
    xs = -radius + (np.arange(n) + 0.5) * 2.0 * radius / n
    x, z = np.meshgrid(xs, xs)
    shade = ground[..., 0] < 0.5
    area = shade.sum() * (2.0 * radius / n) ** 2
    assert area == pytest.approx(math.pi * r * r / ell[1], rel=0.02)
    centre = -ell * r / ell[1]
    assert x[shade].mean() == pytest.approx(centre[0], abs=0.01)
    assert z[shade].mean() == pytest.approx(centre[2], abs=0.01)
    assert ground[..., 0].min() == 0.0 and ground[..., 0].max() == 1.0
    # The frame: a ground point in the ellipse, 1.0 from the contact point away from the sun (past the
    # sphere's footprint, about 0.2 short of the ellipse's far end), against its mirror image about the contact
    # point (the same occlusion by symmetry) differs by the sun's direct part albedo · l_y Φ / π.
    cam = Camera((0.0, 5.0, 0.5), (0.0, 0.0, 0.0), fov_deg=60.0)
    with GLRenderer(sun_basis, 160, 120, ctx=gl_ctx) as gl:
        frame = gl.render_mesh(mesh, [_diffuse()], camera=cam, stage=stage, linear=True)
    origin, dirs = cam.rays(160, 120)
    hit = origin + (-origin[1] / np.minimum(dirs[..., 1], -1e-9))[..., None] * dirs  # on the ground y = 0

    def pixel(point: np.ndarray) -> np.ndarray:
        i = np.argmin(np.linalg.norm(hit - point, axis=-1))
        return frame.reshape(-1, 3)[i]

    away = -np.array([ell[0], 0.0, ell[2]]) / math.hypot(ell[0], ell[2])
    gap = pixel(-away) - pixel(away)
    direct = stage.ground_albedo * ell[1] * sun_basis.lights.flux[0] / math.pi
    assert gap == pytest.approx(direct, rel=0.03)


@pytest.mark.gl
def test_box_shadows_the_plate_it_stands_on(gl_ctx, sun_basis) -> None:
    """A box on a plate (one mesh): plate points whose ray to the sun meets the box are shadowed, the others
    lit (closed-form slab test, 3 cm margin for the penumbra), and the frame's plate radiance there
    differs by the sun's Lambertian part w_D l_y Φ / π exactly (no more is shadowed)."""
    from station.render.gl_renderer import GLRenderer

    plate = (np.array([-1.5, -0.1, -1.5]), np.array([1.5, 0.0, 1.5]))
    box = (np.array([-0.2, 0.0, -0.2]), np.array([0.2, 0.6, 0.2]))
    mesh = _flat_boxes([plate, box])
    ell = sun_basis.lights.directions[0]
    cam = Camera((0.0, 4.0, 2.5), (0.0, 0.0, 0.0), fov_deg=50.0)
    stage = Stage(backdrop=False)
    paint = _diffuse()
    with GLRenderer(sun_basis, 160, 120, ctx=gl_ctx) as gl:
        _, model = gl.shadow_probe(mesh, [paint], camera=cam, stage=stage)
        frame = gl.render_mesh(mesh, [paint], camera=cam, stage=stage, linear=True)
    top = (model[..., 0] >= 0.0) & (np.abs(model[..., 2]) < 1e-4)
    p = model[top][:, 1:]
    outside = (np.abs(p[:, 0]) > 0.25) | (np.abs(p[:, 2]) > 0.25)
    d = np.array([0.03, 0.03, 0.03])
    surely_dark = _ray_hits_box(p, ell, box[0] + d, box[1] - d) & outside
    surely_lit = ~_ray_hits_box(p, ell, box[0] - d, box[1] + d) & outside
    assert surely_dark.sum() > 100 and surely_lit.sum() > 1000
    vis = model[top][:, 0]
    assert vis[surely_dark].max() < 0.05
    assert vis[surely_lit].min() > 0.95
    rgb = frame[top]
    sun_part = paint.map_weights()[0] * ell[1] * sun_basis.lights.flux[0] / math.pi
    gap = rgb[surely_lit].mean(axis=0) - rgb[surely_dark].mean(axis=0)
    assert gap == pytest.approx(sun_part, rel=0.02)


@pytest.mark.gl
def test_ground_occlusion_of_a_sphere_is_the_closed_form(gl_ctx, sun_basis) -> None:
    """1 − O on the ground under a sphere: in [0, 1], O equal to the cosine-weighted occluded fraction
    (r/d)² cos β of the sphere (station.render.stage.sphere_occlusion) within 0.03, falling with the
    distance from the contact point (near 1 there), below 0.01 beyond 3 units (1 − O → 1 far away)."""
    from station.render.gl_renderer import GLRenderer

    r = 0.5
    mesh = _uv_sphere(r, (0.0, r, 0.0))
    stage = Stage(backdrop=False)
    with GLRenderer(sun_basis, 64, 48, ctx=gl_ctx) as gl:
        ground, _ = gl.shadow_probe(mesh, [_diffuse()], stage=stage, size=256)
    n, radius = ground.shape[0], stage.ground_radius
    xs = -radius + (np.arange(n) + 0.5) * 2.0 * radius / n
    x, z = np.meshgrid(xs, xs)
    occ = 1.0 - ground[..., 2]
    assert occ.min() >= 0.0 and occ.max() <= 1.0
    ref = sphere_occlusion(np.stack([x.ravel(), np.zeros(x.size), z.ravel()], -1), [[0.0, r, 0.0, r]])
    assert np.abs(occ - ref.reshape(n, n)).max() < 0.03
    dist = np.hypot(x, z)
    rings = [occ[(dist >= a) & (dist < a + 0.25)].mean() for a in np.arange(0.0, 3.0, 0.25)]
    assert all(a > b for a, b in itertools.pairwise(rings))
    assert rings[0] > 0.8  # the closed form's mean over the innermost ring: 0.846
    assert occ[dist > 3.0].max() < 0.01  # the closed form: at most 0.0044 there


@pytest.mark.gl
def test_a_lit_sphere_has_no_shadow_acne(gl_ctx, sun_basis) -> None:
    """A convex sphere can shadow only its own far side: no pixel facing the sun (N·l > 0) is shadowed."""
    from station.render.gl_renderer import GLRenderer

    r = 0.5
    mesh = _uv_sphere(r, (0.0, r, 0.0))
    ell = sun_basis.lights.directions[0]
    for cam in (
        Camera((0.0, 3.0, 4.0), (0.0, 0.3, 0.0), fov_deg=30.0),
        Camera((3.0, 0.6, -2.0), (0.0, 0.5, 0.0), fov_deg=30.0),
    ):
        with GLRenderer(sun_basis, 200, 150, ctx=gl_ctx) as gl:
            _, model = gl.shadow_probe(mesh, [_diffuse()], camera=cam, stage=Stage(backdrop=False))
        on = model[..., 0] >= 0.0
        normal = (model[on][:, 1:] - [0.0, r, 0.0]) / r
        facing = normal @ ell > 0.0
        assert facing.sum() > 2000
        assert model[on][facing, 0].min() > 0.99
        assert model[on][normal @ ell < -0.3, 0].max() < 0.01  # the far side is in its own shadow


@pytest.mark.gl
def test_maps_are_drawn_once_per_light_and_model_not_per_orbit_frame(gl_ctx, sun_basis) -> None:
    from station.render.gl_renderer import GLRenderer

    mesh = _uv_sphere(0.5, (0.0, 0.5, 0.0), 32, 16)
    with GLRenderer(sun_basis, 64, 48, ctx=gl_ctx) as gl:
        gl.render_mesh(mesh, [_diffuse()], stage=Stage())
        drawn = gl.shadow_redraws
        assert drawn > 0
        for yaw in (10.0, 20.0, 30.0):  # an orbit: the camera moves, the environment does not
            eye = (4.0 * math.sin(math.radians(yaw)), 1.0, 4.0 * math.cos(math.radians(yaw)))
            gl.render_mesh(mesh, [_diffuse()], camera=Camera(eye, (0.0, 0.0, 0.0)), stage=Stage())
        assert gl.shadow_redraws == drawn
        gl.render_mesh(mesh, [_diffuse()], stage=Stage(rotation_deg=30.0))  # the sun turns: new maps
        assert gl.shadow_redraws == drawn + 1
        gl.shadows = False
        gl.render_mesh(mesh, [_diffuse()], stage=Stage(rotation_deg=45.0))
        assert gl.shadow_redraws == drawn + 1
        with pytest.raises(RenderInputError, match="mesh"):
            gl.shadow_probe(mesh, [_diffuse()])


# Ray-cast shapes (station.render.shapes): their depth is ray cast from the light (ShapeCaster), the lookups
# are the meshes'.


@pytest.mark.gl
@pytest.mark.parametrize("rotation", [0.0, 90.0])
def test_raycast_sphere_shadow_is_the_analytic_ellipse(gl_ctx, sun_basis, rotation) -> None:
    """The ray-cast unit sphere on its floor y = −1: its ground shadow is the ellipse of area π / l_y
    centred at (0, −1, 0) − l / l_y (the contact point moved along the light by the centre's height 1)."""
    from station.render.gl_renderer import GLRenderer

    stage = Stage(backdrop=False, rotation_deg=rotation)
    ell = lookup_matrix(rotation).T @ sun_basis.lights.directions[0]
    with GLRenderer(sun_basis, 64, 48, ctx=gl_ctx) as gl:
        ground, _ = gl.shadow_probe(None, [_diffuse()], stage=stage, size=512, shape="sphere")
    x, z = _ground_grid(ground.shape[0], stage.ground_radius, (0.0, 0.0))
    shade = ground[..., 0] < 0.5
    area = shade.sum() * (2.0 * stage.ground_radius / ground.shape[0]) ** 2
    assert area == pytest.approx(math.pi / ell[1], rel=0.02)
    assert x[shade].mean() == pytest.approx(-ell[0] / ell[1], abs=0.01)
    assert z[shade].mean() == pytest.approx(-ell[2] / ell[1], abs=0.01)


def _ground_grid(n: int, radius: float, centre: tuple[float, float]) -> tuple[np.ndarray, np.ndarray]:
    """World x, z (n, n) of the texel centres of shadow_probe's ground (row: z, column: x)."""
    xs = -radius + (np.arange(n) + 0.5) * 2.0 * radius / n
    x, z = np.meshgrid(xs + centre[0], xs + centre[1])
    return x, z


@pytest.mark.gl
def test_a_lit_raycast_sphere_has_no_acne_and_is_unchanged(gl_ctx, sun_basis) -> None:
    """The ray-cast sphere is convex: no point facing the sun is shadowed, its far side is, and the frame's
    sphere pixels facing the sun (N·l > 0.05) equal those of the frame without shadow maps."""
    from station.render.gl_renderer import GLRenderer
    from station.render.shapes import Scene

    ell = sun_basis.lights.directions[0]
    stage = Stage(backdrop=False)
    for cam in (
        Camera((0.0, 1.5, 4.5), (0.0, 0.0, 0.0), fov_deg=30.0),
        Camera((4.0, 0.2, -2.5), (0.0, 0.0, 0.0), fov_deg=30.0),
    ):
        with GLRenderer(sun_basis, 200, 150, ctx=gl_ctx) as gl:
            _, model = gl.shadow_probe(None, [_diffuse()], camera=cam, stage=stage, shape="sphere")
            on = gl.render_linear(Scene("sphere", camera=cam, stage=stage), [_diffuse()])
            gl.shadows = False
            off = gl.render_linear(Scene("sphere", camera=cam, stage=stage), [_diffuse()])
        hit = model[..., 0] >= 0.0
        normal = model[hit][:, 1:]  # the unit sphere: the point is its normal
        facing = normal @ ell > 0.0
        assert facing.sum() > 2000
        assert model[hit][facing, 0].min() > 0.99
        assert model[hit][normal @ ell < -0.3, 0].max() < 0.01
        lit = normal @ ell > 0.05
        rel = np.abs(on[hit][lit] - off[hit][lit]) / off[hit][lit]
        assert rel.max() < 0.01


def _brute_force_shadow(shape: str, ell: np.ndarray, x: np.ndarray, z: np.ndarray, y: float) -> np.ndarray:
    """Whether the ray from each ground point (x, y, z) towards the light ell meets *shape*: the NumPy
    renderer's own ray-shape intersection (station.render.shapes.intersect, its origins broadcast: one
    ray per point)."""
    from station.render.shapes import Scene, intersect

    p = np.stack([x.ravel(), np.full(x.size, y), z.ravel()], -1)
    return intersect(Scene(shape), p, np.broadcast_to(ell, p.shape)).mask.reshape(x.shape)


@pytest.mark.gl
@pytest.mark.parametrize("rotation", [0.0, 120.0])
def test_speedshape_ground_shadow_is_one_region_of_the_ray_cast_outline(gl_ctx, sun_basis, rotation) -> None:
    """The speed shape's ground shadow is one connected region whose outline is the brute-force ray cast's:
    every ground texel more than 2 texels from the brute-force outline agrees with it (dark where the ray to
    the sun meets the shape). The sphere proxies' shadow does not pass the same check."""
    from scipy import ndimage

    from station.render.gl_renderer import GLRenderer
    from station.render.shapes import GROUNDS, OCCLUDERS

    stage = Stage(backdrop=False, rotation_deg=rotation, ground_radius=3.0)
    ell = lookup_matrix(rotation).T @ sun_basis.lights.directions[0]
    gx, gy, gz = GROUNDS["speedshape"]
    with GLRenderer(sun_basis, 64, 48, ctx=gl_ctx) as gl:
        ground, _ = gl.shadow_probe(None, [_diffuse()], stage=stage, size=512, shape="speedshape")
    x, z = _ground_grid(ground.shape[0], stage.ground_radius, (gx, gz))
    shade = ground[..., 0] < 0.5
    _, regions = ndimage.label(shade)
    assert regions == 1
    truth = _brute_force_shadow("speedshape", ell, x, z, gy)
    assert truth.sum() > 5000
    edge = ndimage.binary_dilation(truth, iterations=2) & ~ndimage.binary_erosion(truth, iterations=2)
    assert not np.any((shade != truth) & ~edge)
    assert abs(int(shade.sum()) - int(truth.sum())) < 0.02 * truth.sum()
    # the check can fail: the proxies' shadow (station.render.stage.light_visibility) is not the outline
    p = np.stack([x.ravel(), np.full(x.size, gy), z.ravel()], -1)
    proxies = light_visibility(p, OCCLUDERS["speedshape"], ell[None]).reshape(x.shape) < 0.5
    assert np.any((proxies != truth) & ~edge)


@pytest.mark.gl
def test_raycast_sphere_ground_occlusion_is_the_closed_form(gl_ctx, sun_basis) -> None:
    """1 − O on the ground under the ray-cast unit sphere (floor y = −1): O equal to the sphere's
    cosine-weighted occluded fraction (r/d)² cos β (station.render.stage.sphere_occlusion) within 0.03."""
    from station.render.gl_renderer import GLRenderer

    stage = Stage(backdrop=False)
    with GLRenderer(sun_basis, 64, 48, ctx=gl_ctx) as gl:
        ground, _ = gl.shadow_probe(None, [_diffuse()], stage=stage, size=256, shape="sphere")
    x, z = _ground_grid(ground.shape[0], stage.ground_radius, (0.0, 0.0))
    occ = 1.0 - ground[..., 2]
    ref = sphere_occlusion(
        np.stack([x.ravel(), np.full(x.size, -1.0), z.ravel()], -1), [[0.0, 0.0, 0.0, 1.0]]
    )
    assert np.abs(occ - ref.reshape(occ.shape)).max() < 0.03
    assert occ.max() > 0.8


@pytest.mark.gl
def test_raycast_maps_are_drawn_per_shape_and_light_not_per_orbit_frame(gl_ctx, sun_basis) -> None:
    from station.render.gl_renderer import GLRenderer
    from station.render.shapes import Scene

    with GLRenderer(sun_basis, 64, 48, ctx=gl_ctx) as gl:
        gl.render(Scene("speedshape", stage=Stage()), [_diffuse()])
        drawn = gl.shadow_redraws
        assert drawn > 0
        for yaw in (10.0, 20.0, 30.0):
            eye = (4.0 * math.sin(math.radians(yaw)), 1.0, 4.0 * math.cos(math.radians(yaw)))
            gl.render(Scene("speedshape", camera=Camera(eye, (0.0, 0.0, 0.0)), stage=Stage()), [_diffuse()])
        assert gl.shadow_redraws == drawn
        gl.render(Scene("speedshape", stage=Stage(rotation_deg=30.0)), [_diffuse()])
        assert gl.shadow_redraws == drawn + 1
        gl.render(Scene("panels", misalignment_deg=10.0, stage=Stage(rotation_deg=30.0)), [_diffuse()])
        assert gl.shadow_redraws == drawn + 2  # a new caster; an open sheet has no occlusion map
        gl.shadows = False
        gl.render(Scene("speedshape", stage=Stage(rotation_deg=45.0)), [_diffuse()])
        assert gl.shadow_redraws == drawn + 2
        with pytest.raises(RenderInputError, match="mesh"):
            gl.shadow_probe(None, [_diffuse()], shape="speedshape")
    with pytest.raises(RenderInputError, match="shape"):
        gs.ShapeCaster("cube")
    with pytest.raises(RenderInputError, match="misalignment_deg"):
        gs.ShapeCaster("panels", 60.0)


@pytest.mark.gl
@pytest.mark.parametrize("misalignment", [-30.0, -45.0])
def test_turned_panel_shadows_the_other_as_the_ray_cast_says(gl_ctx, sun_basis, misalignment) -> None:
    """Self-shadowing of a ray-cast shape: the right panel, turned towards the camera, shadows the left
    one's front. A left-panel point is shadowed where its NumPy ray to the sun meets the panels
    (station.render.shapes.intersect): visibility < 0.05 more than 2 pixels inside that region, > 0.95 more
    than 2 pixels outside it, and the frame there differs by the sun's Lambertian part w_D (N·l) Φ / π of
    the flat panel exactly (within 2 %)."""
    from scipy import ndimage

    from station.render.gl_renderer import GLRenderer
    from station.render.shapes import Scene, intersect

    stage = Stage(backdrop=False, rotation_deg=20.0)
    ell = lookup_matrix(20.0).T @ sun_basis.lights.directions[0]
    cam = Camera((-1.0, 0.5, 3.5), (-0.2, 0.0, 0.0), fov_deg=40.0)
    paint = _diffuse()
    with GLRenderer(sun_basis, 200, 150, ctx=gl_ctx) as gl:
        _, model = gl.shadow_probe(
            None, [paint], camera=cam, stage=stage, shape="panels", misalignment_deg=misalignment
        )
        frame = gl.render_linear(Scene("panels", misalignment, camera=cam, stage=stage), [paint, paint])
    p = model[..., 1:]
    left = (model[..., 0] >= 0.0) & (p[..., 0] < -0.02) & (np.abs(p[..., 2]) < 1e-3)  # front at z = 0
    truth = np.zeros(left.shape, bool)
    q = p[left]
    truth[left] = intersect(Scene("panels", misalignment), q + 1e-4 * ell, np.broadcast_to(ell, q.shape)).mask
    dark = ndimage.binary_erosion(truth, iterations=2) & left
    lit = ~ndimage.binary_dilation(truth, iterations=2) & left
    assert dark.sum() > 500 and lit.sum() > 1000
    assert model[dark, 0].max() < 0.05
    assert model[lit, 0].min() > 0.95
    sun_part = paint.map_weights()[0] * ell[2] * sun_basis.lights.flux[0] / math.pi
    assert frame[lit].mean(axis=0) - frame[dark].mean(axis=0) == pytest.approx(sun_part, rel=0.02)


@pytest.mark.gl
def test_a_convex_shape_skips_its_own_shadow_maps_and_draws_the_same_frame(
    gl_ctx, sun_basis, monkeypatch
) -> None:
    """The sphere cannot shadow itself: its frames (a stage, a clear coat) are shaded without the shadow-map
    lookups (``FrameShadows.object_key`` is ()) and equal, value for value, the frames shaded with them
    (CONVEX_SHAPES emptied); the ground keeps its shadow. The speed shape keeps its maps."""
    from station.model.fresnel import ClearCoat
    from station.render import gl_frame_shadows
    from station.render.gl_renderer import GLRenderer
    from station.render.shapes import Scene

    frames = {}
    for convex in (("sphere",), ()):
        monkeypatch.setattr(gl_frame_shadows, "CONVEX_SHAPES", convex)
        with GLRenderer(sun_basis, 160, 120, ctx=gl_ctx) as gl:
            scenes = [
                Scene("sphere", camera=Camera(eye, (0.0, 0.0, 0.0), fov_deg=30.0), stage=Stage())
                for eye in ((0.0, 1.5, 4.5), (4.0, 0.2, -2.5))
            ]
            keys = [gl._frame_shadows.object_key(s, None, True, True, False) for s in scenes]
            assert (keys[0] == ()) == bool(convex)
            speed = gl._frame_shadows.object_key(Scene("speedshape", stage=Stage()), None, True, True, False)
            assert speed != ()
            frames[convex] = [gl.render_linear(s, [_diffuse()], coat=ClearCoat()) for s in scenes]
            gl.shadows = False
            unshadowed = gl.render_linear(scenes[0], [_diffuse()], coat=ClearCoat())
    for skipped, mapped in zip(frames[("sphere",)], frames[()], strict=True):
        assert np.array_equal(skipped, mapped)
    # the ground keeps the maps' shadow, not the sphere proxies' (which the frames without maps draw)
    assert np.abs(unshadowed - frames[("sphere",)][0]).max() > 0.01
