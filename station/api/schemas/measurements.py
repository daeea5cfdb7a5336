"""Measurements: what is stored per reading, queries, corrections."""

from __future__ import annotations

import datetime as dt
import uuid
from typing import Annotated

from pydantic import BaseModel, ConfigDict, Field
from pydantic.config import JsonDict

from station.ingest import Reading, TextureValue
from station.schema_config import strict_config


class MeasurementPublic(BaseModel):
    """A stored, immutable measurement (angles in degrees, Lab D65/10° unless stated, gloss in GU).

    ``geometries_deg`` are aspecular angles under ``illumination_deg`` (45° unless the row is another
    block of a two-illumination reading, e.g. an MA-T12's 15° block stored beside its 45° block);
    ``texture`` lists the vendor texture values (sparkle, graininess) as the vendor reported them, or
    ``null``.
    """

    model_config = ConfigDict(from_attributes=True)

    id: int
    client_id: uuid.UUID
    panel_id: int | None
    instrument_id: int
    instrument_serial: str
    calibration_id: int | None
    operator: str
    measured_at: dt.datetime
    received_at: dt.datetime
    illuminant: str
    observer: str
    illumination_deg: float
    geometries_deg: list[float]
    lab: list[list[float]]
    texture: list[TextureValue] | None = None
    wavelengths_nm: list[float] | None
    spectra: list[list[float]] | None
    gloss_gu: float | None
    gloss_geometry_deg: float | None
    payload_sha256: str
    supersedes_id: int | None
    superseded_by_id: int | None = None
    correction_reason: str | None
    created_by_id: int | None


def _first_example(model: type[BaseModel]) -> JsonDict:
    """The first ``examples`` entry of *model*'s JSON-schema extra, so an example is written once."""
    extra = model.model_config.get("json_schema_extra")
    examples = extra.get("examples") if isinstance(extra, dict) else None
    if isinstance(examples, list) and examples and isinstance(examples[0], dict):
        return examples[0]
    raise TypeError(f"{model.__name__} declares no JSON-schema example")


class CorrectionCreate(BaseModel):
    """A corrected reading for a stored measurement, and why (the original stays, superseded)."""

    model_config = strict_config(
        examples=[
            {
                "reason": "wrong panel scanned; re-measured",
                "reading": _first_example(Reading) | {"client_id": "0e7f3a52-9c1d-4d8e-b7a4-3f6b2c9d1e22"},
            }
        ]
    )

    reason: Annotated[
        str, Field(min_length=3, max_length=1000, examples=["wrong panel scanned; re-measured"])
    ]
    reading: Reading


class MeasurementQuery(BaseModel):
    """Filters of ``GET /measurements`` and its CSV export (all optional, combined with AND)."""

    job: str | None = None
    part: str | None = None
    panel_id: int | None = None
    instrument: str | None = None
    since: dt.datetime | None = None
    until: dt.datetime | None = None
    include_superseded: bool = False
    illumination_deg: float | None = None
