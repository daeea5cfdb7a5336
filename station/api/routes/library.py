"""Library paints: ``/api/v1/library``."""

from __future__ import annotations

from typing import Annotated, Literal

from fastapi import APIRouter, Path, Query

from db.models import User
from station.api.deps import SessionDep, scoped
from station.api.errors import ERROR_RESPONSES, NOT_FOUND
from station.api.schemas.common import Limit, Offset, Page
from station.api.schemas.library import LibraryPaintPublic
from station.api.security import Scope
from station.api.services import library as service

router = APIRouter(prefix="/library", tags=["library"], responses=ERROR_RESPONSES)
Reader = Annotated[User, scoped(Scope.LIBRARY_READ)]


@router.get("", response_model=Page[LibraryPaintPublic])
def list_paints(session: SessionDep, _user: Reader, category: Literal["solid", "metallic", "pearl"] | None = None,
                code_prefix: Annotated[str | None, Query(max_length=64)] = None, limit: Limit = 100,
                offset: Offset = 0) -> Page[LibraryPaintPublic]:
    """Library paints by category and code prefix, in code order."""
    rows, total = service.list_paints(session=session, category=category, code_prefix=code_prefix, limit=limit,
                                      offset=offset)
    return Page[LibraryPaintPublic](data=[LibraryPaintPublic.model_validate(r) for r in rows], count=total)


@router.get("/{code}", response_model=LibraryPaintPublic, responses=NOT_FOUND)
def get_paint(session: SessionDep, _user: Reader,
              code: Annotated[str, Path(min_length=1, max_length=64)]) -> LibraryPaintPublic:
    """One library paint."""
    return LibraryPaintPublic.model_validate(service.get_paint(session=session, code=code))
