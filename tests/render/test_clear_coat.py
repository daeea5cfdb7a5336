"""The physical clear coat (exact dielectric Fresnel on the gloss, 1 − F on the base): hand values, white
furnace, closed forms, GL, ground truth."""

from __future__ import annotations

import math

import numpy as np
import pytest

from station.model.colorimetry import linear_srgb_to_lab
from station.model.difference import delta_e
from station.model.errors import ModelInputError
from station.model.gloss import ClearCoat, fresnel_schlick, fresnel_unpolarised
from station.render import numpy_renderer as nr
from station.render import prefilter, shapes
from station.render import truth as tr
from station.render.environment import Environment
from station.render.weights import LobeWeights

EXPS = (1.0, 8.0, 64.0, 512.0)


def test_fresnel_hand_values_and_bounds() -> None:
    # n = 1.5: F0 = (0.5/2.5)² = 0.04 head-on, 1 at grazing; at 60° the exact value 0.0892 (Born & Wolf).
    coat = ClearCoat()
    assert coat.index == 1.5
    assert coat.f0 == pytest.approx(0.04, abs=1e-15)
    cos = np.linspace(0.0, 1.0, 2001)
    f = coat.fresnel(cos)
    assert f[-1] == pytest.approx(0.04, abs=1e-12) and f[0] == pytest.approx(1.0, abs=1e-12)
    assert np.all(f <= 1.0 + 1e-12) and np.all(np.diff(f) <= 1e-15)  # never above 1, falls towards normal
    for deg in (0.0, 30.0, 60.0, 80.0, 89.0):
        assert float(coat.fresnel(math.cos(math.radians(deg)))) == pytest.approx(
            fresnel_unpolarised(deg, 1.5), rel=1e-9
        )
    assert float(coat.fresnel(0.5)) == pytest.approx(0.0892, abs=5e-5)
    # The gloss factor divides by the full-gloss lobe albedo ρ_ref = F(60°; 1.567); the base keeps 1 − F.
    assert coat.reference == pytest.approx(fresnel_unpolarised(60.0, 1.567), rel=1e-12)
    assert coat.gloss_scale(cos) * coat.reference == pytest.approx(f, rel=1e-12)
    assert coat.base_scale(cos) + f == pytest.approx(np.ones_like(cos), abs=1e-12)
    # Schlick stays in the model for comparison: equal head-on, 0.019 low at 60° (0.070 vs 0.089).
    assert float(fresnel_schlick(1.0, 1.5)) == pytest.approx(0.04, abs=1e-12)
    assert float(coat.fresnel(0.5)) - float(fresnel_schlick(0.5, 1.5)) == pytest.approx(0.0192, abs=5e-4)
    assert ClearCoat(2.0).f0 == pytest.approx(1.0 / 9.0)


@pytest.mark.parametrize("bad", [1.0, 0.5, 3.5, math.nan, True, "1.5"])
def test_bad_coat_index_names_the_field(bad) -> None:
    with pytest.raises(ModelInputError, match="coat_index"):
        ClearCoat(bad)


def _gloss_only(albedo: float, e: float) -> LobeWeights:
    k_g = np.zeros(len(EXPS))
    k_g[EXPS.index(e)] = albedo * (e + 1) / (2 * np.pi)
    return LobeWeights(EXPS, np.zeros(3), np.zeros((len(EXPS), 3)), k_g)


@pytest.fixture(scope="module")
def const_basis():
    return prefilter.prefilter_basis(
        Environment("c", np.full((32, 64, 3), 2.0, np.float32)), EXPS, engine="numpy"
    )


def _furnace_paints() -> tuple[LobeWeights, LobeWeights]:
    """A white Lambertian base under a full-gloss coat lobe, and the same lobe over a black base."""
    rho_ref = ClearCoat().reference
    lobe = _gloss_only(rho_ref, 512.0)
    white = LobeWeights(EXPS, np.full(3, 1.0 / np.pi), np.zeros((4, 3)), lobe.k_g)
    return white, lobe


def test_numpy_white_furnace(const_basis) -> None:
    """Uniform radiance 2: a white Lambert base under the coat returns 2 (F + (1 − F) = 1), never more; a black
    base returns the coat's own reflection 2 F(N·V) (exact Fresnel, :func:`fresnel_unpolarised`)."""
    scene = shapes.Scene("sphere")
    g = nr.gbuffer(scene, 48, 48)
    white, black = _furnace_paints()
    coat = ClearCoat()
    c = g.n_dot_v[g.mask]
    on = nr.render_linear(scene, const_basis, [white], 48, 48, coat=coat)[g.mask]
    assert on.max() <= 2.0 * 1.003  # never more light than arrives (0.3 %: the cube maps' filtering)
    unclipped = c > 0.2  # the E = 512 lobe lies above the horizon there (h = 1)
    assert on[unclipped] == pytest.approx(np.full((int(unclipped.sum()), 3), 2.0), rel=3e-3)
    coat_only = nr.render_linear(scene, const_basis, [black], 48, 48, coat=coat)[g.mask][:, 1]
    exact = np.array([fresnel_unpolarised(math.degrees(math.acos(x)), 1.5) for x in c])
    assert coat_only[unclipped] == pytest.approx(2.0 * exact[unclipped], rel=3e-3)
    assert coat_only.max() <= 2.0 * 1.003
    # Without the coat (the thesis's model) the colour terms are untouched and the lobe reflects ρ_ref.
    off = nr.render_linear(scene, const_basis, [black], 48, 48)[g.mask][:, 1]
    assert off[unclipped] == pytest.approx(np.full(int(unclipped.sum()), 2.0 * coat.reference), rel=3e-3)


@pytest.mark.gl
def test_gl_applies_the_same_coat_and_passes_the_furnace(gl_ctx, const_basis) -> None:
    from station.render.gl_renderer import GLRenderer

    scene = shapes.Scene("speedshape")
    white, _ = _furnace_paints()
    paint = [white, _gloss_only(0.08, 64.0)]
    g = nr.gbuffer(scene, 64, 48)
    with GLRenderer(const_basis, 64, 48, ctx=gl_ctx) as gl:
        on = gl.render_linear(scene, paint, coat=ClearCoat(1.6))
        off = gl.render_linear(scene, paint)
        furnace = gl.render_linear(scene, [white, white], coat=ClearCoat())
    ref_on = nr.render_linear(scene, const_basis, paint, 64, 48, coat=ClearCoat(1.6))
    ref_off = nr.render_linear(scene, const_basis, paint, 64, 48)
    inner = g.mask & (np.abs(on - ref_on).max(axis=-1) < 0.5 * ref_on.max())
    assert inner.mean() > 0.97 * g.mask.mean()
    assert on[inner] == pytest.approx(ref_on[inner], rel=0.02, abs=2e-3)
    assert off[inner] == pytest.approx(ref_off[inner], rel=0.02, abs=2e-3)
    assert np.abs(on[inner] - off[inner]).max() > 0.05  # the coat is visible at grazing pixels
    # White furnace on the GPU path: radiance 2 in, at most 2 out, 2 where the lobe is above the horizon.
    assert furnace[g.mask].max() <= 2.0 * 1.01
    assert np.median(furnace[g.mask & (g.n_dot_v > 0.2)]) == pytest.approx(2.0, rel=0.01)


def test_truth_closed_form_and_renderer_agreement() -> None:
    from station.model import FaceFlopTravelGloss
    from station.render import lobe_fit as lf

    # Closed form: a grey solid head-on in a constant radiance 1: ρ (1 − F) + ρ_s s(N·V).
    n, v = tr.sphere_pixels(12)
    scene = tr.TruthScene(np.ones((64, 128, 3)), n, v, samples=128, quadrature_width=128)
    design = FaceFlopTravelGloss((60.0, 0.0, 0.0), (60.0, 0.0, 0.0), None, 60.0, "grey")
    brdf = lf.designed_brdf(design)
    head_on = n[:, 2] > 0.97
    coat = ClearCoat()
    got = scene.truth(brdf, coat)[head_on]
    f = np.array([fresnel_unpolarised(math.degrees(math.acos(x)), 1.5) for x in n[head_on, 2]])
    expected = brdf.reflectance[0][0] * (1.0 - f) + brdf.specular_albedo * f / coat.reference
    assert got[:, 0] == pytest.approx(expected, rel=5e-3)
    assert scene.truth_direct(brdf, coat)[head_on] == pytest.approx(got, rel=5e-3)
    # The lobe model evaluated exactly carries the same factors: s on K_G, 1 − F on K_D.
    w = _gloss_only(0.05, 512.0)
    s_px, t_px = scene.coat_factors(coat)
    assert scene.lobes(w, "exact", coat) == pytest.approx(scene.lobes(w) * s_px, rel=1e-9)
    lam = LobeWeights(EXPS, np.full(3, 0.1), np.zeros((4, 3)), np.zeros(4))
    # (K_D also sees the light entering the coat, whose weight averages to 1 in this uniform map)
    assert scene.lobes(lam, "exact", coat) == pytest.approx(scene.lobes(lam) * t_px, rel=2e-3)

    # Against ground truth on the sky: the NumPy renderer with the coat tracks the truth with the coat
    # as closely as the thesis model tracks the thesis truth, and the coat changes the picture.
    from station.render import procedural

    env = procedural.sunny_sky(128)
    weights = lf.fit_design(FaceFlopTravelGloss((45.0, 40.0, 25.0), (20.0, 30.0, 15.0), 60.0, 85.0, "red"))
    basis = prefilter.prefilter_basis(env, weights.exponents, engine="numpy", max_size=32)
    sc = shapes.Scene("sphere")
    gb = nr.gbuffer(sc, 28, 28)
    truth = tr.TruthScene(env, gb.normal[gb.mask], gb.view[gb.mask], samples=64, quadrature_width=64)
    brdf_red = lf.designed_brdf(
        FaceFlopTravelGloss((45.0, 40.0, 25.0), (20.0, 30.0, 15.0), 60.0, 85.0, "red")
    )
    errors = {}
    for key, c in (("on", coat), ("off", None)):
        img = nr.render_linear(sc, basis, [weights], 28, 28, coat=c)[gb.mask]
        ref = truth.truth_direct(brdf_red, c)
        errors[key] = delta_e(linear_srgb_to_lab(img), linear_srgb_to_lab(ref), method="cie2000")
    assert errors["on"].mean() <= errors["off"].mean() + 0.3
    on_off = delta_e(
        linear_srgb_to_lab(truth.truth_direct(brdf_red, coat)),
        linear_srgb_to_lab(truth.truth_direct(brdf_red)),
        method="cie2000",
    )
    assert on_off.max() > 3.0 * errors["on"].mean()


def test_basis_images_fold_the_coat_in(const_basis) -> None:
    """Cached basis images with the coat re-weight to the NumPy renderer's picture with the coat."""
    from station.render import procedural
    from station.render.basis_images import build_basis_images

    basis = prefilter.prefilter_basis(procedural.sunny_sky(64), EXPS, max_size=32)
    paint = LobeWeights(
        EXPS, np.array([0.05, 0.04, 0.03]), np.full((4, 3), 0.03), np.array([0.0, 0.2, 0.5, 2.0])
    )
    scene = shapes.Scene("sphere")
    coat = ClearCoat()
    cached = build_basis_images(scene, basis, 40, 40, coat=coat)
    assert ("Cg", 3) in cached.layout and ("Cd", 3) in cached.layout
    ref = nr.render_linear(scene, basis, [paint], 40, 40, coat=coat)
    assert cached.linear_image([paint]) == pytest.approx(ref, rel=1e-4, abs=1e-5)
    plain = nr.render_linear(scene, basis, [paint], 40, 40)
    assert np.abs(ref - plain).max() > 0.05
