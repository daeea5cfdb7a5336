"""Designs: versioned face/flop/travel/gloss bodies in the ``cacad.design/1`` schema."""

from __future__ import annotations

import datetime as dt
from typing import Annotated, Literal

from pydantic import AliasChoices, BaseModel, ConfigDict, Field
from pydantic.config import JsonDict

from station.api.schemas.common import StrictFloat
from station.model.domain import FACE_ANGLE_DEG, GLOSS_MAX_GU, GLOSS_MIN_GU, LAB_RANGES, TRAVEL_MAX_DEG
from station.schema_config import strict_config

# Ranges are the domain's effect-paint bound (station.model.domain): 0 <= L* <= 200, |a*|, |b*| <= 150.
Lab = Annotated[
    tuple[
        Annotated[StrictFloat, Field(ge=LAB_RANGES["L"][0], le=LAB_RANGES["L"][1], allow_inf_nan=False)],
        Annotated[StrictFloat, Field(ge=LAB_RANGES["a"][0], le=LAB_RANGES["a"][1], allow_inf_nan=False)],
        Annotated[StrictFloat, Field(ge=LAB_RANGES["b"][0], le=LAB_RANGES["b"][1], allow_inf_nan=False)],
    ],
    Field(description="[L*, a*, b*], D65/10°"),
]
Name = Annotated[str, Field(min_length=1, max_length=128, pattern=r"^[^\x00-\x1f]+$")]

#: The example design of the OpenAPI schema (also the service tests' design).
DESIGN_EXAMPLE: JsonDict = {
    "schema": "cacad.design/1",
    "name": "Blue metallic",
    "face": [62.0, -4.0, -38.0],
    "flop": [24.0, 1.0, -20.0],
    "travel_deg": 70.0,
    "gloss_gu": 88.0,
}


class DesignBody(BaseModel):
    """A ``cacad.design/1`` design (thesis §3.3: face at 15°, flop at the travel angle θ_clamp)."""

    model_config = ConfigDict(
        extra="ignore", populate_by_name=True, json_schema_extra={"examples": [DESIGN_EXAMPLE]}
    )

    schema_: Literal["cacad.design/1"] = Field("cacad.design/1", alias="schema")
    name: Annotated[str, Field(max_length=128)] = ""
    face: Lab
    flop: Lab
    travel_deg: (
        Annotated[
            StrictFloat,
            Field(gt=FACE_ANGLE_DEG, le=TRAVEL_MAX_DEG, description="θ_clamp, degrees; null for a solid"),
        ]
        | None
    )
    gloss_gu: (
        Annotated[StrictFloat, Field(ge=GLOSS_MIN_GU, le=GLOSS_MAX_GU, description="60° gloss units")] | None
    ) = None


class DesignCreate(BaseModel):
    """Properties to receive on creation (becomes version 1)."""

    model_config = strict_config(
        examples=[{"name": "Blue metallic", "design": DESIGN_EXAMPLE, "note": "first proposal"}]
    )

    name: Name
    design: DesignBody
    note: Annotated[str, Field(max_length=1000)] = ""


class DesignUpdate(BaseModel):
    """A new version of an existing design."""

    model_config = strict_config(examples=[{"design": DESIGN_EXAMPLE, "note": "less travel"}])

    design: DesignBody
    note: Annotated[str, Field(max_length=1000)] = ""


class DesignVersionPublic(BaseModel):
    """One stored version (read from its ``design_versions`` row, whose ``body`` is the design)."""

    model_config = ConfigDict(from_attributes=True)

    design_id: int
    version: int
    design: dict[str, object] = Field(validation_alias=AliasChoices("design", "body"))
    note: str
    created_at: dt.datetime
    created_by_id: int | None


class DesignPublic(BaseModel):
    """A design with its latest version's body."""

    id: int
    name: str
    latest_version: int
    archived: bool
    created_at: dt.datetime
    created_by_id: int | None
    design: dict[str, object]
