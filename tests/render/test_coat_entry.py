"""Light entering the clear coat: the diffuse base sees each direction through the coat, weighted by
(1 − F(N·l))/(1 − F_dr,ext) (Mitsuba's ``plastic``), in the model, the prefilter, the renderers and the
ground truth; the white furnace unchanged."""

from __future__ import annotations

import math

import numpy as np
import pytest

from station.model.fresnel import ClearCoat, fresnel_diffuse_reflectance, fresnel_unpolarised
from station.render import cubemap, prefilter, shapes
from station.render import numpy_renderer as nr
from station.render import truth as tr
from station.render.weights import LobeWeights

EXPS = (1.0, 8.0, 64.0, 512.0)


def _f(cos_theta: float, n: float = 1.5) -> float:
    """The scalar closed form (Fresnel's equations at the angle itself)."""
    return fresnel_unpolarised(math.degrees(math.acos(min(max(cos_theta, 0.0), 1.0))), n)


def _trapezoid(y: np.ndarray, x: np.ndarray) -> float:
    return float(np.sum((y[1:] + y[:-1]) * 0.5 * np.diff(x)))


@pytest.mark.parametrize("n", [1.3, 1.5, 2.0])
def test_hemispherical_fresnel_and_the_entry_weight(n: float) -> None:
    """F_dr,ext = 2 ∫ F μ dμ by the trapezoid rule over the scalar closed form; the entry weight's
    cosine-weighted mean is 1 (a uniform environment delivers through the coat what it did without)."""
    mu = np.linspace(0.0, 1.0, 20001)
    f = np.array([_f(x, n) for x in mu])
    assert fresnel_diffuse_reflectance(n) == pytest.approx(_trapezoid(2.0 * f * mu, mu), abs=2e-6)
    coat = ClearCoat(n)
    assert _trapezoid(2.0 * coat.entry_scale(mu) * mu, mu) == pytest.approx(1.0, abs=2e-6)
    assert float(coat.entry_scale(0.0)) == 0.0  # no light enters at grazing


def test_hemispherical_fresnel_against_the_published_fit() -> None:
    """Egan & Hilgeman's fit of the internal diffuse reflectance, F_dr,int(1.5) ≈ 0.5967, with
    1 − F_dr,int = (1 − F_dr,ext)/η² (reciprocity): F_dr,ext ≈ 0.0926 (the fit is good to about 1 %)."""
    eta = 1.5
    f_int = -1.440 / eta**2 + 0.710 / eta + 0.668 + 0.0636 * eta
    assert fresnel_diffuse_reflectance(eta) == pytest.approx(1.0 - eta**2 * (1.0 - f_int), abs=2e-3)


def test_prefilter_coat_map_is_the_closed_form_per_light_and_unchanged_in_a_furnace() -> None:
    """One bright source texel: the coat map over the plain map is t(R·ω) at every output texel, exactly
    (the same brute-force sum); a constant environment c gives c (E_coat = π c, the furnace)."""
    s = 32
    src = np.zeros((6, s, s, 3), np.float32)
    src[2, 9, 13] = 100.0  # one texel of the +Y face
    coat = ClearCoat()
    plain = prefilter.prefilter_brute(src, 1.0, 8)
    coated = prefilter.prefilter_brute(src, 1.0, 8, coat)
    light = cubemap.face_directions(s)[2, 9, 13]
    r = cubemap.face_directions(8).reshape(-1, 3)
    lit = (r @ light) > 0.05
    ratio = coated.reshape(-1, 3)[lit, 0] / plain.reshape(-1, 3)[lit, 0]
    expected = np.array([(1.0 - _f(c)) / (1.0 - fresnel_diffuse_reflectance(1.5)) for c in r[lit] @ light])
    assert ratio == pytest.approx(expected, abs=5e-5)  # the NumPy sum's table of t (prefilter_brute)
    const = prefilter.prefilter_brute(np.full((6, s, s, 3), 0.7, np.float32), 1.0, 8, coat)
    assert const == pytest.approx(np.full_like(const, 0.7), rel=3e-5)


def test_truth_directional_light_scales_the_base_by_both_fresnel_passes() -> None:
    """A single point light: the diffuse base with the coat over without it is (1 − F(N·l))(1 − F(N·V))
    / (1 − F_dr,ext) per pixel, against the scalar closed form; the gloss term is untouched by it."""
    env = np.zeros((64, 128, 3))
    env[20, 70] = 5.0e4
    n, v = tr.sphere_pixels(16)
    scene = tr.TruthScene(env, n, v, samples=32, quadrature_width=64)
    assert scene.lighting.point_dirs.shape[0] == 1
    light = scene.lighting.point_dirs[0]
    lam = LobeWeights(EXPS, np.full(3, 0.2), np.zeros((4, 3)), np.zeros(4))
    coat = ClearCoat()
    on, off = scene.lobes(lam, "exact", coat)[:, 1], scene.lobes(lam)[:, 1]
    lit = (n @ light) > 0.05
    f_dr = fresnel_diffuse_reflectance(1.5)
    expected = np.array(
        [
            (1.0 - _f(nl)) * (1.0 - _f(nv)) / (1.0 - f_dr)
            for nl, nv in zip(n[lit] @ light, np.sum(n * v, 1)[lit], strict=True)
        ]
    )
    assert on[lit] / off[lit] == pytest.approx(expected, rel=1e-9)
    # The designed BRDF of a solid (flat ρ: all of it the diffuse floor) gets the same factor.
    from station.model import FaceFlopTravelGloss
    from station.render import lobe_fit as lf

    brdf = lf.designed_brdf(FaceFlopTravelGloss((60.0, 0.0, 0.0), (60.0, 0.0, 0.0), None, 0.0, "grey"))
    assert np.ptp(brdf.reflectance[:, 1]) < 1e-9
    direct_on, direct_off = scene.truth_direct(brdf, coat)[:, 1], scene.truth_direct(brdf)[:, 1]
    assert direct_on[lit] / direct_off[lit] == pytest.approx(expected, rel=1e-3)  # the gloss is ~0


@pytest.fixture(scope="module")
def sky_basis():
    from station.render import procedural

    return prefilter.prefilter_basis(procedural.sunny_sky(64), EXPS, max_size=32)


def _white() -> LobeWeights:
    return LobeWeights(EXPS, np.full(3, 0.8 / np.pi), np.zeros((4, 3)), np.zeros(4))


def test_numpy_coat_reads_the_coat_map_for_the_diffuse_base_only(sky_basis) -> None:
    """NumPy renderer on the sky: K_D times (1 − F(N·V)) D_coat(N); the fall-off (K_A) keeps D; the
    coat map (GL prefilter) matches its NumPy twin (another index, summed on the basis's source cube)."""
    coat = ClearCoat()
    scene = shapes.Scene("sphere")
    g = nr.gbuffer(scene, 24, 24)
    got = nr.render_linear(scene, sky_basis, [_white()], 24, 24, coat=coat)[g.mask]
    d_coat = cubemap.sample_cube(prefilter.coat_diffuse_map(sky_basis, coat), g.normal[g.mask])
    expected = 0.8 * coat.base_scale(g.n_dot_v[g.mask])[:, None] * d_coat
    assert got == pytest.approx(expected, rel=1e-5, abs=1e-7)
    plain = cubemap.sample_cube(sky_basis.diffuse, g.normal[g.mask])
    assert np.abs(d_coat / plain - 1.0).max() > 0.02  # the sky is not uniform: the map differs
    twin = prefilter.prefilter_brute(sky_basis.diffuse_source, 1.0, prefilter.COAT_DIFFUSE_SIZE, coat)
    assert twin == pytest.approx(prefilter.coat_diffuse_map(sky_basis, coat), rel=1e-4)
    # K_A through the plain map: a fall-off paint's picture moves by π K_A (D − D_coat) only
    k_a = np.array([0.1, 0.05, 0.02])
    fall = LobeWeights(EXPS, np.zeros(3), np.zeros((4, 3)), np.zeros(4), k_a)
    n_env, r_env = g.normal[g.mask], g.reflect[g.mask]
    ndv = g.n_dot_v[g.mask]
    on = nr.shade_pixels(sky_basis, fall, n_env, r_env, ndv, coat=coat)
    assert on == pytest.approx(
        coat.base_scale(ndv)[:, None] * nr.shade_pixels(sky_basis, fall, n_env, r_env, ndv)
    )


@pytest.mark.gl
@pytest.mark.parametrize("diffuse", ["cube", "sh"])
def test_gl_draws_the_coat_map_as_numpy_does(gl_ctx, sky_basis, diffuse: str) -> None:
    from station.render.gl_renderer import GLRenderer

    scene = shapes.Scene("sphere")
    g = nr.gbuffer(scene, 40, 40)
    paints = [_white()]
    with GLRenderer(sky_basis, 40, 40, ctx=gl_ctx, diffuse=diffuse) as gl:
        on = gl.render_linear(scene, paints, coat=ClearCoat())[g.mask]
        other = gl.render_linear(scene, paints, coat=ClearCoat(1.8))[g.mask]
        off = gl.render_linear(scene, paints)[g.mask]
    ref, ref_other, ref_off = (
        nr.render_linear(scene, sky_basis, paints, 40, 40, diffuse=diffuse, coat=c)[g.mask]
        for c in (ClearCoat(), ClearCoat(1.8), None)
    )
    # the pixels where the two renderers agree without a coat (a few beside the sun differ by up to 10 %
    # there already: the lights' share of the diffuse map), then the same with it
    inner = (g.n_dot_v[g.mask] > 0.1) & (np.abs(off / ref_off - 1.0).max(axis=1) < 0.02)
    assert inner.mean() > 0.95
    assert on[inner] == pytest.approx(ref[inner], rel=0.03, abs=2e-3)
    assert other[inner] == pytest.approx(ref_other[inner], rel=0.03, abs=2e-3)
    # the coat's own factor (on over off) per pixel, GL against NumPy: 99 % within 1 %, all within 3 %
    for gl_img, np_img in ((on, ref), (other, ref_other)):
        dev = np.abs((gl_img / off)[inner] / (np_img / ref_off)[inner] - 1.0)
        assert np.quantile(dev, 0.99) < 0.01 and dev.max() < 0.03
    exit_only = (
        nr.render_linear(scene, sky_basis, paints, 40, 40, diffuse=diffuse)[g.mask]
        * ClearCoat().base_scale(g.n_dot_v[g.mask])[:, None]
    )
    assert np.abs(on[inner] / exit_only[inner] - 1.0).max() > 0.02  # the entry weight is drawn


def test_sh_coat_gains_keep_a_uniform_environment() -> None:
    """Band 0 of the coat kernel is π (the furnace); the SH coat map of a constant environment is c."""
    from station.render.sh import coat_band_gain, sh_diffuse, sh_project

    gain = coat_band_gain(ClearCoat())
    assert gain[0] == pytest.approx(np.pi, rel=1e-9)
    coeffs = sh_project(np.full((32, 64, 3), 0.4))
    d = sh_diffuse(coeffs, cubemap.face_directions(4).reshape(-1, 3), ClearCoat())
    assert d == pytest.approx(np.full_like(d, 0.4), rel=2e-3)


@pytest.mark.gl
def test_gl_coat_map_sum_is_the_numpy_sum(gl_ctx, sky_basis) -> None:
    """The GL twin of the coat map's brute-force sum (prefilter_brute.frag.glsl) agrees with NumPy's."""
    coat = ClearCoat(1.7)
    src = sky_basis.diffuse_source
    with prefilter.GLBrute(gl_ctx) as gl:
        got = gl.run(src, 1.0, 16, coat)
    assert got == pytest.approx(prefilter.prefilter_brute(src, 1.0, 16, coat), rel=2e-4, abs=1e-6)


def test_truth_designed_metallic_floor_through_the_coat() -> None:
    """A metallic's colour floor (its flop) goes through the coat, the rest of ρ(ψ) does not: the binned
    and the direct truth agree, and under one light the coat changes the base by at most both passes."""
    from station.model import FaceFlopTravelGloss
    from station.render import lobe_fit as lf

    brdf = lf.designed_brdf(FaceFlopTravelGloss((70.0, 5.0, 5.0), (25.0, 20.0, 10.0), 60.0, 0.0, "m"))
    floor = tr.diffuse_floor(brdf)
    assert np.all(floor >= 0.0) and np.all(floor <= brdf.reflectance.max(axis=0))
    env = np.full((64, 128, 3), 0.05)
    env[20, 70] = 5.0e4
    n, v = tr.sphere_pixels(12)
    scene = tr.TruthScene(env, n, v, samples=32, quadrature_width=64)
    coat = ClearCoat()
    binned, direct = scene.truth(brdf, coat), scene.truth_direct(brdf, coat)
    assert binned == pytest.approx(direct, rel=2e-2, abs=1e-4)
    # without the floor's entry weight (the exit-only coat) the picture differs
    exit_only = scene.truth_direct(brdf) * scene.coat_factors(coat)[1].reshape(direct.shape[:-1] + (1,))
    assert np.abs(direct - exit_only).max() > 1e-3
