"""SPC of one part of a job: per geometry the ΔE control chart, its rule hits, capability and drift.

:func:`part_spc` takes a :class:`~station.qc.jobs.JobSummary` (samples oldest first, one per panel when
panels were averaged) and charts each geometry's ΔE (:mod:`station.qc.spc`): an individuals chart, or an
X̄/R chart of consecutive subgroups. Capability is judged against the ΔE limit each sample was judged
with at that geometry (:attr:`station.qc.tolerance.GeometryVerdict.limit`), over the baseline period
(capability presumes a process in control: the points after the baseline are what the rules judge). **Drift** is a rising trend
or shift hit (:func:`station.qc.spc.drift_hits`); it is reported with the first sample that failed,
so a report says whether the drift was flagged before the fail.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from station.qc.errors import QcInputError
from station.qc.jobs import JobSummary, PartSummary, SampleResult
from station.qc.spc import (
    CONSTANTS,
    Capability,
    Chart,
    RuleHit,
    capability,
    drift_hits,
    individuals_chart,
    xbar_r_chart,
)

__all__ = ["GeometrySpc", "PartSpc", "part_spc", "sample_name"]


def sample_name(s: SampleResult) -> str:
    """A trial as a lab names it: its panel (or measurement), part and job, and its sample text."""
    r = s.row
    who = f"panel {r.panel_id}" if r.panel_id is not None else f"measurement {r.measurement_id}"
    extra = r.reading.sample
    named = f" “{extra}”" if extra and not extra.startswith(("standard", "panel ")) else ""
    return f"{who}{named}, {r.part}, {r.job}"


@dataclass(frozen=True)
class GeometrySpc:
    """One geometry's chart, capability (None without a limit) and drift hits, with the first failure."""

    geometry: str
    chart: Chart
    capability: Capability | None
    drift: tuple[RuleHit, ...]
    first_fail: int | None

    @property
    def drift_before_fail(self) -> bool:
        """True when a drift was flagged at a point before the first failing point (or with no fail)."""
        first = min((p for h in self.drift for p in h.points), default=None)
        return first is not None and (self.first_fail is None or first < self.first_fail)

    def to_dict(self) -> dict[str, Any]:
        return {
            "geometry": self.geometry,
            "chart": self.chart.to_dict(),
            "capability": None if self.capability is None else self.capability.to_dict(),
            "drift": [h.to_dict() for h in self.drift],
            "first_fail": self.first_fail,
            "drift_before_fail": self.drift_before_fail,
        }


@dataclass(frozen=True)
class PartSpc:
    """The SPC of a part: its samples' names in chart order and one :class:`GeometrySpc` per geometry."""

    job: str
    part: str
    samples: tuple[str, ...]
    baseline: int | None
    subgroup: int
    geometries: tuple[GeometrySpc, ...]

    def drift_lines(self) -> list[str]:
        """Per geometry with a drift: where it was first flagged, by which rules, and whether before a fail.

        Samples are numbered from 1 in chart order (the chart's x axis); a subgroup by its last sample.
        """
        out = []
        step = self.subgroup
        for g in self.geometries:
            first = min((p for h in g.drift for p in h.points), default=None)
            if first is None:
                continue
            rules = ", ".join(h.rule for h in g.drift if first in h.points)
            at = first * step + step - 1
            if g.first_fail is None:
                fail = "no fail yet"
            else:
                when = "before" if first < g.first_fail else "at or after"
                fail = f"{when} the first fail (sample #{g.first_fail * step + step})"
            out.append(f"{g.geometry}: drift from sample #{at + 1} ({self.samples[at]}) by {rules}; {fail}")
        return out

    def to_dict(self) -> dict[str, Any]:
        return {
            "job": self.job,
            "part": self.part,
            "samples": len(self.samples),
            "sample_names": list(self.samples),
            "baseline": "all points" if self.baseline is None else self.baseline,
            "chart": "individuals" if self.subgroup == 1 else f"X̄/R, subgroups of {self.subgroup}",
            "geometries": [g.to_dict() for g in self.geometries],
            "drift": self.drift_lines(),
        }


def _part(summary: JobSummary, part: str) -> PartSummary:
    match = [p for p in summary.parts if p.part == part]
    if not match:
        raise QcInputError(
            "part", f"a part of job {summary.job} ({', '.join(p.part for p in summary.parts)})", part
        )
    return match[0]


def _geometry(samples: Sequence[SampleResult], name: str, baseline: int | None, subgroup: int) -> GeometrySpc:
    by = [next((g for g in s.verdict.per_geometry if g.geometry == name), None) for s in samples]
    got = [g for g in by if g is not None]
    values = [g.de for g in got]
    if subgroup == 1:
        chart = individuals_chart(values, baseline)
    else:
        chart = xbar_r_chart(values, subgroup, baseline)
    fails = [i for i, g in enumerate(got) if g.verdict == "fail"]
    first_fail = None if not fails else fails[0] // subgroup
    limit = got[0].limit
    base = values[: chart.baseline * subgroup]  # capability of the in-control baseline period
    cap = None if limit is None else capability(base, limit, chart.sigma_process)
    return GeometrySpc(name, chart, cap, drift_hits(chart), first_fail)


def part_spc(summary: JobSummary, part: str, baseline: int | None = None, subgroup: int = 1) -> PartSpc:
    """Per geometry the SPC of *part*'s samples (module docstring); *baseline* points (subgroups) set
    the centre and limits (all when None); *subgroup* 1 is an individuals chart, 2 … 10 an X̄/R chart."""
    if subgroup != 1 and subgroup not in CONSTANTS:
        raise QcInputError(
            "subgroup", f"1 (individuals) or a subgroup size from 2 to {max(CONSTANTS)}", subgroup
        )
    p = _part(summary, part)
    samples = list(p.samples)
    if len(samples) < 2 * max(subgroup, 1):
        raise QcInputError(
            "part", f"a part with at least {2 * max(subgroup, 1)} judged samples", len(samples)
        )
    names: list[str] = []
    for s in samples:
        names += [g.geometry for g in s.verdict.per_geometry if g.geometry not in names]
    geoms = tuple(_geometry(samples, n, baseline, subgroup) for n in names)
    return PartSpc(summary.job, part, tuple(sample_name(s) for s in samples), baseline, subgroup, geoms)
