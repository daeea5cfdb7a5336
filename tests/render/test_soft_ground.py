"""Soft ground shadows of the NumPy renderer (station.render.ground): the shadowed lights as discs of
angular radius a, the visible share of a Fibonacci spiral of directions over the disc. Against the closed
form of a disc half hidden by the unit sphere's angular disc, the penumbra's growth from the contact,
GL's percentage-closer soft shadows on the same ground, and the single ray's hard shadow under the sun."""

from __future__ import annotations

import math

import numpy as np
import pytest

from station.render import numpy_renderer as nr
from station.render import prefilter
from station.render.camera import Camera
from station.render.cubemap import equirect_directions
from station.render.environment import Environment
from station.render.errors import RenderInputError
from station.render.ground import (
    LIGHT_SAMPLES,
    SUN_RADIUS_DEG,
    disc_directions,
    ground_light_visibility,
    light_radius_rad,
)
from station.render.shapes import Scene, ray_cast_visibility
from station.render.stage import Stage
from station.render.weights import LobeWeights

EXPS = (1.0, 8.0, 64.0, 512.0)
#: Measured worst error of the share of LIGHT_SAMPLES spiral directions inside a disc against its exact
#: area share (blocker discs of radius a, 3a and 1000a at every offset and 48 orientations: 0.046).
SPIRAL_ERROR = 0.05


def _lens(a: float, b: float, beta: float) -> float:
    """Area of the overlap of two flat discs of radii *a*, *b* whose centres are *beta* apart, by hand."""
    if beta >= a + b:
        return 0.0
    if beta <= abs(a - b):
        return math.pi * min(a, b) ** 2
    c1 = (beta * beta + a * a - b * b) / (2.0 * beta * a)
    c2 = (beta * beta + b * b - a * a) / (2.0 * beta * b)
    k = (-beta + a + b) * (beta + a - b) * (beta - a + b) * (beta + a + b)
    return a * a * math.acos(c1) + b * b * math.acos(c2) - 0.5 * math.sqrt(k)


def test_disc_directions_fill_the_cone_deterministically() -> None:
    """The spiral's directions are unit, within the cone (cos θ ≥ cos a), centred on the light (mean
    direction within 1 % of a), the same on every call; a = 0 gives the light's direction; bad input is a
    typed error naming the field; light_radius_rad is 2 s, at least the sun's."""
    ell = np.array([0.3, 0.8, -0.2]) / np.linalg.norm([0.3, 0.8, -0.2])
    a = math.radians(4.0)
    d = disc_directions(ell, a)
    assert d.shape == (LIGHT_SAMPLES, 3)
    assert np.allclose(np.linalg.norm(d, axis=1), 1.0)
    assert (d @ ell).min() >= math.cos(a) - 1e-12
    m = d.mean(axis=0)
    assert math.acos(min(1.0, m @ ell / np.linalg.norm(m))) < 0.01 * a
    assert np.array_equal(d, disc_directions(ell, a))
    assert np.allclose(disc_directions(ell, 0.0), ell)
    assert light_radius_rad(a * a / 4.0) == pytest.approx(a)
    assert light_radius_rad(0.0) == pytest.approx(math.radians(SUN_RADIUS_DEG))
    with pytest.raises(RenderInputError, match="count"):
        disc_directions(ell, a, 0)
    with pytest.raises(RenderInputError, match="spreads"):
        ground_light_visibility(Scene("sphere"), np.zeros((1, 3)), ell[None], (0,), np.zeros(2))


@pytest.mark.parametrize("a_deg", [3.0, 8.0])
def test_overhead_disc_light_under_the_sphere_is_the_closed_form(a_deg: float) -> None:
    """The unit sphere over the ground y = −1 under a light straight overhead of angular radius a: at
    horizontal distance ρ from below the centre the sphere's angular disc (radius b = arcsin(1/d), d² = 1 + ρ²)
    is β = atan ρ from the light; the visible share is 1 − lens(a, b, β)/(π a²) (flat discs). Across the
    penumbra (|β − b| < a, 15 points, and a point inside and outside it) the NumPy ground agrees within
    SPIRAL_ERROR (the spiral's worst error, 0.046 measured) + 0.01 (the flat approximation of a circle of
    angular radius b ≈ 45°: its curvature cot b against 1/b bends the edge across the light's disc by
    a²(1/b − cot b)/2, under 0.3 % of the disc's area at 8°); the mean error is under 0.015."""
    a = math.radians(a_deg)
    lo, hi = math.tan(math.pi / 4 - a / 2), math.tan(math.pi / 4 + a / 2)  # where |β − b| = a
    rho = np.r_[lo - 0.05, np.linspace(lo, hi, 15), hi + 0.05]
    pts = np.stack([rho * math.cos(0.7), np.full(rho.size, -1.0), rho * math.sin(0.7)], -1)
    up = np.array([[0.0, 1.0, 0.0]])
    vis = ground_light_visibility(Scene("sphere"), pts, up, (0,), np.array([a * a / 4.0]))[:, 0]
    exact = np.array(
        [1.0 - _lens(a, math.asin(1.0 / math.hypot(1.0, r)), math.atan(r)) / (math.pi * a * a) for r in rho]
    )
    assert exact[0] < 1e-12 and exact[-1] == 1.0 and 0.3 < exact[8] < 0.7
    err = np.abs(vis - exact)
    assert err.max() < SPIRAL_ERROR + 0.01, err
    assert err.mean() < 0.015, err


def _profile(a_deg: float, elevation_deg: float, xs: np.ndarray) -> np.ndarray:
    """NumPy visibility of a light at *elevation_deg* towards +x of radius a along the ground line z = 0
    (points *xs*, y = −1) under the unit sphere."""
    e = math.radians(elevation_deg)
    ell = np.array([[math.cos(e), math.sin(e), 0.0]])
    pts = np.stack([xs, np.full(xs.size, -1.0), np.zeros(xs.size)], -1)
    a = math.radians(a_deg)
    return ground_light_visibility(Scene("sphere"), pts, ell, (0,), np.array([a * a / 4.0]))[:, 0]


def _width(xs: np.ndarray, v: np.ndarray) -> float:
    """Ground distance between the 10 % and the 90 % crossings of the monotonic profile *v* along *xs*."""
    if v[0] > v[-1]:
        xs, v = xs[::-1], v[::-1]
    return abs(float(np.interp(0.9, v, xs) - np.interp(0.1, v, xs)))


def test_penumbra_is_hard_at_the_contact_and_widens_away() -> None:
    """Under a light at 60° of radius 1.5°, the sphere's shadow on its floor runs from x = −√3 (far edge,
    blocker D = √3 away along the light) to x = 1/√3 (near the contact, D = 1/√3). A disc crossed by a
    straight edge goes from 10 % to 90 % visible over 1.374 times its radius, so the ground's 10–90 %
    widths are 1.374 D tan a / sin 60°: 0.0257 and 0.0771 (three times wider away from the contact);
    the NumPy ground meets both within 10 % plus 0.002 (the profile's 0.5 mm steps)."""
    t = math.tan(math.radians(1.5)) / math.sin(math.radians(60.0)) * 1.3739
    near_x = np.linspace(0.577 - 0.06, 0.577 + 0.06, 241)
    far_x = np.linspace(-1.732 - 0.1, -1.732 + 0.1, 401)
    near = _width(near_x, _profile(1.5, 60.0, near_x))
    far = _width(far_x, _profile(1.5, 60.0, far_x))
    assert near == pytest.approx(t / math.sqrt(3.0), rel=0.1, abs=0.002)
    assert far == pytest.approx(t * math.sqrt(3.0), rel=0.1, abs=0.002)
    assert far > 2.5 * near


def test_the_sun_stays_the_single_rays_shadow() -> None:
    """Under a sun of the smallest radius (0.27°, spread 0) at 40° over the speed shape's ground (a 200²
    grid), the soft ground is the single ray's hard shadow (ray_cast_visibility) but for a band along the
    outline: under 1 % of the grid's points differ (measured 0.3 %), by at most the whole light only within the sun's
    penumbra, 2 D tan a / sin θ ≤ 2.5 cm of the outline (D ≤ 2.6 on this grid: 2 grid steps), and the
    shadowed area agrees within 0.5 % (measured 0.08 %)."""
    e, z = math.radians(40.0), math.radians(-100.0)
    ell = np.array([math.cos(e) * math.cos(z), math.sin(e), math.cos(e) * math.sin(z)])
    xs = np.linspace(-1.5, 2.5, 200)
    x, zz = np.meshgrid(xs, np.linspace(-2.0, 2.0, 200))
    pts = np.stack([x.ravel(), np.full(x.size, -0.42), zz.ravel()], -1)
    scene = Scene("speedshape")
    soft = ground_light_visibility(scene, pts, ell[None], (0,), np.zeros(1))[:, 0]
    hard = ray_cast_visibility(scene, pts, np.broadcast_to([0.0, 1.0, 0.0], pts.shape), ell[None])[:, 0]
    assert (1.0 - hard).sum() > 3000
    diff = soft != hard
    assert diff.mean() < 0.01
    assert (1.0 - soft).sum() == pytest.approx((1.0 - hard).sum(), rel=0.005)
    from scipy import ndimage

    grid = hard.reshape(200, 200).astype(bool)
    step = xs[1] - xs[0]  # 2 cm
    band = ndimage.binary_dilation(grid, iterations=2) & ~ndimage.binary_erosion(grid, iterations=2)
    assert not (diff.reshape(200, 200) & ~band).any(), step


def _edge_frames(gl_ctx, a: float, elevation: float) -> dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Per edge of the unit sphere's shadow ("near": the contact's side, "far"), (ground x (rows), NumPy
    G, GL G) along the line z = 0, seen from its own side by a narrow camera, under a dim sky and one light
    of radius *a* (rad) at *elevation* (rad) towards +x (its spread set exactly)."""
    import dataclasses

    from station.render.environment import Lights
    from station.render.gl_renderer import GLRenderer

    ell = np.array([math.cos(elevation), math.sin(elevation), 0.0])
    eq = np.full((128, 256, 3), 0.02, np.float32)
    eq[equirect_directions(128, 256) @ ell > math.cos(math.radians(2.0))] = 300.0
    basis = prefilter.prefilter_basis(Environment("disc", eq), EXPS, max_size=32)
    assert basis.lights is not None and basis.lights.count == 1
    lights = Lights(ell[None], basis.lights.flux, np.array([a * a / 4.0]))
    basis = dataclasses.replace(basis, lights=lights)
    paint = LobeWeights(EXPS, np.array([0.4, 0.3, 0.2]), np.zeros((4, 3)), np.zeros(4))
    stage = Stage(backdrop=False, ground_radius=3.6)
    cot, csc = 1.0 / math.tan(elevation), 1.0 / math.sin(elevation)  # the shadow's ellipse: −cot ± csc
    out = {}
    with GLRenderer(basis, 32, 192, ctx=gl_ctx, half_float=False) as gl:
        for name, x0, eye_x in (("near", csc - cot, 4.0), ("far", -cot - csc, -5.0)):
            cam = Camera((eye_x, 1.5, 0.0), (x0, -1.0, 0.0), fov_deg=3.0)
            scene = Scene("sphere", camera=cam, stage=stage)
            ref = nr.render_linear(scene, basis, [paint, paint], 32, 192)[:, 15:17, 1].mean(axis=1)
            frame = gl.render_linear(scene, [paint, paint])[:, 15:17, 1].mean(axis=1)
            origin, dirs = cam.rays(32, 192)
            d = dirs[:, 15:17].mean(axis=1)
            xs = origin[0] + (-1.0 - origin[1]) / d[:, 1] * d[:, 0]
            out[name] = (xs, ref.astype(float), frame.astype(float))
    return out


def _crossing(xs: np.ndarray, v: np.ndarray, level: float) -> float:
    """Where the monotonic profile *v* along *xs* crosses *level*."""
    if v[0] > v[-1]:
        xs, v = xs[::-1], v[::-1]
    return float(np.interp(level, v, xs))


@pytest.mark.gl
def test_penumbra_agrees_with_gls_soft_shadows(gl_ctx) -> None:
    """The unit sphere on its floor under a light of radius 0.9° at 60° (its far penumbra, D tan a = 0.027,
    stays inside GL's widest filter, MAX_RADIUS_TEXELS of its 1.3 mm depth-map texels), seen along the line
    through the contact, each edge by its own narrow camera (about 2 mm of ground a row). Closed form: 10–90 %
    widths 1.374 D tan a / sin 60° = 0.0144 near the contact and 0.0432 far from it. The far edge: NumPy
    and GL within 15 % of each other (measured 0.0450 and 0.0413) and of the closed form; near the contact
    GL's width is its baked ground map's texel (7 mm at this disc) wider at most (measured 0.0150 and
    0.0209); the umbra (between the two edges' 10 % crossings) within a texel (measured 2.2801 and 2.2756); the far
    edge at least 1.8 times the near one in both."""
    a, e = math.radians(0.9), math.radians(60.0)
    texel = 2.0 * 3.6 / 1024  # GL's ground map: GROUND_MAP texels over the disc's square
    t = 1.3739 * math.tan(a) / math.sin(e)
    widths, tens = {}, {}
    for name, (xs, ref, frame) in _edge_frames(gl_ctx, a, e).items():
        for engine, img in (("numpy", ref), ("gl", frame)):
            v = (img - img.min()) / (img.max() - img.min())
            widths[name, engine] = _width(xs, v)
            tens[name, engine] = _crossing(xs, v, 0.1)
    far_np, far_gl = widths["far", "numpy"], widths["far", "gl"]
    assert far_np == pytest.approx(far_gl, rel=0.15)
    assert far_np == pytest.approx(t * math.sqrt(3.0), rel=0.15)
    assert far_gl == pytest.approx(t * math.sqrt(3.0), rel=0.15)
    near_np, near_gl = widths["near", "numpy"], widths["near", "gl"]
    assert near_np == pytest.approx(t / math.sqrt(3.0), rel=0.15)
    assert abs(near_gl - near_np) < texel
    umbra = {k: tens["near", k] - tens["far", k] for k in ("numpy", "gl")}
    assert umbra["numpy"] == pytest.approx(umbra["gl"], abs=texel)
    assert far_np > 1.8 * near_np and far_gl > 1.8 * near_gl
