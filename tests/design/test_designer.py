"""Designer operations (thesis §3.4): data-point editor, HSB group edit, picker, gloss."""

from __future__ import annotations

import dataclasses
import itertools
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

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
from station.model import ANGLES_3, FaceFlopTravelGloss


def test_data_points_sample_the_curve(red_metallic) -> None:
    pts = data_points(red_metallic)
    assert pts.angles_deg == (15.0, 25.0, 45.0, 75.0, 110.0)
    assert pts.lab[0] == pytest.approx(red_metallic.face)
    assert pts.lab[-1] == pytest.approx(red_metallic.flop)  # 110° is beyond θ_clamp = 70°


def test_moving_a_point_refits_live_and_passes_through_three_points(red_metallic) -> None:
    pts = data_points(red_metallic, ANGLES_3)
    edit = move_point(pts, "L", 45.0, 35.0)
    assert edit.points.lab[1][0] == 35.0
    assert edit.points.lab[0] == pts.lab[0]  # the other points did not move
    # three angles: L passes exactly through the points (closed form, eq 3.3.8–3.3.10)
    assert edit.design.lab_at(np.array(ANGLES_3))[:, 0] == pytest.approx(
        [p[0] for p in edit.points.lab], abs=1e-6
    )
    assert edit.design.face[0] == pytest.approx(60.0, abs=1e-6)
    assert len(edit.fit.residual_de) == 3
    assert pts.lab[1][0] != 35.0  # immutable input


def test_moving_a_point_on_a_and_b_refits(red_metallic) -> None:
    pts = data_points(red_metallic)
    edit = move_point(pts, "b", 15.0, 25.0)
    # five points: a least-squares refit pulls the face towards the moved point ...
    assert 10.0 < edit.design.face[2] < 25.0
    # ... and fits the moved points better than the unedited design does
    moved = edit.points.as_array()
    old_sse = np.sum((red_metallic.lab_at(np.array(pts.angles_deg)) - moved) ** 2)
    new_sse = np.sum(np.square(edit.fit.residual_de))
    assert new_sse < old_sse


@pytest.mark.parametrize(
    ("channel", "angle", "value", "field"),
    [
        ("X", 15.0, 1.0, "channel"),
        ("L", 30.0, 1.0, "angle_deg"),
        ("L", 15.0, 250.0, "value"),
        ("a", 15.0, 200.0, "value"),
        ("L", 15.0, float("nan"), "value"),
    ],
)
def test_move_point_rejects_bad_requests(red_metallic, channel, angle, value, field) -> None:
    with pytest.raises(DesignInputError) as err:
        move_point(data_points(red_metallic), channel, angle, value)
    assert err.value.field == field


def _pairwise(ab: np.ndarray) -> np.ndarray:
    return np.array([np.linalg.norm(p - q) for p, q in itertools.combinations(ab, 2)])


def test_hsb_group_edit_keeps_relative_spacing(red_metallic) -> None:
    pts = data_points(red_metallic)
    edit = hsb_edit_points(pts, hue_deg=40.0, saturation=1.5, brightness=-5.0)
    before, after = pts.as_array(), edit.points.as_array()
    assert _pairwise(after[:, 1:]) == pytest.approx(1.5 * _pairwise(before[:, 1:]), rel=1e-12)
    assert after[:, 0] == pytest.approx(before[:, 0] - 5.0)
    # hue angle of every point advanced by 40°
    h0 = np.degrees(np.arctan2(before[:, 2], before[:, 1]))
    h1 = np.degrees(np.arctan2(after[:, 2], after[:, 1]))
    assert (h1 - h0) % 360 == pytest.approx(np.full(5, 40.0))


def test_hsb_edit_of_a_design_equals_editing_every_point(red_metallic) -> None:
    new = hsb_edit(red_metallic, hue_deg=-75.0, saturation=0.6, brightness=8.0)
    angles = np.linspace(0, 150, 31)
    old = red_metallic.lab_at(angles)
    h = math.radians(-75.0)
    expect = np.stack(
        [
            old[:, 0] + 8.0,
            0.6 * (math.cos(h) * old[:, 1] - math.sin(h) * old[:, 2]),
            0.6 * (math.sin(h) * old[:, 1] + math.cos(h) * old[:, 2]),
        ],
        axis=1,
    )
    assert new.lab_at(angles) == pytest.approx(expect, abs=1e-9)
    assert new.travel_deg == red_metallic.travel_deg


def test_hsb_edit_refuses_out_of_range(red_metallic) -> None:
    with pytest.raises(DesignInputError, match=r"face\.L"):
        hsb_edit(red_metallic, brightness=150.0)
    with pytest.raises(DesignInputError, match="saturation"):
        hsb_edit(red_metallic, saturation=-1.0)


def test_picker_moves_face_flop_and_arrow(red_metallic: FaceFlopTravelGloss) -> None:
    d = move_face(red_metallic, 40.0, -5.0)
    assert d.face == (60.0, 40.0, -5.0) and d.flop == red_metallic.flop
    d = move_flop(red_metallic, 0.0, 0.0, L=20.0)
    assert d.flop == (20.0, 0.0, 0.0) and d.face == red_metallic.face
    d = move_arrow(red_metallic, 5.0, -3.0)
    assert np.subtract(d.face, red_metallic.face) == pytest.approx([0, 5, -3])
    assert np.subtract(d.flop, red_metallic.flop) == pytest.approx([0, 5, -3])
    assert set_travel(red_metallic, 100.0).travel_deg == 100.0
    assert set_gloss(red_metallic, 80.0).gloss_gu == 80.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        red_metallic.gloss_gu = 10.0  # type: ignore[misc]


def test_picker_on_a_solid_gains_and_loses_travel() -> None:
    solid = FaceFlopTravelGloss((50.0, 10.0, 10.0), (50.0, 10.0, 10.0), None, 40.0)
    moved = move_face(solid, 20.0, 10.0)
    assert moved.travel_deg == 75.0 and not moved.is_solid
    back = move_face(moved, 10.0, 10.0)
    assert back.is_solid and back.travel_deg is None
    with pytest.raises(DesignInputError, match="travel_deg"):
        set_travel(solid, 60.0)


@pytest.mark.parametrize(
    ("fn", "args", "field"),
    [
        (set_travel, (15.0,), "travel_deg"),
        (set_travel, (181.0,), "travel_deg"),
        (set_gloss, (101.0,), "gloss_gu"),
        (set_gloss, (-0.1,), "gloss_gu"),
        (move_face, (0.0, 0.0, 201.0), "face.L"),
        (move_flop, (151.0, 0.0), "flop.a"),
        (move_arrow, (float("inf"), 0.0), "da"),
    ],
)
def test_picker_and_gloss_reject_out_of_range(red_metallic, fn, args, field) -> None:
    with pytest.raises(DesignInputError) as err:
        fn(red_metallic, *args)
    assert err.value.field == field


@settings(max_examples=40, deadline=None)
@given(hue=st.floats(-180, 180), sat=st.floats(0.2, 1.8), bright=st.floats(-10, 10))
def test_hsb_edit_is_undone_by_its_inverse(hue, sat, bright) -> None:
    d = FaceFlopTravelGloss((60.0, 30.0, 10.0), (25.0, 20.0, 15.0), 70.0, 50.0)
    there = hsb_edit(d, hue, sat, bright)
    back = hsb_edit(hsb_edit(there, -hue, 1.0, -bright), 0.0, 1.0 / sat, 0.0)
    assert back.face == pytest.approx(d.face, abs=1e-9) and back.flop == pytest.approx(d.flop, abs=1e-9)
