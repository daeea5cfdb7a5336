"""Colour QC through the service: gloss readings, the measurement view that pairs them with colour,
checks, standards, job summaries, metamerism, repeat readings and reports.

The pairing rule is ``station.ingest.pair_gloss`` (linked reading first, else the same panel's
nearest in time within ``station.ingest.PAIR_WINDOW``), applied by
``station.ingest.gloss_of_measurements`` over every colour measurement of the panels concerned, so a
reading pairs the same way whatever page it is seen on. Everything colorimetric is ``station.qc``'s
(which applies ``station.qc.tolerance``); this module only maps requests and rows onto it.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, cast

from sqlalchemy import func, select
from sqlalchemy.orm import Session

from db.models import GlossReading, Measurement, Panel, User
from station.api.errors import NotFoundError
from station.api.schemas.measurements import MeasurementPublic, MeasurementQuery
from station.api.schemas.qc import (
    CheckRequest,
    CheckResult,
    GlossPublic,
    JobOut,
    JobSummaryOut,
    LabSource,
    MetamerismOut,
    MetamerismRequest,
    PartSummaryOut,
    QcMeasurement,
    RepeatsOut,
    RepeatsRequest,
    StandardOut,
    StandardSet,
)
from station.api.services import audit
from station.api.services import measurements as measurement_service
from station.errors import InputError
from station.ingest import GlossRecord, gloss_of_measurements, store_gloss
from station.model.domain import QC_FORMULA
from station.qc import jobs
from station.qc.check import check_pair, formula_name
from station.qc.illuminant_rows import PairVerdict, check_illuminants, parse_illuminant_limits
from station.qc.metamerism import metamerism
from station.qc.readings import Reading, reading_from_measurement
from station.qc.repeats import summarise
from station.qc.spc_part import PartSpc
from station.qc.texture import parse_texture_limits
from station.qc.tolerance import ToleranceSet


def get_gloss(*, session: Session, gloss_id: int) -> GlossPublic:
    """Gloss reading *gloss_id* or :class:`NotFoundError`."""
    row = session.get(GlossReading, gloss_id)
    if row is None:
        raise NotFoundError(f"gloss reading {gloss_id} not found")
    return GlossPublic.model_validate(row)


def ingest_gloss(*, session: Session, actor: User, record: GlossRecord) -> tuple[GlossPublic, bool]:
    """Store *record* once with its audit row; ``(reading, created)``."""
    result = store_gloss(session, record, created_by_id=actor.id)
    stored = get_gloss(session=session, gloss_id=result.measurement_id)
    session.commit()
    return stored, result.created


def list_gloss(
    *, session: Session, job: str | None, part: str | None, panel_id: int | None, limit: int, offset: int
) -> tuple[list[GlossPublic], int]:
    """Gloss readings of a job, part and/or panel, newest first."""
    query = select(GlossReading).outerjoin(Panel, Panel.id == GlossReading.panel_id)
    if job:
        query = query.where(Panel.job == job)
    if part:
        query = query.where(Panel.part == part)
    if panel_id is not None:
        query = query.where(GlossReading.panel_id == panel_id)
    total = session.scalar(
        select(func.count()).select_from(query.with_only_columns(GlossReading.id).subquery())
    )
    rows = session.scalars(
        query.order_by(GlossReading.measured_at.desc(), GlossReading.id.desc()).limit(limit).offset(offset)
    ).all()
    return [GlossPublic.model_validate(r) for r in rows], total or 0


def paired(*, session: Session, measurements: Sequence[MeasurementPublic]) -> list[QcMeasurement]:
    """*measurements* with their panel's job and part and their paired gloss reading (or ``None``)."""
    gloss = gloss_of_measurements(session, [m.id for m in measurements])
    panel_ids = {m.panel_id for m in measurements if m.panel_id is not None}
    panels = {p.id: p for p in session.scalars(select(Panel).where(Panel.id.in_(panel_ids))).all()}
    out: list[QcMeasurement] = []
    for m in measurements:
        g = gloss.get(m.id)
        panel = panels.get(m.panel_id) if m.panel_id is not None else None
        out.append(
            QcMeasurement(
                **m.model_dump(),
                job=panel.job if panel else None,
                part=panel.part if panel else None,
                gloss=GlossPublic.model_validate(g) if g is not None else None,
            )
        )
    return out


def list_measurements(
    *, session: Session, q: MeasurementQuery, limit: int, offset: int
) -> tuple[list[QcMeasurement], int]:
    """Measurements matching *q* (job, part, panel, instrument, time), newest first, gloss paired."""
    rows, total = measurement_service.query(session=session, q=q, limit=limit, offset=offset)
    return paired(session=session, measurements=rows), total


def get_measurement(*, session: Session, measurement_id: int) -> QcMeasurement:
    """One measurement with its gloss reading, or :class:`NotFoundError`."""
    m = measurement_service.get_measurement(session=session, measurement_id=measurement_id)
    return paired(session=session, measurements=[m])[0]


def _reading(session: Session, source: LabSource, field: str) -> Reading:
    """*source* as a QC reading: a stored measurement (404 when missing) or the inline Lab."""
    if source.measurement_id is not None:
        m = session.get(Measurement, source.measurement_id)
        if m is None:
            raise NotFoundError(f"{field}.measurement_id: measurement {source.measurement_id} not found")
        return reading_from_measurement(m, sample=f"measurement {m.id}")
    angles, labs = source.geometries_deg or [], source.lab or []  # both given: the schema's rule
    return Reading(tuple(angles), tuple((lab[0], lab[1], lab[2]) for lab in labs), sample=field, where=field)


def _tolerance(request: CheckRequest, angles: Sequence[float]) -> ToleranceSet | None:
    """The request's tolerance set, or ``de_limit`` at every angle, or ``None`` (the product default)."""
    if request.tolerance is not None:
        return ToleranceSet.from_dict(request.tolerance)
    if request.de_limit is not None:
        return ToleranceSet.uniform(
            tuple(angles),
            request.de_limit,
            formula=formula_name(request.formula or QC_FORMULA),
            mean_limit=request.de_limit,
        )
    return None


def check(*, session: Session, request: CheckRequest) -> CheckResult:
    """Verdict of the sample against the standard (``station.qc.check.check_pair``).

    Judged at every geometry of the standard (or of the tolerance set), each of which the sample must
    have (422 naming ``sample.geometries``).
    """
    std = _reading(session, request.standard, "standard")
    smp = _reading(session, request.sample, "sample")
    tol = _tolerance(request, std.aspecular_deg)
    verdict = check_pair(std, smp, tol, request.formula if tol is None else None)
    booth = None
    if request.illuminant_limits is not None:
        booth = check_illuminants(std, smp, request.illuminant_limits, verdict.formula)
    ids = {
        "standard_measurement_id": request.standard.measurement_id,
        "sample_measurement_id": request.sample.measurement_id,
    }
    return cast(CheckResult, {**PairVerdict(verdict, booth).to_dict(), **ids})


def set_standard(*, session: Session, actor: User, job: str, part: str, body: StandardSet) -> StandardOut:
    """Make a measurement or design the standard of *job*/*part* (``station.qc.jobs.set_standard``), audited.

    The body's fields are that function's keywords, passed as they are.
    """
    std = jobs.set_standard(session, job, part, created_by_id=actor.id, **body.model_dump())
    audit.record(
        session=session,
        actor=actor,
        action="qc.standard.set",
        entity="standard",
        entity_id=std.id,
        job=job,
        part=part,
        measurement_id=body.measurement_id,
        design_id=body.design_id,
        replace=body.replace,
    )
    session.commit()
    return StandardOut.model_validate(std)


def get_standard(*, session: Session, job: str, part: str) -> StandardOut:
    """The standard of *job*/*part*, or :class:`NotFoundError`."""
    std = jobs.get_standard(session, job, part)
    if std is None:
        raise NotFoundError(f"no standard set for {job}/{part}")
    return StandardOut.model_validate(std)


def list_jobs(*, session: Session, contains: str | None) -> list[JobOut]:
    """Every job (optionally whose name contains *contains*) with its parts and counts."""
    return [JobOut.model_validate(j.to_dict()) for j in jobs.list_jobs(session, contains)]


@dataclass(frozen=True)
class SummaryOptions:
    """How a job is judged (the query of the summary and report routes; ``station qc summary``'s options).

    *formula* ``din6175-2 | cie2000 | cie94 | cie76``; *illuminant_limits* ``"A=1.0,F11=1.5"``;
    *average_panels* judges each panel once at the mean of its repeat readings, the flagged outliers left
    out unless *keep_outliers*; *texture_limits* ``"ds=1.0,dg=0.5"`` judges sparkle (ΔS) and graininess
    (ΔG) within one vendor, in the vendor's units; *tolerance* a tolerance set as ``station qc tolerance
    --json`` writes it (``station qc summary --tolerance FILE``; the POST routes' body).
    """

    formula: str | None = None
    illuminant_limits: str | None = None
    average_panels: bool = False
    keep_outliers: bool = False
    texture_limits: str | None = None
    tolerance: Mapping[str, Any] | None = None


def _summary(
    session: Session, job: str, options: SummaryOptions, parts: Sequence[str] | None = None
) -> jobs.JobSummary:
    """The job's summary under *options* (of *parts* only when given); ``keep_outliers`` without
    ``average_panels`` is refused (422)."""
    if options.keep_outliers and not options.average_panels:
        raise InputError("keep_outliers", "true only with average_panels=true (nothing is averaged)", True)
    limits = None if options.illuminant_limits is None else parse_illuminant_limits(options.illuminant_limits)
    texture = None if options.texture_limits is None else parse_texture_limits(options.texture_limits)
    tolerance = None if options.tolerance is None else ToleranceSet.from_dict(options.tolerance)
    return jobs.job_summary(
        session,
        job,
        tolerance,
        formula=options.formula,
        parts=parts,
        illuminant_limits=limits,
        average_panels=options.average_panels,
        keep_outliers=options.keep_outliers,
        texture_limits=texture,
    )


def job_summary(*, session: Session, job: str, options: SummaryOptions) -> JobSummaryOut:
    """Every part's standard and each sample's verdict (``station.qc.jobs.job_summary``), with each
    sample's paired gloss reading."""
    data = _summary(session, job, options).to_dict()
    ids = [s["measurement_id"] for p in data["parts"] for s in p["samples"]]
    gloss = gloss_of_measurements(session, ids)

    def paired_gloss(mid: int) -> GlossPublic | None:
        g = gloss.get(mid)
        return None if g is None else GlossPublic.model_validate(g)

    parts: list[PartSummaryOut] = [
        {**p, "samples": [{**s, "gloss": paired_gloss(s["measurement_id"])} for s in p["samples"]]}
        for p in data["parts"]
    ]
    return {**data, "parts": parts}


def report_pdf(*, session: Session, job: str, options: SummaryOptions) -> bytes:
    """The job's QC report as PDF bytes (``station.qc.report.pdf_bytes``) under *options*."""
    from station.qc import report  # matplotlib loads here, not with the service

    return report.pdf_bytes(_summary(session, job, options))


def report_csv(*, session: Session, job: str, options: SummaryOptions) -> str:
    """The job's QC report as CSV text, one row per sample and geometry (``station.qc.report.csv_text``)."""
    from station.qc import report

    return report.csv_text(_summary(session, job, options))


def part_spc(
    *, session: Session, job: str, part: str, options: SummaryOptions, baseline: int | None, subgroup: int
) -> PartSpc:
    """The SPC of *part* of *job* judged under *options*, as ``station qc spc`` computes it
    (:func:`station.qc.spc_part.part_spc` over the part's summary); a bad *baseline* or *subgroup* is
    :class:`~station.qc.errors.QcInputError` naming it (422)."""
    from station.qc import spc_part

    return spc_part.part_spc(_summary(session, job, options, [part]), part, baseline, subgroup)


def spc_png(
    *, session: Session, job: str, part: str, options: SummaryOptions, baseline: int | None, subgroup: int
) -> bytes:
    """The chart of :func:`part_spc` as PNG bytes, as ``station qc spc --out`` draws it."""
    from station.qc.spc_chart import spc_png_bytes  # matplotlib loads here, not with the service

    spc = part_spc(session=session, job=job, part=part, options=options, baseline=baseline, subgroup=subgroup)
    return spc_png_bytes(spc)


def stored_reading(session: Session, measurement_id: int, field: str) -> Reading:
    """The stored measurement *measurement_id* as a QC reading; 404 naming *field* when there is none."""
    m = session.get(Measurement, measurement_id)
    if m is None:
        raise NotFoundError(f"{field}: measurement {measurement_id} not found")
    return reading_from_measurement(m, sample=f"measurement {m.id}")


def metamerism_of(*, session: Session, request: MetamerismRequest) -> MetamerismOut:
    """Metamerism index D65 → A, F11 per geometry of two stored measurements (``station.qc.metamerism``)."""
    std = stored_reading(session, request.standard_measurement_id, "standard_measurement_id")
    smp = stored_reading(session, request.sample_measurement_id, "sample_measurement_id")
    return MetamerismOut.model_validate(metamerism(std, smp, request.formula).to_dict())


def repeats_of(*, session: Session, request: RepeatsRequest) -> RepeatsOut:
    """Mean, sd per geometry and outliers of repeat readings (``station.qc.repeats.summarise``)."""
    ids = request.measurement_ids
    if len(set(ids)) != len(ids):
        raise InputError("measurement_ids", "distinct measurement ids", ids)
    readings = [stored_reading(session, mid, f"measurement_ids[{i}]") for i, mid in enumerate(ids)]
    out = summarise(readings).to_dict()
    rows = [{**row, "measurement_id": ids[row["index"]]} for row in out["readings"]]
    return RepeatsOut.model_validate({**out, "readings": rows})
