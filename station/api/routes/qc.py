"""Colour QC: ``/api/v1/qc`` (gloss readings, the paired measurement view, checks against standards,
standards per job and part, job summaries, metamerism, repeat readings, PDF/CSV reports)."""

from __future__ import annotations

import asyncio
from typing import Annotated

from fastapi import APIRouter, Depends, Query, Request, Response, status
from fastapi import Path as PathParam

from db.models import User
from station.api.deps import ReadSessionDep, SessionDep, scoped
from station.api.errors import CONFLICT, ERROR_RESPONSES, NOT_FOUND, UNAVAILABLE
from station.api.instruments import InstrumentHub
from station.api.routes.measurements import Filters
from station.api.schemas.common import Id, Limit, Offset, Page
from station.api.schemas.panels import Job, Part
from station.api.schemas.qc import (
    CheckRequest,
    CheckResult,
    GlossMeasureRequest,
    GlossPublic,
    JobOut,
    JobSummaryOut,
    JudgeOptions,
    MetamerismOut,
    MetamerismRequest,
    QcMeasurement,
    RepeatsOut,
    RepeatsRequest,
    SpcJudgeOptions,
    StandardOut,
    StandardSet,
)
from station.api.security import Scope
from station.api.services import qc as service
from station.ingest import GlossRecord
from station.qc.spc_part import PartSpcWire

router = APIRouter(prefix="/qc", tags=["qc"], responses=ERROR_RESPONSES)
Reader = Annotated[User, scoped(Scope.MEASUREMENTS_READ)]
Writer = Annotated[User, scoped(Scope.MEASUREMENTS_WRITE)]
Operator = Annotated[User, scoped(Scope.INSTRUMENTS_OPERATE)]


@router.get("/measurements", response_model=Page[QcMeasurement])
def list_measurements(
    session: ReadSessionDep, _user: Reader, q: Filters, limit: Limit = 100, offset: Offset = 0
) -> Page[QcMeasurement]:
    """Measurements by job, part, panel, instrument and time, newest first, each with its paired gloss reading."""
    rows, total = service.list_measurements(session=session, q=q, limit=limit, offset=offset)
    return Page[QcMeasurement](data=rows, count=total)


@router.get("/measurements/{measurement_id}", response_model=QcMeasurement, responses=NOT_FOUND)
def get_measurement(session: ReadSessionDep, _user: Reader, measurement_id: Id) -> QcMeasurement:
    """One measurement with its job, part and paired gloss reading."""
    return service.get_measurement(session=session, measurement_id=measurement_id)


@router.post(
    "/gloss",
    status_code=status.HTTP_201_CREATED,
    response_model=GlossPublic,
    responses={
        200: {"model": GlossPublic, "description": "already stored (same client_id)"},
        **NOT_FOUND,
        **CONFLICT,
    },
)
def create_gloss(session: SessionDep, user: Writer, record: GlossRecord, response: Response) -> GlossPublic:
    """Store a gloss reading once (gloss-only, or naming its colour measurement); a re-send returns 200."""
    stored, created = service.ingest_gloss(session=session, actor=user, record=record)
    if not created:
        response.status_code = status.HTTP_200_OK
    return stored


@router.get("/gloss", response_model=Page[GlossPublic])
def list_gloss(
    session: ReadSessionDep,
    _user: Reader,
    job: Annotated[Job | None, Query()] = None,
    part: Part | None = None,
    panel_id: Annotated[int | None, Query(ge=1, le=2**31 - 1)] = None,
    limit: Limit = 100,
    offset: Offset = 0,
) -> Page[GlossPublic]:
    """Gloss readings of a job, part and/or panel, newest first."""
    rows, total = service.list_gloss(
        session=session, job=job, part=part, panel_id=panel_id, limit=limit, offset=offset
    )
    return Page[GlossPublic](data=rows, count=total)


@router.get("/gloss/{gloss_id}", response_model=GlossPublic, responses=NOT_FOUND)
def get_gloss(session: ReadSessionDep, _user: Reader, gloss_id: Id) -> GlossPublic:
    """One gloss reading."""
    return service.get_gloss(session=session, gloss_id=gloss_id)


@router.post(
    "/gloss/measure",
    status_code=status.HTTP_201_CREATED,
    response_model=GlossPublic,
    responses={**NOT_FOUND, **UNAVAILABLE},
)
async def measure_gloss(
    request: Request, session: SessionDep, user: Operator, body: GlossMeasureRequest
) -> GlossPublic:
    """Measure once on an attached gloss meter and store the reading (20/60/85 GU, haze, DOI, Rspec)."""
    hub: InstrumentHub = request.app.state.instruments
    gloss_id = await asyncio.to_thread(
        hub.measure_gloss,
        instrument_id=body.instrument_id,
        panel_id=body.panel_id,
        measurement_id=body.measurement_id,
        actor=user,
    )
    return service.get_gloss(session=session, gloss_id=gloss_id)


@router.post("/check", response_model=CheckResult, responses=NOT_FOUND)
def check(session: SessionDep, _user: Reader, body: CheckRequest) -> CheckResult:
    """Pass / warn / fail of a sample against a standard (stored measurements or inline Lab), per geometry and overall."""
    return service.check(session=session, request=body)


JobPath = Annotated[
    str, PathParam(min_length=1, max_length=64, pattern=r"^[^\x00-\x1f/]+$", examples=["J-2026-0113"])
]
Formula = Annotated[
    str | None,
    Query(min_length=1, max_length=32, description="din6175-2 | cie2000 | cie94 | cie76 (default din6175-2)"),
]
StandardWriter = Annotated[User, scoped(Scope.QC_STANDARDS_WRITE)]
IlluminantLimits = Annotated[
    str | None,
    Query(
        min_length=1,
        max_length=200,
        description="illuminant rows: ILLUMINANT=LIMIT pairs, the limit on the metamerism index from D65 "
        "per geometry in the formula's ΔE units, e.g. A=1.0,F11=1.5 (samples and standard need spectra)",
        examples=["A=1.0,F11=1.5"],
    ),
]


@router.get("/jobs", response_model=list[JobOut])
def list_jobs(
    session: ReadSessionDep,
    _user: Reader,
    contains: Annotated[
        str | None, Query(min_length=1, max_length=64, description="part of the job name")
    ] = None,
) -> list[JobOut]:
    """Every job with its parts, panel and measurement counts and its first and last reading time."""
    return service.list_jobs(session=session, contains=contains)


@router.put("/jobs/{job}/standards/{part}", response_model=StandardOut, responses=NOT_FOUND)
def set_standard(
    session: SessionDep, user: StandardWriter, job: JobPath, part: Part, body: StandardSet
) -> StandardOut:
    """Make a stored measurement or a design the standard of a job's part (``replace`` to change it)."""
    return service.set_standard(session=session, actor=user, job=job, part=part, body=body)


@router.get("/jobs/{job}/standards/{part}", response_model=StandardOut, responses=NOT_FOUND)
def get_standard(session: ReadSessionDep, _user: Reader, job: JobPath, part: Part) -> StandardOut:
    """The standard of a job's part (404 when none is set)."""
    return service.get_standard(session=session, job=job, part=part)


def summary_options(
    formula: Formula = None,
    illuminant_limits: IlluminantLimits = None,
    average_panels: Annotated[
        bool,
        Query(
            description="judge each panel once, at the mean of its repeat readings; the flagged outliers "
            "(robust z > 3.5) are left out and listed in left_out_readings"
        ),
    ] = False,
    keep_outliers: Annotated[
        bool, Query(description="with average_panels: average the flagged outliers in too")
    ] = False,
    texture_limits: Annotated[
        str | None,
        Query(
            min_length=1,
            max_length=64,
            description="judge texture within one vendor: ds=LIMIT (every sparkle quantity, ΔS) and/or "
            "dg=LIMIT (graininess, ΔG) in the vendor's units, e.g. ds=1.0,dg=0.5",
            examples=["ds=1.0,dg=0.5"],
        ),
    ] = None,
) -> service.SummaryOptions:
    """The query of the summary and report routes as :class:`~station.api.services.qc.SummaryOptions`."""
    return service.SummaryOptions(formula, illuminant_limits, average_panels, keep_outliers, texture_limits)


Options = Annotated[service.SummaryOptions, Depends(summary_options)]


@router.get("/jobs/{job}/summary", response_model=JobSummaryOut)
def job_summary(session: ReadSessionDep, _user: Reader, job: JobPath, options: Options) -> JobSummaryOut:
    """Every part of the job with its standard and each sample's pass / warn / fail per geometry with the
    limit used, the reason, the outliers left out of a panel's mean (``average_panels``), the texture
    verdict (``texture_limits``) and the illuminant rows (``illuminant_limits``)."""
    return service.job_summary(session=session, job=job, options=options)


@router.get(
    "/jobs/{job}/report.pdf",
    response_class=Response,
    responses={200: {"content": {"application/pdf": {"schema": {"type": "string", "format": "binary"}}}}},
)
def report_pdf(session: ReadSessionDep, _user: Reader, job: JobPath, options: Options) -> Response:
    """The job's QC report: verdict table per geometry (illuminant rows with ``illuminant_limits``), L*a*b*
    against angle, ΔE bars and trend, as PDF."""
    body = service.report_pdf(session=session, job=job, options=options)  # a worker thread: a sync route
    return Response(
        body,
        media_type="application/pdf",
        headers={"Content-Disposition": 'attachment; filename="qc-report.pdf"'},
    )


@router.get(
    "/jobs/{job}/report.csv",
    response_class=Response,
    responses={200: {"content": {"text/csv": {"schema": {"type": "string"}}}}},
)
def report_csv(session: ReadSessionDep, _user: Reader, job: JobPath, options: Options) -> Response:
    """The job's QC report as CSV: one row per sample and geometry with standard and sample Lab, differences and verdicts."""
    return Response(
        service.report_csv(session=session, job=job, options=options),
        media_type="text/csv",
        headers={"Content-Disposition": 'attachment; filename="qc-report.csv"'},
    )


def spc_options(
    part: Annotated[Part, Query(description="the part whose samples are charted (oldest first)")],
    baseline: Annotated[
        int | None,
        Query(
            description="points (subgroups with subgroup > 1) that set the centre and control limits, from 2 "
            "to their number (default: all)"
        ),
    ] = None,
    subgroup: Annotated[
        int, Query(description="1: individuals chart (default); 2 … 10: X̄/R chart of consecutive subgroups")
    ] = 1,
) -> tuple[str, int | None, int]:
    """The chart's query (``station qc spc``'s ``--part``, ``--baseline``, ``--subgroup``); ranges are
    judged by ``station.qc.spc_part.part_spc`` (422 naming ``baseline`` or ``subgroup``)."""
    return part, baseline, subgroup


SpcChoice = Annotated[tuple[str, int | None, int], Depends(spc_options)]


@router.get("/jobs/{job}/spc", response_model=PartSpcWire)
def job_spc(
    session: ReadSessionDep, _user: Reader, job: JobPath, chart: SpcChoice, options: Options
) -> PartSpcWire:
    """``station qc spc``: per geometry (and per texture quantity with ``texture_limits``) the part's ΔE
    control chart (individuals or X̄/R) with its Western Electric and Nelson rule hits, Cp/Cpk against the
    limit each sample was judged with, and the drift flagged with whether it came before the first fail;
    the samples judged as the summary judges them under the same options."""
    part, baseline, subgroup = chart
    spc = service.part_spc(
        session=session, job=job, part=part, options=options, baseline=baseline, subgroup=subgroup
    )
    return spc.to_dict()


@router.get(
    "/jobs/{job}/spc.png",
    response_class=Response,
    responses={200: {"content": {"image/png": {"schema": {"type": "string", "format": "binary"}}}}},
)
def job_spc_png(
    session: ReadSessionDep, _user: Reader, job: JobPath, chart: SpcChoice, options: Options
) -> Response:
    """The SPC chart of ``GET /qc/jobs/{job}/spc`` as ``station qc spc --out`` draws it: a panel per chart with
    centre, control limits, the baseline shaded, the limit with Cpk, each rule hit ringed and the drift marked."""
    part, baseline, subgroup = chart
    body = service.spc_png(
        session=session, job=job, part=part, options=options, baseline=baseline, subgroup=subgroup
    )
    return Response(body, media_type="image/png")


def _posted(body: JudgeOptions) -> service.SummaryOptions:
    """The body's options as :class:`~station.api.services.qc.SummaryOptions` (tolerance set included)."""
    return service.SummaryOptions(
        body.formula,
        body.illuminant_limits,
        body.average_panels,
        body.keep_outliers,
        body.texture_limits,
        body.tolerance,
    )


@router.post("/jobs/{job}/summary", response_model=JobSummaryOut)
def job_summary_judged(
    session: ReadSessionDep, _user: Reader, job: JobPath, body: JudgeOptions
) -> JobSummaryOut:
    """``GET /qc/jobs/{job}/summary`` with a tolerance set (``station qc summary --tolerance FILE``): the
    options in the body, the tolerance as ``station qc tolerance --json`` writes it. Reads only."""
    return service.job_summary(session=session, job=job, options=_posted(body))


@router.post(
    "/jobs/{job}/report.pdf",
    response_class=Response,
    responses={200: {"content": {"application/pdf": {"schema": {"type": "string", "format": "binary"}}}}},
)
def report_pdf_judged(session: ReadSessionDep, _user: Reader, job: JobPath, body: JudgeOptions) -> Response:
    """``GET /qc/jobs/{job}/report.pdf`` with a tolerance set in the body."""
    return Response(
        service.report_pdf(session=session, job=job, options=_posted(body)),
        media_type="application/pdf",
        headers={"Content-Disposition": 'attachment; filename="qc-report.pdf"'},
    )


@router.post(
    "/jobs/{job}/report.csv",
    response_class=Response,
    responses={200: {"content": {"text/csv": {"schema": {"type": "string"}}}}},
)
def report_csv_judged(session: ReadSessionDep, _user: Reader, job: JobPath, body: JudgeOptions) -> Response:
    """``GET /qc/jobs/{job}/report.csv`` with a tolerance set in the body."""
    return Response(
        service.report_csv(session=session, job=job, options=_posted(body)),
        media_type="text/csv",
        headers={"Content-Disposition": 'attachment; filename="qc-report.csv"'},
    )


@router.post("/jobs/{job}/spc", response_model=PartSpcWire)
def job_spc_judged(
    session: ReadSessionDep, _user: Reader, job: JobPath, body: SpcJudgeOptions
) -> PartSpcWire:
    """``GET /qc/jobs/{job}/spc`` with a tolerance set (``station qc spc --tolerance FILE``): capability
    against the set's limits; the chart's and the judging's options in the body."""
    spc = service.part_spc(
        session=session,
        job=job,
        part=body.part,
        options=_posted(body),
        baseline=body.baseline,
        subgroup=body.subgroup,
    )
    return spc.to_dict()


@router.post("/metamerism", response_model=MetamerismOut, responses=NOT_FOUND)
def metamerism(session: SessionDep, _user: Reader, body: MetamerismRequest) -> MetamerismOut:
    """Metamerism index of a sample against its standard from D65 to A and F11, per geometry."""
    return service.metamerism_of(session=session, request=body)


@router.post("/repeats", response_model=RepeatsOut, responses=NOT_FOUND)
def repeats(session: SessionDep, _user: Reader, body: RepeatsRequest) -> RepeatsOut:
    """Average of repeat readings of one panel with the sd per geometry and the outliers flagged."""
    return service.repeats_of(session=session, request=body)
