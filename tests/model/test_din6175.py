"""DIN 6175-2 (as published in a public implementation) against hand calculations, its limiting
behaviours, CIEDE2000 with l:c against colour-science's textile weights, and the AUDI2000 slot.

The hand calculation :func:`_by_hand` is the formula of the issue written out with :mod:`math`, one
pair at a time, independent of the vectorised implementation.
"""

from __future__ import annotations

import itertools
import math

import colour
import numpy as np
import pytest

from station.model.difference import (
    DinFactors,
    FormulaUnavailableError,
    delta_e,
    delta_e_cie2000_lc,
    delta_e_din6175,
    din6175_summary,
    din6175_terms,
)
from station.model.errors import ModelInputError

FIVE = (15.0, 25.0, 45.0, 75.0, 110.0)


def _by_hand(ref, smp, alpha, g=(1.0, 1.0, 1.0, 1.0, 1.0)) -> tuple[float, float]:
    """(ΔE_eff, σ) of one pair at aspecular angle alpha, g = (g_L, g_C, g_H, g_a, g_b)."""
    g_l, g_c, g_h, g_a, g_b = g
    l1, a1, b1 = ref
    l2, a2, b2 = smp
    c1, c2 = math.sqrt(a1 * a1 + b1 * b1), math.sqrt(a2 * a2 + b2 * b2)
    lm, cm = math.sqrt(l1 * l2), math.sqrt(c1 * c2)
    s_l = 0.15 * math.sqrt(lm) + 31.5 / alpha
    s_c = max(0.7, 0.48 * math.sqrt(cm) - 0.35 * math.sqrt(lm) + 42 / alpha)
    s_h = max(0.7, 0.14 * math.sqrt(cm) - 0.20 * math.sqrt(lm) + 21 / alpha + 0.7)
    dl, da, db, dc = l2 - l1, a2 - a1, b2 - b1, c2 - c1
    dh2 = max(da * da + db * db - dc * dc, 0.0)
    de_ab = math.sqrt((dl / (g_l * s_l)) ** 2 + (da / (g_a * 0.7)) ** 2 + (db / (g_b * 0.7)) ** 2)
    de_ch = math.sqrt((dl / (g_l * s_l)) ** 2 + (dc / (g_c * s_c)) ** 2 + dh2 / (g_h * s_h) ** 2)
    c0 = 10 + 8 / (1 + math.exp(27 - lm))
    sigma = 1 / (1 + math.exp(cm - c0))
    return sigma * de_ab + (1 - sigma) * de_ch, sigma


NEAR_GREY = ((52.0, 0.6, -0.8), (53.1, 1.4, 0.3))  # C̄ ≈ 1: σ ≈ 1, the a*b* form
CHROMATIC = ((38.0, 24.0, -41.0), (36.5, 27.0, -38.5))  # C̄ ≈ 47: σ ≈ 0, the C*H* form
MID = ((20.0, 9.0, 5.0), (21.0, 10.0, 6.5))  # C̄ ≈ 11 near C₀ at dark L̄: a true blend


@pytest.mark.parametrize("pair", [NEAR_GREY, CHROMATIC, MID], ids=["near-grey", "chromatic", "blend"])
@pytest.mark.parametrize("alpha", FIVE)
def test_matches_the_hand_calculation_at_five_angles(pair, alpha) -> None:
    ref, smp = pair
    expected, sigma = _by_hand(ref, smp, alpha)
    assert delta_e_din6175(ref, smp, alpha) == pytest.approx(expected, rel=1e-12)
    assert din6175_terms(ref, smp, alpha).sigma == pytest.approx(sigma, rel=1e-12)


def test_the_three_pairs_exercise_both_blend_branches() -> None:
    assert _by_hand(*NEAR_GREY, 45.0)[1] > 0.9999
    assert _by_hand(*CHROMATIC, 45.0)[1] < 1e-10
    assert 0.05 < _by_hand(*MID, 45.0)[1] < 0.95


def test_worked_lightness_example() -> None:
    # L̄ = √(51.2 · 80) = 64, √L̄ = 8; α = 45°: S_L = 0.15·8 + 31.5/45 = 1.9. Achromatic, so both forms
    # are ΔL*/S_L = 28.8/1.9 whatever σ is.
    got = delta_e_din6175([51.2, 0, 0], [80.0, 0, 0], 45.0)
    assert got == pytest.approx(28.8 / 1.9, rel=1e-12)


def test_worked_chroma_example() -> None:
    # Same hue, C*₁ = 35, C*₂ = 68.6: C̄ = 49, √C̄ = 7; L̄ = 64, √L̄ = 8; α = 45°:
    # S_C = 0.48·7 − 0.35·8 + 42/45 = 1.49333…; ΔC* = 33.6, ΔH* = 0, Δa* = 20.16, Δb* = 26.88.
    # ΔE_ab,w = 33.6/0.7 = 48; ΔE_CH,w = 33.6/S_C = 22.5; C₀ = 10 + 8/(1 + e^(27−64)), σ = 1/(1 + e^(49−C₀)).
    c0 = 10 + 8 / (1 + math.exp(27 - 64))
    sigma = 1 / (1 + math.exp(49 - c0))
    got = delta_e_din6175([64.0, 21.0, 28.0], [64.0, 41.16, 54.88], 45.0)
    assert got == pytest.approx(sigma * 48.0 + (1 - sigma) * 22.5, rel=1e-12)
    assert 33.6 / (0.48 * 7 - 0.35 * 8 + 42 / 45) == pytest.approx(22.5)


def test_parametric_factors_divide_their_terms() -> None:
    g = (2.0, 1.5, 0.8, 1.2, 0.9)
    expected, _ = _by_hand(*MID, 25.0, g)
    got = delta_e_din6175(*MID, 25.0, DinFactors(*g))
    assert got == pytest.approx(expected, rel=1e-12)
    # a pure lightness difference scales with 1/g_L
    base = delta_e_din6175([40, 0, 0], [42, 0, 0], 45.0)
    assert delta_e_din6175([40, 0, 0], [42, 0, 0], 45.0, DinFactors(g_l=2.0)) == pytest.approx(base / 2)


def test_sigma_limits() -> None:
    grey = din6175_terms([60, 0, 0], [61, 0.5, 0.5], 45.0)
    assert grey.sigma == pytest.approx(1.0, abs=1e-4)  # C̄ = 0 ≪ C₀ ≥ 10
    assert grey.de_eff == pytest.approx(grey.de_ab_w, rel=1e-4)
    vivid = din6175_terms([50, 60, 20], [51, 62, 18], 45.0)
    assert vivid.sigma < 1e-15  # C̄ ≈ 64 ≫ C₀ ≤ 18
    assert vivid.de_eff == pytest.approx(vivid.de_ch_w, rel=1e-12)
    # σ falls monotonically with chroma at fixed lightness
    sig = [din6175_terms([50, c, 0], [50, c, 0], 45.0).sigma for c in (0, 5, 10, 15, 20, 30)]
    assert all(x > y for x, y in itertools.pairwise(sig))


def test_angle_dependence() -> None:
    # A lightness difference is weighed by S_L = 0.15√L̄ + 31.5/α: tolerated most near specular.
    ref, smp = [60, 0, 0], [62, 0, 0]
    per = delta_e(np.tile(ref, (5, 1)), np.tile(smp, (5, 1)), "din6175", aspecular_deg=FIVE)
    assert np.all(np.diff(per) > 0)
    # at large α the weights approach their α-free parts
    lm = math.sqrt(60 * 62)
    assert delta_e_din6175(ref, smp, 180.0) == pytest.approx(
        2 / (0.15 * math.sqrt(lm) + 31.5 / 180), rel=1e-12
    )
    # the sign of the aspecular angle does not matter (|α|, as the behind-gloss −15°)
    assert delta_e_din6175(*CHROMATIC, -15.0) == delta_e_din6175(*CHROMATIC, 15.0)


def test_symmetric_and_zero_for_identical() -> None:
    assert delta_e_din6175(*MID, 45.0) == pytest.approx(delta_e_din6175(MID[1], MID[0], 45.0), rel=1e-12)
    assert delta_e_din6175(MID[0], MID[0], 45.0) == 0.0


def test_summary_mde_and_maxde_with_its_angle() -> None:
    ref = [NEAR_GREY[0], CHROMATIC[0], MID[0], NEAR_GREY[0], CHROMATIC[0]]
    smp = [NEAR_GREY[1], CHROMATIC[1], MID[1], NEAR_GREY[1], CHROMATIC[1]]
    hand = [_by_hand(r, s, a)[0] for r, s, a in zip(ref, smp, FIVE, strict=True)]
    got = din6175_summary(ref, smp, FIVE)
    assert got.mde == pytest.approx(sum(hand) / 5, rel=1e-12)
    assert got.maxde == pytest.approx(max(hand), rel=1e-12)
    assert got.maxde_angle_deg == FIVE[hand.index(max(hand))]


@pytest.mark.parametrize(
    ("angles", "field"),
    [(None, "aspecular_deg"), (0.0, "aspecular_deg"), (np.nan, "aspecular_deg"), (200.0, "aspecular_deg")],
)
def test_bad_angles_are_typed_errors(angles, field) -> None:
    with pytest.raises(ModelInputError, match=field):
        delta_e([50, 0, 0], [51, 0, 0], "din6175", aspecular_deg=angles)


def test_bad_factors_name_the_factor() -> None:
    with pytest.raises(ModelInputError, match=r"din6175\.g_c"):
        DinFactors(g_c=0.0)
    with pytest.raises(ModelInputError, match=r"din6175\.g_l"):
        DinFactors(g_l=math.inf)


def test_audi2000_refuses_until_its_coefficients_are_supplied() -> None:
    with pytest.raises(FormulaUnavailableError, match="AUDI2000 coefficients are not supplied"):
        delta_e([50, 0, 0], [51, 0, 0], "audi2000", aspecular_deg=45.0)


def test_cie2000_lc_equals_colour_science_at_1_1_and_its_textile_weights_at_2_1() -> None:
    rng = np.random.default_rng(4)
    a = rng.uniform([0, -90, -90], [120, 90, 90], (400, 3))
    b = a + rng.normal(0, 4, a.shape)
    b[::9, 1:] = 0.0
    np.testing.assert_allclose(delta_e_cie2000_lc(a, b), colour.delta_E(a, b, method="CIE 2000"), atol=1e-12)
    np.testing.assert_allclose(
        delta_e_cie2000_lc(a, b, 2.0, 1.0), colour.delta_E(a, b, method="CIE 2000", textiles=True), atol=1e-12
    )
    with pytest.raises(ModelInputError, match=r"cie2000\.k_l"):
        delta_e_cie2000_lc(a, b, 0.0)
