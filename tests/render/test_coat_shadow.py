"""A shadowed light under the clear coat: the GL shadow takes from the diffuse base the light's coat-weighted
share (1 − F(N·V)) t(N·l) π K_D (N·l) Φ/π, t = (1 − F(N·l))/(1 − F_dr,ext), the share the coat-transmitted
diffuse map holds, not its plain share; the shader's coat functions (shaders/coat.glsl) agree with
station.model.fresnel. Expectations from Fresnel's equations written out here (Snell's law, the s and p
amplitudes) and F_dr,ext by the trapezoid rule."""

from __future__ import annotations

import math

import numpy as np
import pytest

from station.model.fresnel import ClearCoat, fresnel_dielectric
from station.render import prefilter
from station.render.camera import Camera
from station.render.cubemap import equirect_directions
from station.render.environment import Environment
from station.render.stage import Stage, lookup_matrix
from station.render.weights import LobeWeights
from tests.render._fresnel_hand import diffuse_transmission as _diffuse_transmission
from tests.render._fresnel_hand import fresnel as _fresnel
from tests.render.fragment_pass import fragment_pass

EXPS = (1.0, 8.0, 64.0, 512.0)
SUN = np.array([0.5, 0.6, 0.35]) / np.linalg.norm([0.5, 0.6, 0.35])
SKY = 0.2


def _sun_env(sun: bool) -> Environment:
    """A uniform sky of SKY with (or without) a 1° sun disc of 2000 towards SUN."""
    eq = np.full((256, 512, 3), SKY, np.float32)
    if sun:
        eq[equirect_directions(256, 512) @ SUN > math.cos(math.radians(1.0))] = 2000.0
    return Environment("sun" if sun else "sky", eq)


@pytest.fixture(scope="module")
def bases():
    """(the sun basis, whose one light is the sun; the same sky without it)."""
    sun = prefilter.prefilter_basis(_sun_env(True), EXPS, max_size=32)
    assert sun.lights is not None and sun.lights.count == 1
    return sun, prefilter.prefilter_basis(_sun_env(False), EXPS, max_size=32)


def test_hand_fresnel_is_the_model_and_its_entry_weight() -> None:
    """The test's own Fresnel and F_dr,ext reproduce the model's (so the GL checks below are independent)."""
    mu = np.linspace(0.0, 1.0, 101)
    for n in (1.33, 1.5, 2.0):
        f = _fresnel(mu, n)
        assert fresnel_dielectric(mu, n) == pytest.approx(f, abs=1e-12)
        assert ClearCoat(n).entry_scale(mu) == pytest.approx((1.0 - f) / _diffuse_transmission(n), abs=1e-6)


@pytest.mark.gl
def test_glsl_coat_functions_agree_with_the_model(gl_ctx) -> None:
    """shaders/coat.glsl's dielectric_fresnel and coat_entry_weight at 256 cosines in [0, 1] and three indices:
    station.model.fresnel's fresnel_dielectric and ClearCoat.entry_scale within float32 rounding."""
    from station.render.gl_context import load_shader

    frag = "\n".join(
        [
            "#version 430",
            load_shader("coat.glsl"),
            "uniform float u_n, u_t;",
            "out vec4 f_color;",
            "void main() {",
            "    float c = (gl_FragCoord.x - 0.5) / 255.0;",
            "    f_color = vec4(dielectric_fresnel(c, u_n), coat_entry_weight(c, u_n, u_t), c, 1.0);",
            "}",
        ]
    )
    with fragment_pass(gl_ctx, frag, (256, 1)) as fp:
        for n in (1.33, 1.5, 2.0):
            coat = ClearCoat(n)
            fp.prog["u_n"].value = n
            fp.prog["u_t"].value = coat.diffuse_transmission
            out = fp.draw().reshape(256, 4)
            c = out[:, 2].astype(float)
            assert c[0] == 0.0 and c[-1] == pytest.approx(1.0)
            assert out[:, 0] == pytest.approx(fresnel_dielectric(c, n), abs=2e-6)
            assert out[:, 1] == pytest.approx(coat.entry_scale(c), abs=2e-6)


def _left_panel_pixels(model: np.ndarray, ell: np.ndarray, misalignment: float):
    """(dark, lit) masks of the left panel's front (z = 0) in shadow_probe's *model*: more than 2 pixels
    inside / outside the region whose NumPy ray to the light *ell* meets the panels."""
    from scipy import ndimage

    from station.render.shapes import Scene, intersect

    p = model[..., 1:]
    left = (model[..., 0] >= 0.0) & (p[..., 0] < -0.02) & (np.abs(p[..., 2]) < 1e-3)
    truth = np.zeros(left.shape, bool)
    q = p[left]
    hit = intersect(Scene("panels", misalignment), q + 1e-4 * ell, np.broadcast_to(ell, q.shape))
    truth[left] = hit.mask
    dark = ndimage.binary_erosion(truth, iterations=2) & left
    lit = ~ndimage.binary_dilation(truth, iterations=2) & left
    return dark, lit


@pytest.mark.gl
@pytest.mark.parametrize(("n", "k_a"), [(1.5, 0.0), (1.8, 0.05)])
def test_a_shadowed_coated_panel_loses_the_coat_weighted_share(gl_ctx, bases, n: float, k_a: float) -> None:
    """The right panel (turned −30°) shadows the left one's front from the sun (N·l = 0.18, where the coat
    lets in t = 0.71 of the plain share at n = 1.5). Per pixel in the shadow, the frame without shadow
    maps less the frame with them is (1 − F(N·V)) t(N·l) π K_D (N·l) Φ/π (hand Fresnel, F(N·V) at the
    pixel's own view), within 1e-3 relative, plus the plain share π K_A (N·l) Φ/π of a fall-off weight K_A
    (it reads the diffuse map D, not D_coat); the shadowed pixels equal the same panel under the sky
    without the sun within 1 % (the plain share would leave them 17 % too dark); lit pixels are unchanged."""
    from station.render.gl_renderer import GLRenderer
    from station.render.shapes import Scene

    sun_basis, sky_basis = bases
    misalignment, rotation = -30.0, 20.0
    stage = Stage(backdrop=False, rotation_deg=rotation)
    ell = lookup_matrix(rotation).T @ sun_basis.lights.directions[0]
    cam = Camera((-1.0, 0.5, 3.5), (-0.2, 0.0, 0.0), fov_deg=40.0)
    scene = Scene("panels", misalignment, camera=cam, stage=stage)
    paint = LobeWeights(EXPS, np.array([0.4, 0.3, 0.2]), np.zeros((4, 3)), np.zeros(4), np.full(3, k_a))
    coat = ClearCoat(n)
    with GLRenderer(sun_basis, 200, 150, ctx=gl_ctx) as gl:
        _, model = gl.shadow_probe(
            None, [paint], camera=cam, stage=stage, shape="panels", misalignment_deg=misalignment
        )
        on = gl.render_linear(scene, [paint, paint], coat=coat).astype(float)
        gl.shadows = False
        off = gl.render_linear(scene, [paint, paint], coat=coat).astype(float)
    with GLRenderer(sky_basis, 200, 150, ctx=gl_ctx) as gl:
        sky = gl.render_linear(scene, [paint, paint], coat=coat).astype(float)
    dark, lit = _left_panel_pixels(model, ell, misalignment)
    assert dark.sum() > 500 and lit.sum() > 1000
    assert model[dark, 0].max() < 1e-6
    nl = float(ell[2])  # the left panel's normal is +z
    view = np.asarray(cam.eye, float) - model[dark][:, 1:]
    ndv = view[:, 2] / np.linalg.norm(view, axis=1)
    entry = (1.0 - _fresnel(np.array(nl), n)) / _diffuse_transmission(n)
    share = (paint.k_d * entry + paint.k_a) * math.pi * nl * sun_basis.lights.flux[0] / math.pi
    expected = (1.0 - _fresnel(ndv, n))[:, None] * share[None, :]
    assert off[dark] - on[dark] == pytest.approx(expected, rel=1e-3)
    assert np.abs(on[dark] / sky[dark] - 1.0).max() < 0.01
    assert on[lit] == pytest.approx(off[lit], rel=1e-5)
