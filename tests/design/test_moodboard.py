"""Mood board (thesis §3.5): boards, face/flop eyedroppers, gloss eyedropper and its limits."""

from __future__ import annotations

import numpy as np
import pytest

from station.design.errors import DesignInputError
from station.design.moodboard import (
    Board,
    BoardImage,
    ContrastGloss,
    GlossBlend,
    MoodBoard,
    contrast_gloss,
    eyedrop_design,
    eyedrop_lab,
    region,
)
from station.model.colorimetry import lab_to_linear_srgb, srgb_encode


def _patch_image(face_lab, flop_lab, size=40) -> np.ndarray:
    """Left half the face colour, right half the flop colour (sRGB-encoded floats, unquantised)."""
    img = np.zeros((size, size, 3))
    img[:, : size // 2] = srgb_encode(lab_to_linear_srgb(face_lab))
    img[:, size // 2 :] = srgb_encode(lab_to_linear_srgb(flop_lab))
    return img


def test_boards_round_trip_through_json(tmp_path) -> None:
    board = Board("Hydrogen Blue").add(BoardImage("a.png", 10, 20, 1.5)).add(BoardImage("b.jpg"))
    board = board.move(1, 300.0, 40.0).zoom(0, 2.0)
    mb = MoodBoard((board, Board("Orange Ball of Paris")))
    mb.save(tmp_path / "mb.json")
    back = MoodBoard.load(tmp_path / "mb.json")
    assert back == mb
    assert back.board("Hydrogen Blue").images[1] == BoardImage("b.jpg", 300.0, 40.0, 1.0)
    assert (
        back.with_board(Board("Orange Ball of Paris", (BoardImage("c.png"),)))
        .board("Orange Ball of Paris")
        .images[0]
        .path
        == "c.png"
    )


def test_board_validation() -> None:
    with pytest.raises(DesignInputError, match="unique"):
        MoodBoard((Board("x"), Board("x")))
    with pytest.raises(DesignInputError, match="zoom"):
        BoardImage("a.png", zoom=0.0)
    with pytest.raises(DesignInputError, match="index"):
        Board("x").move(0, 1, 1)
    with pytest.raises(DesignInputError, match="schema"):
        MoodBoard.from_dict({"boards": []})
    with pytest.raises(DesignInputError, match="moodboard"):
        MoodBoard.from_json("{not json")


def test_eyedropper_reads_lab_of_a_patch() -> None:
    img = _patch_image((60.0, 25.0, 10.0), (30.0, 10.0, 20.0))
    assert eyedrop_lab(img, (5, 5), 3) == pytest.approx([60.0, 25.0, 10.0], abs=1e-6)
    assert eyedrop_lab(img, (35, 30), 0) == pytest.approx([30.0, 10.0, 20.0], abs=1e-6)
    assert region(img, (0, 0), 2).shape == (6, 3)  # x, y >= 0 with x² + y² <= 4: six pixels
    assert region(img, (20, 20), 1).shape == (5, 3)


def test_eyedropper_is_robust_to_outlier_pixels() -> None:
    img = _patch_image((60.0, 25.0, 10.0), (30.0, 10.0, 20.0))
    dirty = img.copy()
    dirty[4, 4] = [1.0, 1.0, 1.0]
    dirty[6, 6] = [0.0, 0.0, 0.0]  # two specks inside a 3-px disc of 29 pixels
    assert eyedrop_lab(dirty, (5, 5), 3) == pytest.approx(eyedrop_lab(img, (5, 5), 3), abs=1e-9)


def test_design_from_eyedroppers_with_auto_swap() -> None:
    img = _patch_image((60.0, 25.0, 10.0), (30.0, 10.0, 20.0))
    r = eyedrop_design(img, face_xy=(35, 20), flop_xy=(5, 20), travel_deg=60.0, gloss_gu=70.0)
    assert r.swapped
    assert r.design.face == pytest.approx((60.0, 25.0, 10.0), abs=1e-6)
    assert r.design.travel_deg == 60.0 and r.design.gloss_gu == 70.0
    retro = eyedrop_design(img, face_xy=(35, 20), flop_xy=(5, 20), auto_swap=False)
    assert not retro.swapped and retro.design.face[0] == pytest.approx(30.0, abs=1e-6)
    solid = eyedrop_design(img, (3, 3), (5, 5))
    assert solid.design.is_solid and solid.design.travel_deg is None


def test_eyedropper_rejects_bad_input() -> None:
    img = _patch_image((60.0, 25.0, 10.0), (30.0, 10.0, 20.0))
    with pytest.raises(DesignInputError, match="xy"):
        eyedrop_lab(img, (40, 0))
    with pytest.raises(DesignInputError, match="radius"):
        eyedrop_lab(img, (1, 1), 100)
    with pytest.raises(DesignInputError, match="image"):
        eyedrop_lab(img * 2.0, (1, 1))
    with pytest.raises(DesignInputError, match="travel_deg"):
        eyedrop_design(img, (5, 5), (35, 5), travel_deg=10.0)


def _grey(values) -> np.ndarray:
    v = np.asarray(values, dtype=float)
    return np.repeat(v[:, None], 3, axis=1)


def test_contrast_gloss_rule() -> None:
    # 90 pixels at 0.2, 10 at 0.6: top-10 % mean 0.6, bottom-10 % mean 0.2 → contrast 0.4 → 80 GU
    g = contrast_gloss(_grey([0.2] * 90 + [0.6] * 10))
    assert g.contrast == pytest.approx(0.4) and g.gloss_gu == pytest.approx(80.0) and not g.clipped
    # contrast 0.8 is above the 0.5 full scale: 100 GU, and the clip is reported
    g = contrast_gloss(_grey([0.1] * 50 + [0.9] * 50))
    assert g.gloss_gu == 100.0 and g.clipped and g.contrast == pytest.approx(0.8)
    # linear in between: contrast 0.1 → 20 GU
    assert contrast_gloss(_grey([0.5] * 50 + [0.6] * 50)).gloss_gu == pytest.approx(20.0)


def test_contrast_gloss_limits_texture_shadow_and_uniform_regions() -> None:
    """The documented limits: texture and shadow edges read as gloss; a uniform mirror reads 0."""
    yy, xx = np.mgrid[0:21, 0:21]
    weave = _grey((((xx // 2 + yy // 2) % 2) * 0.6 + 0.2).ravel())  # matt black-and-white texture
    assert contrast_gloss(weave).gloss_gu == 100.0
    shadow = _grey(np.where(xx < 10, 0.15, 0.55).ravel())  # a matt wall across a shadow boundary
    assert contrast_gloss(shadow).gloss_gu == pytest.approx(80.0)
    assert contrast_gloss(_grey([0.7] * 100)).gloss_gu == 0.0  # uniform: no cue at all


def test_gloss_blend_over_samples() -> None:
    b = GlossBlend(weight=0.5).update(80.0).update(40.0).update(ContrastGloss(40.0, 0.2, False, 9))
    assert b.gloss_gu == pytest.approx(50.0) and b.samples == 3
    with pytest.raises(DesignInputError, match="weight"):
        GlossBlend(weight=0.0)
    with pytest.raises(DesignInputError, match="sample"):
        GlossBlend().update(120.0)


def test_gloss_eyedropper_in_eyedrop_design() -> None:
    img = _patch_image((60.0, 25.0, 10.0), (30.0, 10.0, 20.0))
    img[18:23, 18:23] = 1.0  # a highlight on the boundary
    r = eyedrop_design(img, (5, 5), (35, 5), gloss_xy=(20, 20), radius=4)
    assert r.gloss is not None and r.design.gloss_gu == r.gloss.gloss_gu > 50.0
