"""The virtual light booth: ``/api/v1/booth`` (standard against sample under booth illuminants)."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter

from db.models import User
from station.api.deps import SessionDep, scoped
from station.api.errors import ERROR_RESPONSES, NOT_FOUND
from station.api.schemas.booth import BoothCatalogue, BoothOut, BoothRequest
from station.api.security import Scope
from station.api.services import booth as service

router = APIRouter(prefix="/booth", tags=["booth"], responses=ERROR_RESPONSES)
Reader = Annotated[User, scoped(Scope.MEASUREMENTS_READ)]


@router.get("/illuminants", response_model=BoothCatalogue)
def illuminants(_user: Reader) -> BoothCatalogue:
    """The booth's illuminants, observers and shapes, and the metamerism index's reference illuminant."""
    return service.catalogue()


@router.post("", response_model=BoothOut, responses=NOT_FOUND)
def booth(session: SessionDep, _user: Reader, body: BoothRequest) -> BoothOut:
    """Standard against sample per booth illuminant and geometry: Lab, ΔE00 and the metamerism index from D65."""
    return service.booth_of(session=session, request=body)
