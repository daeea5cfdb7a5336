"""The virtual light booth over stored measurements, stored formulation jobs' recipes (predicted by the
colorant model) or spectra in the body (``station.qc.booth``)."""

from __future__ import annotations

from sqlalchemy.orm import Session

from db.models import FormulationJob
from station.api.errors import NotFoundError
from station.api.schemas.booth import BoothCatalogue, BoothOut, BoothRequest, BoothSpectra
from station.api.services.qc import stored_reading
from station.errors import InputError
from station.formulate.recipe_spectra import is_recipe_document, recipe_from_document, recipe_spectra
from station.model.domain import ANGLES_3, BOOTH_SHAPES
from station.model.errors import ModelInputError
from station.model.illuminants import (
    BOOTH_ILLUMINANTS,
    OBSERVERS,
    REFERENCE_ILLUMINANT,
    Illuminant,
    illuminant_from_spd,
    illuminant_name,
)
from station.qc.booth import BoothRecipe, booth_compare, booth_sides
from station.qc.readings import Reading, reading_from_dict

__all__ = ["booth_of", "catalogue", "stored_recipe"]


def catalogue() -> BoothCatalogue:
    """The booth illuminants (catalogue names), observers and shapes."""
    return BoothCatalogue(
        illuminants=list(BOOTH_ILLUMINANTS),
        observers=dict(OBSERVERS),
        shapes=list(BOOTH_SHAPES),
        reference=REFERENCE_ILLUMINANT,
    )


def _side(session: Session, request: BoothRequest, role: str) -> Reading | BoothRecipe:
    measurement_id = getattr(request, f"{role}_measurement_id")
    recipe_id = getattr(request, f"{role}_recipe_id")
    body: BoothSpectra | None = getattr(request, role)
    if measurement_id is not None:
        return stored_reading(session, measurement_id, f"{role}_measurement_id")
    if recipe_id is not None:
        return stored_recipe(session, recipe_id, f"{role}_recipe_id")
    if body is None:  # the request's validator allows exactly one of the three
        raise InputError(role, f"{role}_measurement_id, {role}_recipe_id or {role}", None)
    return reading_from_dict(body.model_dump(), role)


def stored_recipe(session: Session, recipe_id: int, field: str) -> BoothRecipe:
    """The recipe of the stored formulation job *recipe_id*: 404 naming *field* when there is no such
    job, 422 naming it when the job holds no recipe (its paints' recipes are not from the colorants)."""
    job = session.get(FormulationJob, recipe_id)
    if job is None:
        raise NotFoundError(f"{field}: recipe {recipe_id} not found")
    if not is_recipe_document(job.recipe):
        raise InputError(
            field, "a formulation job with a recipe of the colorants", f"recipe {recipe_id}: no recipe"
        )
    fractions = recipe_from_document(job.recipe, field)
    recipe_spectra(fractions, ANGLES_3, where=field)  # 422 naming the field: a colorant the model lacks
    return BoothRecipe(fractions, f"recipe {recipe_id}")


def _illuminants(request: BoothRequest) -> list[str | Illuminant]:
    users: dict[str, Illuminant] = {}
    for i, u in enumerate(request.user_illuminants):
        ill = illuminant_from_spd(u.name, u.wavelengths_nm, u.values, f"user_illuminants[{i}]")
        if ill.name in users:
            raise InputError(f"user_illuminants[{i}].name", "distinct names", u.name)
        users[ill.name] = ill
    out: list[str | Illuminant] = []
    for i, name in enumerate(request.illuminants):
        if name.strip() in users:
            out.append(users[name.strip()])
            continue
        try:
            out.append(illuminant_name(name))
        except ModelInputError as exc:
            names = ", ".join([*BOOTH_ILLUMINANTS, *users])
            raise InputError(f"illuminants[{i}]", f"one of {names}", name) from exc
    return out


def booth_of(*, session: Session, request: BoothRequest) -> BoothOut:
    """Standard against sample per illuminant and geometry: Lab, ΔE00, metamerism index from D65."""
    illuminants = _illuminants(request)
    std, smp = booth_sides(_side(session, request, "standard"), _side(session, request, "sample"))
    return BoothOut.model_validate(booth_compare(std, smp, illuminants, request.observer).to_dict())
