"""SPC: chart constants against the published table and their defining integrals, each run rule on a
series built to trip it alone, charts and capability by hand, limits from a baseline, drift before a fail."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate, stats

from station.qc.errors import QcInputError
from station.qc.spc import CONSTANTS, capability, drift_hits, individuals_chart, rule_hits, xbar_r_chart

#: d₃ (standard deviation of the range of m normal values), Montgomery Appendix VI, a column the module
#: does not store: D₄ = 1 + 3d₃/d₂ and D₃ = max(0, 1 − 3d₃/d₂) must follow from it.
D3_SMALL = {2: 0.853, 3: 0.888, 4: 0.880, 5: 0.864, 6: 0.848, 7: 0.833, 8: 0.820, 9: 0.808, 10: 0.797}


def _d2(m: int) -> float:
    """E[range of m standard normals] = ∫ 1 − Φ(x)^m − (1 − Φ(x))^m dx."""
    f = lambda x: 1 - stats.norm.cdf(x) ** m - stats.norm.sf(x) ** m  # noqa: E731
    return float(integrate.quad(f, -np.inf, np.inf)[0])


@pytest.mark.parametrize("m", sorted(CONSTANTS))
def test_constants_match_their_definitions(m: int) -> None:
    a2, d2, d3_, d4 = CONSTANTS[m]
    exact = _d2(m)
    assert d2 == pytest.approx(exact, abs=5e-4)  # the table rounds to 3 decimals
    assert a2 == pytest.approx(3 / (exact * math.sqrt(m)), abs=5e-4)
    assert d4 == pytest.approx(1 + 3 * D3_SMALL[m] / d2, abs=2e-3)
    assert d3_ == pytest.approx(max(0.0, 1 - 3 * D3_SMALL[m] / d2), abs=2e-3)


#: A series per rule, in σ units about centre 0, built to trip that rule and no other (its twin in the
#: other family, e.g. WE1 = N1, fires too; nine on one side are also eight on one side).
SERIES = {
    ("WE1", "N1"): [0.2, -0.4, 0.5, 3.5, 0.1, -0.3],
    ("WE2", "N5"): [0.2, -0.2, 2.5, 0.1, 2.5, -0.2],
    ("WE3", "N6"): [0.2, -0.2, 1.5, 1.5, -0.1, 1.5, 1.5, -0.3],
    ("WE4",): [-0.3, 0.3, 0.5, 0.2, 0.6, 0.4, 0.7, 0.1, 0.5, -0.4],
    ("N2", "WE4"): [-0.3, 0.3, 0.5, 0.2, 0.6, 0.4, 0.7, 0.1, 0.5, 0.3, -0.4],
    ("N3",): [-0.8, -0.5, -0.2, 0.1, 0.4, 0.7],
    ("N4",): [0.5, -0.5] * 7,
    ("N7",): [0.1, -0.2, 0.3, 0.2, -0.1, -0.3, 0.1, 0.4, -0.2, -0.1, 0.2, 0.3, -0.4, 0.1, -0.1],
    ("N8",): [1.5, -1.5] * 4,
}


@pytest.mark.parametrize(("rules", "series"), list(SERIES.items()))
def test_each_rule_alone(rules: tuple[str, ...], series: list[float]) -> None:
    hits = rule_hits(series, 0.0, 1.0)
    assert {h.rule for h in hits} == set(rules)
    # the same series scaled into the centre band of a wider chart trips nothing but N7's kind
    calm = {h.rule for h in rule_hits(series, 0.0, 10.0)}
    assert calm <= {"WE4", "N2", "N3", "N4", "N7"} and "WE1" not in calm


def test_individuals_chart_by_hand_with_a_baseline() -> None:
    x = [0.2, 0.4, 0.3, 0.5, 0.4, 1.5]
    ch = individuals_chart(x, baseline=5)
    mr = (0.2 + 0.1 + 0.2 + 0.1) / 4
    assert ch.centre == pytest.approx(0.36) and ch.sigma == pytest.approx(mr / 1.128)
    assert ch.ucl == pytest.approx(0.36 + 3 * mr / 1.128) and ch.lcl == 0.0  # 0.36 − 0.399 < 0
    assert ch.flagged == (5,) and {h.rule for h in ch.hits} == {"WE1", "N1"}
    # limits from every point move with the outlier: centre 0.55, σ from all five moving ranges
    every = individuals_chart(x)
    assert every.centre == pytest.approx(0.55) and every.sigma == pytest.approx((mr * 4 + 1.1) / 5 / 1.128)
    with pytest.raises(QcInputError, match="baseline"):
        individuals_chart(x, baseline=1)


def test_xbar_r_chart_by_hand() -> None:
    x = [1.0, 1.2, 0.9, 1.1, 1.0, 1.3, 0.8, 1.0, 1.1, 1.4, 1.2, 1.3]
    ch = xbar_r_chart(x, 3)
    groups = np.array(x).reshape(4, 3)
    means = groups.mean(axis=1)
    r = groups.max(axis=1) - groups.min(axis=1)  # 0.3, 0.3, 0.3, 0.2
    assert ch.points == pytest.approx(means) and ch.ranges == pytest.approx(r)
    assert ch.r_bar == pytest.approx(0.275) and ch.centre == pytest.approx(means.mean())
    assert ch.ucl == pytest.approx(means.mean() + 1.023 * 0.275)
    assert ch.r_ucl == pytest.approx(2.574 * 0.275) and ch.r_lcl == 0.0
    assert ch.sigma_process == pytest.approx(0.275 / 1.693)
    with pytest.raises(QcInputError, match="subgroup"):
        xbar_r_chart(x, 11)


def test_capability_by_hand() -> None:
    x = [0.2, 0.4, 0.3, 0.5, 0.4]
    sigma = 0.15 / 1.128
    cap = capability(x, 1.0, sigma)
    assert cap.cp == pytest.approx(1.0 / (6 * sigma)) and cap.cpk == pytest.approx((1.0 - 0.36) / (3 * sigma))
    assert cap.ppk == pytest.approx((1.0 - 0.36) / (3 * np.std(x, ddof=1)))
    assert capability([0.3, 0.3], 1.0, 0.0).cp is None


def test_an_eight_sample_drift_is_flagged_before_it_fails() -> None:
    # a stable process (baseline of 10), then eight readings creeping up to a fail at limit 1.0
    stable = [0.30, 0.34, 0.28, 0.33, 0.31, 0.27, 0.32, 0.35, 0.29, 0.31]
    drift = [0.36, 0.44, 0.52, 0.61, 0.70, 0.80, 0.91, 1.03]
    x = stable + drift
    ch = individuals_chart(x, baseline=len(stable))
    hits = drift_hits(ch)
    first_fail = next(i for i, v in enumerate(x) if v > 1.0)
    first_flag = min(p for h in hits for p in h.points)
    assert first_flag < first_fail and first_flag >= len(stable)
    assert "N3" in {h.rule for h in hits}  # the monotonic run itself
