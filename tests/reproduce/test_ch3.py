"""§3.3: the conversions against independent routes; the erratum-5 residual against a by-hand fit."""

from __future__ import annotations

import numpy as np
import pytest

from station.model.domain import ANGLES_3
from station.reproduce import ch3


def test_direct_solve_matches_a_hand_calculation() -> None:
    # face 80 at 15°, flop 30 at 60°: X_a = 50/45² (eq 3.3.8), X_b = −2·60·X_a, X_c = 30 + X_a·60².
    xa = 50.0 / 45.0**2
    np.testing.assert_allclose(
        ch3.direct_coefficients(80.0, 30.0, 60.0), [xa, -120.0 * xa, 30.0 + 3600.0 * xa]
    )


def test_conversions_are_exact_and_erratum_5_is_reported() -> None:
    r = ch3.representations(None)
    verdicts = {q.quantity: q.verdict for q in r.quantities}
    differs = [k for k, v in verdicts.items() if v == "differs"]
    assert len(differs) == 1 and "a*b* residual" in differs[0]
    for q in r.quantities:
        if q.verdict == "agrees":
            assert abs(q.ours) <= q.tolerance


def test_erratum_5_residual_equals_a_by_hand_least_squares() -> None:
    """θ_clamp from L* alone (bisection on the closed form), then a*, b* by numpy least squares."""
    meas = ch3.erratum5_measurements()
    t = np.asarray(ANGLES_3)
    lab = meas.lab

    def l_mismatch(tc: float) -> float:
        s2 = ((tc - np.minimum(t, tc)) / (tc - 15.0)) ** 2
        flop = lab[2, 0]  # 110° is beyond θ_clamp
        return float(flop + (lab[0, 0] - flop) * s2[1] - lab[1, 0])

    lo, hi = 45.01, 109.99
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if np.sign(l_mismatch(mid)) == np.sign(l_mismatch(lo)) else (lo, mid)
    tc = 0.5 * (lo + hi)
    s2 = ((tc - np.minimum(t, tc)) / (tc - 15.0)) ** 2
    a = np.column_stack([s2, 1.0 - s2])
    model = np.empty((3, 2))
    for j, ch in enumerate((1, 2)):
        coef, *_ = np.linalg.lstsq(a, lab[:, ch], rcond=None)
        model[:, j] = a @ coef
    expected = float(np.max(np.linalg.norm(model - lab[:, 1:], axis=1)))
    q = next(q for q in ch3.representations(None).quantities if "a*b* residual" in q.quantity)
    assert expected > 1.0  # the case really has no shared vertex
    assert q.ours == pytest.approx(expected, rel=1e-6)
    assert tc == pytest.approx(60.0, abs=1e-6)  # L* came from a 60° travel


def test_tweaker_agrees_and_matches_eqs_365_366_by_hand() -> None:
    from station.design.tweaker import adjust_at
    from station.model.examples import EXAMPLES

    r = ch3.tweaker(None)
    assert all(q.verdict == "agrees" for q in r.quantities)
    d = EXAMPLES["pearl"]
    theta, tc = 30.0, d.travel_deg
    assert tc is not None
    ratio = (tc - theta) / (tc - 15.0)  # erratum 1
    t = adjust_at(d, np.array([[theta]]), (0, 0), "L", 10.0)
    assert t.design.face[0] == pytest.approx(d.face[0] + 10.0 * ratio)  # eq 3.6.5
    assert t.design.flop[0] == pytest.approx(d.flop[0] + 10.0 * (1.0 - ratio))  # eq 3.6.6


def test_variations_agree_and_the_hue_step_is_the_chord_by_hand() -> None:
    import math

    from station.design.variations import variations
    from station.model.examples import EXAMPLES

    assert all(q.verdict == "agrees" for q in ch3.variations_ring(None).quantities)
    d = EXAMPLES["pearl"]
    _, a, b = d.face
    c = math.hypot(a, b)
    dh = 2.0 * math.asin(5.0 / (2.0 * c))  # ΔH*ab = 5 along the hue circle
    ring = {v.label: v.design for v in variations(d, 5.0, "face").variations}
    hue_plus = ring["hue +"]
    assert hue_plus is not None
    expected = (a * math.cos(dh) - b * math.sin(dh), a * math.sin(dh) + b * math.cos(dh))
    assert hue_plus.face[1:] == pytest.approx(expected, abs=1e-9)


def test_hsb_edit_is_a_rotate_and_scale_of_every_point() -> None:
    r = ch3.hsb(None)
    assert len(r.quantities) == 2
    assert all(q.verdict == "agrees" and abs(q.ours) <= q.tolerance for q in r.quantities)
