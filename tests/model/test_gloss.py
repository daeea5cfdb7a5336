"""Gloss ⇄ lobe mapping checked against an independent Monte Carlo gloss meter."""

from __future__ import annotations

import math

import numpy as np
import pytest

from station.model.errors import ModelInputError
from station.model.gloss import (
    APERTURES_DEG,
    STANDARD_INDEX,
    SpecularLobe,
    fresnel_unpolarised,
    lobe_from_gloss,
    max_gloss_gu,
    simulate_gloss_meter,
)


def monte_carlo_meter_phong(n: float, geometry: int, samples: int = 400_000, seed: int = 0) -> float:
    """Brute-force meter: uniform source points, Phong-sampled reflections, receptor hit test."""
    rng = np.random.default_rng(seed)
    su, sv, ru, rv = (math.radians(x) / 2 for x in APERTURES_DEG[geometry])
    th = math.radians(geometry)
    us = rng.uniform(-su, su, samples)
    vs = rng.uniform(-sv, sv, samples)
    # mirror direction of each source point
    r = np.stack([np.sin(th + us) * np.cos(vs), np.sin(vs), np.cos(th + us) * np.cos(vs)], axis=1)
    # sample the normalised Phong lobe about r: cos ψ = ξ^(1/(n+1))
    cos_psi = rng.random(samples) ** (1.0 / (n + 1.0))
    sin_psi = np.sqrt(1 - cos_psi**2)
    phi = rng.uniform(0, 2 * np.pi, samples)
    a = np.where(np.abs(r[:, [0]]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]])
    t1 = np.cross(r, a)
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    t2 = np.cross(r, t1)
    d = cos_psi[:, None] * r + sin_psi[:, None] * (np.cos(phi)[:, None] * t1 + np.sin(phi)[:, None] * t2)
    v = np.arcsin(np.clip(d[:, 1], -1, 1))
    u = np.arctan2(d[:, 0], d[:, 2]) - th
    hit = (np.abs(u) <= ru) & (np.abs(v) <= rv)
    return 100.0 * hit.mean()  # albedo = F(1.567) cancels against the standard


@pytest.mark.parametrize("gu", [1, 5, 20, 50, 80, 95, 100])
def test_round_trip_within_half_gu(gu: float) -> None:
    lobe = lobe_from_gloss(gu)
    assert simulate_gloss_meter(lobe, 60, "phong") == pytest.approx(gu, abs=0.5)
    assert simulate_gloss_meter(lobe, 60, "ward") == pytest.approx(gu, abs=0.5)


@pytest.mark.parametrize(("n", "geometry"), [(30.0, 60), (400.0, 60), (3000.0, 60), (400.0, 20), (400.0, 85)])
def test_meter_matches_monte_carlo(n: float, geometry: int) -> None:
    lobe = SpecularLobe(n, fresnel_unpolarised(60, STANDARD_INDEX), 0.05)
    mc = monte_carlo_meter_phong(n, geometry)
    # 400k samples: binomial standard error ≤ 0.08 GU
    assert simulate_gloss_meter(lobe, geometry) == pytest.approx(mc, abs=0.4)


def test_monotone_in_exponent() -> None:
    readings = [simulate_gloss_meter(SpecularLobe(n, 0.1, 0.1), 60) for n in (1, 10, 100, 1000, 10_000)]
    assert readings == sorted(readings)


def test_mirror_reads_100() -> None:
    assert simulate_gloss_meter(
        SpecularLobe(1e9, fresnel_unpolarised(60, STANDARD_INDEX), 1e-4)
    ) == pytest.approx(100.0, abs=1e-3)


def test_fresnel_black_glass() -> None:
    # n = 1.567 at 60°: rs = 0.1811, rp = 0.0193 by hand → F ≈ 0.1002
    assert fresnel_unpolarised(60.0, 1.567) == pytest.approx(0.10006, abs=2e-4)
    assert fresnel_unpolarised(0.0, 1.5) == pytest.approx(0.04, abs=1e-12)


def test_lower_coat_index_caps_gloss() -> None:
    top = max_gloss_gu(1.5)
    assert 85 < top < 95
    with pytest.raises(ModelInputError, match="gloss_gu"):
        lobe_from_gloss(top + 1, coat_index=1.5)


def test_energy_conserving() -> None:
    for gu in (1, 30, 90):
        lobe = lobe_from_gloss(gu)
        assert lobe.specular_albedo <= fresnel_unpolarised(60, STANDARD_INDEX) + 1e-12


def test_tiny_gloss_scales_albedo() -> None:
    lobe = lobe_from_gloss(0.05)
    assert lobe.phong_exponent == 1.0
    assert simulate_gloss_meter(lobe) == pytest.approx(0.05, abs=1e-6)


@pytest.mark.parametrize("bad", [-1, 101, float("nan"), "x"])
def test_bad_gloss(bad) -> None:
    with pytest.raises(ModelInputError, match="gloss_gu"):
        lobe_from_gloss(bad)


def test_bad_geometry() -> None:
    with pytest.raises(ModelInputError, match="geometry_deg"):
        simulate_gloss_meter(lobe_from_gloss(50), 45)


@pytest.mark.parametrize("alpha", [0.005, 0.03, 0.2, 0.6])
def test_thinned_ward_rule_matches_full(alpha: float) -> None:
    from station.model.gloss import _ward_fraction

    full = _ward_fraction(alpha, 60, n_rad=64, phi_step=1)
    assert 100 * _ward_fraction(alpha, 60) == pytest.approx(
        100 * full, abs=0.01
    )  # in GU per unit albedo ratio
