"""Variations ring (thesis §3.4.4): step sizes checked against CIELAB's own definitions."""

from __future__ import annotations

import math

import numpy as np
import pytest

from station.design.errors import DesignInputError
from station.design.variations import COLOUR_RING, TRAVEL_GLOSS_RING, Variation, variations
from station.model import FaceFlopTravelGloss


def _delta_h(lab1, lab2) -> float:
    """ΔH*ab from its definition ΔH² = ΔE² − ΔL² − ΔC² (CIE 15)."""
    d = np.subtract(lab1, lab2)
    dc = math.hypot(*lab1[1:]) - math.hypot(*lab2[1:])
    return math.sqrt(max(float(d @ d) - d[0] ** 2 - dc**2, 0.0))


def _design(v: Variation) -> FaceFlopTravelGloss:
    """The design of a reachable cell."""
    assert v.design is not None, v.reason
    return v.design


def test_face_ring_steps_are_one_degree_each(red_metallic: FaceFlopTravelGloss) -> None:
    ring = variations(red_metallic, 4.0, "face")
    assert tuple(v.label for v in ring.variations) == COLOUR_RING
    by = {v.label: _design(v) for v in ring.variations}
    f = red_metallic.face
    assert by["lighter"].face[0] - f[0] == pytest.approx(4.0)
    assert by["darker"].face[0] - f[0] == pytest.approx(-4.0)
    c0 = math.hypot(*f[1:])
    assert math.hypot(*by["more chroma"].face[1:]) - c0 == pytest.approx(4.0)
    assert math.hypot(*by["less chroma"].face[1:]) - c0 == pytest.approx(-4.0)
    for label, sign in (("hue +", 1), ("hue -", -1)):
        new = by[label].face
        assert _delta_h(new, f) == pytest.approx(4.0, abs=1e-9)
        assert math.hypot(*new[1:]) == pytest.approx(c0)
        turn = math.atan2(new[2], new[1]) - math.atan2(f[2], f[1])
        assert math.copysign(1, turn) == sign
    for v in ring.variations:  # face category never touches the flop
        assert _design(v).flop == red_metallic.flop and _design(v).travel_deg == red_metallic.travel_deg


def test_flop_and_travel_gloss_rings(red_metallic: FaceFlopTravelGloss) -> None:
    flop = variations(red_metallic, 3.0, "flop")
    assert all(_design(v).face == red_metallic.face for v in flop.variations)
    assert flop.variations[0].design is not None
    assert flop.variations[0].design.flop[0] == pytest.approx(28.0)
    tg = variations(red_metallic, 10.0, "travel-gloss")
    assert tuple(v.label for v in tg.variations) == TRAVEL_GLOSS_RING
    assert [_design(v).travel_deg for v in tg.variations[:2]] == [80.0, 60.0]
    assert [_design(v).gloss_gu for v in tg.variations[2:]] == [60.0, 40.0]


def test_ring_is_deterministic(red_metallic: FaceFlopTravelGloss) -> None:
    assert variations(red_metallic, 2.5, "flop") == variations(red_metallic, 2.5, "flop")


def test_unreachable_variations_are_listed_with_the_reason() -> None:
    # Face L* 198 + 5 leaves the effect-paint bound 0 <= L* <= 200 of station.model.domain.
    d = FaceFlopTravelGloss((198.0, 1.0, 0.0), (60.0, 1.0, 0.0), 20.0, 95.0)
    ring = {v.label: v for v in variations(d, 5.0, "face").variations}
    assert ring["lighter"].design is None and "outside 0 <= L* <= 200" in ring["lighter"].reason
    assert ring["darker"].design is not None
    assert ring["darker"].design.face[0] == 193.0
    assert ring["less chroma"].design is None and "chroma" in ring["less chroma"].reason
    assert ring["hue +"].design is None and "impossible" in ring["hue +"].reason
    tg = {v.label: v for v in variations(d, 10.0, "travel-gloss").variations}
    assert tg["less travel"].design is None and tg["more gloss"].design is None
    assert tg["more travel"].design is not None
    assert tg["more travel"].design.travel_deg == 30.0


def test_achromatic_colour_has_no_hue_step_even_for_the_smallest_degree() -> None:
    """A grey's hue cannot turn: at the smallest positive degree (5e-324, where degree / 2 underflows to
    0; a fuzzed request once divided by its zero chroma) both hue steps are unreachable with a reason,
    and lighter/darker still step."""
    grey = FaceFlopTravelGloss((60.0, 0.0, 0.0), (30.0, 0.0, 0.0), 40.0, 50.0)
    for degree in (5e-324, 5.0):
        ring = {v.label: v for v in variations(grey, degree, "face").variations}
        for label in ("hue +", "hue -", "hue −"):
            if label in ring:
                assert ring[label].design is None and "no hue" in ring[label].reason
        assert sum("hue" in label for label in ring) == 2
        assert ring["lighter"].design is not None


def test_solid_varies_as_one_colour() -> None:
    solid = FaceFlopTravelGloss((50.0, 20.0, 0.0), (50.0, 20.0, 0.0), None, 50.0)
    ring = {v.label: v for v in variations(solid, 5.0, "flop").variations}
    assert ring["lighter"].design is not None
    assert ring["lighter"].design.is_solid and ring["lighter"].design.face[0] == 55.0
    assert variations(solid, 5.0, "travel-gloss").variations[0].design is None


@pytest.mark.parametrize(
    ("degree", "category", "field"),
    [
        (0.0, "face", "degree"),
        (51.0, "face", "degree"),
        (float("nan"), "face", "degree"),
        (1.0, "gloss", "category"),
    ],
)
def test_bad_requests_raise(red_metallic, degree, category, field) -> None:
    with pytest.raises(DesignInputError) as err:
        variations(red_metallic, degree, category)
    assert err.value.field == field
