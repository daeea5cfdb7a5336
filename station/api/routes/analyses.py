"""Analyses: ``/api/v1/analyses`` (QA runs seam analyses of measured panels; everyone who reads measurements reads them)."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Query, Response, status

from db.models import User
from station.api.deps import ReadSessionDep, SessionDep, scoped
from station.api.errors import ERROR_RESPONSES, NOT_FOUND
from station.api.schemas.analyses import (
    AnalysisPublic,
    GgIndexEnvironmentRequest,
    GgIndexOut,
    GgIndexRequest,
    SeamQaCreate,
    SweepOut,
    SweepRequest,
    TrompeOut,
    TrompeRequest,
)
from station.api.schemas.common import Id, Limit, Offset, Page
from station.api.security import Scope
from station.api.services import analyses as service

router = APIRouter(prefix="/analyses", tags=["analyses"], responses=ERROR_RESPONSES)
Reader = Annotated[User, scoped(Scope.MEASUREMENTS_READ)]
Analyst = Annotated[User, scoped(Scope.ANALYSIS_WRITE)]


@router.post("/seam", status_code=status.HTTP_201_CREATED, response_model=AnalysisPublic, responses=NOT_FOUND)
def seam_qa(session: SessionDep, user: Analyst, request: SeamQaCreate) -> AnalysisPublic:
    """Judge the seam between two panels (measured or designed) at a misalignment β (thesis ch. 4) and store
    the report: seam ΔE, geometric vs formulation share, goniogeometric index, advice and a corrected paint
    for B."""
    return AnalysisPublic.model_validate(service.seam_qa(session=session, actor=user, request=request))


# The computations below are CPU work: plain ``def`` routes, so FastAPI runs them in its thread pool.
@router.post("/gg-index", response_model=GgIndexOut)
def gg_index(_user: Analyst, request: GgIndexRequest) -> dict[str, Any]:
    """Goniogeometric index β_min (eq 4.3.1): the smallest misalignment whose seam ΔE reaches ε over the
    given geometries, the direction and the geometry attaining it (resolution 1e-6°). Nothing is stored."""
    return service.gg_index(request=request)


@router.post("/gg-index/environment", response_model=GgIndexOut)
def gg_index_environment(_user: Analyst, request: GgIndexEnvironmentRequest) -> dict[str, Any]:
    """Environment-lit goniogeometric index β_min (eq 4.3.1, thesis §4.3): the smallest misalignment whose
    seam ΔE reaches ε with both panels lit by a built-in environment or an uploaded .hdr/.exr
    (``environment_hdr``, base64, size-capped as for ``/styling/render``), turned by ``rotation_deg``,
    panel A facing up or front; nothing is stored. The answer adds ``environment`` and ``samples``."""
    return service.gg_index_environment(request=request)


@router.post("/trompe-loeil", response_model=TrompeOut)
def trompe_loeil(_user: Analyst, request: TrompeRequest) -> dict[str, Any]:
    """Inverse trompe l'oeil (§4.4): the paint for the misaligned panel that minimises the seam ΔE (one
    geometry, RMS, minimax or per geometry), kept paintable. Nothing is stored."""
    return service.trompe_loeil(request=request)


@router.post("/sweep", response_model=SweepOut)
def sweep(_user: Analyst, request: SweepRequest) -> dict[str, Any]:
    """Seam ΔE of one paint on both panels over β × light × view (thesis Fig. 4.3). Nothing is stored."""
    return service.sweep(request=request)


@router.get("", response_model=Page[AnalysisPublic])
def list_analyses(
    session: ReadSessionDep,
    _user: Reader,
    kind: Annotated[str | None, Query(max_length=32)] = None,
    limit: Limit = 100,
    offset: Offset = 0,
) -> Page[AnalysisPublic]:
    """Stored analyses, newest first."""
    rows, total = service.list_analyses(session=session, kind=kind, limit=limit, offset=offset)
    return Page[AnalysisPublic](data=[AnalysisPublic.model_validate(r) for r in rows], count=total)


@router.get(
    "/{analysis_id}/report.png",
    response_class=Response,
    responses={
        **NOT_FOUND,
        200: {
            "content": {"image/png": {"schema": {"type": "string", "format": "binary"}}},
            "description": "the seam QA report picture",
        },
    },
)
def report_png(session: ReadSessionDep, _user: Reader, analysis_id: Id) -> Response:
    """The seam QA report as a PNG: both panels rendered side by side as painted and with the corrected
    paint, and the BRDF curves of paint A, paint B and the correction compared (thesis Fig. 4.7)."""
    return Response(service.report_png(session=session, analysis_id=analysis_id), media_type="image/png")


@router.get("/{analysis_id}", response_model=AnalysisPublic, responses=NOT_FOUND)
def get_analysis(session: ReadSessionDep, _user: Reader, analysis_id: Id) -> AnalysisPublic:
    """One stored analysis."""
    return AnalysisPublic.model_validate(service.get_analysis(session=session, analysis_id=analysis_id))
