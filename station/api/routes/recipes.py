"""Recipes: ``/api/v1/recipes`` (ColorSnap formulation jobs; chemists write, others read)."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Query, Request, status

from db.models import User
from station.api.deps import ReadSessionDep, SessionDep, scoped
from station.api.errors import CONFLICT, ERROR_RESPONSES, NOT_FOUND
from station.api.schemas.common import Id, Limit, Offset, Page
from station.api.schemas.recipes import RecipeCreate, RecipePublic
from station.api.security import Scope
from station.api.services import recipes as service
from station.api.services.formulation import app_cache

router = APIRouter(prefix="/recipes", tags=["recipes"], responses=ERROR_RESPONSES)
Reader = Annotated[User, scoped(Scope.LIBRARY_READ)]
Chemist = Annotated[User, scoped(Scope.RECIPES_WRITE)]


@router.post(
    "", status_code=status.HTTP_201_CREATED, response_model=RecipePublic, responses={**NOT_FOUND, **CONFLICT}
)
def create_recipe(
    request: Request, session: SessionDep, user: Chemist, recipe_in: RecipeCreate
) -> RecipePublic:
    """Snap a design version to its k nearest library paints (summed ΔE at 15°/45°/110°) and store the job."""
    return service.create_recipe(
        session=session, actor=user, cache=app_cache(request.app.state), recipe_in=recipe_in
    )


@router.get("", response_model=Page[RecipePublic])
def list_recipes(
    session: ReadSessionDep,
    _user: Reader,
    design_id: Annotated[int | None, Query(ge=1, le=2**31 - 1)] = None,
    limit: Limit = 100,
    offset: Offset = 0,
) -> Page[RecipePublic]:
    """Formulation jobs, newest first."""
    rows, total = service.list_recipes(session=session, design_id=design_id, limit=limit, offset=offset)
    return Page[RecipePublic](data=rows, count=total)


@router.get("/{recipe_id}", response_model=RecipePublic, responses=NOT_FOUND)
def get_recipe(session: ReadSessionDep, _user: Reader, recipe_id: Id) -> RecipePublic:
    """One formulation job."""
    return service.get_recipe(session=session, recipe_id=recipe_id)
