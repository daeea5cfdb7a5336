"""The virtual light booth: standard against sample under booth illuminants (``/api/v1/booth``)."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator

from station.api.schemas.common import StrictFloat, StrictInt
from station.ingest.schema import MAX_GEOMETRIES
from station.model.domain import DEFAULT_BOOTH_ILLUMINANTS
from station.schema_config import strict_config

#: At most this many values in one spectrum or user SPD (a 1 nm grid from 300 to 830 nm fits).
MAX_BANDS = 531
#: At most this many illuminants in one booth request.
MAX_ILLUMINANTS = 16

MeasurementId = Annotated[StrictInt, Field(ge=1, le=2**31 - 1)]
Name = Annotated[str, Field(min_length=1, max_length=64)]


class BoothSpectra(BaseModel):
    """Reflectance per geometry in the body (measured elsewhere, imported or recipe-predicted)."""

    model_config = ConfigDict(extra="forbid")

    geometries: Annotated[
        list[Annotated[str, Field(min_length=1, max_length=16)]],
        Field(min_length=1, max_length=MAX_GEOMETRIES),
    ]
    spectra: Annotated[
        list[Annotated[list[StrictFloat], Field(min_length=2, max_length=MAX_BANDS)]],
        Field(min_length=1, max_length=MAX_GEOMETRIES),
    ]
    wavelengths_nm: Annotated[list[StrictFloat], Field(min_length=2, max_length=MAX_BANDS)] | None = None


class UserIlluminant(BaseModel):
    """A lamp of the lab's own: relative spectral power per wavelength, covering 400–700 nm, all > 0."""

    model_config = ConfigDict(extra="forbid")

    name: Name
    wavelengths_nm: Annotated[list[StrictFloat], Field(min_length=2, max_length=MAX_BANDS)]
    values: Annotated[list[StrictFloat], Field(min_length=2, max_length=MAX_BANDS)]


class BoothRequest(BaseModel):
    """Standard and sample (stored measurement ids, stored formulation jobs' recipes or spectra in the
    body), illuminants and observer. A recipe is predicted by the colorant model at the other side's
    geometries (15/45/110° when both sides are recipes)."""

    model_config = strict_config(
        examples=[
            {
                "standard_measurement_id": 1,
                "sample_measurement_id": 2,
                "illuminants": list(DEFAULT_BOOTH_ILLUMINANTS),
                "observer": "10",
            }
        ]
    )

    standard_measurement_id: MeasurementId | None = None
    sample_measurement_id: MeasurementId | None = None
    standard_recipe_id: MeasurementId | None = None
    sample_recipe_id: MeasurementId | None = None
    standard: BoothSpectra | None = None
    sample: BoothSpectra | None = None
    illuminants: Annotated[list[Name], Field(min_length=1, max_length=MAX_ILLUMINANTS)] = list(
        DEFAULT_BOOTH_ILLUMINANTS
    )
    user_illuminants: Annotated[list[UserIlluminant], Field(max_length=MAX_ILLUMINANTS)] = []
    observer: Literal["2", "10"] = "10"

    @model_validator(mode="after")
    def _one_source_each(self) -> BoothRequest:
        for role in ("standard", "sample"):
            keys = (f"{role}_measurement_id", f"{role}_recipe_id", role)
            if sum(getattr(self, k) is not None for k in keys) != 1:
                raise ValueError(f"{role}: give exactly one of {', '.join(keys)}")
        return self


class BoothGeometryOut(BaseModel):
    """One geometry under one illuminant: both Lab (that illuminant's white), ΔE00 and the metamerism index."""

    geometry: str
    standard_lab: list[float]
    sample_lab: list[float]
    dE00: float
    metamerism_index: float


class BoothIlluminantOut(BaseModel):
    """Every shared geometry under one illuminant, and the mean ΔE00 over them."""

    name: str
    per_geometry: list[BoothGeometryOut]
    mean_de: float


class BoothOut(BaseModel):
    """Per illuminant and geometry: Lab of both, ΔE00, the CIE special metamerism index from the reference."""

    illuminants: list[BoothIlluminantOut]
    reference: str


class BoothCatalogue(BaseModel):
    """The booth's illuminants, observers and shapes."""

    illuminants: list[str]
    observers: dict[str, str]
    shapes: list[str]
    reference: str
