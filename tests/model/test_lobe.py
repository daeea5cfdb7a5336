"""The one gloss → lobe mapping (station.model.lobe) against the gloss meter it inverts."""

from __future__ import annotations

import math

import numpy as np
import pytest

from station.model.errors import ModelInputError
from station.model.gloss import (
    PHONG_MAX,
    STANDARD_INDEX,
    SpecularLobe,
    fresnel_unpolarised,
    gloss_from_lobe,
    lobe_from_gloss,
)
from station.model.lobe import lobe_brdf_cos, lobe_reflectance, phong_lobe


@pytest.mark.parametrize("gu", [5.0, 20.0, 37.5, 60.0, 88.0, 95.0])
def test_phong_lobe_agrees_with_the_meter_inverse(gu: float) -> None:
    ref = lobe_from_gloss(gu)  # Brent on the simulated meter, no table
    n, rho_s = phong_lobe(gu)
    assert float(n) == pytest.approx(ref.phong_exponent, rel=1e-4)
    assert float(rho_s) == pytest.approx(ref.specular_albedo, rel=1e-12)


def test_gloss_meter_round_trip_over_the_range() -> None:
    grid = np.concatenate([np.linspace(1.0, 99.0, 33), [0.3, 99.5, 99.9]])
    n, rho_s = phong_lobe(grid)
    assert n.shape == grid.shape
    readings = [gloss_from_lobe(SpecularLobe(float(a), float(b), 0.0)) for a, b in zip(n, rho_s, strict=True)]
    np.testing.assert_allclose(readings, grid, atol=2e-3)


def test_albedo_is_the_coats_fresnel_reflectance_and_the_ends() -> None:
    # F(60°; 1.567) by hand: rs, rp of a dielectric
    ti = math.radians(60.0)
    tt = math.asin(math.sin(ti) / 1.567)
    rs = ((math.cos(ti) - 1.567 * math.cos(tt)) / (math.cos(ti) + 1.567 * math.cos(tt))) ** 2
    rp = ((1.567 * math.cos(ti) - math.cos(tt)) / (1.567 * math.cos(ti) + math.cos(tt))) ** 2
    assert float(phong_lobe(60.0)[1]) == pytest.approx(0.5 * (rs + rp), rel=1e-12)
    assert float(phong_lobe(100.0)[0]) == PHONG_MAX
    assert tuple(map(float, phong_lobe(0.0))) == (1.0, 0.0)
    # below the widest lobe's reading the exponent stays 1 and the albedo dims linearly
    widest = gloss_from_lobe(SpecularLobe(1.0, fresnel_unpolarised(60.0, STANDARD_INDEX), 0.0))
    n, rho_s = phong_lobe(0.5 * widest)
    assert float(n) == 1.0
    assert float(rho_s) == pytest.approx(0.5 * fresnel_unpolarised(60.0, STANDARD_INDEX), rel=1e-9)


@pytest.mark.parametrize("bad", [-0.1, 100.5, float("nan"), "shiny"])
def test_bad_gloss_names_the_field_and_range(bad: object) -> None:
    with pytest.raises(ModelInputError, match=r"gloss_gu: expected 0 <= gloss_gu <= 100 GU"):
        phong_lobe(bad)  # type: ignore[arg-type]


def test_lobe_is_normalised_and_peaks_at_the_mirror() -> None:
    n, rho_s = 40.0, 0.1
    psi = np.linspace(0.0, np.pi / 2, 200001)
    flux = np.trapezoid(lobe_brdf_cos(n, rho_s, np.cos(psi)) * 2 * np.pi * np.sin(psi), psi)
    assert flux == pytest.approx(rho_s, rel=1e-6)  # ∫ (n+1)/(2π) cosⁿψ dω = 1
    assert lobe_brdf_cos(n, rho_s, -0.3) == 0.0
    g, r = (float(x) for x in phong_lobe(50.0))
    refl = lobe_reflectance(50.0, np.array([0.0, 10.0, 90.0, 120.0]))
    np.testing.assert_allclose(refl[:2], [r * (g + 1) / 2, r * (g + 1) / 2 * math.cos(math.radians(10)) ** g])
    assert refl[2] == pytest.approx(0.0, abs=1e-300) and refl[3] == 0.0
