"""Panels: ``/api/v1/panels``."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Query, status

from db.models import User
from station.api.deps import ReadSessionDep, SessionDep, scoped
from station.api.errors import ERROR_RESPONSES, NOT_FOUND
from station.api.schemas.common import Id, Limit, Offset, Page
from station.api.schemas.panels import Job, PanelCreate, PanelPublic, Part
from station.api.security import Scope
from station.api.services import panels as service

router = APIRouter(prefix="/panels", tags=["panels"], responses=ERROR_RESPONSES)
Reader = Annotated[User, scoped(Scope.MEASUREMENTS_READ)]
Writer = Annotated[User, scoped(Scope.MEASUREMENTS_WRITE)]


@router.post("", status_code=status.HTTP_201_CREATED, response_model=PanelPublic)
def create_panel(session: SessionDep, user: Writer, panel_in: PanelCreate) -> PanelPublic:
    """Register a painted panel."""
    return PanelPublic.model_validate(service.create_panel(session=session, actor=user, panel_in=panel_in))


@router.get("", response_model=Page[PanelPublic])
def list_panels(
    session: ReadSessionDep,
    _user: Reader,
    job: Annotated[Job | None, Query()] = None,
    part: Part | None = None,
    limit: Limit = 100,
    offset: Offset = 0,
) -> Page[PanelPublic]:
    """Panels of a job and/or part, newest first."""
    rows, total = service.list_panels(session=session, job=job, part=part, limit=limit, offset=offset)
    return Page[PanelPublic](data=[PanelPublic.model_validate(r) for r in rows], count=total)


@router.get("/{panel_id}", response_model=PanelPublic, responses=NOT_FOUND)
def get_panel(session: ReadSessionDep, _user: Reader, panel_id: Id) -> PanelPublic:
    """One panel."""
    return PanelPublic.model_validate(service.get_panel(session=session, panel_id=panel_id))
