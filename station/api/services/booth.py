"""The virtual light booth over stored measurements or spectra in the body (``station.qc.booth``)."""

from __future__ import annotations

from sqlalchemy.orm import Session

from station.api.schemas.booth import BoothCatalogue, BoothOut, BoothRequest, BoothSpectra
from station.api.services.qc import stored_reading
from station.errors import InputError
from station.model.booth import BOOTH_SHAPES
from station.model.errors import ModelInputError
from station.model.illuminants import (
    BOOTH_ILLUMINANTS,
    OBSERVERS,
    REFERENCE_ILLUMINANT,
    Illuminant,
    illuminant_from_spd,
    illuminant_name,
)
from station.qc.booth import booth_compare
from station.qc.readings import Reading, reading_from_dict

__all__ = ["booth_of", "catalogue"]


def catalogue() -> BoothCatalogue:
    """The booth illuminants (catalogue names), observers and shapes."""
    return BoothCatalogue(
        illuminants=list(BOOTH_ILLUMINANTS),
        observers=dict(OBSERVERS),
        shapes=list(BOOTH_SHAPES),
        reference=REFERENCE_ILLUMINANT,
    )


def _reading(session: Session, measurement_id: int | None, body: BoothSpectra | None, role: str) -> Reading:
    if measurement_id is not None:
        return stored_reading(session, measurement_id, f"{role}_measurement_id")
    if body is None:  # the request's validator allows exactly one of the two
        raise InputError(role, f"{role}_measurement_id or {role}", None)
    return reading_from_dict(body.model_dump(), role)


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
    std = _reading(session, request.standard_measurement_id, request.standard, "standard")
    smp = _reading(session, request.sample_measurement_id, request.sample, "sample")
    return BoothOut.model_validate(booth_compare(std, smp, illuminants, request.observer).to_dict())
