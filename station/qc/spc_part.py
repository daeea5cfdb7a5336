"""SPC of one part of a job: per geometry the ΔE control chart, its rule hits, capability and drift.

:func:`part_spc` takes a :class:`~station.qc.jobs.JobSummary` (samples oldest first, one per panel when
panels were averaged) and charts each geometry's ΔE (:mod:`station.qc.spc`): an individuals chart, or an
X̄/R chart of consecutive subgroups. Capability is judged against the ΔE limit each sample was judged
with at that geometry (:attr:`station.qc.tolerance.GeometryVerdict.limit`), over the baseline period
(capability presumes a process in control: the points after the baseline are what the rules judge). **Drift** is a rising trend
or shift hit (:func:`station.qc.spc.drift_hits`); it is reported with the first sample that failed,
so a report says whether the drift was flagged before the fail.

**Texture** (a summary judged with texture limits, :mod:`station.qc.texture`): each texture quantity of
one vendor at one geometry (sparkle intensity, area and grade per geometry; graininess per sample) is
charted the same way, its points |Δ| = |sample − standard| in the vendor's units, its tolerance ΔS or ΔG
the limit, with the same rules, capability and drift. Values of another vendor are never judged against
the standard (:class:`~station.qc.texture.TextureVendorError`), so a chart never mixes vendors.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from typing_extensions import TypedDict

from station.qc.errors import QcInputError
from station.qc.jobs import JobSummary, PartSummary, SampleResult
from station.qc.spc import (
    CONSTANTS,
    Capability,
    CapabilityWire,
    Chart,
    ChartWire,
    RuleHit,
    RuleHitWire,
    capability,
    drift_hits,
    individuals_chart,
    xbar_r_chart,
)
from station.qc.texture import TextureRow

__all__ = ["GeometrySpc", "GeometrySpcWire", "PartSpc", "PartSpcWire", "part_spc", "sample_name"]


class GeometrySpcWire(TypedDict):
    """One chart of a part's SPC (``GeometrySpc.to_dict()``): what is charted, the chart, capability against
    the limit (``null`` without one), the drift hits and the first failing point (0-based; ``null``: none)."""

    geometry: str
    quantity: str
    vendor: str
    chart: ChartWire
    capability: CapabilityWire | None
    drift: list[RuleHitWire]
    first_fail: int | None
    drift_before_fail: bool


class PartSpcWire(TypedDict):
    """The SPC of a part (``PartSpc.to_dict()``, what ``station qc spc --json`` prints and the service
    answers): its samples in chart order, the baseline (points or subgroups; ``"all points"``), the chart
    kind, a chart per geometry and per texture quantity, and the drift in words."""

    job: str
    part: str
    samples: int
    sample_names: list[str]
    baseline: int | str
    chart: str
    geometries: list[GeometrySpcWire]
    texture: list[GeometrySpcWire]
    drift: list[str]


def sample_name(s: SampleResult) -> str:
    """A trial as a lab names it: its panel (or measurement), part and job, and its sample text."""
    r = s.row
    who = f"panel {r.panel_id}" if r.panel_id is not None else f"measurement {r.measurement_id}"
    extra = r.reading.sample
    named = f" “{extra}”" if extra and not extra.startswith(("standard", "panel ")) else ""
    return f"{who}{named}, {r.part}, {r.job}"


@dataclass(frozen=True)
class GeometrySpc:
    """One geometry's chart, capability (None without a limit) and drift hits, with the first failure.

    *quantity* is what is charted: ``ΔE``, or a texture quantity with its tolerance (``ΔS sparkle
    intensity``, ``ΔG graininess``) and its *vendor*; *geometry* is ``""`` for a per-sample texture value.
    """

    geometry: str
    chart: Chart
    capability: Capability | None
    drift: tuple[RuleHit, ...]
    first_fail: int | None
    quantity: str = "ΔE"
    vendor: str = ""

    @property
    def label(self) -> str:
        """The chart's name: the geometry for ΔE, else the quantity at its geometry (or ``sample``)."""
        if self.quantity == "ΔE":
            return self.geometry
        return f"{self.quantity} {self.geometry or 'sample'}"

    @property
    def drift_before_fail(self) -> bool:
        """True when a drift was flagged at a point before the first failing point (or with no fail)."""
        first = min((p for h in self.drift for p in h.points), default=None)
        return first is not None and (self.first_fail is None or first < self.first_fail)

    def to_dict(self) -> GeometrySpcWire:
        return {
            "geometry": self.geometry,
            "quantity": self.quantity,
            "vendor": self.vendor,
            "chart": self.chart.to_dict(),
            "capability": None if self.capability is None else self.capability.to_dict(),
            "drift": [h.to_dict() for h in self.drift],
            "first_fail": self.first_fail,
            "drift_before_fail": self.drift_before_fail,
        }

    @classmethod
    def from_wire(cls, d: GeometrySpcWire) -> GeometrySpc:
        """The chart of its wire form (what :meth:`to_dict` returns, e.g. from the service)."""
        cap = d["capability"]
        return cls(
            d["geometry"],
            Chart.from_wire(d["chart"]),
            None if cap is None else Capability.from_wire(cap),
            tuple(RuleHit.from_wire(h) for h in d["drift"]),
            d["first_fail"],
            d["quantity"],
            d["vendor"],
        )


@dataclass(frozen=True)
class PartSpc:
    """The SPC of a part: its samples' names in chart order and one :class:`GeometrySpc` per geometry."""

    job: str
    part: str
    samples: tuple[str, ...]
    baseline: int | None
    subgroup: int
    geometries: tuple[GeometrySpc, ...]
    texture: tuple[GeometrySpc, ...] = ()

    def drift_lines(self) -> list[str]:
        """Per geometry with a drift: where it was first flagged, by which rules, and whether before a fail.

        Samples are numbered from 1 in chart order (the chart's x axis); a subgroup by its last sample.
        """
        out = []
        step = self.subgroup
        for g in (*self.geometries, *self.texture):
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
            out.append(f"{g.label}: drift from sample #{at + 1} ({self.samples[at]}) by {rules}; {fail}")
        return out

    def to_dict(self) -> PartSpcWire:
        return {
            "job": self.job,
            "part": self.part,
            "samples": len(self.samples),
            "sample_names": list(self.samples),
            "baseline": "all points" if self.baseline is None else self.baseline,
            "chart": "individuals" if self.subgroup == 1 else f"X̄/R, subgroups of {self.subgroup}",
            "geometries": [g.to_dict() for g in self.geometries],
            "texture": [g.to_dict() for g in self.texture],
            "drift": self.drift_lines(),
        }

    @classmethod
    def from_wire(cls, d: PartSpcWire) -> PartSpc:
        """The SPC of its wire form (what :meth:`to_dict` returns: the service's ``GET /qc/jobs/{job}/spc``);
        the subgroup size is that of the charts (1 without any)."""
        charts = [*d["geometries"], *d["texture"]]
        subgroup = charts[0]["chart"]["subgroup"] if charts else 1
        baseline = d["baseline"] if isinstance(d["baseline"], int) else None
        return cls(
            d["job"],
            d["part"],
            tuple(d["sample_names"]),
            baseline,
            subgroup,
            tuple(GeometrySpc.from_wire(g) for g in d["geometries"]),
            tuple(GeometrySpc.from_wire(g) for g in d["texture"]),
        )


def _part(summary: JobSummary, part: str) -> PartSummary:
    match = [p for p in summary.parts if p.part == part]
    if not match:
        raise QcInputError(
            "part", f"a part of job {summary.job} ({', '.join(p.part for p in summary.parts)})", part
        )
    return match[0]


def _spc(
    values: Sequence[float],
    verdicts: Sequence[str | None],
    limit: float | None,
    baseline: int | None,
    subgroup: int,
) -> tuple[Chart, Capability | None, int | None]:
    """The chart of *values* (time order), its capability against *limit* over the baseline, and the
    first point (subgroup) whose verdict is ``fail``."""
    chart = individuals_chart(values, baseline) if subgroup == 1 else xbar_r_chart(values, subgroup, baseline)
    fails = [i for i, v in enumerate(verdicts) if v == "fail"]
    first_fail = None if not fails else fails[0] // subgroup
    base = values[: chart.baseline * subgroup]  # capability of the in-control baseline period
    cap = None if limit is None else capability(base, limit, chart.sigma_process)
    return chart, cap, first_fail


def _geometry(samples: Sequence[SampleResult], name: str, baseline: int | None, subgroup: int) -> GeometrySpc:
    by = [next((g for g in s.verdict.per_geometry if g.geometry == name), None) for s in samples]
    got = [g for g in by if g is not None]
    chart, cap, first_fail = _spc(
        [g.de for g in got], [g.verdict for g in got], got[0].limit, baseline, subgroup
    )
    return GeometrySpc(name, chart, cap, drift_hits(chart), first_fail)


def _texture(samples: Sequence[SampleResult], baseline: int | None, subgroup: int) -> tuple[GeometrySpc, ...]:
    """One chart per judged texture quantity (vendor, name, geometry); a quantity judged on fewer samples than
    two subgroups, or than the baseline, has none."""
    series: dict[tuple[str, str, str], list[TextureRow]] = {}
    for s in samples:
        if s.texture is None:
            continue
        for r in s.texture.rows:
            if r.delta is not None and r.verdict is not None:
                series.setdefault((s.texture.vendor, r.name, r.geometry), []).append(r)
    out = []
    for (vendor, name, geometry), rows in series.items():
        if len(rows) < max(2, baseline or 0) * subgroup:
            continue
        values = [abs(r.delta) for r in rows if r.delta is not None]
        chart, cap, first_fail = _spc(values, [r.verdict for r in rows], rows[0].limit, baseline, subgroup)
        quantity = f"{rows[0].tolerance} {name}"
        out.append(GeometrySpc(geometry, chart, cap, drift_hits(chart), first_fail, quantity, vendor))
    return tuple(out)


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
    texture = _texture(samples, baseline, subgroup)
    trials = tuple(sample_name(s) for s in samples)
    return PartSpc(summary.job, part, trials, baseline, subgroup, geoms, texture)
