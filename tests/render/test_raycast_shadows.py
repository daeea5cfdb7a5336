"""A light's visibility decided by the shape's own ray cast (station.render.shapes.ray_cast_visibility) instead
of sphere proxies, and the shadows the NumPy renderer and the ground truth draw with it: the sphere's shadow
ellipse in closed form, the speed shape's shadow against its projected surface (where the proxies fail), a
shadowed coated panel in the NumPy renderer against a hand calculation and the GL frame, and the truth's
shadowed panel against the truth under the sky without the sun."""

from __future__ import annotations

import math

import numpy as np
import pytest

from station.model.fresnel import ClearCoat
from station.render import numpy_renderer as nr
from station.render import prefilter
from station.render.camera import Camera
from station.render.cubemap import equirect_directions
from station.render.environment import Environment
from station.render.shapes import (
    GROUNDS,
    OCCLUDERS,
    SPEED_H,
    SPEED_NOSE,
    SPEED_TAIL,
    SPEED_W,
    Scene,
    intersect,
    ray_cast_visibility,
)
from station.render.stage import Stage, light_visibility, lookup_matrix
from station.render.weights import LobeWeights
from tests.render._fresnel_hand import entry_weight, fresnel

EXPS = (1.0, 8.0, 64.0, 512.0)
SUN = np.array([0.5, 0.6, 0.35]) / np.linalg.norm([0.5, 0.6, 0.35])
MISALIGN, TURN = -30.0, 20.0
CAMERA = Camera((-1.0, 0.5, 3.5), (-0.2, 0.0, 0.0), fov_deg=40.0)


def _grid(n: int, half: float, centre: tuple[float, float], y: float) -> tuple[np.ndarray, float]:
    """Ground points (n², 3) at the centres of an n × n grid of side 2·half about *centre* at height y; the
    texel area."""
    xs = -half + (np.arange(n) + 0.5) * 2.0 * half / n
    x, z = np.meshgrid(xs + centre[0], xs + centre[1])
    return np.stack([x.ravel(), np.full(x.size, y), z.ravel()], -1), (2.0 * half / n) ** 2


def test_ray_cast_sphere_shadow_is_the_analytic_ellipse() -> None:
    """The unit sphere over its floor y = −1 under a light l: its shadow is the ellipse of area π/l_y about
    −(l_x, l_z)/l_y (the centre moved along −l to the floor); the ray cast matches within 0.5 % (area) and
    1 cm (centroid), and no point is half visible (a point light)."""
    ell = SUN
    pts, texel = _grid(600, 3.0, (0.0, 0.0), -1.0)
    vis = ray_cast_visibility(Scene("sphere"), pts, np.tile([0.0, 1.0, 0.0], (len(pts), 1)), ell[None])[:, 0]
    assert set(np.unique(vis)) == {0.0, 1.0}
    shade = vis == 0.0
    assert shade.sum() * texel == pytest.approx(math.pi / ell[1], rel=0.005)
    assert pts[shade, 0].mean() == pytest.approx(-ell[0] / ell[1], abs=0.01)
    assert pts[shade, 2].mean() == pytest.approx(-ell[2] / ell[1], abs=0.01)


def _speedshape_shadow(ell: np.ndarray, pts: np.ndarray, y: float) -> np.ndarray:
    """Whether ground *pts* lie in the speed shape's shadow, without a ray cast: its surface sampled
    parametrically (two half-ellipsoids, semi-axes nose/tail × height × width), projected along −ell onto
    the floor, and the convex hull of the projections (the shape is convex: its shadow is that hull)."""
    from scipy.spatial import Delaunay

    u, v = np.meshgrid(np.linspace(0.0, 0.5 * np.pi, 181), np.linspace(0.0, 2.0 * np.pi, 361))
    surface = [
        np.stack([side * a * np.cos(u), SPEED_H * np.sin(u) * np.cos(v), SPEED_W * np.sin(u) * np.sin(v)], -1)
        for a, side in ((SPEED_NOSE, -1.0), (SPEED_TAIL, 1.0))
    ]
    s = np.concatenate([x.reshape(-1, 3) for x in surface])
    foot = s - ell[None, :] * ((s[:, 1] - y) / ell[1])[:, None]
    return Delaunay(foot[:, [0, 2]]).find_simplex(pts[:, [0, 2]]) >= 0


@pytest.mark.parametrize("turn", [0.0, 120.0])
def test_speedshape_shadow_is_its_own_outline_not_the_proxies(turn: float) -> None:
    """The speed shape's ground shadow by the ray cast is its projected outline (every texel farther than 2
    texels from the outline agrees); the sphere proxies' shadow (station.render.stage.light_visibility)
    disagrees with it on thousands of texels."""
    from scipy import ndimage

    ell = lookup_matrix(turn).T @ SUN
    gx, gy, gz = GROUNDS["speedshape"]
    n = 400
    pts, _ = _grid(n, 2.5, (gx, gz), gy)
    up = np.tile([0.0, 1.0, 0.0], (len(pts), 1))
    shade = (ray_cast_visibility(Scene("speedshape"), pts, up, ell[None])[:, 0] == 0.0).reshape(n, n)
    truth = _speedshape_shadow(ell, pts, gy).reshape(n, n)
    assert truth.sum() > 5000
    edge = ndimage.binary_dilation(truth, iterations=2) & ~ndimage.binary_erosion(truth, iterations=2)
    assert not np.any((shade != truth) & ~edge)
    proxies = (light_visibility(pts, OCCLUDERS["speedshape"], ell[None])[:, 0] < 0.5).reshape(n, n)
    assert ((proxies != truth) & ~edge).sum() > 1000


def _env(sun: np.ndarray | None) -> Environment:
    """A uniform sky of 0.2, with a sun disc of 1.5° and 1000 towards *sun* (None: none)."""
    eq = np.full((128, 256, 3), 0.2, np.float32)
    if sun is not None:
        eq[equirect_directions(128, 256) @ sun > math.cos(math.radians(1.5))] = 1000.0
    return Environment("sun" if sun is not None else "sky", eq)


@pytest.fixture(scope="module")
def bases():
    sun = prefilter.prefilter_basis(_env(SUN), EXPS, max_size=32, engine="numpy")
    assert sun.lights is not None and sun.lights.count == 1
    return sun, prefilter.prefilter_basis(_env(None), EXPS, max_size=32, engine="numpy")


def _panel_pixels(scene: Scene, ell: np.ndarray, size: tuple[int, int]):
    """(gbuffer, dark, lit): left-panel front pixels (z = 0) whose ray to *ell* meets / misses the panels,
    2 pixels inside / outside that region."""
    from scipy import ndimage

    g = nr.gbuffer(scene, *size)
    left = g.mask & (g.position[..., 0] < -0.02) & (np.abs(g.position[..., 2]) < 1e-6)
    hit = np.zeros(left.shape, bool)
    q = g.position[left]
    hit[left] = intersect(Scene("panels", MISALIGN), q + 1e-4 * ell, np.broadcast_to(ell, q.shape)).mask
    return (
        g,
        ndimage.binary_erosion(hit, iterations=2) & left,
        ~ndimage.binary_dilation(hit, iterations=2) & left,
    )


def test_numpy_shadowed_coated_panel_loses_the_coat_weighted_share(bases) -> None:
    """The NumPy renderer on a stage: the right panel shadows the left one from the sun. In the shadow the
    frame is the unshadowed shading less (1 − F(N·V)) t(N·l) π K_D (N·l) Φ/π (hand Fresnel; the wide lobes'
    light terms are zero for this paint), and equals the frame under the sky alone within 1 %; lit pixels
    are the unshadowed shading."""
    sun_basis, sky_basis = bases
    coat = ClearCoat(1.5)
    paint = LobeWeights(EXPS, np.array([0.4, 0.3, 0.2]), np.zeros((4, 3)), np.zeros(4))
    scene = Scene("panels", MISALIGN, camera=CAMERA, stage=Stage(backdrop=False, rotation_deg=TURN))
    ell = lookup_matrix(TURN).T @ sun_basis.lights.directions[0]
    frame = nr.render_linear(scene, sun_basis, [paint, paint], 160, 120, coat=coat).astype(float)
    sky = nr.render_linear(scene, sky_basis, [paint, paint], 160, 120, coat=coat).astype(float)
    g, dark, lit = _panel_pixels(scene, ell, (160, 120))
    assert dark.sum() > 300 and lit.sum() > 800
    rot = lookup_matrix(TURN)
    free = np.zeros_like(frame)
    free[g.mask] = nr.shade_pixels(
        sun_basis, paint, g.normal[g.mask] @ rot.T, g.reflect[g.mask] @ rot.T, g.n_dot_v[g.mask], coat=coat
    )
    nl = float(ell[2])  # the left panel's normal is +z
    share = entry_weight(nl, 1.5) * paint.k_d * nl * sun_basis.lights.flux[0]  # t(N·l) π K_D (N·l) Φ/π
    lost = (1.0 - fresnel(g.n_dot_v[dark], 1.5))[:, None] * share[None, :]
    assert free[dark] - frame[dark] == pytest.approx(lost, rel=1e-5)
    assert frame[lit] == pytest.approx(free[lit], rel=1e-6)
    assert np.abs(frame[dark] / sky[dark] - 1.0).max() < 0.01


@pytest.mark.gl
def test_numpy_and_gl_shadow_the_coated_panel_alike(gl_ctx, bases) -> None:
    """The same frame by the GL renderer (shadow maps): per pixel on the left panel, 2 pixels and more from
    the ray cast's shadow outline, within 0.1 % (GL's exponential shadow map leaks light near the hinge,
    its blocker's contact: there the outline's 2 pixels are not enough, so the margin is the outline's)."""
    from station.render.gl_renderer import GLRenderer

    sun_basis, _ = bases
    coat = ClearCoat(1.5)
    paint = LobeWeights(
        EXPS, np.array([0.4, 0.3, 0.2]), np.full((4, 3), 0.02), np.array([0.0, 0.01, 0.0, 0.0])
    )
    stage = Stage(backdrop=False, rotation_deg=TURN)
    scene = Scene("panels", MISALIGN, camera=CAMERA, stage=stage)
    with GLRenderer(sun_basis, 160, 120, ctx=gl_ctx) as gl:
        frame = gl.render_linear(scene, [paint, paint], coat=coat).astype(float)
        _, model = gl.shadow_probe(
            None, [paint], camera=CAMERA, stage=stage, shape="panels", misalignment_deg=MISALIGN
        )
    ref = nr.render_linear(scene, sun_basis, [paint, paint], 160, 120, coat=coat).astype(float)
    _, dark, lit = _panel_pixels(scene, lookup_matrix(TURN).T @ sun_basis.lights.directions[0], (160, 120))
    assert dark.sum() > 300 and lit.sum() > 800
    assert model[dark, 0].max() < 1e-3 and model[lit, 0].min() > 1.0 - 1e-3
    m = dark | lit
    assert np.abs(frame - ref)[m] / ref[m] == pytest.approx(0.0, abs=1e-3)


def test_truth_shadows_a_point_light_by_the_shapes_ray_cast() -> None:
    """The ground truth of a design on the panels with positions and scene: where the right panel hides the
    sun, the left panel reads the truth under the sky without the sun (to 1e-9: the sun is a point light,
    the rest of the map the same sky); elsewhere the unshadowed truth, exactly."""
    from station.model import FaceFlopTravelGloss
    from station.render.truth import render_truth

    design = FaceFlopTravelGloss((70.0, 10.0, 20.0), (40.0, 5.0, 10.0), 110.0, 60.0, "warm metallic")
    scene = Scene("panels", MISALIGN, camera=CAMERA)
    ell = lookup_matrix(TURN).T @ SUN  # the sun where the turned environment of the tests above has it
    g, dark, lit = _panel_pixels(scene, ell, (80, 60))
    assert dark.sum() > 50 and lit.sum() > 200
    m = dark | lit
    args = (design, _env(ell), g.normal[m], g.view[m])
    shadowed = render_truth(*args, positions=g.position[m], scene=scene, quadrature_width=64, samples=64)
    free = render_truth(*args, quadrature_width=64, samples=64)
    sky = render_truth(design, _env(None), g.normal[m], g.view[m], quadrature_width=64, samples=64)
    d, li = dark[m], lit[m]
    assert shadowed[d] == pytest.approx(sky[d], rel=1e-9)
    assert shadowed[li] == pytest.approx(free[li], rel=1e-12)
    assert np.all(free[d] > 1.2 * sky[d])  # unshadowed, the sun adds 28 % there
