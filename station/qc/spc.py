"""Statistical process control of ΔE over time: individuals and X̄/R charts, run rules, capability.

Charts (Montgomery, *Introduction to Statistical Quality Control*, 7th ed., ch. 6; ASTM E2587):

* **individuals (X) chart** of x_1 … x_n in time order: moving ranges MR_i = |x_i − x_{i−1}|,
  σ̂ = MR̄ / d₂(2), centre x̄, limits x̄ ± 3σ̂;
* **X̄/R chart** of subgroups of size m (2 … 10): centre X̄̄, limits X̄̄ ± A₂R̄; range chart centre R̄,
  limits D₃R̄ and D₄R̄; σ̂ = R̄ / d₂(m); the X̄ chart's σ is A₂R̄ / 3.

Centre and σ̂ come from a **baseline** (the first *baseline* points or subgroups; all of them when
``None``) and every point is judged against them, so a process that moves after the baseline shows.
A lower limit below 0 is shown as 0 (ΔE >= 0); the zones of the run rules use the unclipped centre ± kσ.

Run rules (:data:`RULES`): Western Electric (*Statistical Quality Control Handbook*, 1956, rules 1–4)
and Nelson (*J. Quality Technology* 16(4), 1984, tests 1–8). A hit names the points (0-based) that end
each qualifying run. **Drift** is a hit of a trend rule (Nelson 3: six points in a row steadily
increasing or decreasing) or a shift rule (WE 2–4, Nelson 2, 5, 6) on the high side: it is flagged at the
point that completes the run, which for a slow drift comes before the point that fails the tolerance.

Capability against the ΔE tolerance (one-sided upper specification USL = the limit; ΔE is bounded
below by 0): Cp = (USL − 0) / 6σ̂ and Cpk = Cpu = (USL − μ) / 3σ̂ with the short-term σ̂ of the chart
(Montgomery §8.2); Ppk uses the overall sample standard deviation instead.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray
from typing_extensions import TypedDict

from station.model.domain import QC_SPC_SIGMAS
from station.qc.errors import QcInputError
from station.wire import wire_form

__all__ = [
    "CONSTANTS",
    "D2_RANGE_OF_TWO",
    "RULES",
    "Capability",
    "CapabilityWire",
    "Chart",
    "ChartWire",
    "ControlLimits",
    "RuleHit",
    "RuleHitWire",
    "capability",
    "control_limits",
    "drift_hits",
    "individuals_chart",
    "rule_hits",
    "xbar_r_chart",
]

#: Control-chart constants by subgroup size m: (A₂, d₂, D₃, D₄), Montgomery Appendix VI (= ASTM E2587
#: Table 6). d₂ is E[range of m standard normal values]; A₂ = 3 / (d₂√m); D₃,₄ = 1 ∓ 3d₃/d₂ (≥ 0).
CONSTANTS: dict[int, tuple[float, float, float, float]] = {
    2: (1.880, 1.128, 0.0, 3.267),
    3: (1.023, 1.693, 0.0, 2.574),
    4: (0.729, 2.059, 0.0, 2.282),
    5: (0.577, 2.326, 0.0, 2.114),
    6: (0.483, 2.534, 0.0, 2.004),
    7: (0.419, 2.704, 0.076, 1.924),
    8: (0.373, 2.847, 0.136, 1.864),
    9: (0.337, 2.970, 0.184, 1.816),
    10: (0.308, 3.078, 0.223, 1.777),
}
#: d₂ for subgroups of two: E[range of two standard normal values] = 2/√π.
D2_RANGE_OF_TWO = CONSTANTS[2][1]


class RuleHitWire(TypedDict):
    """A run rule that fired (``RuleHit.to_dict()``): its name, meaning and the 0-based points it names."""

    rule: str
    meaning: str
    points: list[int]


class ChartWire(TypedDict):
    """A control chart (``Chart.to_dict()``): ΔE (or |Δ| texture) points and lines in the points' units."""

    kind: str
    subgroup: int
    points: list[float]
    centre: float
    sigma: float
    sigma_process: float
    lcl: float
    ucl: float
    baseline: int
    hits: list[RuleHitWire]
    ranges: list[float]
    r_bar: float | None
    r_lcl: float | None
    r_ucl: float | None


class CapabilityWire(TypedDict):
    """Capability against the limit (``Capability.to_dict()``): USL, mean and σ in ΔE, the indices, the rule."""

    usl: float
    mean: float
    sigma_within: float
    sigma_overall: float
    cp: float | None
    cpk: float | None
    ppk: float | None
    rule: str


@dataclass(frozen=True)
class RuleHit:
    """A run rule that fired: its name, what it means, and the points (0-based) that end a qualifying run."""

    rule: str
    meaning: str
    points: tuple[int, ...]

    def to_dict(self) -> RuleHitWire:
        return {"rule": self.rule, "meaning": self.meaning, "points": list(self.points)}

    @classmethod
    def from_wire(cls, d: RuleHitWire) -> RuleHit:
        """The hit of its wire form (what :meth:`to_dict` returns)."""
        return cls(d["rule"], d["meaning"], tuple(int(p) for p in d["points"]))


def _side(z: NDArray[np.float64], k: float) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
    return z > k, z < -k


def _k_of_m(z: NDArray[np.float64], k: float, need: int, window: int) -> list[int]:
    """Ends of windows of *window* points with at least *need* beyond k σ on the same side."""
    hi, lo = _side(z, k)
    out = []
    for end in range(window - 1, z.size):
        w = slice(end - window + 1, end + 1)
        # the rule counts windows whose last point is itself beyond the zone (WE handbook)
        if (hi[end] and hi[w].sum() >= need) or (lo[end] and lo[w].sum() >= need):
            out.append(end)
    return out


def _same_side(z: NDArray[np.float64], run: int) -> list[int]:
    sign = np.sign(z)
    return [
        e for e in range(run - 1, z.size) if sign[e] != 0 and np.all(sign[e - run + 1 : e + 1] == sign[e])
    ]


def _trend(z: NDArray[np.float64], run: int) -> list[int]:
    d = np.sign(np.diff(z))
    return [e for e in range(run - 1, z.size) if abs(d[e - run + 1 : e].sum()) == run - 1]


def _alternating(z: NDArray[np.float64], run: int) -> list[int]:
    d = np.sign(np.diff(z))
    out = []
    for e in range(run - 1, z.size):
        seg = d[e - run + 1 : e]
        if np.all(seg != 0) and np.all(seg[1:] == -seg[:-1]):
            out.append(e)
    return out


def _all_within(z: NDArray[np.float64], run: int, k: float, inside: bool) -> list[int]:
    ok = np.abs(z) < k if inside else np.abs(z) > k
    return [e for e in range(run - 1, z.size) if np.all(ok[e - run + 1 : e + 1])]


_Rule = tuple[str, str, Callable[[NDArray[np.float64]], list[int]]]
#: Every run rule: (name, meaning, test on z = (x − centre) / σ). Western Electric rules 1–4 and Nelson 1–8.
RULES: tuple[_Rule, ...] = (
    (
        "WE1",
        f"one point beyond {QC_SPC_SIGMAS:g}σ (the control limit)",
        lambda z: [int(i) for i in np.flatnonzero(np.abs(z) > QC_SPC_SIGMAS)],
    ),
    ("WE2", "2 of 3 points beyond 2σ, same side", lambda z: _k_of_m(z, 2, 2, 3)),
    ("WE3", "4 of 5 points beyond 1σ, same side", lambda z: _k_of_m(z, 1, 4, 5)),
    ("WE4", "8 points in a row on one side of the centre", lambda z: _same_side(z, 8)),
    (
        "N1",
        f"one point beyond {QC_SPC_SIGMAS:g}σ (the control limit)",
        lambda z: [int(i) for i in np.flatnonzero(np.abs(z) > QC_SPC_SIGMAS)],
    ),
    ("N2", "9 points in a row on one side of the centre", lambda z: _same_side(z, 9)),
    ("N3", "6 points in a row steadily increasing or decreasing", lambda z: _trend(z, 6)),
    ("N4", "14 points in a row alternating up and down", lambda z: _alternating(z, 14)),
    ("N5", "2 of 3 points beyond 2σ, same side", lambda z: _k_of_m(z, 2, 2, 3)),
    ("N6", "4 of 5 points beyond 1σ, same side", lambda z: _k_of_m(z, 1, 4, 5)),
    ("N7", "15 points in a row within 1σ of the centre", lambda z: _all_within(z, 15, 1, True)),
    ("N8", "8 points in a row beyond 1σ, either side", lambda z: _all_within(z, 8, 1, False)),
)
_DRIFT = ("WE2", "WE3", "WE4", "N2", "N3", "N5", "N6")


def rule_hits(
    values: Sequence[float] | NDArray[np.float64], centre: float, sigma: float
) -> tuple[RuleHit, ...]:
    """Every rule of :data:`RULES` that fires on *values* for the chart's *centre* and *sigma* (> 0)."""
    x = np.asarray(values, dtype=float).reshape(-1)
    if sigma <= 0 or not math.isfinite(sigma):
        return ()
    z = (x - centre) / sigma
    out = []
    for name, meaning, test in RULES:
        points = test(z)
        if points:
            out.append(RuleHit(name, meaning, tuple(int(p) for p in points)))
    return tuple(out)


@dataclass(frozen=True)
class Chart:
    """A control chart: its points, centre, σ (of a plotted point), limits, baseline and rule hits.

    *kind* is ``individuals`` or ``xbar``; for ``xbar`` *ranges* are the subgroup ranges with their
    centre *r_bar* and limits *r_lcl*, *r_ucl*. *sigma_process* is σ̂ of one reading (MR̄/d₂ or R̄/d₂).
    """

    kind: str
    points: tuple[float, ...]
    centre: float
    sigma: float
    sigma_process: float
    lcl: float
    ucl: float
    baseline: int
    hits: tuple[RuleHit, ...]
    subgroup: int = 1
    ranges: tuple[float, ...] = ()
    r_bar: float | None = None
    r_lcl: float | None = None
    r_ucl: float | None = None

    @property
    def flagged(self) -> tuple[int, ...]:
        """Every point some rule names."""
        return tuple(sorted({p for h in self.hits for p in h.points}))

    def to_dict(self) -> ChartWire:
        return {
            "kind": self.kind,
            "subgroup": self.subgroup,
            "points": list(self.points),
            "centre": self.centre,
            "sigma": self.sigma,
            "sigma_process": self.sigma_process,
            "lcl": self.lcl,
            "ucl": self.ucl,
            "baseline": self.baseline,
            "hits": [h.to_dict() for h in self.hits],
            "ranges": list(self.ranges),
            "r_bar": self.r_bar,
            "r_lcl": self.r_lcl,
            "r_ucl": self.r_ucl,
        }

    @classmethod
    def from_wire(cls, d: ChartWire) -> Chart:
        """The chart of its wire form (what :meth:`to_dict` returns, e.g. from the service)."""
        return cls(
            d["kind"],
            tuple(map(float, d["points"])),
            d["centre"],
            d["sigma"],
            d["sigma_process"],
            d["lcl"],
            d["ucl"],
            d["baseline"],
            tuple(RuleHit.from_wire(h) for h in d["hits"]),
            d["subgroup"],
            tuple(map(float, d["ranges"])),
            d["r_bar"],
            d["r_lcl"],
            d["r_ucl"],
        )


def _values(values: Sequence[float], field: str, least: int) -> NDArray[np.float64]:
    x = np.asarray(values, dtype=float).reshape(-1)
    if x.size < least or not np.all(np.isfinite(x)):
        raise QcInputError(field, f"at least {least} finite values in time order", x.size)
    return x


def _baseline(n: int, baseline: int | None, least: int) -> int:
    b = n if baseline is None else baseline
    if not least <= b <= n:
        raise QcInputError("baseline", f"a number of points from {least} to {n}", baseline)
    return b


def individuals_chart(values: Sequence[float], baseline: int | None = None) -> Chart:
    """Individuals chart of *values* (module docstring), limits from the first *baseline* values (>= 2)."""
    x = _values(values, "values", 2)
    b = _baseline(x.size, baseline, 2)
    base = x[:b]
    sigma = float(np.abs(np.diff(base)).mean()) / D2_RANGE_OF_TWO
    centre = float(base.mean())
    return _chart("individuals", x, centre, sigma, sigma, QC_SPC_SIGMAS * sigma, b)


def xbar_r_chart(values: Sequence[float], subgroup: int, baseline: int | None = None) -> Chart:
    """X̄/R chart of *values* in consecutive subgroups of *subgroup* (2 … 10) readings (module docstring).

    A trailing incomplete subgroup is left out; *baseline* counts subgroups (>= 2).
    """
    if subgroup not in CONSTANTS:
        raise QcInputError("subgroup", f"a subgroup size from {min(CONSTANTS)} to {max(CONSTANTS)}", subgroup)
    x = _values(values, "values", 2 * subgroup)
    groups = x[: x.size // subgroup * subgroup].reshape(-1, subgroup)
    b = _baseline(groups.shape[0], baseline, 2)
    a2, d2, d3, d4 = CONSTANTS[subgroup]
    means, ranges = groups.mean(axis=1), np.ptp(groups, axis=1)
    r_bar = float(ranges[:b].mean())
    centre = float(means[:b].mean())
    half = a2 * r_bar
    chart = _chart("xbar", means, centre, half / 3.0, r_bar / d2, half, b)
    return replace(
        chart,
        subgroup=subgroup,
        ranges=tuple(map(float, ranges)),
        r_bar=r_bar,
        r_lcl=d3 * r_bar,
        r_ucl=d4 * r_bar,
    )


def _chart(
    kind: str, points: NDArray, centre: float, sigma: float, sigma_process: float, half: float, baseline: int
) -> Chart:
    """The chart of *points* about *centre* with limits ``centre ± half`` (the lower one at least 0: ΔE
    is not negative), *sigma* of a plotted point and the rule hits (:func:`rule_hits`) over all points."""
    return Chart(
        kind,
        tuple(map(float, points)),
        centre,
        sigma,
        sigma_process,
        max(0.0, centre - half),
        centre + half,
        baseline,
        rule_hits(points, centre, sigma),
    )


def drift_hits(chart: Chart) -> tuple[RuleHit, ...]:
    """The hits of the shift and trend rules (module docstring) whose runs end on the high side.

    A trend counts when it rises; a run on one side counts above the centre (ΔE growing).
    """
    z = (np.asarray(chart.points) - chart.centre) / chart.sigma if chart.sigma > 0 else None
    if z is None:
        return ()
    out = []
    for h in chart.hits:
        if h.rule not in _DRIFT:
            continue
        if h.rule == "N3":
            pts = tuple(p for p in h.points if z[p] > z[p - 1])
        else:
            pts = tuple(p for p in h.points if z[p] > 0)
        if pts:
            out.append(RuleHit(h.rule, h.meaning, pts))
    return tuple(out)


@dataclass(frozen=True)
class Capability:
    """Cp, Cpk (= Cpu) and Ppk of ΔE against its limit *usl* (module docstring); None when σ is 0."""

    usl: float
    mean: float
    sigma_within: float
    sigma_overall: float
    cp: float | None
    cpk: float | None
    ppk: float | None

    def to_dict(self) -> CapabilityWire:
        return {
            "usl": self.usl,
            "mean": self.mean,
            "sigma_within": self.sigma_within,
            "sigma_overall": self.sigma_overall,
            "cp": self.cp,
            "cpk": self.cpk,
            "ppk": self.ppk,
            "rule": "one-sided: Cp = USL / 6σ, Cpk = (USL − mean) / 3σ (σ within), Ppk with σ overall",
        }

    @classmethod
    def from_wire(cls, d: CapabilityWire) -> Capability:
        """The capability of its wire form (what :meth:`to_dict` returns)."""
        return cls(d["usl"], d["mean"], d["sigma_within"], d["sigma_overall"], d["cp"], d["cpk"], d["ppk"])


def capability(values: Sequence[float], usl: float, sigma_within: float) -> Capability:
    """Capability of *values* (ΔE) against the limit *usl* (> 0) with the chart's short-term σ."""
    x = _values(values, "values", 2)
    if not (math.isfinite(usl) and usl > 0):
        raise QcInputError("usl", "a positive ΔE limit", usl)
    mu = float(x.mean())
    s = float(x.std(ddof=1))

    def ratio(num: float, den: float) -> float | None:
        return num / den if den > 0 else None

    return Capability(
        usl,
        mu,
        sigma_within,
        s,
        ratio(usl, 6 * sigma_within),
        ratio(usl - mu, 3 * sigma_within),
        ratio(usl - mu, 3 * s),
    )


# ----------------------------------------------------------------- the individuals chart's limits alone


@dataclass(frozen=True)
class ControlLimits:
    """Centre line, σ̂ from the moving range, lower and upper control limits and the points beyond them."""

    centre: float
    sigma: float
    mr_bar: float
    lcl: float
    ucl: float
    out_of_control: tuple[int, ...]

    def to_dict(self) -> dict[str, Any]:
        rule = (
            f"individuals chart, sigma = mean moving range / {D2_RANGE_OF_TWO}, "
            f"limits centre ± {QC_SPC_SIGMAS:g} sigma (lower clipped at 0)"
        )
        return wire_form(self, after={"out_of_control": {"rule": rule}})


def control_limits(values: Sequence[float]) -> ControlLimits:
    """Individuals-chart limits of *values* in time order (module docstring); needs n >= 2 finite values."""
    x = _values(values, "values", 2)
    mr_bar = float(np.abs(np.diff(x)).mean())
    sigma = mr_bar / D2_RANGE_OF_TWO
    centre = float(x.mean())
    ucl = centre + QC_SPC_SIGMAS * sigma
    lcl = max(0.0, centre - QC_SPC_SIGMAS * sigma)
    out = tuple(int(i) for i in np.flatnonzero((x > ucl) | (x < lcl)))
    return ControlLimits(centre, sigma, mr_bar, lcl, ucl, out)
