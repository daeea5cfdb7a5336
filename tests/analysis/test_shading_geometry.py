"""Colour c (eqs 4.3.2–4.3.4) and seam geometry against independent computations."""

from __future__ import annotations

import math

import colour
import numpy as np
import pytest

from station.analysis import AnalysisInputError, Environment
from station.analysis.geometry import aspecular_deg, direction, rotated_normals
from station.analysis.shading import Exposure, environment_colour, point_colour, shade_lab
from station.model import FaceFlopTravelGloss
from station.model.colorimetry import WHITEPOINT


@pytest.mark.parametrize("k", [0.0, 0.003, 0.5, 0.93, 1.0, 1.2])
def test_shade_lab_scales_xyz_like_colour_science(k):
    lab = np.array([[60.0, 20.0, -30.0], [5.0, 2.0, 1.0], [95.0, -3.0, 8.0]])
    xyz = colour.Lab_to_XYZ(lab, WHITEPOINT)
    expected = colour.XYZ_to_Lab(xyz * k, WHITEPOINT)
    np.testing.assert_allclose(shade_lab(lab, np.full(3, k)), expected, atol=1e-9)


def test_grey_closed_form_lightness():
    """ΔL* = (L* + 16)(k^⅓ − 1) above the linear segment (the issue's bar formula)."""
    for L in (20.0, 60.0, 95.0):
        for k in (0.8, 0.95, 1.1):
            out = shade_lab(np.array([L, 0.0, 0.0]), np.array(k))
            assert out[0] - L == pytest.approx((L + 16) * (k ** (1 / 3) - 1), abs=1e-10)
            assert abs(out[1]) < 1e-10 and abs(out[2]) < 1e-10


def test_aspecular_in_plane_is_view_plus_light():
    z = np.array([0.0, 0.0, 1.0])
    for light, view in [(45, -30), (45, 0), (45, 65), (20, -20), (60, -50)]:
        assert aspecular_deg(direction(light), direction(view), z) == pytest.approx(
            abs(view + light), abs=1e-9
        )


def test_in_plane_rotation_shifts_aspecular_by_two_beta():
    """Mirror law: turning the panel by β turns the mirror direction by 2β."""
    n = rotated_normals(np.array([2.0, -3.0]))
    a = aspecular_deg(direction(45.0), direction(0.0), n)
    np.testing.assert_allclose(a, [45.0 - 4.0, 45.0 + 6.0], atol=1e-9)


def test_out_of_plane_rotation_is_second_order():
    n = rotated_normals(np.array([2.0]), "out-of-plane")
    np.testing.assert_allclose(n[0], [0.0, math.sin(math.radians(2)), math.cos(math.radians(2))], atol=1e-12)
    a = aspecular_deg(direction(45.0), direction(0.0), n)[0]
    # R·V = 2 cos θl cos θv cos²β − cos(θl − θv) = cos 45° cos 4° here: a second-order change
    assert a == pytest.approx(
        math.degrees(math.acos(math.cos(math.radians(45)) * math.cos(math.radians(4)))), abs=1e-9
    )
    assert abs(a - 45.0) < 0.2  # vs 4° in-plane


def test_point_colour_reference_exposure_shows_the_paint_on_panel_a():
    p = FaceFlopTravelGloss((70.0, 5.0, -20.0), (30.0, 2.0, -10.0), 60.0)
    L, V = direction(30.0), direction(10.0)
    c = point_colour(p, L, V, np.array([0.0, 0.0, 1.0]))
    np.testing.assert_allclose(c, p.lab_at(40.0), atol=1e-10)
    c_abs = point_colour(p, L, V, np.array([0.0, 0.0, 1.0]), exposure="absolute")
    np.testing.assert_allclose(c_abs, shade_lab(p.lab_at(40.0), math.cos(math.radians(30))), atol=1e-10)


def test_panel_turned_away_from_light_is_black():
    p = FaceFlopTravelGloss((50.0, 0.0, 0.0), (50.0, 0.0, 0.0), None)
    n = rotated_normals(np.array([-60.0]))  # light at 40° is now behind panel B
    c = point_colour(p, direction(40.0), direction(0.0), n)
    np.testing.assert_allclose(c, [[0.0, 0.0, 0.0]], atol=1e-9)


def test_gloss_option_brightens_near_specular_only():
    p = FaceFlopTravelGloss((50.0, 0.0, 0.0), (20.0, 0.0, 0.0), 60.0, gloss_gu=60.0)
    z = np.array([0.0, 0.0, 1.0])
    near = (
        point_colour(p, direction(45.0), direction(-44.0), z, gloss=True)[0]
        - point_colour(p, direction(45.0), direction(-44.0), z)[0]
    )
    far = (
        point_colour(p, direction(45.0), direction(40.0), z, gloss=True)[0]
        - point_colour(p, direction(45.0), direction(40.0), z)[0]
    )
    assert near > 1.0
    assert far == pytest.approx(0.0, abs=1e-6)


def test_gloss_lobe_at_the_mirror_matches_the_model_lobe():
    """At the mirror geometry the lobe adds ρ_s (n+1)/2 (not scaled by L·N), ÷ L·N_A for the reference."""
    from station.model.gloss import lobe_from_gloss

    p = FaceFlopTravelGloss((50.0, 0.0, 0.0), (50.0, 0.0, 0.0), None, gloss_gu=60.0)
    z = np.array([0.0, 0.0, 1.0])
    lobe = lobe_from_gloss(60.0)
    peak = lobe.specular_albedo * (lobe.phong_exponent + 1.0) / 2.0
    y = ((50.0 + 16.0) / 116.0) ** 3
    for light in (20.0, 45.0, 70.0):
        k_a = math.cos(math.radians(light))
        exposures: tuple[tuple[Exposure, float], ...] = (("reference", k_a), ("absolute", 1.0))
        for exposure, white in exposures:
            c = point_colour(p, direction(light), direction(-light), z, exposure=exposure, gloss=True)
            expected = 116.0 * ((k_a * y + peak) / white) ** (1 / 3) - 16.0
            assert c[0] == pytest.approx(expected, rel=1e-4)


def test_equirect_weights_sum_to_sphere():
    env = Environment.from_equirect(np.ones((32, 64, 3)))
    assert env.radiance[:, 0].sum() == pytest.approx(4 * math.pi, rel=1e-3)


def test_environment_uniform_sky_equals_lambert_sky_fraction():
    """A white uniform sky over a grey solid: panel A shows its paint (reference exposure)."""
    p = FaceFlopTravelGloss((50.0, 0.0, 0.0), (50.0, 0.0, 0.0), None)
    env = Environment.from_equirect(np.ones((64, 128, 3)))
    c = environment_colour(p, env, direction(0.0), np.array([[0.0, 0.0, 1.0]]))
    np.testing.assert_allclose(c[0], [50.0, 0.0, 0.0], atol=1e-6)


def test_environment_bad_input():
    with pytest.raises(AnalysisInputError):
        Environment(np.zeros((0, 3)), np.zeros((0, 3)))
    with pytest.raises(AnalysisInputError):
        Environment(np.ones((2, 3)), -np.ones((2, 3)))
    with pytest.raises(AnalysisInputError):
        Environment.from_equirect(np.ones((4, 4)))
