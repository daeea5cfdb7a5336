"""The bright silver (L*15 = 125, flop 38, travel 65°, 90 GU) through the appearance model.

Expectations are hand-computed from the closed form X(θ) = flop + (face − flop)·s(θ)², with
s(θ) = (θ_c − min(θ, θ_c)) / (θ_c − 15°), and from eqs 5.3.1–5.3.3 for the indices.
"""

from __future__ import annotations

import numpy as np
import pytest

from station.model import (
    ANGLES_3,
    ANGLES_5,
    AspecularMeasurements,
    ClampedQuadratic,
    FaceFlopTravelGloss,
    ModelInputError,
    fit_fftg,
)
from station.model.domain import L_MAX, check_lab
from station.model.indices import library_indices


def _by_hand(design: FaceFlopTravelGloss, theta: float) -> np.ndarray:
    tc = design.travel_deg
    assert tc is not None
    s = (tc - min(theta, tc)) / (tc - 15.0)
    return np.asarray(design.flop) + (np.asarray(design.face) - np.asarray(design.flop)) * s * s


def test_the_fixture_is_the_issue_s_silver(bright_silver) -> None:
    assert bright_silver.face[0] == 125.0 and bright_silver.flop[0] == 38.0
    assert bright_silver.gloss_gu == 90.0 and bright_silver.travel_deg == 65.0
    assert 100.0 < bright_silver.face[0] <= L_MAX  # above diffuse white, inside the effect-paint bound


def test_eval_matches_the_closed_form(bright_silver) -> None:
    lab = bright_silver.lab_at(np.array(ANGLES_5))
    # at 45°: s = (65 − 45)/50 = 0.4, s² = 0.16 → L* = 38 + 87·0.16 = 51.92
    assert lab[2, 0] == pytest.approx(51.92, abs=1e-12)
    assert lab[0, 0] == pytest.approx(125.0) and lab[-1, 0] == pytest.approx(38.0)  # 15° face, 110° flop
    for theta, row in zip(ANGLES_5, lab, strict=True):
        np.testing.assert_allclose(row, _by_hand(bright_silver, theta), atol=1e-12)


def test_from_angles_round_trip(bright_silver) -> None:
    meas = AspecularMeasurements.from_design(bright_silver, ANGLES_3)
    fit = fit_fftg(meas)
    assert fit.exact
    np.testing.assert_allclose(fit.design.face, bright_silver.face, atol=1e-8)
    np.testing.assert_allclose(fit.design.flop, bright_silver.flop, atol=1e-8)
    assert fit.design.travel_deg == pytest.approx(65.0, abs=1e-8)
    five = fit_fftg(AspecularMeasurements.from_design(bright_silver, ANGLES_5))
    np.testing.assert_allclose(five.design.face, bright_silver.face, atol=1e-6)


def test_quadratic_round_trip(bright_silver) -> None:
    q = bright_silver.to_quadratic()
    # eq 3.3.8: X_a = (face − flop)/(15 − θc)²
    assert q.coefficients[0, 0] == pytest.approx(87.0 / 50.0**2)
    back = ClampedQuadratic.from_coefficients(q.coefficients, 90.0).to_fftg()
    np.testing.assert_allclose(back.face, bright_silver.face, atol=1e-9)
    assert back.travel_deg == pytest.approx(65.0)


def test_indices(bright_silver) -> None:
    l15, l45, l110 = (bright_silver.lab_at(a) for a in ANGLES_3)
    r = library_indices(l15, l45, l110)
    assert r.flop_index == pytest.approx(2.69 * (125.0 - 38.0) ** 1.11 / 51.92**0.86, rel=1e-9)  # eq 5.3.1
    c15, c110 = np.hypot(*l15[1:]), np.hypot(*l110[1:])
    assert r.chroma_index == pytest.approx(abs(c15 - c110), abs=1e-9)  # eq 5.3.2
    # eq 5.3.3 divides by C15 ≈ 1.9: a near-neutral silver's hue shift is undefined and says so
    assert c15 < 2.0 and r.hue_shift_index is None and r.warnings


def test_out_of_range_names_field_and_range(bright_silver) -> None:
    with pytest.raises(ModelInputError) as err:
        bright_silver.replace(face=(250.0, 0.0, 0.0))
    assert err.value.field == "face.L" and err.value.accepted == "0 <= L* <= 200"
    assert str(err.value) == "face.L: expected 0 <= L* <= 200, got 250.0"
    with pytest.raises(ModelInputError) as err:
        check_lab((250.0, 0.0, 0.0), "face")
    assert str(err.value) == "face.L: expected 0 <= L* <= 200, got 250.0"
