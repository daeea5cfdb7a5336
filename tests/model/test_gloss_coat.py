"""The two-lobe clear coat (peak + haze) the gloss meter reads, against independent integrations.

Expectations: a Monte Carlo meter (uniform source points, Phong-sampled reflections of each lobe drawn
by its weight, receptor hit test), the hand forms of haze and DOI (cos^n 1.9° = 1/2 by construction of the
haze lobe), and the published figures the coat is built on (DOI 0.9 of a mirror, ASTM D4039 haze).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from station.model.errors import ModelInputError
from station.model.gloss import (
    CLEAR_COAT_INDEX,
    HAZE_EXPONENT,
    HAZE_OMEGA_SR,
    PEAK_EXPONENT,
    STANDARD_INDEX,
    CoatLobes,
    coat_from_gloss,
    coat_from_lobe,
    coat_meter_gloss,
    coat_readings,
    fresnel_unpolarised,
    lobe_from_gloss,
    simulate_gloss_meter,
)
from tests.model.test_gloss import monte_carlo_meter_phong


def monte_carlo_coat(coat: CoatLobes, geometry: int) -> float:
    """Brute-force meter of a lobe mixture: the meter is linear in the lobes, so each lobe's receptor share
    is drawn by the Monte Carlo meter of test_gloss.py (uniform source points, Phong-sampled rays, hit
    test) and the shares are weighted, times the coat's Fresnel ratio to the black glass."""
    rel = coat.albedo_at(geometry) / fresnel_unpolarised(geometry, STANDARD_INDEX)
    return rel * sum(w * monte_carlo_meter_phong(n, geometry) for w, n in coat.lobes if w > 0.0)


@pytest.mark.parametrize("geometry", [20, 60, 85])
@pytest.mark.parametrize("gloss", [50.0, 80.0, 88.0, 95.0])
def test_coat_readings_match_monte_carlo(gloss: float, geometry: int) -> None:
    coat = coat_from_gloss(gloss)
    # 400k rays per lobe: binomial standard error <= 0.08 GU
    assert coat_meter_gloss(coat, geometry) == pytest.approx(monte_carlo_coat(coat, geometry), abs=0.4)


def test_an_88_gu_coat_reads_like_a_clear_coat() -> None:
    """The issue's coat: one lobe read 34 GU at 20° and DOI 2.3; the clear coat reads ~78/88/97, DOI 90."""
    r = coat_readings(coat_from_gloss(88.0))
    assert r.g60_gu == pytest.approx(88.0, abs=1e-6)
    assert r.g20_gu == pytest.approx(77.8, abs=0.5) and r.g85_gu == pytest.approx(96.9, abs=0.5)
    assert r.doi == pytest.approx(90.0, abs=0.5)
    # ASTM D4039: H = G60 − G20; a mirror of index 1.50 already reads H from Fresnel alone
    mirror = {
        g: 100 * fresnel_unpolarised(g, CLEAR_COAT_INDEX) / fresnel_unpolarised(g, STANDARD_INDEX)
        for g in (20, 60)
    }
    assert 0.0 <= r.d4039_haze_gu - (mirror[60] - mirror[20]) <= 5.0
    assert r.g85_gu >= r.g60_gu
    one = lobe_from_gloss(88.0)  # the render lobe alone: what the meter read before
    assert simulate_gloss_meter(one, 20) < 40.0 < r.g20_gu


def test_haze_doi_and_rspec_by_hand() -> None:
    coat = coat_from_gloss(85.0)
    r = coat_readings(coat)
    (wp, n_p), (wh, n_h) = coat.lobes
    rel20 = fresnel_unpolarised(20, CLEAR_COAT_INDEX) / fresnel_unpolarised(20, STANDARD_INDEX)
    # cos^n_h(1.9°) = 1/2 (the haze lobe's half maximum); the peak is 0 there to 1e-100
    assert r.haze_hu == pytest.approx(100 * rel20 * HAZE_OMEGA_SR * wh * (n_h + 1) / (4 * math.pi), rel=1e-9)
    assert r.log_haze == pytest.approx(1285 * math.log10(r.haze_hu / 20 + 1), rel=1e-12)
    c = math.cos(math.radians(0.3))
    p0, p03 = wp * (n_p + 1) + wh * (n_h + 1), wp * (n_p + 1) * c**n_p + wh * (n_h + 1) * c**n_h
    assert r.doi == pytest.approx(100 * (1 - p03 / p0), rel=1e-9)
    cr = math.cos(math.radians(0.0991))
    rspec = 100 * rel20 * (wp * (1 - cr ** (n_p + 1)) + wh * (1 - cr ** (n_h + 1)))
    assert r.rspec_gu == pytest.approx(rspec, rel=1e-6)
    # a lone peak reads DOI 90 (luxury top coats, 0.9 of a mirror); the haze lobe is half max at 1.9°
    assert 100 * (1 - c**PEAK_EXPONENT) == pytest.approx(90.0, abs=1e-9)
    assert math.cos(math.radians(1.9)) ** HAZE_EXPONENT == pytest.approx(0.5, abs=1e-12)


def test_sixty_degree_reading_is_the_design_gloss_and_rises_continuously() -> None:
    grid = np.concatenate([np.linspace(0.0, 100.0, 201), [73.2, 73.3, 73.4, 89.1, 89.14, 89.2]])
    grid.sort()
    g60 = [coat_meter_gloss(coat_from_gloss(float(g)), 60) for g in grid]
    assert np.allclose(g60[:-1], grid[:-1], atol=1e-6) and g60[-1] == pytest.approx(100.0, abs=0.05)
    readings = [coat_readings(coat_from_gloss(float(g))) for g in grid]
    for geometry in (20, 85):
        vals = np.array([x.gloss_gu(geometry) for x in readings])
        assert np.all(np.diff(vals) > -1e-9)  # 20° and 85° rise with the 60° gloss
    # continuous across the regime boundaries (haze-free | peak + haze | one lobe)
    for edge in (
        coat_meter_gloss(CoatLobes(CLEAR_COAT_INDEX, 0.0, HAZE_EXPONENT), 60),
        coat_meter_gloss(CoatLobes(CLEAR_COAT_INDEX, 1.0, HAZE_EXPONENT), 60),
    ):
        lo, hi = coat_readings(coat_from_gloss(edge - 1e-7)), coat_readings(coat_from_gloss(edge + 1e-7))
        assert lo.g20_gu == pytest.approx(hi.g20_gu, abs=1e-4) and lo.doi == pytest.approx(hi.doi, abs=1e-3)


def test_one_lobe_coat_reads_what_the_lobe_reads() -> None:
    for gu in (0.05, 30.0, 88.0):
        lobe = lobe_from_gloss(gu)
        coat = coat_from_lobe(lobe)
        for g in (20, 60, 85):
            assert coat_meter_gloss(coat, g) == pytest.approx(simulate_gloss_meter(lobe, g), abs=1e-9)


@pytest.mark.parametrize("bad", [-1, 101, float("nan"), "x"])
def test_bad_gloss(bad) -> None:
    with pytest.raises(ModelInputError, match="gloss_gu"):
        coat_from_gloss(bad)


@pytest.mark.parametrize(
    ("field", "kw"), [("haze_weight", {"haze_weight": 1.5}), ("coat_index", {"coat_index": 3.0})]
)
def test_bad_coat(field: str, kw: dict) -> None:
    args = {"coat_index": 1.5, "haze_weight": 0.5, "haze_exponent": 100.0} | kw
    with pytest.raises(ModelInputError, match=field):
        CoatLobes(**args)
