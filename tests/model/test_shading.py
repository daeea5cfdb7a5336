"""Reference point-light shading (station.model.shading) against closed forms."""

from __future__ import annotations

import math

import colour
import numpy as np
import pytest

from station.model import FaceFlopTravelGloss
from station.model.colorimetry import WHITEPOINT
from station.model.gloss import lobe_from_gloss
from station.model.shading import design_reflectance, point_light_rgb, shade_lab


def _grey_y(lightness: float) -> float:
    """Y/Y_n of a neutral grey (CIE 1976, above the linear segment)."""
    return ((lightness + 16.0) / 116.0) ** 3


def test_lambertian_grey_under_one_light() -> None:
    grey = FaceFlopTravelGloss((50.0, 0.0, 0.0), (50.0, 0.0, 0.0), None, 0.0)
    incidence = np.array([0.0, 30.0, 60.0, 89.0, 95.0])
    lambert = np.cos(np.radians(incidence))
    rgb = point_light_rgb(grey, lambert, np.full(5, 40.0), irradiance=1.7)
    expected = 1.7 * np.maximum(lambert, 0.0) * _grey_y(50.0)
    np.testing.assert_allclose(rgb, np.repeat(expected[:, None], 3, axis=1), atol=1e-12)


def test_gloss_lobe_at_the_mirror_is_not_scaled_by_lambert() -> None:
    """Eq 2.3.2's K_G lobe: at α = 0 the pixel is ϕ·Y + ρ_s (n + 1)/2 whatever the incidence."""
    d = FaceFlopTravelGloss((70.0, 0.0, 0.0), (70.0, 0.0, 0.0), None, 60.0)
    lobe = lobe_from_gloss(60.0)
    peak = lobe.specular_albedo * (lobe.phong_exponent + 1.0) / 2.0
    for incidence in (10.0, 45.0, 75.0):
        phi = math.cos(math.radians(incidence))
        got = point_light_rgb(d, phi, 0.0)
        assert got == pytest.approx(np.full(3, phi * _grey_y(70.0) + peak), rel=1e-4)
    # a surface turned away from the light is black, highlight included
    assert np.all(point_light_rgb(d, -0.2, 0.0) == 0.0)
    assert np.all(point_light_rgb(d, 0.7, 0.0, specular=False) == pytest.approx(0.7 * _grey_y(70.0)))


def test_design_reflectance_is_the_clamped_quadratic_in_linear_srgb() -> None:
    d = FaceFlopTravelGloss((60.0, 0.0, 0.0), (20.0, 0.0, 0.0), 75.0, 90.0)
    theta = np.array([15.0, 45.0, 75.0, 110.0])
    s2 = ((75.0 - np.minimum(theta, 75.0)) / 60.0) ** 2  # eq 3.3.2 by hand
    lightness = 20.0 + 40.0 * s2
    np.testing.assert_allclose(design_reflectance(d, theta)[:, 1], _grey_y(lightness), rtol=1e-9)


@pytest.mark.parametrize("k", [0.0, 0.25, 1.0, 1.8])
def test_shade_lab_scales_tristimulus_like_colour_science(k: float) -> None:
    lab = np.array([[52.0, 48.0, 30.0], [118.0, -0.9, -1.5], [5.0, 2.0, -3.0]])
    expected = colour.XYZ_to_Lab(colour.Lab_to_XYZ(lab, WHITEPOINT) * k, WHITEPOINT)
    np.testing.assert_allclose(shade_lab(lab, np.full(3, k)), expected, atol=1e-9)
    # neutral grey above the linear segment: ΔL* = (L* + 16)(k^⅓ − 1)
    if k > 0.1:
        assert shade_lab(np.array([60.0, 0.0, 0.0]), k)[0] == pytest.approx(60.0 + 76.0 * (k ** (1 / 3) - 1))


def test_shade_lab_adds_a_neutral_lobe_before_shading() -> None:
    out = shade_lab(np.array([50.0, 0.0, 0.0]), 0.5, 0.2)
    assert out[0] == pytest.approx(116.0 * (0.5 * (_grey_y(50.0) + 0.2)) ** (1 / 3) - 16.0)
    assert out[1:] == pytest.approx([0.0, 0.0], abs=1e-9)


def test_aspecular_angle_in_plane_and_by_the_mirror_vector() -> None:
    from station.model.shading import aspecular_deg

    def polar(deg: float) -> np.ndarray:
        t = math.radians(deg)
        return np.array([math.sin(t), 0.0, math.cos(t)])

    z = np.array([0.0, 0.0, 1.0])
    # in the plane of incidence the aspecular angle is |view + light| (thesis §3.3.3): 45as15 … 45as110
    for view in (-30.0, 0.0, 30.0, 65.0):
        assert aspecular_deg(polar(45.0), polar(view), z) == pytest.approx(abs(45.0 + view), abs=1e-9)
    rng = np.random.default_rng(7)
    v = rng.normal(size=(3, 200, 3))
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    light, view, normal = v
    r = 2.0 * np.sum(light * normal, axis=-1, keepdims=True) * normal - light
    expected = np.degrees(np.arccos(np.clip(np.sum(r * view, axis=-1), -1.0, 1.0)))
    np.testing.assert_allclose(aspecular_deg(light, view, normal), expected, atol=1e-9)
