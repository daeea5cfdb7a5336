"""Image-based BRDF tweaker (thesis §3.6, docs/design.md erratum 1)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from station.design.errors import DesignInputError
from station.design.tweaker import (
    adjust_at,
    drag_highlight_centre,
    drag_highlight_edge,
    drag_travel,
    gloss_from_edge,
    highlight_edge_deg,
    hit_test,
    ratio_r,
)
from station.model import FaceFlopTravelGloss


def _pixel_at(scene, theta: float) -> tuple[int, int]:
    """Lit foreground pixel whose aspecular angle is nearest *theta*."""
    cost = np.where(scene.mask & (scene.lambert > 0.1), np.abs(scene.aspecular_deg - theta), np.inf)
    y, x = np.unravel_index(np.argmin(cost), cost.shape)
    return int(x), int(y)


def test_ratio_follows_the_corrected_equation() -> None:
    r = ratio_r([0.0, 15.0, 30.0, 42.5, 70.0, 120.0], 70.0)
    assert r == pytest.approx([1.0, 1.0, 40 / 55, 0.5, 0.0, 0.0])


def test_face_region_adjustment_leaves_the_flop_alone(sphere, red_metallic) -> None:
    xy = _pixel_at(sphere, 12.0)
    t = adjust_at(red_metallic, sphere.aspecular_deg, xy, "L", 5.0, sphere.mask)
    assert t.ratio == 1.0 and t.theta_deg < 15.0
    assert t.design.face == pytest.approx((65.0, 30.0, 10.0)) and t.design.flop == red_metallic.flop


def test_flop_region_adjustment_leaves_the_face_alone(sphere, red_metallic) -> None:
    xy = _pixel_at(sphere, 100.0)
    t = adjust_at(red_metallic, sphere.aspecular_deg, xy, "C", 0.2, sphere.mask)
    assert t.ratio == 0.0
    assert t.design.face == red_metallic.face
    assert t.design.flop == pytest.approx((25.0, 24.0, 18.0))


def test_in_between_adjusts_both_by_the_ratio(sphere, red_metallic) -> None:
    xy = _pixel_at(sphere, 42.5)
    t = adjust_at(red_metallic, sphere.aspecular_deg, xy, "H", 30.0, sphere.mask)
    r = (70.0 - t.theta_deg) / 55.0
    assert t.ratio == pytest.approx(r)
    h = math.radians(30.0)

    def rot(lab):
        return np.array(
            [lab[0], lab[1] * math.cos(h) - lab[2] * math.sin(h), lab[1] * math.sin(h) + lab[2] * math.cos(h)]
        )

    face, flop = np.array(red_metallic.face), np.array(red_metallic.flop)
    assert t.design.face == pytest.approx((1 - r) * face + r * rot(face))  # eq 3.6.5
    assert t.design.flop == pytest.approx(r * flop + (1 - r) * rot(flop))  # eq 3.6.6


def test_solid_is_adjusted_fully(sphere) -> None:
    solid = FaceFlopTravelGloss((50.0, 10.0, 0.0), (50.0, 10.0, 0.0), None, 50.0)
    t = adjust_at(solid, sphere.aspecular_deg, _pixel_at(sphere, 80.0), "L", -10.0)
    assert t.design.face == t.design.flop == (40.0, 10.0, 0.0)


def test_adjust_rejects_bad_requests(sphere, red_metallic) -> None:
    with pytest.raises(DesignInputError, match="xy"):
        adjust_at(red_metallic, sphere.aspecular_deg, (0, 0), "L", 1.0, sphere.mask)  # background
    with pytest.raises(DesignInputError, match="xy"):
        adjust_at(red_metallic, sphere.aspecular_deg, (64, 3), "L", 1.0)
    with pytest.raises(DesignInputError, match="kind"):
        adjust_at(red_metallic, sphere.aspecular_deg, (32, 32), "S", 1.0)  # type: ignore[arg-type]  # the bad kind under test
    with pytest.raises(DesignInputError, match="delta"):
        adjust_at(red_metallic, sphere.aspecular_deg, (32, 32), "C", -1.5)
    with pytest.raises(DesignInputError, match="delta"):
        adjust_at(red_metallic, sphere.aspecular_deg, _pixel_at(sphere, 5.0), "L", 160.0)


def test_drag_travel_takes_the_angle_under_the_cursor(sphere, red_metallic) -> None:
    xy = _pixel_at(sphere, 95.0)
    d = drag_travel(red_metallic, sphere.aspecular_deg, xy, sphere.mask)
    assert d.travel_deg == sphere.aspecular_deg[xy[1], xy[0]]
    with pytest.raises(DesignInputError, match="xy"):
        drag_travel(red_metallic, sphere.aspecular_deg, _pixel_at(sphere, 5.0))


def test_highlight_edge_and_gloss_invert_each_other(sphere, red_metallic) -> None:
    edge = highlight_edge_deg(50.0)
    # the 50 GU lobe: cos^n(edge) = 1/2 by definition of the edge
    from station.model.lobe import phong_lobe

    assert math.cos(math.radians(edge)) ** float(phong_lobe(50.0)[0]) == pytest.approx(0.5)
    # gloss_from_edge reads the edge's lobe with the model's simulated meter (exact forward direction)
    assert gloss_from_edge(edge) == pytest.approx(50.0, abs=0.05)
    assert gloss_from_edge(highlight_edge_deg(90.0)) == pytest.approx(90.0, abs=0.05)
    assert highlight_edge_deg(10.0) > highlight_edge_deg(50.0) > highlight_edge_deg(90.0)
    xy = _pixel_at(sphere, 8.0)
    d = drag_highlight_edge(red_metallic, sphere.aspecular_deg, xy, sphere.mask)
    assert highlight_edge_deg(d.gloss_gu) == pytest.approx(sphere.aspecular_deg[xy[1], xy[0]], rel=2e-3)
    with pytest.raises(DesignInputError, match="theta_edge_deg"):
        gloss_from_edge(75.0)


def test_drag_highlight_centre_puts_the_highlight_under_the_cursor(sphere) -> None:
    xy = _pixel_at(sphere, 60.0)
    light = drag_highlight_centre(sphere.light_dirs, xy, sphere.mask)
    assert np.linalg.norm(light) == pytest.approx(1.0)
    moved = sphere.with_light(light)
    assert moved.aspecular_deg[xy[1], xy[0]] == pytest.approx(0.0, abs=1e-5)
    with pytest.raises(DesignInputError):
        drag_highlight_centre(sphere.light_dirs, (0, 0), sphere.mask)


def test_hit_test_classifies_clicks(red_metallic) -> None:
    edge = highlight_edge_deg(red_metallic.gloss_gu)
    assert hit_test(red_metallic, 0.1) == "highlight-centre"
    assert hit_test(red_metallic, edge + 1.0) == "highlight-edge"
    assert hit_test(red_metallic, 71.0) == "travel-ring"
    assert hit_test(red_metallic, 40.0) == "object"
