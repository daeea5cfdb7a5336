"""Analyses: seam QA of two stored measurements (``station.analysis.seam_qa``), stored and audited."""

from __future__ import annotations

import numpy as np
from sqlalchemy import func, select
from sqlalchemy.orm import Session

from db.models import AnalysisResult, Measurement, User
from station.api.errors import NotFoundError
from station.api.schemas.analyses import SeamQaCreate
from station.api.services import audit
from station.model import AspecularMeasurements


def _aspecular(session: Session, measurement_id: int) -> AspecularMeasurements:
    m = session.get(Measurement, measurement_id)
    if m is None:
        raise NotFoundError(f"measurement {measurement_id} not found")
    order = np.argsort(m.geometries_deg)
    return AspecularMeasurements(angles_deg=tuple(float(m.geometries_deg[i]) for i in order),
                                 lab=np.asarray(m.lab, dtype=float)[order], gloss_gu=m.gloss_gu,
                                 illuminant=m.illuminant, observer=m.observer)


def seam_qa(*, session: Session, actor: User, request: SeamQaCreate) -> AnalysisResult:
    """Fit both measurements (eqs 3.3.x), judge the seam at β and store the report."""
    from station.analysis import seam_qa as run_seam_qa

    a = _aspecular(session, request.measurement_a)
    b = _aspecular(session, request.measurement_b)
    report = run_seam_qa(a, b, request.beta_deg, tolerance=request.tolerance, method=request.method)
    row = AnalysisResult(kind="seam_qa", inputs=request.model_dump(), result=report.to_dict(),
                         created_by_id=actor.id)
    session.add(row)
    session.flush()
    audit.record(session=session, actor=actor, action="analysis.seam_qa", entity="analysis", entity_id=row.id,
                 measurement_a=request.measurement_a, measurement_b=request.measurement_b,
                 passed=report.passed)
    session.commit()
    return row


def get_analysis(*, session: Session, analysis_id: int) -> AnalysisResult:
    """Analysis *analysis_id*."""
    row = session.get(AnalysisResult, analysis_id)
    if row is None:
        raise NotFoundError(f"analysis {analysis_id} not found")
    return row


def list_analyses(*, session: Session, kind: str | None, limit: int, offset: int) -> tuple[list[AnalysisResult], int]:
    """Analyses, newest first."""
    query = select(AnalysisResult)
    if kind:
        query = query.where(AnalysisResult.kind == kind)
    total = session.scalar(select(func.count()).select_from(query.subquery())) or 0
    rows = session.scalars(query.order_by(AnalysisResult.id.desc()).limit(limit).offset(offset)).all()
    return list(rows), total
