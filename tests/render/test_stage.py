"""Stage: environment backdrop (blur, rotation), ground with contact shadow; NumPy closed forms and GL."""

from __future__ import annotations

import math

import numpy as np
import pytest

from station.render import numpy_renderer as nr
from station.render import prefilter, procedural, shapes
from station.render import stage as st
from station.render.camera import Camera
from station.render.cubemap import equirect_directions
from station.render.environment import Environment
from station.render.errors import RenderInputError
from station.render.weights import LobeWeights

EXPS = (1.0, 8.0, 64.0, 512.0)
G = np.array([0.3, 0.5, -0.2])


@pytest.fixture(scope="module")
def linear_basis():
    eq = (1.0 + equirect_directions(32, 64) @ G)[..., None].repeat(3, -1).astype(np.float32)
    return prefilter.prefilter_basis(Environment("lin", eq), EXPS, engine="numpy")


@pytest.fixture(scope="module")
def sky_basis():
    return prefilter.prefilter_basis(procedural.sunny_sky(128), EXPS, max_size=32)


def _paint() -> LobeWeights:
    return LobeWeights(
        EXPS, np.array([0.1, 0.05, 0.03]), np.full((4, 3), 0.02), np.array([0.0, 0.0, 0.1, 1.0])
    )


def test_stage_validation_names_fields() -> None:
    for kw, name in (
        ({"backdrop_blur_deg": 91.0}, "backdrop_blur_deg"),
        ({"rotation_deg": math.inf}, "rotation_deg"),
        ({"ground_albedo": 1.5}, "ground_albedo"),
        ({"ground_radius": 0.0}, "ground_radius"),
        ({"ground": "yes"}, "ground"),
    ):
        with pytest.raises(RenderInputError, match=name):
            st.Stage(**kw)
    with pytest.raises(RenderInputError, match="stage"):
        shapes.Scene("sphere", stage="studio")  # type: ignore[arg-type]


def test_half_widths_and_backdrop_lobe() -> None:
    # cos^E ψ = ½ → E = 1: ψ = 60°; E = 8: arccos(2^(−1/8)) = 23.5°.
    assert st.half_width_deg(1.0) == pytest.approx(60.0)
    assert st.half_width_deg(8.0) == pytest.approx(math.degrees(math.acos(0.5**0.125)))
    assert st.backdrop_lobe(EXPS, 0.0) == 3
    assert st.backdrop_lobe(EXPS, 20.0) == 1
    assert st.backdrop_lobe(EXPS, 90.0) == 0


def test_sphere_occlusion_against_brute_force() -> None:
    # Unit sphere resting on y = −1; a ground point at horizontal distance x: closed form (1 + x²)^(−3/2),
    # checked against a cosine-weighted hemisphere quadrature of rays hitting the sphere.
    occ = [(0.0, 0.0, 0.0, 1.0)]
    u = (np.arange(400) + 0.5) / 400
    ct = np.sqrt(u)  # cosine-weighted: cos θ = √u, φ uniform
    phi = 2 * np.pi * (np.arange(400) + 0.5) / 400
    st_ = np.sqrt(1 - ct**2)
    dirs = np.stack(
        [st_[:, None] * np.cos(phi)[None], np.repeat(ct[:, None], 400, 1), st_[:, None] * np.sin(phi)[None]],
        -1,
    ).reshape(-1, 3)
    for x in (0.5, 1.0, 2.0, 3.0):
        p = np.array([x, -1.0, 0.0])
        b = dirs @ p
        hit = (b * b - (p @ p - 1.0) > 0) & (b < 0)
        brute = hit.mean()
        closed = st.sphere_occlusion(p[None], occ)[0]
        assert closed == pytest.approx((1 + x * x) ** -1.5, rel=1e-9)
        assert closed == pytest.approx(brute, abs=0.01)
    assert st.sphere_occlusion(np.array([[0.0, -1.0, 0.0]]), occ)[0] == 1.0  # the contact point


def test_backdrop_and_rotation_in_a_linear_environment(linear_basis) -> None:
    # The sharpest lobe (E = 512) of L = 1 + G·ω holds 1 + (E+1)/(E+2) G·d; turned by θ the backdrop
    # at world direction d shows the map at R_y(−θ)d.
    rng = np.random.default_rng(1)
    d = rng.normal(size=(50, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    e = 512.0
    for theta in (0.0, 90.0, -35.0):
        scene = shapes.Scene("sphere", stage=st.Stage(rotation_deg=theta, ground=False))
        got = nr.stage_background(scene, linear_basis, np.zeros(3), d)
        a = math.radians(-theta)
        rot = np.array([[math.cos(a), 0, math.sin(a)], [0, 1, 0], [-math.sin(a), 0, math.cos(a)]])
        expected = 1.0 + (e + 1) / (e + 2) * (d @ rot.T) @ G
        assert got[:, 0] == pytest.approx(expected, abs=0.015)
    # Lighting turns with the backdrop: the front point (N = R = +Z) of a gloss sphere, env turned 90°,
    # reflects the map at R_y(−90°)(+Z) = −X... within the lobe's first moment.
    cam = shapes.Camera((0.0, 0.0, 4.0), (0.0, 0.0, 0.0))
    gloss = LobeWeights(EXPS, np.zeros(3), np.zeros((4, 3)), np.array([0.0, 0.0, 0.0, (e + 1) / (2 * np.pi)]))
    img = nr.render_linear(
        shapes.Scene("sphere", camera=cam, stage=st.Stage(rotation_deg=90.0)), linear_basis, [gloss], 33, 33
    )
    assert img[16, 16, 0] == pytest.approx(1.0 + (e + 1) / (e + 2) * -G[0], abs=0.01)


def test_ground_radiance_and_contact_shadow() -> None:
    # Constant radiance 2: D(+Y) = 2, so the ground reads albedo · 2 · (1 − O).
    basis = prefilter.prefilter_basis(
        Environment("c", np.full((32, 64, 3), 2.0, np.float32)), EXPS, engine="numpy"
    )
    stage = st.Stage(backdrop=False, ground_albedo=0.5, ground_radius=20.0)
    scene = shapes.Scene("sphere", stage=stage)
    eye = np.array([0.0, 3.0, 3.0])
    targets = np.array([[1.5, -1.0, 0.0], [0.0, -1.0, 1.2], [4.0, -1.0, 2.0]])
    d = targets - eye
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    got = nr.stage_background(scene, basis, eye, d)
    x2 = np.sum(targets[:, [0, 2]] ** 2, axis=1)
    assert got[:, 1] == pytest.approx(0.5 * 2.0 * (1 - (1 + x2) ** -1.5), rel=3e-3)
    # Far out the floor fades into the flat background.
    far = nr.stage_background(
        shapes.Scene("sphere", stage=st.Stage(backdrop=False, ground_radius=2.0)), basis, eye, d[2:]
    )
    assert far[0] == pytest.approx(nr.BACKGROUND)


@pytest.mark.gl
@pytest.mark.parametrize(
    "stage",
    [
        st.Stage(rotation_deg=40.0),
        st.Stage(backdrop_blur_deg=25.0, rotation_deg=-120.0),
        st.Stage(backdrop=False),
    ],
)
def test_gl_stage_agrees_with_numpy(gl_ctx, sky_basis, stage) -> None:
    from station.render.gl_renderer import GLRenderer

    scene = shapes.Scene("speedshape", stage=stage)
    w, h = 96, 64
    with GLRenderer(sky_basis, w, h, ctx=gl_ctx) as gl:
        got = gl.render_linear(scene, [_paint()])
    ref = nr.render_linear(scene, sky_basis, [_paint()], w, h)
    close = np.abs(got - ref).max(axis=-1) <= 0.02 + 0.03 * np.abs(ref).max(axis=-1)
    assert close.mean() > 0.97
    g = nr.gbuffer(scene, w, h)
    assert np.abs(ref[~g.mask] - nr.BACKGROUND).max() > 0.1  # the stage is visible


def test_basis_images_carry_the_stage(sky_basis) -> None:
    """The cached basis images of a staged, rotated view re-weight to the NumPy renderer's picture."""
    from station.render.basis_images import build_basis_images
    from station.render.tonemap import to_display

    scene = shapes.Scene("speedshape", stage=st.Stage(rotation_deg=70.0))
    cached = build_basis_images(scene, sky_basis, 64, 40)
    ref = nr.render_linear(scene, sky_basis, [_paint()], 64, 40)
    assert cached.linear_image([_paint()]) == pytest.approx(ref, rel=1e-4, abs=1e-5)
    frame = cached.edit([_paint()], 0.5)
    assert np.abs(frame.astype(int) - to_display(ref, 0.5).astype(int)).max() <= 1


def _sun_world(rotation_deg: float) -> np.ndarray:
    """The brightest direction of the procedural sky's map, turned by the stage's rotation R_y(θ)."""
    eq = procedural.sunny_sky(128).equirect
    lum = eq @ np.array([0.2126, 0.7152, 0.0722])
    j, i = np.unravel_index(np.argmax(lum), lum.shape)
    e = equirect_directions(*lum.shape)[j, i]
    a = math.radians(rotation_deg)
    return np.array([math.cos(a) * e[0] + math.sin(a) * e[2], e[1], -math.sin(a) * e[0] + math.cos(a) * e[2]])


def test_light_visibility_edges_where_the_ray_grazes_the_sphere() -> None:
    c, r, gy = np.array([0.2, 0.0, -0.3]), 1.0, -1.0
    light = np.array([0.5, 0.6, 0.4])
    light /= np.linalg.norm(light)
    centre = c - light * (c[1] - gy) / light[1]  # where the ray through the sphere's centre meets the ground
    occ = [(*c, r)]
    assert st.light_visibility([centre], occ, [light])[0, 0] == 0.0
    assert st.light_visibility([centre + np.array([6.0, 0.0, 0.0])], occ, [light])[0, 0] == 1.0
    assert st.light_visibility([centre], occ, [[0.3, -0.2, 0.93]])[0, 0] == 0.0  # below the horizon
    # Walking sideways out of the shadow, V = 1/2 where the ray from the point just grazes the sphere:
    # the distance from c to the line p + t·l equals r (bisection on that distance, no angles).
    side = np.cross(light, [0.0, 1.0, 0.0])
    side /= np.linalg.norm(side)

    def miss(s: float) -> float:
        v = c - (centre + s * side)
        return float(np.linalg.norm(v - (v @ light) * light)) - r

    lo, hi = 0.0, 4.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if miss(mid) < 0 else (lo, mid)
    assert st.light_visibility([centre + lo * side], occ, [light])[0, 0] == pytest.approx(0.5, abs=0.02)
    assert st.light_visibility([centre + (lo - 0.1) * side], occ, [light])[0, 0] < 0.05
    assert st.light_visibility([centre + (lo + 0.1) * side], occ, [light])[0, 0] > 0.95


@pytest.mark.parametrize("rotation", [0.0, 90.0])
def test_sun_shadow_falls_where_the_sun_ray_meets_the_sphere(sky_basis, rotation) -> None:
    """Ground pixels whose ray to the sun hits the sphere (brute-force ray cast) are darker by the sun's
    direct part albedo · l_y Φ/π; the others keep it."""
    stage = st.Stage(backdrop=False, rotation_deg=rotation, ground_radius=20.0)
    cam = Camera((0.0, 4.0, 4.5), (0.0, -1.0, 0.0), fov_deg=50.0)
    scene = shapes.Scene("sphere", camera=cam, stage=stage)
    w, h = 120, 90
    img = nr.render_linear(scene, sky_basis, [_paint()], w, h).astype(float)
    g = nr.gbuffer(scene, w, h)
    origin, dirs = cam.rays(w, h)
    ground = ~g.mask & (dirs[..., 1] < 0)
    t = (-1.0 - origin[1]) / np.where(ground, dirs[..., 1], -1.0)
    pts = origin + t[..., None] * dirs
    sun = _sun_world(rotation)
    # Ray p + s·sun against the unit sphere at the origin: hit when the closest approach is < 1 ahead.
    along = -(pts @ sun)  # (c − p)·l with c = 0
    closest = np.linalg.norm(-pts - along[..., None] * sun, axis=-1)
    near_floor = np.hypot(pts[..., 0], pts[..., 2]) < 5.0
    shade = ground & near_floor & (along > 0) & (closest < 0.8)
    lit = ground & near_floor & ((along <= 0) | (closest > 1.3)) & (np.hypot(pts[..., 0], pts[..., 2]) > 2.5)
    assert shade.sum() > 30 and lit.sum() > 30
    direct = stage.ground_albedo * sun[1] * sky_basis.lights.flux[0, 1] / np.pi
    # In the shadow the sun's part is gone (the contact shadow takes a little more of the sky).
    assert img[lit, 1].mean() - img[shade, 1].mean() > 0.9 * direct
    assert img[shade, 1].max() < img[lit, 1].min()


@pytest.mark.gl
def test_gl_sun_shadow_agrees_with_numpy(gl_ctx, sky_basis) -> None:
    from station.render.gl_renderer import GLRenderer

    cam = Camera((0.0, 4.0, 4.5), (0.0, -1.0, 0.0), fov_deg=50.0)
    scene = shapes.Scene("sphere", camera=cam, stage=st.Stage(backdrop=False, rotation_deg=60.0))
    with GLRenderer(sky_basis, 96, 72, ctx=gl_ctx) as gl:
        got = gl.render_linear(scene, [_paint()])
    ref = nr.render_linear(scene, sky_basis, [_paint()], 96, 72)
    floor = ~nr.gbuffer(scene, 96, 72).mask
    assert np.percentile(np.abs(got - ref)[floor], 99) < 0.01
    assert np.ptp(ref[floor][:, 1]) > 0.2  # the shadow is there to agree on (sun part 0.3 · 0.58 · 4.5/π)


def test_overlapping_proxies_combine_as_independent_shares() -> None:
    # Two unit spheres resting on y = −1, 1.2 apart (they overlap, as a car's row of proxies does): the
    # occluded fraction against a cosine-weighted quadrature of rays hitting either sphere. The product
    # 1 − Π(1 − O_k) lies between the larger single share and their sum, nearer the truth than the sum
    # (which reaches 1, a black ground, where the spheres overlap) at every point tried.
    occ = [(0.0, 0.0, 0.0, 1.0), (1.2, 0.0, 0.0, 1.0)]
    n = 600
    ct = np.sqrt((np.arange(n) + 0.5) / n)
    phi = 2 * np.pi * (np.arange(n) + 0.5) / n
    st_ = np.sqrt(1 - ct**2)
    dirs = np.stack(
        [st_[:, None] * np.cos(phi)[None], np.repeat(ct[:, None], n, 1), st_[:, None] * np.sin(phi)[None]], -1
    ).reshape(-1, 3)
    for x, z in ((0.6, 0.0), (0.6, 1.0), (2.0, 0.0), (2.0, 1.5), (-1.0, 1.0)):
        p = np.array([x, -1.0, z])
        hit = np.zeros(len(dirs), bool)
        for c in occ:
            q = p - np.array(c[:3])
            b = dirs @ q
            hit |= (b * b - (q @ q - 1.0) > 0) & (b < 0)
        brute = hit.mean()
        single = [st.sphere_occlusion(p[None], [c])[0] for c in occ]
        both = st.sphere_occlusion(p[None], occ)[0]
        assert max(single) <= both <= min(1.0, sum(single))
        assert both < 1.0
        assert abs(both - brute) <= 0.055
        assert abs(both - brute) < abs(min(1.0, sum(single)) - brute)
