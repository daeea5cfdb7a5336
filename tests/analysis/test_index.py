"""Goniogeometric index (eq 4.3.1): closed forms, brute force, directions, hinges, failure paths."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from station.analysis import AnalysisInputError, Environment, goniogeometric_index
from station.analysis.geometry import rotated_normals
from station.analysis.index import SeamModel
from station.errors import InputError
from station.model import FaceFlopTravelGloss
from station.model.difference import delta_e

from .conftest import brute_force_first_crossing


def closed_form_root(L: float, theta_i: float, sign: float, eps: float = 2.3, k_of=None) -> float | None:
    """Root of (L+16)|k^(1/3) − 1| = ε with k = cos(θ_i − sβ)/cos θ_i (independent of the code)."""

    def k(b: float) -> float:
        if k_of is not None:
            return k_of(b)
        return math.cos(math.radians(theta_i - sign * b)) / math.cos(math.radians(theta_i))

    def f(b: float) -> float:
        return (L + 16.0) * abs(k(b) ** (1.0 / 3.0) - 1.0) - eps

    grid = np.arange(0.0, 30.0 + 1e-9, 0.01)  # plain scan for the first sign change, then Brent
    vals = np.array([f(b) for b in grid])
    hit = np.nonzero(vals >= 0)[0]
    if not hit.size:
        return None
    return brentq(f, grid[hit[0] - 1], grid[hit[0]], xtol=1e-12)


@pytest.mark.parametrize("L", [30.0, 60.0, 95.0])
@pytest.mark.parametrize("theta_i", [10.0, 30.0, 45.0, 60.0, 75.0])
@pytest.mark.parametrize("direction", ["+", "-"])
def test_lambertian_grey_matches_closed_form(L, theta_i, direction):
    """Bar: light at θ_i, L* = L, k = cos(θ_i + β)/cos θ_i → ΔL* = (L+16)(k^⅓ − 1); match to 0.01°."""
    grey = FaceFlopTravelGloss((L, 0.0, 0.0), (L, 0.0, 0.0), None)
    r = goniogeometric_index(grey, theta_i, 0.0, direction=direction)
    sign = 1.0 if direction == "+" else -1.0
    # "+" turns panel B towards the light (θ_i − β); "-" away (θ_i + β), the bar's k.
    expected = closed_form_root(L, theta_i, sign)
    if expected is None:
        assert not r.reached and r.beta_min_deg is None
        return
    assert r.reached and r.beta_min_deg is not None
    assert r.beta_min_deg == pytest.approx(expected, abs=0.01)
    assert abs(r.beta_min_deg - expected) < 1e-5  # the stated resolution is 1e-6°
    assert r.direction == direction


def test_either_direction_picks_the_smaller(grey):
    r = goniogeometric_index(grey, 45.0, 0.0)
    away = closed_form_root(60.0, 45.0, -1.0)
    towards = closed_form_root(60.0, 45.0, 1.0)
    assert away is not None and towards is not None
    assert r.beta_min_deg == pytest.approx(min(away, towards), abs=1e-5)
    assert r.direction == "-"  # turning away from the light darkens faster at 45°


def test_out_of_plane_hinge_solid_is_symmetric(grey):
    """Out-of-plane hinge: L·N_B = cos β cos θ_i, so k = cos β in both directions."""
    expected = closed_form_root(60.0, 45.0, 1.0, k_of=lambda b: math.cos(math.radians(b)))
    for d in ("+", "-"):
        r = goniogeometric_index(grey, 45.0, 0.0, hinge="out-of-plane", direction=d)
        assert r.beta_min_deg == pytest.approx(expected, abs=1e-5)


def test_normal_light_never_reaches_small_epsilon_range(grey):
    """Light at the normal: k = cos β; ε = 2.3 needs β ≈ 24°, so β_max = 10° is not enough: say so."""
    r = goniogeometric_index(grey, 0.0, 0.0, beta_max_deg=10.0)
    assert not r.reached and r.beta_min_deg is None and r.direction is None
    assert "never reached" in r.message
    assert 0.0 < r.max_delta_e < 2.3
    d = r.to_dict()
    assert d["beta_min_deg"] is None and d["reached"] is False


@pytest.mark.parametrize("method", ["cie2000", "cie94", "din6175"])
def test_other_de_formulas_match_brute_force(blue_metallic, method):
    r = goniogeometric_index(blue_metallic, 45.0, -10.0, method=method, direction="+", epsilon=1.0)
    bf = brute_force_first_crossing(blue_metallic, 45.0, -10.0, 1.0, 1.0, method=method)
    assert r.reached and bf is not None
    assert r.beta_min_deg == pytest.approx(bf, abs=2e-3)


def test_cie76_inline_equals_model_delta_e(blue_metallic):
    m = SeamModel([45.0, 30.0], [-30.0, 20.0])
    betas = np.linspace(-5, 5, 11)
    de = m.delta_e(blue_metallic, blue_metallic, betas)
    ca = np.broadcast_to(m.reference(blue_metallic), (2, 11, 3))
    from station.analysis.geometry import rotated_normals

    cb = m.colour(blue_metallic, rotated_normals(betas))
    np.testing.assert_allclose(de, delta_e(ca, cb, method="cie76"), atol=1e-12)


def test_range_minimum_equals_minimum_of_single_geometries(blue_metallic):
    lights, views = [15.5, 45.0], [-20.0, 0.0, 30.0]
    r = goniogeometric_index(blue_metallic, lights, views)
    singles = [goniogeometric_index(blue_metallic, lt, v) for lt in lights for v in views]
    best = min(singles, key=lambda s: math.inf if s.beta_min_deg is None else s.beta_min_deg)
    assert r.beta_min_deg == pytest.approx(best.beta_min_deg, abs=1e-6)
    assert r.geometry["light_deg"] == best.geometry["light_deg"]
    assert r.geometry["view_deg"] == best.geometry["view_deg"]
    assert len(r.per_geometry) == 12


def test_default_views_for_effect_paint_scan_aspecular_range(blue_metallic):
    r = goniogeometric_index(blue_metallic, 45.0)
    assert r.reached
    assert 15.0 - 1e-9 <= r.geometry["aspecular_deg"] <= 110.0 + 1e-9
    # Near the face the colour changes fastest: the minimum sits at a low aspecular angle.
    assert r.geometry["aspecular_deg"] <= 30.0


def test_effect_paint_is_more_sensitive_than_solid(blue_metallic):
    solid = FaceFlopTravelGloss((60.0, -1.0, -11.0), (60.0, -1.0, -11.0), None)
    r_eff = goniogeometric_index(blue_metallic, 45.0, -30.0)
    r_sol = goniogeometric_index(solid, 45.0, -30.0)
    assert r_eff.beta_min_deg is not None and r_sol.beta_min_deg is not None
    assert r_eff.beta_min_deg < r_sol.beta_min_deg / 5  # thesis Fig 4.2: effect ≫ solid


def test_environment_single_white_sample_equals_point_light(blue_metallic):
    light = 40.0
    t = math.radians(light)
    env = Environment.from_samples([((math.sin(t), 0.0, math.cos(t)), (1.0, 1.0, 1.0))])
    r_env = goniogeometric_index(blue_metallic, env, -20.0, direction="+")
    r_pt = goniogeometric_index(blue_metallic, light, -20.0, direction="+")
    assert r_env.beta_min_deg == pytest.approx(r_pt.beta_min_deg, abs=1e-4)
    assert r_env.geometry["light"] == "environment"


def test_environment_uniform_sky_solid_is_insensitive(grey):
    """A uniform sky lights a Lambertian panel by the visible sky fraction only: tilt matters little."""
    env = Environment.from_equirect(np.ones((8, 16, 3)))
    r = goniogeometric_index(grey, env, 0.0, beta_max_deg=10.0)
    assert not r.reached


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"epsilon": 0.0}, "epsilon"),
        ({"epsilon": float("nan")}, "epsilon"),
        ({"beta_max_deg": 95.0}, "beta_max_deg"),
        # below the index's resolution the grid spacing underflowed (a fuzzed request: 5e-324)
        ({"beta_max_deg": 5e-324}, "beta_max_deg"),
        ({"beta_max_deg": 0.9e-6}, "beta_max_deg"),
        ({"beta_max_deg": float("nan")}, "beta_max_deg"),
        ({"grid_step_deg": 1e-300}, "grid_step_deg"),
        ({"grid_step_deg": 2.0}, "grid_step_deg"),
        ({"method": "cmc"}, "method"),
        ({"hinge": "diagonal"}, "hinge"),
        ({"direction": "up"}, "direction"),
    ],
)
def test_bad_input_names_the_field(grey, kwargs, field):
    with pytest.raises(AnalysisInputError) as exc:
        goniogeometric_index(grey, 45.0, 0.0, **kwargs)
    assert exc.value.field == field
    assert isinstance(exc.value, InputError)


def test_smallest_beta_max_is_searched_without_a_warning(grey):
    """β_max at the index's resolution (the lower end of ``BETA_MAX_RANGE_DEG``): a plain answer, no
    floating-point warning (warnings are errors in this suite)."""
    from station.model.domain import BETA_MAX_RANGE_DEG

    r = goniogeometric_index(grey, 45.0, 0.0, beta_max_deg=BETA_MAX_RANGE_DEG[0])
    assert not r.reached and r.beta_max_deg == BETA_MAX_RANGE_DEG[0]


def test_light_at_grazing_limit_is_refused(grey):
    with pytest.raises(AnalysisInputError) as exc:
        goniogeometric_index(grey, 90.0, 0.0)
    assert exc.value.field.startswith("light_deg")


def test_gloss_included_near_specular_lowers_the_index():
    """Optional gloss (excluded in the thesis): near the specular direction the highlight moves with β."""
    p = FaceFlopTravelGloss((50.0, 0.0, -10.0), (20.0, 0.0, -8.0), 60.0, gloss_gu=40.0)
    without = goniogeometric_index(p, 45.0, -40.0, direction="+")
    with_gloss = goniogeometric_index(p, 45.0, -40.0, direction="+", gloss=True)
    assert with_gloss.beta_min_deg is not None and without.beta_min_deg is not None
    assert with_gloss.reached and with_gloss.beta_min_deg < without.beta_min_deg
    far = goniogeometric_index(p, 45.0, 60.0, direction="+", gloss=True)
    far_no = goniogeometric_index(p, 45.0, 60.0, direction="+")
    assert far.reached == far_no.reached
    if far.reached:
        assert far.beta_min_deg == pytest.approx(far_no.beta_min_deg, abs=1e-3)


def test_din6175_weighs_each_geometry_by_its_aspecular_angle(blue_metallic):
    # light +45°, views −30° and 0°: in-plane aspecular angles 45 − 30 = 15° and 45° (view + light)
    m = SeamModel([45.0, 45.0], [-30.0, 0.0], method="din6175")
    betas = np.array([1.0, 3.0])
    de = m.delta_e(blue_metallic, blue_metallic, betas)
    ca = np.broadcast_to(m.reference(blue_metallic), (2, 2, 3))
    cb = m.colour(blue_metallic, rotated_normals(betas, "in-plane"))
    expected = np.stack(
        [delta_e(ca[i], cb[i], "din6175", aspecular_deg=a) for i, a in enumerate((15.0, 45.0))]
    )
    np.testing.assert_allclose(de, expected, rtol=1e-12)


def test_din6175_refuses_environment_lighting():
    env = Environment.from_samples([((0.0, 0.5, 1.0), (1.0, 1.0, 1.0))])
    with pytest.raises(AnalysisInputError, match="method"):
        SeamModel(env, [0.0], method="din6175")
