"""Tolerance sets and QC verdicts: closed-form ΔE*ab cases at the band edges, components against
their definitions, the aggregation rules, DIN 6175-2 and CIEDE2000 l:c through a set, typed errors."""

from __future__ import annotations

import math

import colour
import numpy as np
import pytest

from station.model import domain
from station.model.difference import FormulaUnavailableError
from station.model.errors import ModelInputError
from station.qc.tolerance import GeometryLimits, ToleranceSet, judge, lab_components
from tests.model.test_din6175 import _by_hand

STD = [[90.0, 1.0, -2.0], [50.0, 2.0, -3.0], [30.0, 3.0, -4.0]]
ANGLES = [15.0, 45.0, 110.0]


def _shift(dl: tuple[float, float, float]) -> list[list[float]]:
    """The standard with ΔL* = dl[i] at geometry i (so ΔE*ab = |dl[i]|)."""
    return [[r[0] + d, r[1], r[2]] for r, d in zip(STD, dl, strict=True)]


def test_defaults_come_from_the_domain() -> None:
    t = ToleranceSet.uniform(ANGLES)
    assert t.formula == domain.QC_FORMULA and t.aggregation == domain.QC_AGGREGATION
    assert t.warn_fraction == domain.QC_WARN_FRACTION and t.mean_limit == domain.QC_DE_LIMIT
    assert all(g.de == domain.QC_DE_LIMIT for g in t.geometries)
    assert [g.geometry for g in t.geometries] == ["45as15", "45as45", "45as110"]


@pytest.mark.parametrize(
    ("dl", "expected"),
    [(0.79, "pass"), (0.81, "warn"), (1.0, "warn"), (1.01, "fail"), (-1.01, "fail")],
)
def test_band_edges_with_cie76(dl: float, expected: str) -> None:
    t = ToleranceSet.uniform(ANGLES, 1.0, formula="cie76")
    v = judge(STD, _shift((0.0, dl, 0.0)), ANGLES, t)
    g = v.per_geometry[1]
    assert g.de == pytest.approx(abs(dl), abs=1e-12) and g.verdict == expected
    assert v.verdict == expected
    assert [x.verdict for x in (v.per_geometry[0], v.per_geometry[2])] == ["pass", "pass"]
    if expected != "pass":
        assert "45as45" in v.reason and "ΔE" in v.reason


def test_no_warn_band_at_fraction_one() -> None:
    t = ToleranceSet.uniform(ANGLES, 1.0, formula="cie76", warn_fraction=1.0)
    assert judge(STD, _shift((0.99, 0.0, 0.0)), ANGLES, t).verdict == "pass"


def test_max_rule_reports_the_worst_geometry_and_mean_rule_the_mean() -> None:
    smp = _shift((0.3, 0.6, 1.5))
    t_max = ToleranceSet.uniform(ANGLES, 2.0, formula="cie76")
    v = judge(STD, smp, ANGLES, t_max)
    assert v.max_de == pytest.approx(1.5) and v.worst_geometry == "45as110"
    assert v.mean_de == pytest.approx(0.8)
    assert v.verdict == "pass"  # 1.5 ≤ 0.8 · 2 = 1.6
    t_mean = ToleranceSet.uniform(ANGLES, 1.2, formula="cie76", aggregation="mean", mean_limit=0.9)
    v = judge(STD, smp, ANGLES, t_mean)
    assert v.per_geometry[2].verdict == "fail"  # informational under the mean rule
    assert v.verdict == "warn" and v.reason.startswith("mean ΔE 0.8")  # 0.72 < 0.8 ≤ 0.9
    t_mean_strict = ToleranceSet.uniform(ANGLES, 1.2, formula="cie76", aggregation="mean", mean_limit=0.7)
    assert judge(STD, smp, ANGLES, t_mean_strict).verdict == "fail"


def test_component_limits_count_under_both_rules() -> None:
    smp = [[r[0], r[1], r[2]] for r in STD]
    smp[0] = [90.0, 1.0, -2.0 + 0.6]  # Δb* = 0.6 only
    for rule in ("max", "mean"):
        t = ToleranceSet.uniform(
            ANGLES, 5.0, {"dl": 1.0, "da": 1.0, "db": 0.5}, formula="cie76", aggregation=rule
        )
        v = judge(STD, smp, ANGLES, t)
        assert v.verdict == "fail" and "Δb* 0.6 beyond ±0.5" in v.reason, rule


def test_components_follow_their_definitions() -> None:
    c, h1, dh_deg = 20.0, math.radians(30.0), 10.0
    std = [50.0, c * math.cos(h1), c * math.sin(h1)]
    h2 = h1 + math.radians(dh_deg)
    smp = [51.0, 1.1 * c * math.cos(h2), 1.1 * c * math.sin(h2)]
    d = lab_components(std, smp)
    assert d[0] == pytest.approx(1.0)
    assert d[3] == pytest.approx(0.1 * c)
    assert d[4] == pytest.approx(2 * math.sqrt(c * 1.1 * c) * math.sin(math.radians(dh_deg) / 2))
    assert d[3] ** 2 + d[4] ** 2 == pytest.approx(d[1] ** 2 + d[2] ** 2)
    assert lab_components(smp, std)[4] == pytest.approx(-d[4])  # signed: the other way round


def test_din6175_set_uses_the_angle_of_each_geometry() -> None:
    smp = _shift((0.5, 0.5, 0.5))
    v = judge(STD, smp, ANGLES, ToleranceSet.uniform(ANGLES, 3.0, formula="din6175-2"))
    for g, r, s, a in zip(v.per_geometry, STD, smp, ANGLES, strict=True):
        assert g.de == pytest.approx(_by_hand(r, s, a)[0], rel=1e-12)
    assert v.per_geometry[0].de < v.per_geometry[1].de < v.per_geometry[2].de  # same ΔL*, stricter far


def test_cie2000_l_c_through_a_set() -> None:
    smp = [[91.0, 2.0, -1.0], [49.0, 3.0, -2.0], [31.0, 2.0, -5.0]]
    v = judge(STD, smp, ANGLES, ToleranceSet.uniform(ANGLES, 3.0, formula="cie2000", l_c=(2.0, 1.0)))
    expected = colour.delta_E(np.array(STD), np.array(smp), method="CIE 2000", textiles=True)
    np.testing.assert_allclose([g.de for g in v.per_geometry], expected, atol=1e-12)


def test_round_trip_through_dict() -> None:
    t = ToleranceSet(
        (GeometryLimits(15.0, 1.5, dl=1.0, dc=0.8), GeometryLimits(110.0, 0.9, dh=0.4)),
        formula="cie2000",
        aggregation="mean",
        mean_limit=1.1,
        warn_fraction=0.7,
        l_c=(2.0, 1.0),
        name="fender",
    )
    assert ToleranceSet.from_dict(t.to_dict()) == t


@pytest.mark.parametrize(
    ("build", "field"),
    [
        (lambda: GeometryLimits(15.0, 0.0), "geometry.de"),
        (lambda: GeometryLimits(15.0, 1.0, da=1.0, dh=1.0), "components"),
        (lambda: GeometryLimits(300.0), "aspecular_deg"),
        (lambda: ToleranceSet((GeometryLimits(15.0), GeometryLimits(15.0))), "tolerance.geometries"),
        (lambda: ToleranceSet.uniform(ANGLES, aggregation="median"), "tolerance.aggregation"),
        (lambda: ToleranceSet.uniform(ANGLES, formula="cmc"), "de"),
        (lambda: ToleranceSet.uniform(ANGLES, warn_fraction=0.0), "tolerance.warn_fraction"),
        (lambda: ToleranceSet.uniform(ANGLES, l_c=(1.0, -1.0)), "tolerance.l_c.c"),
        (lambda: ToleranceSet.from_dict({"geometries": [{"geometry": "45as15", "de": 1, "dE": 2}]}), "dE"),
        (lambda: ToleranceSet.from_dict({"geometries": [], "formula": "cie76"}), "tolerance.geometries"),
        (lambda: ToleranceSet.from_dict({"geometries": [{"geometry": "45x15"}]}), "geometry"),
        (lambda: judge(STD, STD, [15.0, 45.0, 75.0], ToleranceSet.uniform(ANGLES)), "angles"),
        (lambda: judge(STD, STD[:2], ANGLES, ToleranceSet.uniform(ANGLES)), "sample"),
        (
            lambda: judge(
                STD,
                [[50.0, 0.0, 0.0], [50.0, 0.0, 0.0], [50.0, 0.0, np.nan]],
                ANGLES,
                ToleranceSet.uniform(ANGLES),
            ),
            "sample",
        ),
    ],
)
def test_bad_input_is_a_typed_error_naming_the_field(build, field) -> None:
    with pytest.raises(ModelInputError) as info:
        build()
    assert field in str(info.value)


def test_audi2000_set_refuses_with_the_clear_message() -> None:
    with pytest.raises(FormulaUnavailableError, match="AUDI2000 coefficients"):
        ToleranceSet.uniform(ANGLES, formula="audi2000")
