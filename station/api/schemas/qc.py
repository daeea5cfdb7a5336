"""Colour QC: gloss readings, the paired measurement view, checks against standards, job summaries."""

from __future__ import annotations

import datetime as dt
import uuid
from typing import Annotated, Any

from pydantic import BaseModel, ConfigDict, Field, model_validator

from station.api.schemas.common import StrictInt
from station.api.schemas.measurements import MeasurementPublic
from station.ingest.schema import MAX_GEOMETRIES, Angle, LabTriple
from station.qc.illuminant_rows import PairVerdictWire
from station.qc.results import JobSummaryWire, PartSummaryWire, SampleWire
from station.schema_config import strict_config


class GlossPublic(BaseModel):
    """A stored, immutable gloss reading (gloss in GU per geometry, haze HU, DOI 0–100, Rspec GU)."""

    model_config = ConfigDict(from_attributes=True)

    id: int
    client_id: uuid.UUID
    panel_id: int | None
    measurement_id: int | None
    instrument_id: int
    calibration_id: int | None
    operator: str
    measured_at: dt.datetime
    received_at: dt.datetime
    gloss_20_gu: float | None
    gloss_60_gu: float | None
    gloss_85_gu: float | None
    haze_hu: float | None
    log_haze: float | None
    doi: float | None
    rspec_gu: float | None
    payload_sha256: str
    created_by_id: int | None


class QcMeasurement(MeasurementPublic):
    """A colour measurement with its panel's job and part and the gloss reading paired with it."""

    job: str | None = None
    part: str | None = None
    gloss: GlossPublic | None = Field(
        default=None, description="the gloss reading of the same panel paired with this measurement"
    )


class GlossMeasureRequest(BaseModel):
    """Measure on an attached gloss meter: gloss-only on a panel, or joining a colour measurement."""

    model_config = strict_config(examples=[{"panel_id": 1}])

    instrument_id: Annotated[
        str, Field(min_length=1, max_length=80, pattern=r"^[a-z0-9_.-]+$", examples=["gloss-gl-0001"])
    ]
    panel_id: Annotated[StrictInt, Field(ge=1, le=2**31 - 1)] | None = None
    measurement_id: Annotated[StrictInt, Field(ge=1, le=2**31 - 1)] | None = None


class LabSource(BaseModel):
    """A standard or a sample: a stored measurement, or Lab per aspecular angle given inline."""

    model_config = strict_config(
        examples=[
            {"measurement_id": 1},
            {
                "geometries_deg": [15.0, 45.0, 110.0],
                "lab": [[82.1, -1.2, -18.5], [55.3, -0.4, -12.0], [31.9, 0.8, -6.2]],
            },
        ]
    )

    measurement_id: Annotated[StrictInt, Field(ge=1, le=2**31 - 1)] | None = None
    geometries_deg: Annotated[list[Angle], Field(min_length=1, max_length=MAX_GEOMETRIES)] | None = None
    lab: Annotated[list[LabTriple], Field(min_length=1, max_length=MAX_GEOMETRIES)] | None = None

    @model_validator(mode="after")
    def _one_source(self) -> LabSource:
        inline = self.geometries_deg is not None or self.lab is not None
        if (self.measurement_id is not None) == inline:
            raise ValueError("measurement_id: expected a measurement_id or geometries_deg with lab, not both")
        if inline:
            if self.geometries_deg is None or self.lab is None:
                raise ValueError("lab: expected geometries_deg and lab together")
            if len(self.lab) != len(self.geometries_deg):
                raise ValueError(f"lab: expected one [L*, a*, b*] per geometry ({len(self.geometries_deg)})")
            if len(set(self.geometries_deg)) != len(self.geometries_deg):
                raise ValueError("geometries_deg: expected distinct angles")
        return self


class CheckRequest(BaseModel):
    """A sample judged against a standard over their common geometries.

    ``tolerance`` is a tolerance set as ``station qc tolerance --json`` writes it; without it the
    limits are ``de_limit`` (default the domain's QC limit) at every common geometry with ``formula``.
    """

    model_config = strict_config(
        examples=[{"standard": {"measurement_id": 1}, "sample": {"measurement_id": 2}, "formula": "din6175"}]
    )

    standard: LabSource
    sample: LabSource
    formula: Annotated[str, Field(min_length=1, max_length=32, examples=["din6175", "cie2000"])] | None = None
    de_limit: Annotated[float, Field(strict=True, gt=0.0, le=100.0, allow_inf_nan=False)] | None = None
    tolerance: dict[str, Any] | None = None
    illuminant_limits: (
        Annotated[
            dict[Annotated[str, Field(min_length=1, max_length=32)], float],
            Field(
                min_length=1,
                max_length=8,
                description="illuminant rows: {test illuminant: limit on the metamerism index from D65, in "
                'the formula\'s ΔE units}, e.g. {"A": 1.0}; both measurements need spectra',
                examples=[{"A": 1.0, "F11": 1.5}],
            ),
        ]
        | None
    ) = None

    @model_validator(mode="after")
    def _set_or_options(self) -> CheckRequest:
        if self.tolerance is not None and (self.formula is not None or self.de_limit is not None):
            raise ValueError("tolerance: expected a tolerance set or formula/de_limit, not both")
        return self


class CheckResult(PairVerdictWire):
    """Overall verdict with the reason, per-geometry verdicts (with the ΔE limit used at each), mean and max
    ΔE and the worst geometry (``station.qc.illuminant_rows.PairVerdictWire``), and the ids judged.

    With illuminant rows, ``verdict`` is the worse of ``d65_verdict`` and ``illuminants.verdict``."""

    standard_measurement_id: int | None
    sample_measurement_id: int | None


class StandardSet(BaseModel):
    """Make a stored measurement or a design the standard of a job and part (exactly one id)."""

    model_config = strict_config(examples=[{"measurement_id": 1, "notes": "master panel"}])

    measurement_id: Annotated[StrictInt, Field(ge=1, le=2**31 - 1)] | None = None
    design_id: Annotated[StrictInt, Field(ge=1, le=2**31 - 1)] | None = None
    notes: Annotated[str, Field(max_length=4000)] = ""
    replace: Annotated[bool, Field(strict=True, description="replace the part's existing standard")] = False


class StandardOut(BaseModel):
    """The standard of a job and part (a reference measurement or a design) and who set it when."""

    model_config = ConfigDict(from_attributes=True)

    id: int
    job: str
    part: str
    measurement_id: int | None
    design_id: int | None
    notes: str
    created_at: dt.datetime
    created_by_id: int | None


class JobOut(BaseModel):
    """A job: its parts, panel and measurement counts, first and last reading time."""

    job: str
    parts: list[str]
    panels: int
    measurements: int
    first_measured: dt.datetime | None
    last_measured: dt.datetime | None


class SampleVerdict(SampleWire):
    """One sample of a part (``station.qc.results.SampleWire``) with the gloss reading paired with it."""

    gloss: GlossPublic | None


#: A part of a job summary: its samples carry their paired gloss readings.
PartSummaryOut = PartSummaryWire[SampleVerdict]
#: Every part of a job with its standard and each sample's verdict (``station.qc.results.JobSummaryWire``).
JobSummaryOut = JobSummaryWire[PartSummaryOut]


class JudgeOptions(BaseModel):
    """How a job is judged, as a body: the summary's query options (``GET /qc/jobs/{job}/summary``) and a
    ``tolerance`` set as ``station qc tolerance --json`` writes it (``station qc summary --tolerance``)."""

    model_config = strict_config(
        examples=[
            {
                "tolerance": {"formula": "cie2000", "geometries": [{"geometry": "45as45", "de": 0.6}]},
                "average_panels": True,
            }
        ]
    )

    tolerance: dict[str, Any]
    formula: Annotated[str, Field(min_length=1, max_length=32)] | None = None
    illuminant_limits: Annotated[str, Field(min_length=1, max_length=200)] | None = None
    average_panels: Annotated[bool, Field(strict=True)] = False
    keep_outliers: Annotated[bool, Field(strict=True)] = False
    texture_limits: Annotated[str, Field(min_length=1, max_length=64)] | None = None


class SpcJudgeOptions(JudgeOptions):
    """The SPC's chart (``part``, ``baseline``, ``subgroup`` as ``GET /qc/jobs/{job}/spc`` takes them)
    with how the job is judged, tolerance set included."""

    model_config = strict_config(
        examples=[
            {
                "part": "fender",
                "baseline": 6,
                "tolerance": {"formula": "cie2000", "geometries": [{"geometry": "45as45", "de": 0.6}]},
            }
        ]
    )

    part: Annotated[str, Field(min_length=1, max_length=64)]
    baseline: StrictInt | None = None
    subgroup: StrictInt = 1


class MetamerismRequest(BaseModel):
    """Two stored measurements with spectra (400–700 nm, 10 nm): the standard and the sample."""

    model_config = strict_config(examples=[{"standard_measurement_id": 1, "sample_measurement_id": 2}])

    standard_measurement_id: Annotated[StrictInt, Field(ge=1, le=2**31 - 1)]
    sample_measurement_id: Annotated[StrictInt, Field(ge=1, le=2**31 - 1)]
    formula: Annotated[str, Field(min_length=1, max_length=32)] = "cie2000"


class MetamerismGeometry(BaseModel):
    """ΔE under D65 and the metamerism index under A and F11 at one geometry."""

    geometry: str
    aspecular_deg: float
    dE_D65: float
    MI_A: float
    MI_F11: float


class MetamerismOut(BaseModel):
    """The metamerism index (D65 → A, F11) per geometry and its maximum per test illuminant."""

    formula: str
    reference_illuminant: str
    per_geometry: list[MetamerismGeometry]
    max_index: dict[str, float]


class RepeatsRequest(BaseModel):
    """Repeat readings of one panel (stored measurement ids, N >= 1)."""

    model_config = strict_config(examples=[{"measurement_ids": [1, 2, 3]}])

    measurement_ids: Annotated[
        list[Annotated[StrictInt, Field(ge=1, le=2**31 - 1)]], Field(min_length=1, max_length=100)
    ]


class RepeatGeometry(BaseModel):
    """Mean Lab and its standard deviation (per channel and as ΔE*ab) at one geometry."""

    geometry: str
    aspecular_deg: float
    mean: list[float]
    sd: list[float] | None
    sd_de: float | None


class RepeatReading(BaseModel):
    """One repeat reading: its ΔE*ab to the centre, robust z and outlier flag."""

    index: int
    measurement_id: int
    de_to_centre: float
    robust_z: float | None
    outlier: bool


class RepeatsOut(BaseModel):
    """Mean of N readings with per-geometry sd and outlier flags (the rule named)."""

    n: int
    per_geometry: list[RepeatGeometry]
    readings: list[RepeatReading]
    outliers: list[int]
    mean_without_outliers: list[list[float]]
    rule: str
