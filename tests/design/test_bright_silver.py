"""The bright silver (L*15 = 125) through every designer operation, the variations and the tweaker.

Expectations are computed by hand from the documented edits: HSB rotates (a*, b*) by the hue angle,
scales them by the saturation and adds the brightness to L*; a lighter/darker variation moves L* by
the degree; a tweaker lightness step at a face pixel (R = 1, eq 3.6.4) adds ΔL to the face only.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from station.design.designer import (
    data_points,
    hsb_edit,
    hsb_edit_points,
    move_arrow,
    move_face,
    move_flop,
    move_point,
    set_gloss,
    set_travel,
)
from station.design.errors import DesignInputError
from station.design.tweaker import adjust_at, drag_travel
from station.design.variations import variations
from station.model import FaceFlopTravelGloss, ModelInputError


def _pixel_at(scene, theta: float) -> tuple[int, int]:
    cost = np.where(scene.mask & (scene.lambert > 0.1), np.abs(scene.aspecular_deg - theta), np.inf)
    y, x = np.unravel_index(np.argmin(cost), cost.shape)
    return int(x), int(y)


def _hsb(lab, hue: float, sat: float, bright: float) -> tuple[float, float, float]:
    h = math.radians(hue)
    L, a, b = lab
    return (L + bright, sat * (a * math.cos(h) - b * math.sin(h)), sat * (a * math.sin(h) + b * math.cos(h)))


def test_hsb_edit(bright_silver: FaceFlopTravelGloss) -> None:
    d = hsb_edit(bright_silver, hue_deg=30.0, saturation=1.5, brightness=10.0)
    assert d.face == pytest.approx(_hsb(bright_silver.face, 30.0, 1.5, 10.0), abs=1e-12)
    assert d.flop == pytest.approx(_hsb(bright_silver.flop, 30.0, 1.5, 10.0), abs=1e-12)
    assert d.face[0] == pytest.approx(135.0) and d.travel_deg == 65.0
    darker = hsb_edit(bright_silver, brightness=-20.0)
    assert darker.face[0] == pytest.approx(105.0) and darker.flop[0] == pytest.approx(18.0)


def test_hsb_on_points_and_point_edit(bright_silver: FaceFlopTravelGloss) -> None:
    pts = data_points(bright_silver)
    edit = hsb_edit_points(pts, brightness=5.0)
    np.testing.assert_allclose(edit.points.as_array()[:, 0], pts.as_array()[:, 0] + 5.0, atol=1e-12)
    assert edit.design.face[0] == pytest.approx(130.0, abs=1e-6)  # a uniform shift refits exactly
    moved = move_point(pts, "L", 15.0, 132.0)
    assert moved.points.lab[0][0] == 132.0 and moved.design.face[0] > 125.0


def test_face_and_flop_edits(bright_silver: FaceFlopTravelGloss) -> None:
    assert move_face(bright_silver, 1.0, -2.0, L=130.0).face == (130.0, 1.0, -2.0)
    assert move_face(bright_silver, 1.0, -2.0).face == (125.0, 1.0, -2.0)
    assert move_flop(bright_silver, 0.5, -4.0, L=40.0).flop == (40.0, 0.5, -4.0)
    arrow = move_arrow(bright_silver, 2.0, 3.0)
    assert arrow.face == pytest.approx((125.0, 1.4, 1.2)) and arrow.flop == pytest.approx((38.0, 1.7, -0.2))
    assert set_travel(bright_silver, 80.0).travel_deg == 80.0
    assert set_gloss(bright_silver, 95.0).gloss_gu == 95.0


def test_variations_lighter_and_darker(bright_silver: FaceFlopTravelGloss) -> None:
    ring = {v.label: v for v in variations(bright_silver, 5.0, "face").variations}
    assert ring["lighter"].design is not None
    assert ring["lighter"].design.face == pytest.approx((130.0, -0.6, -1.8))
    assert ring["darker"].design is not None
    assert ring["darker"].design.face == pytest.approx((120.0, -0.6, -1.8))
    assert ring["lighter"].design.flop == bright_silver.flop
    flop = {v.label: v for v in variations(bright_silver, 5.0, "flop").variations}
    assert flop["lighter"].design is not None
    assert flop["lighter"].design.flop[0] == pytest.approx(43.0)
    assert flop["darker"].design is not None
    assert flop["darker"].design.flop[0] == pytest.approx(33.0)
    # more chroma along the hue: C* grows by 5 at the same hue angle
    c = math.hypot(*bright_silver.face[1:])
    assert ring["more chroma"].design is not None
    more = ring["more chroma"].design.face
    assert math.hypot(*more[1:]) == pytest.approx(c + 5.0)
    tg = {v.label: v for v in variations(bright_silver, 5.0, "travel-gloss").variations}
    assert tg["more gloss"].design is not None
    assert tg["more travel"].design is not None
    assert tg["more travel"].design.travel_deg == 70.0 and tg["more gloss"].design.gloss_gu == 95.0


def test_tweaker_buttons(bright_silver: FaceFlopTravelGloss, sphere) -> None:
    face_px = _pixel_at(sphere, 10.0)
    t = adjust_at(bright_silver, sphere.aspecular_deg, face_px, "L", 5.0, sphere.mask)
    assert t.ratio == 1.0 and t.design.face == pytest.approx((130.0, -0.6, -1.8))
    assert t.design.flop == bright_silver.flop
    t = adjust_at(bright_silver, sphere.aspecular_deg, face_px, "L", -5.0, sphere.mask)
    assert t.design.face[0] == pytest.approx(120.0)
    chroma = adjust_at(bright_silver, sphere.aspecular_deg, face_px, "C", 0.5, sphere.mask)
    assert chroma.design.face == pytest.approx((125.0, -0.9, -2.7))
    hue = adjust_at(bright_silver, sphere.aspecular_deg, face_px, "H", 90.0, sphere.mask)
    assert hue.design.face == pytest.approx((125.0, 1.8, -0.6), abs=1e-12)
    flop_px = _pixel_at(sphere, 100.0)
    t = adjust_at(bright_silver, sphere.aspecular_deg, flop_px, "L", 2.0, sphere.mask)
    assert t.ratio == 0.0 and t.design.flop[0] == pytest.approx(40.0) and t.design.face == bright_silver.face
    travel_px = _pixel_at(sphere, 70.0)
    assert drag_travel(
        bright_silver, sphere.aspecular_deg, travel_px, sphere.mask
    ).travel_deg == pytest.approx(sphere.aspecular_deg[travel_px[1], travel_px[0]])


def test_out_of_range_is_the_model_s_error(bright_silver: FaceFlopTravelGloss, sphere) -> None:
    with pytest.raises(ModelInputError) as model_err:
        bright_silver.replace(face=(250.0, 0.0, 0.0))
    with pytest.raises(DesignInputError) as err:
        move_face(bright_silver, 0.0, 0.0, L=250.0)
    assert (err.value.field, err.value.accepted) == (model_err.value.field, model_err.value.accepted)
    assert str(err.value) == str(model_err.value) == "face.L: expected 0 <= L* <= 200, got 250.0"
    with pytest.raises(DesignInputError, match=r"face\.L: expected 0 <= L\* <= 200"):
        hsb_edit(bright_silver, brightness=125.0)
    with pytest.raises(DesignInputError) as err:
        adjust_at(bright_silver, sphere.aspecular_deg, _pixel_at(sphere, 10.0), "L", 125.0, sphere.mask)
    assert err.value.field == "delta" and "0 <= L* <= 200" in str(err.value)
    ring = {v.label: v for v in variations(bright_silver, 50.0, "face").variations}
    assert ring["lighter"].design is not None  # 175 is inside the bound
    edge = FaceFlopTravelGloss((180.0, -0.6, -1.8), (38.0, -0.3, -3.2), 65.0, 90.0)
    ring = {v.label: v for v in variations(edge, 25.0, "face").variations}
    assert ring["lighter"].design is None and "outside 0 <= L* <= 200" in ring["lighter"].reason
