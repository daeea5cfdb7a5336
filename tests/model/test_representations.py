"""FFTG ⇄ clamped quadratic ⇄ aspecular measurements (thesis eqs 3.3.1–3.3.10, docs/design.md erratum 5)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from station.model import (
    ANGLES_3,
    ANGLES_3_ALT,
    ANGLES_5,
    ANGLES_6,
    AspecularMeasurements,
    ClampedQuadratic,
    FaceFlopTravelGloss,
    FitError,
    ModelInputError,
    fit_fftg,
)

ROUND_TRIP_TOL = 1e-9

lab_l = st.floats(5.0, 95.0)
lab_ab = st.floats(-60.0, 60.0)


def lab3() -> st.SearchStrategy[tuple[float, float, float]]:
    return st.tuples(lab_l, lab_ab, lab_ab)


class TestClosedForms:
    """Hand-derived values of eqs 3.3.8–3.3.10."""

    def test_coefficients_by_hand(self) -> None:
        # face L = 90, flop L = 30, θc = 75: L_a = (90 − 30)/(15 − 75)² = 60/3600 = 1/60,
        # L_b = −2·(1/60)·75 = −2.5, L_c = 30 + (1/60)·75² = 123.75
        cq = FaceFlopTravelGloss((90, 0, 0), (30, 0, 0), 75.0).to_quadratic()
        assert cq.coefficients[0] == pytest.approx([1 / 60, -2.5, 123.75], abs=1e-12)
        assert cq.theta_clamp_deg == 75.0
        # L(45) = (1/60)·2025 − 2.5·45 + 123.75 = 33.75 − 112.5 + 123.75 = 45
        assert cq.lab_at(45.0)[0] == pytest.approx(45.0, abs=1e-12)
        # clamped beyond θc: L(110) = L(75) = flop
        assert cq.lab_at(110.0)[0] == pytest.approx(30.0, abs=1e-12)

    def test_vertex_is_eq_3_3_4(self) -> None:
        cq = FaceFlopTravelGloss((80, 10, -20), (20, 2, -5), 62.5).to_quadratic()
        for row in cq.coefficients:
            assert -row[1] / (2 * row[0]) == pytest.approx(62.5, abs=1e-12)

    def test_from_coefficients_derives_travel(self) -> None:
        cq = ClampedQuadratic.from_coefficients(np.array([[1 / 60, -2.5, 123.75], [0, 0, 5], [0, 0, -3]]), 40)
        d = cq.to_fftg()
        assert d.travel_deg == pytest.approx(75.0)
        assert d.face == pytest.approx((90.0, 5.0, -3.0))
        assert d.flop == pytest.approx((30.0, 5.0, -3.0))

    def test_inconsistent_vertices_refused(self) -> None:
        with pytest.raises(ModelInputError, match=r"coefficients\[a\]"):
            ClampedQuadratic.from_coefficients(
                np.array([[1 / 60, -2.5, 123.75], [1.0, -100.0, 0.0], [0, 0, 0]])
            )

    def test_three_angle_exact_case_b(self) -> None:
        # θc between 45 and 110: L45 = flop + (face − flop)((θc − 45)/(θc − 15))².
        # With face 100, flop 20, θc 75: L45 = 20 + 80·(30/60)² = 40; L110 = 20.
        r = fit_fftg(AspecularMeasurements(ANGLES_3, np.array([[100, 0, 0], [40, 0, 0], [20, 0, 0]])))
        assert r.method == "closed-form"
        assert r.design.travel_deg == pytest.approx(75.0, abs=1e-12)
        assert r.exact

    def test_three_angle_exact_case_a(self) -> None:
        # θc beyond 110: a parabola with vertex 130 through 15/45/110.
        d = FaceFlopTravelGloss((100, 0, 0), (10, 0, 0), 130.0)
        r = fit_fftg(AspecularMeasurements.from_design(d, ANGLES_3))
        assert r.design.travel_deg == pytest.approx(130.0, abs=1e-10)

    def test_ab_least_squares_residual_reported(self) -> None:
        # docs/design.md erratum 5: L is exact, a and b are least squares with the shared θc.
        r = fit_fftg(AspecularMeasurements(ANGLES_3, np.array([[90, 2, -5], [50, 1, -3], [30, 0.5, -1]])))
        assert r.method == "closed-form"
        model = r.design.lab_at(np.asarray(ANGLES_3))
        assert model[:, 0] == pytest.approx([90, 50, 30], abs=1e-9)  # L exact
        assert max(r.residual_de) > 0.1  # a, b not exact
        assert not r.exact
        assert r.residual_de == pytest.approx(
            np.linalg.norm(model - [[90, 2, -5], [50, 1, -3], [30, 0.5, -1]], axis=1), abs=1e-12
        )


class TestRoundTrips:
    """Property-based: FFTG → angles → FFTG reproduces the design where the mapping is exact."""

    @settings(max_examples=150, deadline=None)
    @given(face=lab3(), flop=lab3(), travel=st.floats(46.0, 180.0), gloss=st.floats(0.0, 100.0))
    def test_three_angle_sets(self, face, flop, travel, gloss) -> None:
        design = FaceFlopTravelGloss(face, flop, travel, gloss)
        if np.ptp([face[0], flop[0]]) < 1e-3:
            return  # L gives no travel: covered by test_flat_l
        for angles in (ANGLES_3, ANGLES_3_ALT):
            if angles == ANGLES_3_ALT and travel <= 46.0:
                continue
            fit = fit_fftg(AspecularMeasurements.from_design(design, angles))
            got = fit.design
            assert got.travel_deg == pytest.approx(travel, abs=ROUND_TRIP_TOL * 1e3)
            assert got.face == pytest.approx(design.face, abs=ROUND_TRIP_TOL * 1e2)
            assert got.flop == pytest.approx(design.flop, abs=ROUND_TRIP_TOL * 1e2)
            assert got.gloss_gu == gloss
            assert max(fit.residual_de) < ROUND_TRIP_TOL

    @settings(max_examples=60, deadline=None)
    @given(face=lab3(), flop=lab3(), travel=st.floats(26.0, 180.0))
    def test_five_and_six_angle_sets(self, face, flop, travel) -> None:
        design = FaceFlopTravelGloss(face, flop, travel)
        if np.linalg.norm(np.subtract(face, flop)) < 1.0:
            return
        for angles in (ANGLES_5, ANGLES_6):
            fit = fit_fftg(AspecularMeasurements.from_design(design, angles))
            assert fit.design.travel_deg == pytest.approx(travel, abs=1e-7)
            assert fit.design.face == pytest.approx(design.face, abs=1e-7)
            assert fit.design.flop == pytest.approx(design.flop, abs=1e-7)
            assert max(fit.residual_de) < ROUND_TRIP_TOL

    @settings(max_examples=100, deadline=None)
    @given(face=lab3(), flop=lab3(), travel=st.floats(15.5, 180.0), gloss=st.floats(0.0, 100.0))
    def test_fftg_quadratic_exact(self, face, flop, travel, gloss) -> None:
        design = FaceFlopTravelGloss(face, flop, travel, gloss)
        back = design.to_quadratic().to_fftg()
        assert back.travel_deg == pytest.approx(travel, abs=1e-12)
        assert back.face == pytest.approx(design.face, abs=1e-9)
        assert back.flop == pytest.approx(design.flop, abs=1e-9)
        angles = np.linspace(-15, 170, 38)
        assert design.to_quadratic().lab_at(angles) == pytest.approx(design.lab_at(angles), abs=1e-9)


class TestDegenerate:
    def test_solid(self) -> None:
        r = fit_fftg(AspecularMeasurements(ANGLES_3, np.array([[50, 20, 10]] * 3), 80))
        assert r.design.is_solid and r.design.travel_deg is None
        assert r.exact and "solid" in r.warnings
        assert r.design.lab_at([15, 45, 110]) == pytest.approx(np.tile([50, 20, 10], (3, 1)))

    def test_solid_quadratic_round_trip(self) -> None:
        d = FaceFlopTravelGloss((50, 20, 10), (50, 20, 10), None, 30)
        assert d.to_quadratic().to_fftg() == d

    def test_flop_brighter_than_face_fitted_with_warning(self) -> None:
        d = FaceFlopTravelGloss((30, 0, 0), (60, 0, 0), 80.0)
        r = fit_fftg(AspecularMeasurements.from_design(d, ANGLES_3))
        assert r.design.travel_deg == pytest.approx(80.0)
        assert any("flop brighter" in w for w in r.warnings)

    def test_non_monotone_l_least_squares(self) -> None:
        r = fit_fftg(AspecularMeasurements(ANGLES_3, np.array([[40, 0, 0], [70, 0, 0], [30, 0, 0]])))
        assert r.method == "least-squares" and not r.exact
        assert any("no monotone" in w for w in r.warnings)
        assert all(np.isfinite(r.residual_de)) and max(r.residual_de) > 1.0

    def test_flat_l(self) -> None:
        d = FaceFlopTravelGloss((50, 40, 0), (50, 0, 40), 90.0)
        r = fit_fftg(AspecularMeasurements.from_design(d, ANGLES_3))
        assert r.design.travel_deg == pytest.approx(90.0, abs=1e-6)
        assert any("identical at every angle" in w for w in r.warnings)

    def test_travel_not_identifiable(self) -> None:
        d = FaceFlopTravelGloss((80, 0, 0), (30, 0, 0), 30.0)
        r = fit_fftg(AspecularMeasurements.from_design(d, ANGLES_3))
        assert r.design.travel_deg == 45.0
        assert any("not identifiable" in w for w in r.warnings)
        assert r.exact  # every θc in (15, 45] reproduces the data

    def test_vertex_below_15_refused(self) -> None:
        with pytest.raises(ModelInputError, match="travel_deg"):
            FaceFlopTravelGloss((80, 0, 0), (30, 0, 0), 12.0)

    def test_fit_vertex_below_15_refused(self) -> None:
        # L collapses between 5° and 10° and stays flat: the best vertex is below the face angle
        with pytest.raises(FitError, match="travel_deg"):
            fit_fftg(AspecularMeasurements((5, 10, 110), np.array([[80, 0, 0], [10, 0, 0], [10.5, 0, 0]])))

    def test_coefficients_vertex_below_15_refused(self) -> None:
        # L_a = 1, L_b = −20: vertex at 10° (eq 3.3.4)
        with pytest.raises(ModelInputError, match="theta_clamp_deg"):
            ClampedQuadratic.from_coefficients(np.array([[1.0, -20.0, 150.0], [0, 0, 0], [0, 0, 0]]))

    def test_vertex_inside_the_set_is_not_identifiable_not_refused(self) -> None:
        # only 15° lies below any vertex in (15, 16]: every such vertex fits equally
        r = fit_fftg(AspecularMeasurements((15, 16, 110), np.array([[80, 0, 0], [10, 0, 0], [10.5, 0, 0]])))
        assert r.design.travel_deg == 16.0
        assert any("not identifiable" in w for w in r.warnings)

    @pytest.mark.parametrize(
        ("angles", "field"),
        [
            ((15, 45, 45), "angles_deg"),
            ((45, 15, 110), "angles_deg"),
            ((15, 45, float("nan")), "angles_deg[2]"),
            ((15, 45, 200), "angles_deg[2]"),
        ],
    )
    def test_bad_angles(self, angles, field) -> None:
        with pytest.raises(ModelInputError) as err:
            AspecularMeasurements(angles, np.array([[50, 0, 0]] * 3))
        assert err.value.field == field

    @pytest.mark.parametrize(
        ("lab", "field"),
        [
            ([[50, 0, 0], [50, 0, 0], [-1, 0, 0]], "lab[2].L"),
            ([[50, 0, 0], [50, 200, 0], [50, 0, 0]], "lab[1].a"),
            ([[50, 0, 0], [50, 0, float("nan")], [50, 0, 0]], "lab[1].b"),
            ([[50, 0, 0]] * 2, "lab"),
        ],
    )
    def test_bad_lab(self, lab, field) -> None:
        with pytest.raises(ModelInputError) as err:
            AspecularMeasurements(ANGLES_3, lab)
        assert err.value.field == field
        assert "expected" in str(err.value)

    def test_bad_gloss_and_travel(self) -> None:
        with pytest.raises(ModelInputError, match="gloss_gu"):
            FaceFlopTravelGloss((50, 0, 0), (40, 0, 0), 60, gloss_gu=120)
        with pytest.raises(ModelInputError, match="travel_deg"):
            FaceFlopTravelGloss((50, 0, 0), (40, 0, 0), None)
        with pytest.raises(ModelInputError, match="travel_deg"):
            FaceFlopTravelGloss((50, 0, 0), (40, 0, 0), float("inf"))

    def test_too_few_angles(self) -> None:
        with pytest.raises(FitError, match="at least 3"):
            fit_fftg(AspecularMeasurements((15, 45), np.array([[50, 0, 0], [40, 0, 0]])))

    def test_never_nan(self) -> None:
        rng = np.random.default_rng(3)
        for _ in range(200):
            lab = np.column_stack([rng.uniform(1, 99, 3), rng.uniform(-50, 50, 3), rng.uniform(-50, 50, 3)])
            try:
                r = fit_fftg(AspecularMeasurements(ANGLES_3, lab))
            except FitError:
                continue
            assert np.all(np.isfinite(r.residual_de))
            assert np.all(np.isfinite(r.design.face + r.design.flop))

    def test_immutable(self) -> None:
        m = AspecularMeasurements(ANGLES_3, np.array([[50, 0, 0]] * 3))
        with pytest.raises(ValueError):
            m.lab[0, 0] = 3.0
        d = FaceFlopTravelGloss((50, 0, 0), (40, 0, 0), 60)
        with pytest.raises(AttributeError):
            d.travel_deg = 70  # type: ignore[misc]

    def test_negative_angle_is_unsigned(self) -> None:
        d = FaceFlopTravelGloss((90, 5, 5), (30, 0, 0), 80)
        assert d.lab_at(-15.0) == pytest.approx(d.lab_at(15.0))
