"""Ward anisotropy by off-specular samples (eqs 2.5.4–2.5.7) against brute-force integration of eq 2.5.4."""

from __future__ import annotations

import numpy as np
import pytest

from station.model.colorimetry import linear_srgb_to_lab
from station.model.difference import delta_e
from station.render import anisotropy as an
from station.render import prefilter, procedural, shapes, tonemap
from station.render.environment import Environment
from station.render.errors import RenderInputError
from station.render.numpy_renderer import gbuffer

EXPS = (1.0, 4.0, 16.0, 64.0, 256.0, 1024.0, 4096.0)
SCENE = shapes.Scene("sphere", camera=shapes.Camera((0.0, 0.5, 5.0), (0.0, 0.0, 0.0), fov_deg=28))
LOBE = an.WardLobe((0.8, 0.8, 0.8), 0.05, 0.25)


def test_ward_albedo_under_constant_light_matches_brute_force():
    env = Environment("c", np.full((64, 128, 3), 1.0, np.float32))
    basis = prefilter.prefilter_basis(env, EXPS, engine="numpy")
    m = gbuffer(SCENE, 20, 20).mask
    truth = an.ward_truth(SCENE, env.to_cube(32), LOBE, 20, 20)[m]
    for j in (1, 9):
        got = an.render_anisotropic(SCENE, basis, LOBE, j, 20, 20)[m]
        assert np.median(np.abs(got - truth) / truth) < 0.03


def test_quality_improves_with_off_specular_samples():
    env = procedural.light_booth(128)
    basis = prefilter.prefilter_basis(env, EXPS, engine="numpy")
    w = 24
    m = gbuffer(SCENE, w, w).mask
    truth = an.ward_truth(SCENE, env.to_cube(32), LOBE, w, w)[m]

    def lab(x):
        return linear_srgb_to_lab(tonemap.srgb_decode(tonemap.to_display(x) / 255.0))

    err = {
        j: delta_e(lab(an.render_anisotropic(SCENE, basis, LOBE, j, w, w)[m]), lab(truth)).mean()
        for j in (1, 9)
    }
    assert err[9] < 0.6 * err[1]
    assert err[9] < 1.5


def test_isotropic_fit_is_nonnegative_and_bad_lobes_rejected():
    w = an.fit_isotropic(EXPS, 0.05)
    assert (w >= 0).all() and w.sum() > 0
    with pytest.raises(RenderInputError):
        an.WardLobe((1, 1, 1), 0.2, 0.1)
    with pytest.raises(RenderInputError):
        an.WardLobe((1, 1, 1), 0.0, 0.1)


# --- GL renderer, design parameters, level of detail -------------------------------------------------

BOOTH_SIZE = 40


def _lab(x):
    return linear_srgb_to_lab(tonemap.srgb_decode(tonemap.to_display(x) / 255.0))


def _gloss_paint(p_s: float, map_weights: np.ndarray | None = None):
    """A paint with gloss only: map weights summing to p_s (default: all on the sharpest lobe)."""
    from station.render.weights import LobeWeights

    m = len(EXPS)
    mw = np.zeros(m) if map_weights is None else np.asarray(map_weights, float)
    if map_weights is None:
        mw[-1] = 1.0
    mw = mw / mw.sum() * p_s
    return LobeWeights(EXPS, np.zeros(3), np.zeros((m, 3)), mw * (np.array(EXPS) + 1) / (2 * np.pi))


@pytest.fixture(scope="module")
def booth_basis(gl_ctx):
    return prefilter.prefilter_basis(procedural.light_booth(128), EXPS, ctx=gl_ctx)


@pytest.mark.parametrize("direction", [0.0, 30.0])
def test_gl_matches_the_numpy_reference(gl_ctx, booth_basis, direction):
    from station.model.anisotropy import Anisotropy
    from station.render.gl_renderer import GLRenderer

    a = Anisotropy(0.05, 0.25, direction)
    lobe = an.WardLobe.from_design(a, 0.8)
    w = BOOTH_SIZE
    m = gbuffer(SCENE, w, w).mask
    with GLRenderer(booth_basis, w, w, ctx=gl_ctx, half_float=False) as gl:
        for energy in an.ENERGIES:
            gl.anisotropy_energy = energy
            for j in (1, 9, 31):
                got = gl.render_linear(SCENE, [_gloss_paint(0.8)], anisotropy=a, anisotropic_samples=j)[m]
                ref = an.render_anisotropic(SCENE, booth_basis, lobe, j, w, w, energy)[m]
                # float32 texture filtering and the GL albedo table (bilinear in N·V, azimuth)
                assert np.median(np.abs(got - ref) / np.maximum(ref, 1e-6)) < 2e-3, (energy, j)
                assert delta_e(_lab(got), _lab(ref)).mean() < 0.1, (energy, j)
                assert gl.last_anisotropy is not None
                assert gl.last_anisotropy.samples == j


def test_gl_and_numpy_against_brute_force(gl_ctx):
    from station.model.anisotropy import Anisotropy
    from station.render.gl_renderer import GLRenderer

    a = Anisotropy(0.05, 0.25)
    lobe = an.WardLobe.from_design(a, 0.8)
    w = 20
    m = gbuffer(SCENE, w, w).mask
    const = Environment("c", np.full((64, 128, 3), 1.0, np.float32))
    booth = procedural.light_booth(128)
    for env, bound in ((const, 0.03), (booth, None)):
        basis = prefilter.prefilter_basis(env, EXPS, ctx=gl_ctx)
        truth = an.ward_truth(SCENE, env.to_cube(32), lobe, w, w)[m]
        with GLRenderer(basis, w, w, ctx=gl_ctx, half_float=False) as gl:
            gl.anisotropy_energy = "ward"
            err = {}
            for j in (1, 31):
                got = gl.render_linear(SCENE, [_gloss_paint(0.8)], anisotropy=a, anisotropic_samples=j)[m]
                num = an.render_anisotropic(SCENE, basis, lobe, j, w, w)[m]
                if bound is not None:  # a constant environment: P_s · A · L whatever J is
                    assert np.median(np.abs(got - truth) / truth) < bound
                    assert np.median(np.abs(num - truth) / truth) < bound
                err[j] = (delta_e(_lab(got), _lab(truth)).mean(), delta_e(_lab(num), _lab(truth)).mean())
        if bound is None:  # the booth's panels: the samples draw the highlight out along Y
            assert err[31][0] < 0.6 * err[1][0] and err[31][1] < 0.6 * err[1][1]
            assert err[31][0] < 1.5 and err[31][1] < 1.5


@pytest.mark.parametrize("alpha", [0.03, 0.08, 0.15])
def test_isotropic_limit_is_the_lobe_path(gl_ctx, alpha):
    """α_x = α_y = α on a paint whose own gloss lobes are the Ward-α fit: the anisotropic path renders
    the isotropic path's linear radiance to float rounding (1e-4 relative), at any sample count, with
    the diffuse, wide lobes (horizon factors) and the sky's sun (lights taken out of wide lobes) in play."""
    from station.model.anisotropy import Anisotropy
    from station.render.gl_renderer import GLRenderer
    from station.render.weights import LobeWeights

    basis = prefilter.prefilter_basis(procedural.sunny_sky(128), EXPS, ctx=gl_ctx)
    w = 32
    m = gbuffer(SCENE, w, w).mask
    fit = an.fit_isotropic(EXPS, alpha)
    gloss = _gloss_paint(0.8, fit)
    paint = LobeWeights(EXPS, np.array([0.05, 0.02, 0.01]), np.zeros((len(EXPS), 3)), gloss.k_g)
    with GLRenderer(basis, w, w, ctx=gl_ctx, half_float=False) as gl:
        iso = gl.render_linear(SCENE, [paint])[m]
        assert gl.last_anisotropy is None
        for j in (1, 9):
            got = gl.render_linear(
                SCENE, [paint], anisotropy=Anisotropy(alpha, alpha), anisotropic_samples=j
            )[m]
            np.testing.assert_allclose(got, iso, rtol=1e-4, atol=1e-6)
        got = gl.render_linear(SCENE, [paint], anisotropy=Anisotropy(alpha, alpha))
        assert gl.last_anisotropy is not None and gl.last_anisotropy.samples == 1
    lobe = an.WardLobe((0.8,) * 3, alpha, alpha)
    n = gbuffer(SCENE, w, w)
    one = an.shade_anisotropic(basis, lobe, 1, n.normal[m], n.view[m])
    nine = an.shade_anisotropic(basis, lobe, 9, n.normal[m], n.view[m])
    np.testing.assert_allclose(nine, one, rtol=1e-12)


def test_renderer_takes_the_sample_count_from_the_level_of_detail(gl_ctx, booth_basis):
    from station.model.anisotropy import Anisotropy
    from station.render import lod
    from station.render.gl_renderer import GLRenderer
    from station.render.truth import sphere_pixels

    a = Anisotropy(0.03, 0.3, 0.0)
    lobe = an.WardLobe.from_design(a)
    with GLRenderer(booth_basis, 24, 24, ctx=gl_ctx) as gl:
        chosen = {}
        for tol in (4.0, 0.5):
            gl.anisotropy_tolerance_de = tol
            img = gl.render_linear(SCENE, [_gloss_paint(0.8)], anisotropy=a)
            choice = gl.last_anisotropy
            expect = lod.choose_anisotropic_samples(
                booth_basis, lobe, *sphere_pixels(8), tol, energy="design"
            )
            assert choice is not None
            assert choice.samples == expect.samples and str(choice.samples) in choice.reason
            given = gl.render_linear(
                SCENE, [_gloss_paint(0.8)], anisotropy=a, anisotropic_samples=choice.samples
            )
            np.testing.assert_array_equal(img, given)
            chosen[tol] = choice.samples
        assert 1 < chosen[4.0] <= chosen[0.5]
        gl.render_linear(SCENE, [_gloss_paint(0.8)])
        assert gl.last_anisotropy is None
        with pytest.raises(RenderInputError):
            gl.render_linear(SCENE, [_gloss_paint(0.8)], anisotropy=a, anisotropic_samples=0)


def test_design_file_round_trip(tmp_path):
    import json

    from station.model import FaceFlopTravelGloss
    from station.model import design_io as io
    from station.model.anisotropy import Anisotropy
    from station.model.errors import ModelInputError

    d = FaceFlopTravelGloss((60.0, 20.0, 10.0), (30.0, 25.0, 15.0), 62.0, 85.0, "brushed red")
    a = Anisotropy(0.04, 0.2, 35.0)
    path = io.save_design(d, tmp_path / "a.json", anisotropy=a.to_dict())
    got_d, got_a = io.load_design_anisotropy(path)
    assert got_d == d and got_a == a
    assert json.loads(path.read_text())["anisotropy"] == {
        "alpha_x": 0.04,
        "alpha_y": 0.2,
        "direction_deg": 35.0,
    }
    assert io.load_design_anisotropy(io.save_design(d, tmp_path / "b.json"))[1] is None  # absent: isotropic
    assert io.load_design_anisotropy(io.save_design(d, tmp_path / "c.json", anisotropy=None))[1] is None
    round_lobe = io.anisotropy_from_dict({"anisotropy": {"alpha_x": 0.1, "alpha_y": 0.1}})
    assert round_lobe is not None and round_lobe.direction_deg == 0.0
    assert an.WardLobe.from_design(a).tangent == pytest.approx(
        (np.cos(np.radians(35)), np.sin(np.radians(35)), 0)
    )
    for bad, field in (
        ({"alpha_x": 0.2, "alpha_y": 0.1}, "anisotropy.alpha_y"),
        ({"alpha_x": 0.0, "alpha_y": 0.1}, "anisotropy.alpha_x"),
        ({"alpha_y": 0.1}, "anisotropy.alpha_x"),
        ({"alpha_x": 0.1, "alpha_y": 0.2, "angle": 3}, "anisotropy"),
        ({"alpha_x": 0.1, "alpha_y": 0.2, "direction_deg": 400}, "anisotropy.direction_deg"),
        ("wide", "anisotropy"),
    ):
        with pytest.raises(ModelInputError, match=field.replace(".", r"\.")):
            io.anisotropy_from_dict({"anisotropy": bad})


def test_mesh_takes_the_anisotropy_and_its_isotropic_limit(gl_ctx):
    from station.model.anisotropy import Anisotropy
    from station.render.car import car_body
    from station.render.gl_renderer import GLRenderer
    from station.render.weights import LobeWeights

    basis = prefilter.prefilter_basis(procedural.sunny_sky(128), EXPS, ctx=gl_ctx)
    mesh = car_body(48, 24)
    fit = an.fit_isotropic(EXPS, 0.05)
    paint = LobeWeights(
        EXPS, np.array([0.05, 0.02, 0.01]), np.zeros((len(EXPS), 3)), _gloss_paint(0.8, fit).k_g
    )
    with GLRenderer(basis, 48, 32, ctx=gl_ctx, half_float=False) as gl:
        iso = gl.render_mesh(mesh, [paint], linear=True)
        same = gl.render_mesh(
            mesh, [paint], linear=True, anisotropy=Anisotropy(0.05, 0.05), anisotropic_samples=9
        )
        brushed = gl.render_mesh(
            mesh, [paint], linear=True, anisotropy=Anisotropy(0.05, 0.3), anisotropic_samples=9
        )
    np.testing.assert_allclose(same, iso, rtol=1e-4, atol=1e-6)
    assert np.abs(brushed - iso).max() > 0.05  # the highlight is drawn out across +x
