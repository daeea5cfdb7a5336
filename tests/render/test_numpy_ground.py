"""The NumPy renderer's ground shaded by the shape itself (station.render.ground): the unit sphere's shadow
ellipse in closed form, the sphere's sky occlusion against its closed form, the speed shape's ground
against the GL frame's (shadow maps and ambient-occlusion map), and no change without a stage or lights."""

from __future__ import annotations

import math

import numpy as np
import pytest

from station.render import numpy_renderer as nr
from station.render import prefilter
from station.render.camera import Camera
from station.render.cubemap import equirect_directions
from station.render.environment import Environment
from station.render.ground import ground_occlusion
from station.render.shapes import GROUNDS, OCCLUDERS, Scene, intersect
from station.render.stage import Stage, ground_fade, ground_radiance, lookup_matrix, sphere_occlusion
from station.render.weights import LobeWeights

EXPS = (1.0, 8.0, 64.0, 512.0)


def _sun(elevation_deg: float, azimuth_deg: float = 30.0) -> np.ndarray:
    e, a = math.radians(elevation_deg), math.radians(azimuth_deg)
    return np.array([math.cos(e) * math.cos(a), math.sin(e), math.cos(e) * math.sin(a)])


def _basis(sun: np.ndarray | None) -> prefilter.PrefilteredBasis:
    """A uniform sky of 0.2 with a sun disc of 1.5° and 4000 towards *sun* (None: the sky alone)."""
    eq = np.full((128, 256, 3), 0.2, np.float32)
    if sun is not None:
        eq[equirect_directions(128, 256) @ sun > math.cos(math.radians(1.5))] = 4000.0
    return prefilter.prefilter_basis(Environment("sun", eq), EXPS, max_size=32, engine="numpy")


def _paint() -> LobeWeights:
    return LobeWeights(EXPS, np.array([0.4, 0.3, 0.2]), np.zeros((4, 3)), np.zeros(4))


def _ground_points(n: int, half: float, centre: tuple[float, float], y: float) -> tuple[np.ndarray, float]:
    """Ground points (n², 3) at the centres of an n × n grid of side 2·half about *centre*; the texel area."""
    xs = -half + (np.arange(n) + 0.5) * 2.0 * half / n
    x, z = np.meshgrid(xs + centre[0], xs + centre[1])
    return np.stack([x.ravel(), np.full(x.size, y), z.ravel()], -1), (2.0 * half / n) ** 2


def _seen_from_above(scene: Scene, basis, pts: np.ndarray) -> np.ndarray:
    """The NumPy stage's radiance (P, 3) of ground *pts* seen from 40 units above the ground's centre."""
    origin = np.array([0.0, 40.0, 0.0])
    d = pts - origin
    return nr.stage_background(scene, basis, origin, d / np.linalg.norm(d, axis=1, keepdims=True))


@pytest.mark.parametrize(("elevation", "turn"), [(36.0, 0.0), (60.0, 75.0)])
def test_sphere_ground_shadow_is_the_ellipse(elevation: float, turn: float) -> None:
    """The unit sphere over its floor y = −1 under a sun at elevation θ: on the NumPy stage's ground the
    points darker than halfway between the sky's part albedo · 0.2 and the sun's direct part
    albedo (sin θ) Φ/π form the
    ellipse of area π r² / sin θ about −(l_x, l_z)/l_y (within 1 cm): within 1 % and smaller, as the
    sun's disc (1.5°, a soft shadow) pulls the half-light contour of the convex outline inward (measured
    −0.6 % at 36°; the hard single-ray shadow met 0.06 %)."""
    basis = _basis(_sun(elevation))
    lights = basis.lights
    assert lights is not None and lights.count == 1
    stage = Stage(backdrop=False, rotation_deg=turn, ground_radius=20.0)
    ell = lookup_matrix(turn).T @ lights.directions[0]  # the sun's world direction
    assert ell[1] == pytest.approx(math.sin(math.radians(elevation)), abs=0.01)
    pts, texel = _ground_points(500, 3.5, (-ell[0] / ell[1], -ell[2] / ell[1]), -1.0)
    radiance = _seen_from_above(Scene("sphere", stage=stage), basis, pts)[:, 1]
    direct = stage.ground_albedo * ell[1] * lights.flux[0, 1] / math.pi
    sky = stage.ground_albedo * 0.2  # the uniform sky's irradiance / π, the sun's part taken out
    assert direct > 2.0 * sky  # in the shadow at most the sky's part, in the sun at least the direct part
    shade = radiance < 0.5 * (sky + direct)
    area = shade.sum() * texel
    # the 1.5° sun's penumbra: the half-light contour of a convex outline lies inside the hard one
    assert area == pytest.approx(math.pi / ell[1], rel=0.01)
    assert area < math.pi / ell[1]
    assert pts[shade, 0].mean() == pytest.approx(-ell[0] / ell[1], abs=0.01)
    assert pts[shade, 2].mean() == pytest.approx(-ell[2] / ell[1], abs=0.01)


def test_sphere_ground_occlusion_is_the_closed_form() -> None:
    """O on the ground under the unit sphere (floor y = −1) from its height columns, baked into the map of
    a disc of radius 6 and read bilinearly, equals the sphere's cosine-weighted occluded fraction
    (r/d)² cos β (station.render.stage.sphere_occlusion) within 0.02 (measured 0.013; GL's map meets 0.03),
    and reaches 0.8 near the contact point."""
    pts, _ = _ground_points(41, 3.0, (0.0, 0.0), -1.0)
    occ = ground_occlusion(Scene("sphere"), pts, -1.0, (0.0, 0.0), 6.0)
    ref = sphere_occlusion(pts, [[0.0, 0.0, 0.0, 1.0]])
    assert np.abs(occ - ref).max() < 0.02
    assert occ.max() > 0.8


def _speedshape_frames(gl_ctx, size: tuple[int, int]):
    """(NumPy frame, GL frame, ground pixels 3 pixels and more from the sun's shadow outline and the shape's
    silhouette where the ground is not faded, the ray cast's shadow, the proxies' ground at the kept pixels)
    of the speed shape on a stage under the sun."""
    from scipy import ndimage

    from station.render.gl_renderer import GLRenderer

    basis = _basis(_sun(40.0, -100.0))
    lights = basis.lights
    assert lights is not None and lights.count == 1
    stage = Stage(backdrop=False, rotation_deg=20.0)
    camera = Camera((0.9, 3.2, 3.4), (0.5, -0.4, 0.5), fov_deg=50.0)
    scene = Scene("speedshape", camera=camera, stage=stage)
    ref = nr.render_linear(scene, basis, [_paint(), _paint()], *size).astype(float)
    with GLRenderer(basis, *size, ctx=gl_ctx) as gl:
        frame = gl.render_linear(scene, [_paint(), _paint()]).astype(float)
    g = nr.gbuffer(scene, *size)
    origin, dirs = camera.rays(*size)
    gx, gy, gz = GROUNDS["speedshape"]
    t = (gy - origin[1]) / np.minimum(dirs[..., 1], -1e-9)
    pts = origin + t[..., None] * dirs
    full = (ground_fade(np.hypot(pts[..., 0] - gx, pts[..., 2] - gz), stage.ground_radius) == 1.0) & (t > 0)
    ell = lookup_matrix(stage.rotation_deg).T @ lights.directions[0]
    q = pts.reshape(-1, 3)
    dark = intersect(Scene("speedshape"), q + 1e-4 * np.array([0.0, 1.0, 0.0]), np.broadcast_to(ell, q.shape))
    dark_img = dark.mask.reshape(g.mask.shape)
    edge = ndimage.binary_dilation(dark_img, iterations=3) & ~ndimage.binary_erosion(dark_img, iterations=3)
    near_shape = ndimage.binary_dilation(g.mask, iterations=3)
    keep = full & ~edge & ~near_shape
    up = nr.diffuse_lookup(basis, np.array([[0.0, 1.0, 0.0]]))[0]
    proxies = ground_radiance(
        pts[keep], OCCLUDERS["speedshape"], stage.ground_albedo, up, ell[None], lights.flux
    )
    return ref, frame, keep, dark_img, proxies


@pytest.mark.gl
def test_speedshape_ground_agrees_with_the_gl_frame(gl_ctx) -> None:
    """The speed shape's ground in the NumPy frame and the GL frame (its shadow maps and ambient-occlusion
    map), 3 pixels and more from the sun's shadow outline and the shape's silhouette: in the sun within
    0.2 % per pixel (measured 0.11 %); in the shadow, the sky's part alone, where the occlusion maps of the
    two engines differ by where their height texels fall, within 0.6 % at the 99th percentile and 1.5 % at
    most (measured 0.38 % and 0.86 %, the most by the contact). The proxies' ground
    (station.render.stage.ground_radiance with the proxies' V and O) differs from the GL frame by more
    than 2.5 % on hundreds of those pixels (measured 730 of 12925)."""
    ref, frame, keep, dark, proxies = _speedshape_frames(gl_ctx, (160, 120))
    shade, lit = keep & dark, keep & ~dark
    assert shade.sum() > 500 and lit.sum() > 5000
    rel = (np.abs(frame - ref) / ref).max(axis=-1)
    assert rel[lit].max() < 0.002
    assert np.percentile(rel[shade], 99) < 0.006 and rel[shade].max() < 0.015
    off = (np.abs(frame[keep] - proxies) / proxies).max(axis=-1)
    assert (off > 0.025).sum() > 200


def test_no_stage_or_no_lights_keeps_the_frame() -> None:
    """Without a stage the frame off the shape is the flat background; on a stage under a sky without
    extracted lights the ground is the sphere proxies' closed form (station.render.stage.ground_radiance,
    proxies' V and O), as before the shape's own ground (within 1e-12: the test's ground points and the
    frame's rays' differ in the last bits)."""
    sky = _basis(None)
    assert sky.lights is None or sky.lights.count == 0
    bare = Scene("speedshape")
    img = nr.render_linear(bare, sky, [_paint(), _paint()], 64, 48)
    g = nr.gbuffer(bare, 64, 48)
    assert np.all(img[~g.mask] == np.float32(nr.BACKGROUND))
    stage = Stage(backdrop=False, ground_radius=3.0)
    scene = Scene("speedshape", stage=stage)
    gx, gy, gz = GROUNDS["speedshape"]
    pts, _ = _ground_points(30, 2.0, (gx, gz), gy)
    got = _seen_from_above(scene, sky, pts)
    up = nr.diffuse_lookup(sky, np.array([[0.0, 1.0, 0.0]]))[0]
    proxies = ground_radiance(pts, OCCLUDERS["speedshape"], stage.ground_albedo, up)
    w = ground_fade(np.hypot(pts[:, 0] - gx, pts[:, 2] - gz), stage.ground_radius)[:, None]
    assert got == pytest.approx(nr.BACKGROUND * (1.0 - w) + proxies * w, rel=1e-12, abs=0.0)


def test_lights_past_the_strongest_two_and_open_shapes_keep_the_proxies() -> None:
    """Of three lights, the two strongest (ground.shadow_lights) are shadowed on the speed shape's ground by
    its ray cast (the brute-force intersection's 0 or 1 but on under 2 % of the points: the smallest light
    disc's, the sun's 0.27°, penumbra along the outline; the single ray's answer was exact when the ground's
    shadows were hard) and the third by the sphere proxies
    (station.render.stage.light_visibility), as GL's maps are drawn for two; the open panels have no
    height columns (a typed error naming the shape)."""
    from station.render.environment import Lights
    from station.render.errors import RenderInputError
    from station.render.ground import ground_light_visibility, height_columns, shadow_lights
    from station.render.stage import light_visibility

    dirs = np.array([_sun(40.0, -100.0), _sun(55.0, 20.0), _sun(30.0, 150.0)])
    lights = Lights(dirs, np.array([[1.0, 1.0, 1.0], [0.2, 0.2, 0.2], [3.0, 3.0, 3.0]]))
    slots = shadow_lights(lights)
    assert slots == (2, 0)
    gx, gy, gz = GROUNDS["speedshape"]
    pts, _ = _ground_points(60, 2.5, (gx, gz), gy)
    vis = ground_light_visibility(Scene("speedshape"), pts, dirs, slots, np.zeros(3))
    for k in slots:
        hit = intersect(Scene("speedshape"), pts + [0.0, 1e-4, 0.0], np.broadcast_to(dirs[k], pts.shape))
        differ = vis[:, k] != (~hit.mask).astype(float)  # the 0.27° sun's penumbra along the outline
        assert 0 < differ.sum() < 0.02 * len(pts)
    proxies = light_visibility(pts, OCCLUDERS["speedshape"], dirs[1:2])[:, 0]
    assert vis[:, 1] == pytest.approx(proxies, abs=1e-9)  # the matrix product's rounding aside
    assert proxies.min() == 0.0 and proxies.max() == 1.0  # the proxies do shadow it
    with pytest.raises(RenderInputError, match="shape"):
        height_columns("panels")


@pytest.mark.gl
def test_ground_only_maps_leave_the_object_unshadowed(gl_ctx) -> None:
    """GLRenderer.object_shadows False (the viewer's frames of a ray-cast shape without flakes, before its
    cached images): the object's pixels are those of the frame without shadows and the ground's those of
    the frame with them, value for value; that ground is not the proxies' (the frame without shadows)."""
    from scipy import ndimage

    from station.render.gl_renderer import GLRenderer

    size = (96, 72)
    basis = _basis(_sun(35.0, -100.0))
    camera = Camera((0.9, 3.2, 3.4), (0.5, -0.4, 0.5), fov_deg=50.0)
    scene = Scene("speedshape", camera=camera, stage=Stage(backdrop=False, rotation_deg=20.0))
    frames = {}
    with GLRenderer(basis, *size, ctx=gl_ctx) as gl:
        for name, shadows, on_object in (
            ("full", True, True),
            ("none", False, True),
            ("ground", True, False),
        ):
            gl.shadows, gl.object_shadows = shadows, on_object
            frames[name] = gl.render_linear(scene, [_paint(), _paint()]).astype(float)
    mask = nr.gbuffer(scene, *size).mask
    inside = ndimage.binary_erosion(mask, iterations=1)
    outside = ~ndimage.binary_dilation(mask, iterations=1)
    assert inside.sum() > 300 and outside.sum() > 3000
    np.testing.assert_array_equal(frames["ground"][inside], frames["none"][inside])
    np.testing.assert_array_equal(frames["ground"][outside], frames["full"][outside])
    assert np.max(np.abs(frames["ground"][outside] - frames["none"][outside])) > 0.01
