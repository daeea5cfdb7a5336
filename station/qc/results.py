"""The results of a job's QC: a measurement found, a part's standard, a sample's verdict, a part, a job.

Frozen dataclasses with ``to_dict()``, built by :func:`station.qc.jobs.search_measurements` and
:func:`station.qc.jobs.job_summary`. What ``to_dict()`` returns is typed by the ``*Wire`` TypedDicts
below: they are the one definition of the wire form, which ``station qc summary --json`` prints and the
service answers (its response models are these TypedDicts, :mod:`station.api.schemas.qc`). The part and
the job are generic in their sample's form, so the service can add what it pairs with a sample (its gloss
reading) without a second copy of the fields.
"""

from __future__ import annotations

import datetime as dt
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Generic, NotRequired, TypeVar, cast

from typing_extensions import TypedDict

from station.qc.illuminant_rows import IlluminantCheck, PairVerdict, PairVerdictWire
from station.qc.panels import PanelMean
from station.qc.readings import Reading
from station.qc.repeats import RepeatSummary, RepeatSummaryWire
from station.qc.texture import TextureTolerance, TextureVerdict, TextureVerdictWire
from station.qc.tolerance import QcVerdict, ToleranceSet, Verdict

__all__ = [
    "JobSummary",
    "JobSummaryWire",
    "LeftOutWire",
    "MeasurementRow",
    "MeasurementRowWire",
    "PartSummary",
    "PartSummaryWire",
    "SampleResult",
    "SampleWire",
    "StandardInfo",
    "StandardWire",
    "left_out_readings",
]


class MeasurementRowWire(TypedDict):
    """A stored measurement with its panel's job and part: Lab (D65/10°) per geometry, oldest first."""

    measurement_id: int
    measured_at: str
    instrument: str
    operator: str
    panel_id: int | None
    job: str | None
    part: str | None
    geometries: list[str]
    lab: list[list[float]]


class LeftOutWire(TypedDict):
    """A repeat reading left out of a panel's mean: its robust z (above the outlier threshold) and its
    mean ΔE*ab to the median reading (:mod:`station.qc.repeats`)."""

    measurement_id: int
    robust_z: float | None
    de_to_centre: float


class StandardWire(TypedDict):
    """A part's standard as judged: its ids, its Lab at the samples' geometries and, when averaged, the
    readings averaged and those left out."""

    job: str
    part: str
    measurement_id: int | None
    design_id: int | None
    created_at: str
    geometries: list[str]
    lab: list[list[float]]
    measurement_ids: list[int]
    left_out: list[int]
    left_out_readings: list[LeftOutWire]


class SampleWire(MeasurementRowWire):
    """A sample and its verdict: ``qc`` (per-geometry ΔE and the limit used there), ``overall`` (the worst
    of colour, illuminant rows and texture), ``texture`` (ΔS/ΔG within one vendor, with limits); for a
    panel averaged, its repeat statistics, every reading and those left out of the mean."""

    qc: PairVerdictWire
    overall: Verdict
    texture: NotRequired[TextureVerdictWire]
    repeats: NotRequired[RepeatSummaryWire]
    measurement_ids: NotRequired[list[int]]
    left_out: NotRequired[list[int]]
    left_out_readings: NotRequired[list[LeftOutWire]]


S = TypeVar("S", bound=SampleWire)
P = TypeVar("P")


class PartSummaryWire(TypedDict, Generic[S]):
    """A part: its standard (``null`` when none is set), pass/warn/fail counts, samples and those unjudged."""

    part: str
    standard: StandardWire | None
    counts: dict[str, int]
    samples: list[S]
    unjudged: list[int]
    note: str


class JobSummaryWire(TypedDict, Generic[P]):
    """Every part of a job with its standard and each sample's verdict, oldest sample first; the tolerance
    set used (per-geometry limits) and the texture limits (ΔS, ΔG) when texture was judged."""

    job: str
    formula: str
    tolerance: dict[str, object] | None
    counts: dict[str, int]
    parts: list[P]
    generated_at: str
    illuminant_limits: dict[str, float] | None
    texture_limits: dict[str, float | None] | None
    averaged: bool
    outliers_kept: bool


def left_out_readings(
    repeats: RepeatSummary | None, measurement_ids: Sequence[int], left_out: Sequence[int]
) -> list[LeftOutWire]:
    """The readings *left_out* of a mean with their robust z and ΔE*ab to the centre (*measurement_ids*
    are the readings in the order *repeats* summarised them)."""
    if repeats is None:
        return []
    out: list[LeftOutWire] = []
    for mid, z, de in zip(measurement_ids, repeats.robust_z, repeats.reading_de, strict=True):
        if mid in left_out:
            out.append(
                {"measurement_id": mid, "robust_z": z if math.isfinite(z) else None, "de_to_centre": de}
            )
    return out


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

    def to_dict(self) -> MeasurementRowWire:
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

    def to_dict(self) -> StandardWire:
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
            "left_out_readings": []
            if avg is None
            else left_out_readings(avg.repeats, avg.measurement_ids, avg.left_out),
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
        rank = {"pass": 0, "warn": 1, "fail": 2}
        return colour if rank[colour] >= rank[self.texture.verdict] else self.texture.verdict

    def to_dict(self) -> SampleWire:
        verdict = PairVerdict(self.verdict, self.illuminants).to_dict()
        # the row's keys and the two required ones; mypy cannot see a ** item's keys as complete
        out = cast(SampleWire, {**self.row.to_dict(), "qc": verdict, "overall": self.overall})
        if self.texture is not None:
            out["texture"] = self.texture.to_dict()
        if self.repeats is not None:
            out["repeats"] = self.repeats.to_dict()
            out["measurement_ids"] = list(self.measurement_ids)
            out["left_out"] = list(self.left_out)
            out["left_out_readings"] = left_out_readings(self.repeats, self.measurement_ids, self.left_out)
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

    def to_dict(self) -> PartSummaryWire[SampleWire]:
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
    texture_limits: TextureTolerance | None = None
    averaged: bool = False
    outliers_kept: bool = False

    def counts(self) -> dict[str, int]:
        out = {"pass": 0, "warn": 0, "fail": 0}
        for p in self.parts:
            for k, v in p.counts().items():
                out[k] += v
        return out

    def to_dict(self) -> JobSummaryWire[PartSummaryWire[SampleWire]]:
        tex = self.texture_limits
        return {
            "job": self.job,
            "formula": self.formula,
            "tolerance": None if self.tolerance is None else self.tolerance.to_dict(),
            "counts": self.counts(),
            "parts": [p.to_dict() for p in self.parts],
            "generated_at": self.generated_at.isoformat(),
            "illuminant_limits": self.illuminant_limits,
            "texture_limits": None if tex is None else {"ds": tex.ds, "dg": tex.dg},
            "averaged": self.averaged,
            "outliers_kept": self.outliers_kept,
        }
