"""§4.3–4.4: the Lambertian index against colour-science by bisection; Figs 4.4–4.7 pinned to the thesis."""

from __future__ import annotations

import math

import colour
import numpy as np
import pytest

from station.analysis.scenarios import BUMPER_PAINT, SILVER_PAINT, SOLID_LIGHTS_DEG, SOLID_PAINT
from station.reproduce import ch4

WHITE = colour.xy_to_XYZ(colour.CCS_ILLUMINANTS["CIE 1964 10 Degree Standard Observer"]["D65"])


def _brute_index(lab: tuple[float, float, float], light: float, eps: float = 2.3) -> float:
    """First β (either direction) with ΔE*ab ≥ ε, by bisection on colour-science's Lab ⇄ XYZ."""
    xyz = colour.Lab_to_XYZ(np.asarray(lab), WHITE)

    def de(beta: np.ndarray | float) -> np.ndarray:
        k = np.maximum(np.cos(np.radians(light + np.asarray(beta))), 0.0) / math.cos(math.radians(light))
        return np.linalg.norm(
            colour.XYZ_to_Lab(xyz * np.asarray(k)[..., None], WHITE) - np.asarray(lab), axis=-1
        )

    best = math.inf
    grid = np.arange(0.0, 30.0, 0.01)
    for sign in (1.0, -1.0):
        vals = de(sign * grid)
        hit = np.nonzero(vals >= eps)[0]
        if not hit.size:
            continue
        lo, hi = grid[hit[0] - 1], grid[hit[0]]
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            lo, hi = (lo, mid) if de(sign * mid) >= eps else (mid, hi)
        best = min(best, hi)
    return best


@pytest.mark.parametrize("light", SOLID_LIGHTS_DEG)
def test_closed_form_matches_brute_force(light: float) -> None:
    assert ch4.lambertian_index_closed_form(SOLID_PAINT.face, light) == pytest.approx(
        _brute_index(SOLID_PAINT.face, light), abs=1e-6
    )


def test_numeric_index_agrees_with_the_closed_form() -> None:
    r = ch4.lambertian_index(None)
    assert len(r.quantities) == len(SOLID_LIGHTS_DEG)
    assert all(q.verdict == "agrees" and abs(q.difference) < 1e-4 for q in r.quantities)


def test_fig44_agrees_with_the_thesis() -> None:
    r = ch4.fig44(None)
    q = {x.quantity: x for x in r.quantities}
    assert abs(q["optimised at 45°: seam ΔE at the 0° light"].ours - 2.0) <= 0.5  # "about 2 ΔE"
    assert abs(q["RMS solution: worst seam ΔE"].ours - 1.0) <= 0.25  # "about 1 ΔE"
    assert q["per row: worst seam ΔE"].ours < 0.05
    assert all(x.verdict == "agrees" for x in r.quantities)


def test_thesis_convention_is_the_shifted_curve() -> None:
    """Face at 0°, shift β, L·V: travel + β exactly, face + (face − flop)((1 + β/θ)² − 1) (exact family)."""
    beta = 2.0
    r = ch4.thesis_convention_solve(SILVER_PAINT, -beta, full=False)
    tc = SILVER_PAINT.travel_deg
    assert tc is not None
    assert r.travel_change_deg == pytest.approx(beta, abs=1e-6)
    expected = (SILVER_PAINT.face[0] - SILVER_PAINT.flop[0]) * ((1 + beta / tc) ** 2 - 1)
    assert r.face_change[0] == pytest.approx(expected, abs=1e-5)
    assert r.rms_after < 1e-6 < r.rms_before
    b = ch4.thesis_convention_solve(BUMPER_PAINT, 8.0, full=True)
    assert b.travel_change_deg == pytest.approx(8.0, abs=1e-5)
    np.testing.assert_allclose(b.flop_change, 0.0, atol=1e-5)


def test_mirror_law_mode_reproduces_the_analysis_module() -> None:
    """Face at 15°, shift 2β, L·N is what station.analysis computes in plane (+19.2 / +4.2°)."""
    from station.analysis.scenarios import silver_black_flop

    ours = silver_black_flop()
    r = ch4.thesis_convention_solve(
        SILVER_PAINT, -2.0, full=False, face_angle_deg=15.0, shift_per_beta=2.0, shading="lambert"
    )
    assert r.face_change[0] == pytest.approx(ours.changes["face_L"], abs=0.05)
    assert r.travel_change_deg == pytest.approx(ours.changes["travel_deg"], abs=0.05)


def test_figs45_47_verdicts_and_reasons() -> None:
    r = ch4.figs45_47(None)
    q = {x.quantity: x for x in r.quantities}
    assert q["Δ travel, thesis convention"].verdict == "agrees"
    assert q["Δ θ_flop, thesis convention (full FFTG)"].verdict == "agrees"
    assert q["Δ travel, ours (in-plane)"].verdict == "differs"
    assert "mirror law" in q["Δ travel, ours (in-plane)"].reason
    # ours in plane is ≈ 2β (mirror law) within the shading's share
    assert q["Δ travel, ours (in-plane)"].ours == pytest.approx(4.0, abs=0.5)
    assert q["Δ θ_flop, ours (in-plane, full FFTG)"].ours == pytest.approx(16.0, abs=4.0)


def test_bad_shading_is_refused() -> None:
    from station.reproduce import ReproduceInputError

    with pytest.raises(ReproduceInputError, match="shading"):
        ch4.thesis_convention_solve(SILVER_PAINT, 2.0, full=False, shading="flat")  # type: ignore[arg-type]
    with pytest.raises(ReproduceInputError, match="paint"):
        ch4.thesis_convention_solve(SOLID_PAINT, 2.0, full=False)


def test_fig43_graphical_index_brackets_the_root() -> None:
    r = ch4.fig43(None)
    q = r.quantities[0]
    assert q.verdict == "agrees"
    assert abs(q.ours - q.thesis) <= ch4.FIG43_STEP_DEG
    assert q.reference == "eq 4.3.1"
