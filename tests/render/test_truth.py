"""Ground-truth integration of the designed BRDF against environments (closed forms, point lights)."""

from __future__ import annotations

import numpy as np
import pytest

from station.errors import InputError
from station.render import lobe_fit as lf
from station.render import truth as tr
from station.render.lobes import LobeBasis
from station.render.weights import LobeWeights


def analytic_env(h: int = 64, sun: bool = True) -> np.ndarray:
    """Sky gradient (+Y up) over a dim ground, optionally with a small bright disc (built here, no files)."""
    d = tr.equirect_directions(h, 2 * h)
    img = np.where(d[..., 1:2] > 0, 0.6 + 0.8 * d[..., 1:2] * np.array([0.8, 0.9, 1.0]), 0.15)
    if sun:
        s = np.array([0.3, 0.8, 0.52])
        s /= np.linalg.norm(s)
        img = img + (d @ s > np.cos(np.radians(4.0)))[..., None] * 200.0
    return img


def solid(grey_l: float, gloss: float):
    from station.model import FaceFlopTravelGloss

    return FaceFlopTravelGloss((grey_l, 0.0, 0.0), (grey_l, 0.0, 0.0), None, gloss, "grey")


def test_constant_environment_closed_forms() -> None:
    n, v = tr.sphere_pixels(12)
    scene = tr.TruthScene(np.ones((64, 128, 3)), n, v, samples=128, quadrature_width=128)
    assert scene.irradiance() == pytest.approx(np.full_like(n, np.pi), rel=2e-3)
    assert scene.white() == pytest.approx(np.ones_like(n), rel=2e-3)
    for e in (3.0, 30.0, 300.0, 3000.0):  # broad (quadrature) and sharp (importance-sampled) lobes
        assert scene.lobe(e, "open") == pytest.approx(np.full_like(n, 2 * np.pi / (e + 1)), rel=5e-3)
    # A grey solid seen head-on: colour ρ (∫(N·ω)/π = 1) plus the whole gloss albedo ρ_s.
    brdf = lf.designed_brdf(solid(60.0, 60.0))
    head_on = n[:, 2] > 0.97
    expected = brdf.reflectance[0] + brdf.specular_albedo
    assert scene.truth(brdf)[head_on] == pytest.approx(
        np.broadcast_to(expected, (head_on.sum(), 3)), rel=5e-3
    )


def test_point_light_matches_the_brdf() -> None:
    from station.model import FaceFlopTravelGloss

    h = 128
    img = np.full((h, 2 * h, 3), 1e-6)
    j, i = 40, 100  # one bright pixel: a point light of flux radiance × solid angle
    img[j, i] = 5.0e4
    light = tr.equirect_directions(h, 2 * h)[j, i]
    flux = 5.0e4 * tr.equirect_solid_angles(h, 2 * h)[j, i]
    design = FaceFlopTravelGloss((70.0, -10.0, -30.0), (30.0, 5.0, -20.0), 100.0, 25.0, "blue")
    brdf = lf.designed_brdf(design)
    rng = np.random.default_rng(3)
    normals = light + rng.normal(0, 0.35, (40, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    views = rng.normal(0, 1, (40, 3))
    views /= np.linalg.norm(views, axis=1, keepdims=True)
    views = np.where(np.einsum("ij,ij->i", views, normals)[:, None] < 0.1, normals, views)
    got = tr.render_truth(brdf, img, normals, views, samples=64, quadrature_width=64)
    n_dot_l = normals @ light
    refl = 2 * np.einsum("ij,ij->i", normals, views)[:, None] * normals - views
    expected = flux * brdf.brdf_cos(n_dot_l, refl @ light)
    assert got == pytest.approx(expected, rel=0.02, abs=1e-4)


def test_exactly_representable_lobes_equal_truth() -> None:
    basis = LobeBasis((3.0, 40.0, 500.0))
    k_d = np.array([0.04, 0.05, 0.08])
    k_dd = np.array([[0.05, 0.04, 0.02], [0.0, 0.0, 0.0], [0.1, 0.1, 0.1]])
    rho = np.pi * (k_d + basis.lobes(np.cos(np.radians(lf.ALPHA_GRID_DEG))) @ k_dd)
    # Without a horizon term the colour integrand is (N·ω)ρ(ψ)/π: the DD lobes exactly.
    brdf = lf.DesignedBRDF(rho, 500.0, 0.1, "exact")
    weights = LobeWeights(basis.exponents, k_d, k_dd, np.array([0.0, 0.0, 0.1 * 501 / (2 * np.pi)]))
    n, v = tr.sphere_pixels(10)
    scene = tr.TruthScene(analytic_env(), n, v, samples=128, quadrature_width=64)
    assert scene.lobes(weights, "exact") == pytest.approx(scene.truth(brdf), rel=2e-3, abs=1e-6)
    # The renderer's (R·N) stand-in for (L·N) is an approximation: visibly different for broad lobes.
    diff = np.abs(scene.lobes(weights, "prefiltered") - scene.truth(brdf)).max()
    assert diff > 1e-3


def test_point_light_extraction_keeps_energy() -> None:
    img = analytic_env(64)
    lighting = tr.prepare_lighting(img, quadrature_width=32)
    om = tr.equirect_solid_angles(64, 128)
    total = (img * om[..., None]).sum(axis=(0, 1))
    split = lighting.quad_flux.sum(axis=0) + lighting.point_flux.sum(axis=0)
    assert split == pytest.approx(total, rel=1e-9)
    assert lighting.point_dirs.shape[0] > 0


def test_input_errors() -> None:
    n, v = tr.sphere_pixels(4)
    with pytest.raises(InputError):
        tr.TruthScene(np.ones((10, 10, 3)), n, v)
    with pytest.raises(InputError):
        tr.TruthScene(np.full((8, 16, 3), np.nan), n, v)
    with pytest.raises(InputError):
        tr.TruthScene(np.ones((8, 16, 3)), n, -v)
    with pytest.raises(InputError):
        tr.TruthScene(np.ones((8, 16, 3)), n, v[:-1])
    scene = tr.TruthScene(np.ones((8, 16, 3)), n, v, samples=16, quadrature_width=16)
    with pytest.raises(InputError):
        scene.lobes(LobeWeights((2.0,), np.zeros(3), np.zeros((1, 3)), np.zeros(1)), mode="gl")


def test_render_truth_keeps_pixel_shape() -> None:
    n, v = tr.sphere_pixels(6)
    grid_n = np.broadcast_to(n[:4], (2, 4, 3))
    grid_v = np.broadcast_to(v[:4], (2, 4, 3))
    out = tr.render_truth(
        solid(50.0, 40.0), np.ones((16, 32, 3)), grid_n, grid_v, samples=32, quadrature_width=32
    )
    assert out.shape == (2, 4, 3) and np.all(np.isfinite(out)) and np.all(out > 0)


def test_horizon_table_makes_prefiltered_exact_in_a_constant_environment() -> None:
    n, v = tr.sphere_pixels(10)
    scene = tr.TruthScene(np.ones((64, 128, 3)), n, v, samples=128, quadrature_width=128)
    w = LobeWeights(
        (2.0, 30.0, 800.0),
        np.array([0.02, 0.03, 0.04]),
        np.array([[0.1, 0.05, 0.0], [0.0, 0.1, 0.0], [0.05, 0.05, 0.05]]),
        np.array([0.0, 0.2, 10.0]),
    )
    exact = scene.lobes(w, "exact")
    assert scene.lobes(w, "prefiltered-lut") == pytest.approx(exact, rel=5e-3)
    assert scene.lobes(w, "prefiltered-bent+lights") == pytest.approx(exact, rel=5e-3)
    assert np.abs(scene.lobes(w, "prefiltered") / exact - 1).max() > 0.05  # eq 2.5.1 as written is not


def test_silhouette_pixels_are_bent_or_refused() -> None:
    n = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.8, 0.0, -0.6]])  # head-on, grazing, back-facing
    v = np.broadcast_to([0.0, 0.0, 1.0], n.shape)
    out = tr.render_truth(solid(50.0, 40.0), np.ones((16, 32, 3)), n, v, samples=32, quadrature_width=32)
    bent, count = tr.bend_silhouettes(n, v)
    assert count == 2  # the grazing and the back-facing normal
    np.testing.assert_allclose(np.einsum("ij,ij->i", bent, v)[1:], tr.BEND_COS)  # turned to N·V = BEND_COS
    np.testing.assert_allclose(np.linalg.norm(bent, axis=-1), 1.0)
    np.testing.assert_array_equal(bent[0], n[0])  # the head-on normal is left alone
    assert np.all(np.isfinite(out)) and np.all(out >= 0)
    with pytest.raises(InputError):
        tr.render_truth(solid(50.0, 40.0), np.ones((16, 32, 3)), n, v, backfacing="error")
    with pytest.raises(InputError):
        tr.render_truth(solid(50.0, 40.0), np.ones((16, 32, 3)), n, v, backfacing="flip")


def test_direct_and_binned_truth_agree() -> None:
    from station.model import FaceFlopTravelGloss

    n, v = tr.sphere_pixels(10)
    scene = tr.TruthScene(analytic_env(), n, v, samples=64, quadrature_width=64)
    for gloss in (10.0, 85.0):  # broad gloss lobe (quadrature) and sharp one (importance sampled)
        brdf = lf.designed_brdf(FaceFlopTravelGloss((90.0, 2.0, 20.0), (35.0, 5.0, 15.0), 100.0, gloss))
        assert scene.truth_direct(brdf) == pytest.approx(scene.truth(brdf), rel=5e-3, abs=1e-5)


def test_bent_direction_limits() -> None:
    from station.render.lobes import bent_direction

    r = np.array([[0.0, 0.6, 0.8]])
    nrm = np.array([[0.0, 0.0, 1.0]])
    assert bent_direction(1e9, r, nrm) == pytest.approx(r)  # narrow lobes: the mirror direction
    assert bent_direction(0.0, r, nrm) == pytest.approx(nrm)  # the cosine alone: the normal
    b = bent_direction(2.0, r, nrm)[0]
    assert np.linalg.norm(b) == pytest.approx(1.0)
    assert r[0] @ nrm[0] < b @ nrm[0] < 1.0  # between R and N
