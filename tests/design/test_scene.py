"""Scene buffers against closed forms (aspecular angle, Lambert term, light-direction buffer, shading)."""

from __future__ import annotations

import numpy as np
import pytest

from station.design.errors import DesignInputError
from station.design.scene import (
    builtin_scene,
    environment_sphere_scene,
    lobe_basis,
    panel_scene,
    shade,
    shade_environment,
    sphere_scene,
    srgb_decode,
    srgb_encode,
)
from station.model import FaceFlopTravelGloss


def _centre(n: int) -> tuple[int, int]:
    return n // 2, n // 2


def test_sphere_buffers_match_closed_form_at_pixels() -> None:
    sc = sphere_scene(64)
    L = sc.light_dir
    # pixel by pixel: θ = acos(R·V), R = 2(N·L)N − L, ϕ = max(N·L, 0), light buffer = 2(N·V)N − V
    rng = np.random.default_rng(1)
    ys, xs = np.nonzero(sc.mask)
    for k in rng.choice(len(ys), 20, replace=False):
        y, x = ys[k], xs[k]
        n = sc.normals[y, x]
        r = 2 * n.dot(L) * n - L
        assert sc.aspecular_deg[y, x] == pytest.approx(np.degrees(np.arccos(np.clip(r[2], -1, 1))), abs=1e-9)
        assert sc.lambert[y, x] == pytest.approx(max(n.dot(L), 0.0), abs=1e-12)
        assert sc.light_dirs[y, x] == pytest.approx(2 * n[2] * n - np.array([0, 0, 1.0]), abs=1e-12)
    assert not sc.mask[0, 0] and sc.aspecular_deg[0, 0] == 0.0 and sc.lambert[0, 0] == 0.0


def test_default_light_is_45_degrees_off_view_and_highlight_is_at_half_vector() -> None:
    sc = sphere_scene(128)
    assert np.degrees(np.arccos(sc.light_dir[2])) == pytest.approx(45.0)
    # the pixel of minimum θ has its normal along the half vector H = (L + V)/|L + V|
    y, x = np.unravel_index(np.argmin(np.where(sc.mask, sc.aspecular_deg, 999)), sc.shape)
    h = sc.light_dir + np.array([0, 0, 1.0])
    h /= np.linalg.norm(h)
    assert np.degrees(np.arccos(sc.normals[y, x].dot(h))) < 1.5
    assert sc.aspecular_deg[y, x] < 3.0


def test_shading_of_a_white_solid_is_the_lambert_term(sphere) -> None:
    white = FaceFlopTravelGloss((100.0, 0.0, 0.0), (100.0, 0.0, 0.0), None, 0.0)
    img = shade(sphere, white, specular=False)
    assert img[sphere.mask] == pytest.approx(np.repeat(sphere.lambert[sphere.mask][:, None], 3, 1), abs=1e-9)
    assert np.all(img[~sphere.mask] == 0.0)


def test_shading_follows_the_design_curve_at_each_pixel(sphere, red_metallic) -> None:
    img = shade(sphere, red_metallic, specular=False)
    y, x = _centre(64)
    from station.model.colorimetry import lab_to_linear_srgb

    expected = sphere.lambert[y, x] * lab_to_linear_srgb(red_metallic.lab_at(sphere.aspecular_deg[y, x]))
    assert img[y, x] == pytest.approx(expected, abs=1e-12)


def test_with_light_moves_the_highlight(sphere) -> None:
    moved = sphere.with_light((0.3, -0.2, 1.0))
    assert not np.allclose(moved.aspecular_deg, sphere.aspecular_deg)
    assert np.allclose(moved.normals, sphere.normals)


def test_srgb_transfer_round_trip_and_reference_values() -> None:
    x = np.linspace(0, 1, 101)
    assert srgb_decode(srgb_encode(x)) == pytest.approx(x, abs=1e-12)
    assert srgb_encode(0.5) == pytest.approx(0.735356983, abs=1e-8)  # IEC 61966-2-1


def test_builtin_scenes_and_bad_input() -> None:
    assert builtin_scene("panel-point", 32).mask.any()
    assert panel_scene(32).aspecular_deg.max() > 0
    with pytest.raises(DesignInputError, match="scene"):
        builtin_scene("teapot")
    with pytest.raises(DesignInputError, match="size"):
        sphere_scene(4)
    with pytest.raises(DesignInputError, match="light_dir"):
        sphere_scene(32, light_dir=(0, 0, 0))


def test_environment_image_is_linear_in_the_basis() -> None:
    env = environment_sphere_scene(24, lights=6)
    basis = lobe_basis(env, (None, 4.0))
    # a design whose curve is exactly K_D + K_4 cos^4θ is not a clamped quadratic, so check linearity
    # directly: the basis image of a lobe equals the sum over lights of radiance × ϕ × lobe value
    m = env.mask
    manual = np.zeros((int(m.sum()), 3))
    for i in range(len(env.light_dirs)):
        c = np.cos(np.radians(env.aspecular_deg[i][m]))
        manual += env.light_rgb[i] * (env.lambert[i][m] * np.where(c > 0, c, 0) ** 4)[:, None]
    assert basis.images[1][m] == pytest.approx(manual, abs=1e-12)
    solid = FaceFlopTravelGloss((100.0, 0.0, 0.0), (100.0, 0.0, 0.0), None, 0.0)
    # a white Lambertian solid renders exactly as the diffuse basis image
    assert shade_environment(env, solid, specular=False)[m] == pytest.approx(basis.images[0][m], abs=1e-9)


def test_shade_is_the_model_reference_shading() -> None:
    """The scene shader adds nothing of its own: a lit pixel is E·[ϕ·ρ(θ) + lobe(θ)] of the model."""
    from station.model.lobe import lobe_reflectance
    from station.model.shading import design_reflectance

    sc = sphere_scene(32, irradiance=2.0)
    d = FaceFlopTravelGloss((60.0, 10.0, -20.0), (30.0, 5.0, -10.0), 60.0, 60.0)
    m = sc.mask & (sc.lambert > 0)
    theta, phi = sc.aspecular_deg[m], sc.lambert[m]
    expected = 2.0 * (phi[:, None] * design_reflectance(d, theta) + lobe_reflectance(60.0, theta)[:, None])
    assert shade(sc, d)[m] == pytest.approx(expected, rel=1e-12, abs=1e-15)


def test_scene_from_external_buffers_matches_the_generator(sphere) -> None:
    from station.design.scene import scene_from_buffers

    inc = np.degrees(np.arccos(np.clip(sphere.normals @ sphere.light_dir, -1, 1)))
    wrapped = scene_from_buffers(
        sphere.aspecular_deg,
        sphere.mask,
        incidence_deg=inc,
        light_dirs=sphere.light_dirs,
        normals=sphere.normals,
        light_dir=sphere.light_dir,
    )
    assert wrapped.lambert == pytest.approx(sphere.lambert, abs=1e-12)
    with pytest.raises(DesignInputError, match="lambert"):
        scene_from_buffers(sphere.aspecular_deg, sphere.mask)
    with pytest.raises(DesignInputError, match="aspecular_deg/mask"):
        scene_from_buffers(sphere.aspecular_deg[:3], sphere.mask, lambert=sphere.lambert)
