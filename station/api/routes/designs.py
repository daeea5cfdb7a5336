"""Designs: ``/api/v1/designs`` (CRUD with versions; delete archives)."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Query, status

from db.models import User
from station.api.deps import ReadSessionDep, SessionDep, scoped
from station.api.errors import CONFLICT, ERROR_RESPONSES, NOT_FOUND
from station.api.schemas.common import Id, Limit, Offset, Page
from station.api.schemas.designs import DesignCreate, DesignPublic, DesignUpdate, DesignVersionPublic
from station.api.security import Scope
from station.api.services import designs as service

router = APIRouter(prefix="/designs", tags=["designs"], responses=ERROR_RESPONSES)
Reader = Annotated[User, scoped(Scope.DESIGNS_READ)]
Writer = Annotated[User, scoped(Scope.DESIGNS_WRITE)]


@router.post("", status_code=status.HTTP_201_CREATED, response_model=DesignPublic)
def create_design(session: SessionDep, user: Writer, design_in: DesignCreate) -> DesignPublic:
    """Create a design (version 1); the body is validated by the appearance model."""
    return service.create_design(
        session=session, actor=user, name=design_in.name, body=design_in.design, note=design_in.note
    )


@router.get("", response_model=Page[DesignPublic])
def list_designs(
    session: ReadSessionDep,
    _user: Reader,
    name: Annotated[str | None, Query(max_length=128, description="substring of the name")] = None,
    include_archived: bool = False,
    limit: Limit = 100,
    offset: Offset = 0,
) -> Page[DesignPublic]:
    """Designs with their latest version, newest first."""
    rows, total = service.list_designs(
        session=session, name=name, include_archived=include_archived, limit=limit, offset=offset
    )
    return Page[DesignPublic](data=rows, count=total)


@router.get("/{design_id}", response_model=DesignPublic, responses=NOT_FOUND)
def get_design(session: ReadSessionDep, _user: Reader, design_id: Id) -> DesignPublic:
    """One design, latest version."""
    return service.get_design(session=session, design_id=design_id)


@router.put("/{design_id}", response_model=DesignPublic, responses={**NOT_FOUND, **CONFLICT})
def update_design(session: SessionDep, user: Writer, design_id: Id, update: DesignUpdate) -> DesignPublic:
    """Save a new version (earlier versions stay readable)."""
    return service.add_version(
        session=session, actor=user, design_id=design_id, body=update.design, note=update.note
    )


@router.delete("/{design_id}", response_model=DesignPublic, responses=NOT_FOUND)
def archive_design(session: SessionDep, user: Writer, design_id: Id) -> DesignPublic:
    """Archive a design (nothing is deleted; versions stay readable)."""
    return service.archive(session=session, actor=user, design_id=design_id)


@router.get("/{design_id}/versions", response_model=list[DesignVersionPublic], responses=NOT_FOUND)
def list_versions(session: ReadSessionDep, _user: Reader, design_id: Id) -> list[DesignVersionPublic]:
    """Every version, oldest first."""
    return service.list_versions(session=session, design_id=design_id)


@router.get("/{design_id}/versions/{version}", response_model=DesignVersionPublic, responses=NOT_FOUND)
def get_version(session: ReadSessionDep, _user: Reader, design_id: Id, version: Id) -> DesignVersionPublic:
    """One version."""
    return service.get_version(session=session, design_id=design_id, version=version)
