"""The simulated meter against clear coats: a mirror reads its Fresnel ratio; one lobe vs two."""

from __future__ import annotations

import math

import pytest

from station.model.gloss import STANDARD_INDEX, fresnel_unpolarised
from station.reproduce import gloss


def test_a_mirror_coat_reads_its_fresnel_ratio_at_every_geometry() -> None:
    n = 1.50
    r = gloss.coat_readings(((1.0, 1.0e8),), fresnel_unpolarised(60.0, n), n)
    for g in (20, 60, 85):
        assert r[f"g{g}"] == pytest.approx(
            100 * fresnel_unpolarised(g, n) / fresnel_unpolarised(g, STANDARD_INDEX), rel=1e-4
        )
    assert r["doi"] == pytest.approx(100.0 * (1 - math.cos(math.radians(0.3)) ** 1.0e8), abs=1e-6)


def test_two_lobe_coat_reads_88_at_60_and_doi_90() -> None:
    mix = gloss.two_lobe_coat()
    assert sum(w for w, _ in mix) == pytest.approx(1.0)
    r = gloss.coat_readings(mix, fresnel_unpolarised(60.0, gloss.CLEAR_COAT_INDEX), gloss.CLEAR_COAT_INDEX)
    assert r["g60"] == pytest.approx(88.0, abs=1e-6)
    # DOI of the mixture by hand: the haze lobe adds to p(0.3°) and p(0°)
    (ws, ns), (wh, nh) = mix
    c = math.cos(math.radians(0.3))
    p0 = ws * (ns + 1) + wh * (nh + 1)
    p03 = ws * (ns + 1) * c**ns + wh * (nh + 1) * c**nh
    assert r["doi"] == pytest.approx(100 * (1 - p03 / p0), rel=1e-9)
    assert abs(r["doi"] - 90.0) < 1.0


def test_one_lobe_differs_and_two_lobes_agree() -> None:
    res = gloss.meter_geometries(None)
    q = {x.quantity: x for x in res.quantities}
    assert q["one lobe: D4039 haze beyond the Fresnel floor"].verdict == "differs"
    assert q["one lobe: DOI"].ours < 10.0  # the 2.3
    assert q["two lobes: D4039 haze beyond the Fresnel floor"].verdict == "agrees"
    assert "two lobes" in q["one lobe: DOI"].reason
