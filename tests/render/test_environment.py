"""Cube-map geometry, equirect → cube conversion and the procedural environments."""

from __future__ import annotations

import numpy as np
import pytest

from station.render import cubemap, procedural
from station.render.environment import Environment
from station.render.errors import RenderInputError
from station.render.procedural import _horizontal_irradiance


def test_face_directions_round_trip_and_solid_angles():
    d = cubemap.face_directions(8)
    face, a, b = cubemap.direction_to_face(d)
    assert (face == np.arange(6)[:, None, None]).all()
    assert np.allclose(a, cubemap.face_coords(8)[None, None, :])
    assert np.allclose(b, cubemap.face_coords(8)[None, :, None])
    assert 6 * cubemap.texel_solid_angles(16).sum() == pytest.approx(4 * np.pi)
    assert 16 * cubemap.equirect_solid_angles(8, 16).sum() == pytest.approx(4 * np.pi)


def test_equirect_to_cube_of_a_linear_field_is_that_field():
    # L(ω) = 1 + ω·(0.3, 0.5, −0.2) is linear, so bilinear resampling keeps it to O(texel²).
    h, w = 128, 256
    g = np.array([0.3, 0.5, -0.2])
    eq = (1.0 + cubemap.equirect_directions(h, w) @ g)[..., None].repeat(3, -1)
    cube = cubemap.equirect_to_cube(eq, 16)
    expect = 1.0 + cubemap.face_directions(16) @ g
    assert np.abs(cube[..., 0] - expect).max() < 0.01


def test_sample_equirect_wraps_in_azimuth():
    eq = np.zeros((4, 8, 1))
    eq[:, 0] = 1.0
    eq[:, -1] = 1.0
    # direction +Z (behind, φ = ±π) lies on the seam between the first and last columns
    assert cubemap.sample_equirect(eq, np.array([0.0, 0.0, 1.0]))[0] == pytest.approx(1.0)


@pytest.mark.parametrize("maker", [procedural.light_booth, procedural.sunny_sky, procedural.overcast_sky])
def test_procedural_environments_are_deterministic_and_normalised(maker):
    a, b = maker(128), maker(128)
    assert a.content_hash == b.content_hash
    # Upward white Lambertian → radiance E/π = 1 (documented normalisation); green channel for the sky.
    assert _horizontal_irradiance(a.equirect)[1] / np.pi == pytest.approx(1.0, rel=2e-3)


def test_overcast_follows_cie_luminance_law():
    env = procedural.overcast_sky(512)
    h = env.height
    zen = env.equirect[0, 0, 0]
    row = int(h * 0.5) - 3  # just above the horizon
    theta = np.pi * (row + 0.5) / h
    ratio = env.equirect[row, 0, 0] / zen
    assert ratio == pytest.approx((1 + 2 * np.cos(theta)) / (1 + 2 * np.cos(np.pi * 0.5 / h)), rel=0.02)
    assert env.equirect[-1, 0, 0] == pytest.approx(procedural.GROUND_ALBEDO)


def test_sunny_sky_sun_position_and_colour():
    env = procedural.sunny_sky(256, sun_elevation_deg=30.0, sun_azimuth_deg=90.0)
    lum = env.equirect @ np.array([0.2126, 0.7152, 0.0722])
    j, i = np.unravel_index(np.argmax(lum), lum.shape)
    d = cubemap.equirect_directions(env.height, 256)[j, i]
    sun = procedural.sun_direction(30.0, 90.0)
    assert np.degrees(np.arccos(np.clip(d @ sun, -1, 1))) < 2.5
    # The clear sky is blue overhead (b > r) and the zenith luminance matches Preetham's ratio
    zenith = env.equirect[0].mean(axis=0)
    assert zenith[2] > 1.5 * zenith[0]


def test_preetham_zenith_published_value():
    # Preetham et al. (1999) Fig. 9 range: T = 2, θs = 30° → Y_z ≈ 5.2 kcd/m² (formula A.2)
    yz, xz, yzc = procedural.preetham_zenith(2.0, np.radians(60.0))
    expect = (
        (4.0453 * 2 - 4.9710) * np.tan((4 / 9 - 2 / 120) * (np.pi - 2 * np.radians(60))) - 0.2155 * 2 + 2.4192
    )
    assert yz == pytest.approx(expect)
    assert 0.2 < xz < 0.35 and 0.2 < yzc < 0.37


def test_booth_lights_are_overhead():
    env = procedural.light_booth(128)
    lum = env.equirect[..., 1]
    dirs = cubemap.equirect_directions(env.height, 128)
    assert dirs[lum > 0.9 * lum.max()][:, 1].min() > 0.5


def test_bad_procedural_parameters_raise():
    with pytest.raises(RenderInputError):
        procedural.sunny_sky(128, turbidity=30)
    with pytest.raises(RenderInputError):
        procedural.light_booth(7)
    with pytest.raises(RenderInputError):
        procedural.procedural_environment("moon")


def test_environment_mean_radiance_of_constant():
    env = Environment("c", np.full((16, 32, 3), 2.5, np.float32))
    assert env.mean_radiance() == pytest.approx([2.5] * 3)
