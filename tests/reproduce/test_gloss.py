"""The simulated meter against clear coats: the product's coat agrees with published figures, the render
lobe alone does not."""

from __future__ import annotations

import math

import pytest

from station.model.gloss import (
    CLEAR_COAT_INDEX,
    STANDARD_INDEX,
    coat_from_gloss,
    coat_readings,
    fresnel_unpolarised,
)
from station.reproduce import gloss


def test_verdicts_and_numbers() -> None:
    res = gloss.meter_geometries(None)
    q = {x.quantity: x for x in res.quantities}
    # the render lobe alone: the 34 GU at 20° (D4039 haze ~47 beyond the floor) and DOI 2.3
    assert q["render lobe alone: D4039 haze beyond the Fresnel floor"].verdict == "differs"
    assert q["render lobe alone: D4039 haze beyond the Fresnel floor"].ours == pytest.approx(46.5, abs=1.0)
    assert q["render lobe alone: DOI"].ours == pytest.approx(2.3, abs=0.2)
    # the clear coat: Fresnel floor of index 1.50 by hand, 82.05 − 89.14 GU → 7.1 GU
    floor = 100 * (
        fresnel_unpolarised(60, CLEAR_COAT_INDEX) / fresnel_unpolarised(60, STANDARD_INDEX)
        - fresnel_unpolarised(20, CLEAR_COAT_INDEX) / fresnel_unpolarised(20, STANDARD_INDEX)
    )
    assert floor == pytest.approx(7.1, abs=0.05)
    d4039 = q["clear coat: D4039 haze beyond the Fresnel floor"]
    assert d4039.verdict == "agrees" and d4039.ours == pytest.approx(88.0 - 77.8 - floor, abs=0.5)
    doi = q["clear coat: DOI (peak and haze together)"]
    assert doi.verdict == "agrees" and doi.ours == pytest.approx(90.0, abs=0.5)
    haze = q["clear coat: E430 haze (high-quality surface)"]
    assert haze.verdict == "agrees" and 0.0 < haze.ours < 1.0
    assert q["clear coat: G85 ≥ G60 (grazing reads at least the 60° gloss)"].verdict == "agrees"
    assert "two-lobe coat" in q["render lobe alone: DOI"].reason


def test_the_experiment_reads_the_products_coat() -> None:
    """One coat model: the experiment's numbers are those of station.model.gloss.coat_readings."""
    r = coat_readings(coat_from_gloss(gloss.COAT_GU))
    res = gloss.meter_geometries(None)
    q = {x.quantity: x for x in res.quantities}
    assert q["clear coat: DOI (peak and haze together)"].ours == r.doi
    assert f"{r.g20_gu:.1f}/{r.g60_gu:.1f}/{r.g85_gu:.1f} GU" in res.notes
    assert math.isclose(r.g60_gu, 88.0, abs_tol=1e-6)
