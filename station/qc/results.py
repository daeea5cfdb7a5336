"""The results of a job's QC: a measurement found, a part's standard, a sample's verdict, a part, a job.

Frozen dataclasses with ``to_dict()`` (what ``station qc summary --json`` and the service answer),
built by :func:`station.qc.jobs.search_measurements` and :func:`station.qc.jobs.job_summary`.
"""

from __future__ import annotations

import datetime as dt
from dataclasses import dataclass, field
from typing import Any

from station.qc.illuminant_rows import IlluminantCheck, PairVerdict
from station.qc.panels import PanelMean
from station.qc.readings import Reading
from station.qc.repeats import RepeatSummary
from station.qc.texture import TextureVerdict
from station.qc.tolerance import QcVerdict, ToleranceSet, Verdict, worst_verdict

__all__ = ["JobSummary", "MeasurementRow", "PartSummary", "SampleResult", "StandardInfo"]


@dataclass(frozen=True)
class MeasurementRow:
    """One measurement found by :func:`search_measurements`, with its panel's job and part."""

    measurement_id: int
    panel_id: int | None
    job: str | None
    part: str | None
    instrument: str
    operator: str
    measured_at: dt.datetime
    reading: Reading

    def to_dict(self) -> dict[str, Any]:
        return {
            "measurement_id": self.measurement_id,
            "panel_id": self.panel_id,
            "job": self.job,
            "part": self.part,
            "instrument": self.instrument,
            "operator": self.operator,
            "measured_at": self.measured_at.isoformat(),
            "geometries": list(self.reading.geometries),
            "lab": [list(r) for r in self.reading.lab],
        }


@dataclass(frozen=True)
class StandardInfo:
    """Which standard a part is judged against: its Lab at the samples' geometries (*reading*) and, for
    a design, its Lab every :data:`CURVE_STEP_DEG` degrees over the samples' angle range (*curve*)."""

    job: str
    part: str
    measurement_id: int | None
    design_id: int | None
    created_at: dt.datetime
    reading: Reading
    curve: Reading | None = None
    averaged: PanelMean[MeasurementRow] | None = None

    def to_dict(self) -> dict[str, Any]:
        avg = self.averaged
        return {
            "job": self.job,
            "part": self.part,
            "measurement_id": self.measurement_id,
            "design_id": self.design_id,
            "created_at": self.created_at.isoformat(),
            "geometries": list(self.reading.geometries),
            "lab": [list(r) for r in self.reading.lab],
            "measurement_ids": [] if avg is None else list(avg.measurement_ids),
            "left_out": [] if avg is None else list(avg.left_out),
        }


@dataclass(frozen=True)
class SampleResult:
    """One sample of a part and its verdict against the part's standard.

    With panels averaged (:func:`job_summary` ``average_panels=True``) a sample is a panel: *row* is its
    newest measurement carrying the mean reading, *repeats* the repeat statistics,
    *measurement_ids* every reading of the panel and *left_out* the outliers not averaged
    (:mod:`station.qc.panels`).
    """

    row: MeasurementRow
    verdict: QcVerdict
    repeats: RepeatSummary | None = None
    measurement_ids: tuple[int, ...] = ()
    illuminants: IlluminantCheck | None = None
    left_out: tuple[int, ...] = ()
    texture: TextureVerdict | None = None

    @property
    def overall(self) -> Verdict:
        """The D65 verdict, or the worst of it, the illuminant rows' and the texture verdict when judged."""
        colour = PairVerdict(self.verdict, self.illuminants).verdict
        if self.texture is None:
            return colour
        return worst_verdict((colour, self.texture.verdict))

    def to_dict(self) -> dict[str, Any]:
        out = {**self.row.to_dict(), "qc": PairVerdict(self.verdict, self.illuminants).to_dict()}
        out["overall"] = self.overall
        if self.texture is not None:
            out["texture"] = self.texture.to_dict()
        if self.repeats is not None:
            out["repeats"] = self.repeats.to_dict()
            out["measurement_ids"] = list(self.measurement_ids)
            out["left_out"] = list(self.left_out)
        return out


@dataclass(frozen=True)
class PartSummary:
    """A part of a job: its standard (``None`` when it has none), its samples and their verdicts."""

    part: str
    standard: StandardInfo | None
    samples: tuple[SampleResult, ...]
    unjudged: tuple[MeasurementRow, ...] = field(default=())
    note: str = ""

    def counts(self) -> dict[str, int]:
        out = {"pass": 0, "warn": 0, "fail": 0}
        for s in self.samples:
            out[s.overall] += 1
        return out

    def to_dict(self) -> dict[str, Any]:
        return {
            "part": self.part,
            "standard": None if self.standard is None else self.standard.to_dict(),
            "counts": self.counts(),
            "samples": [s.to_dict() for s in self.samples],
            "unjudged": [r.measurement_id for r in self.unjudged],
            "note": self.note,
        }


@dataclass(frozen=True)
class JobSummary:
    """A job's parts with their standards and every sample's verdict, oldest sample first."""

    job: str
    formula: str
    tolerance: ToleranceSet | None
    parts: tuple[PartSummary, ...]
    generated_at: dt.datetime
    illuminant_limits: dict[str, float] | None = None

    def counts(self) -> dict[str, int]:
        out = {"pass": 0, "warn": 0, "fail": 0}
        for p in self.parts:
            for k, v in p.counts().items():
                out[k] += v
        return out

    def to_dict(self) -> dict[str, Any]:
        return {
            "job": self.job,
            "formula": self.formula,
            "tolerance": None if self.tolerance is None else self.tolerance.to_dict(),
            "counts": self.counts(),
            "parts": [p.to_dict() for p in self.parts],
            "generated_at": self.generated_at.isoformat(),
            "illuminant_limits": self.illuminant_limits,
        }
